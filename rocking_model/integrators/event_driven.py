"""Event-driven scheme: smooth phases in the reduced coordinates of their contact mode, LCPs at events.

- Each smooth phase is integrated with an adaptive Runge-Kutta scheme (DOP853 by default, or DOPRI5) on
  the reduced state y = [r, r_dot] of the current mode (full contact: the model's free DOFs only, none for
  the rigid block; rocking: phi, plus u for the flexible oscillator; flight: all), with the model's
  float-level right-hand side (`RockingModel.mode_functions`).
- Event functions are positive inside the mode and fall through zero at an event: the approaching corner's
  opening (impact), the normal force of a closed corner (release/uplift), pi/2 - |phi| (overturning). Events
  are located on the dense output by a bracketing root finder to round-off in time; the state is taken on
  the far side of the root, so the LCP that follows sees the event as happened. A function that dips below
  zero and comes back within one step (the base of a vibrating column) is searched for when a cubic Hermite
  estimate of its midpoint value lies below both ends.
- At an impact the velocity-level LCP (Newton's law) gives the post-impact velocities; at every mode entry
  the acceleration-level LCP decides which corners stay closed. An event just handled starts disarmed and is
  re-armed once its function is positive again (masking), so a restart never re-triggers it; a disarmed
  function still fires once it falls below -event_tol (a grazing entry that turns back). An open corner
  that starts a segment at the ground and is back at or below it after the first step is searched for a
  short bounce (above 1e-3 event_tol, sampled towards the start) and then lands at zero; a corner found
  below the ground beyond round-off (a grazing landing) is put back onto it (`project_to_ground`) and
  closed plastically, unless the sticking LCP then has no solution (the corner should slide: bug 7, not
  held then, as a chatter of grazing landings would cost thousands of events).
- Zeno rule (end of impact accumulation; thresholds in `rocking_model.tolerances`): after an impact, a corner at
  the ground is closed plastically if its post-impact separation velocity is below v_Zeno = zeno_tol *
  sqrt(g L) (L the model's length scale; velocity test) or, only while every corner leaves (free flight) and
  none is closed, if it is the corner of lowest free-flight bounce U_N^2 / (2 |a_N|) and that bounce stays
  within gap_tol of the ground (bounce test: U_N < sqrt(2 |a_N| gap_tol), 44.7 v_Zeno at |a_N| = g and the
  defaults). The impact LCP is then solved again from the pre-impact velocities with the closed corners held
  closed, and both tests are applied to the new outcome: a corner that leaves while another is closed rotates
  about it (not a free flight) and is closed only below v_Zeno. The kinetic energy this removes is at most of
  the order of 1/2 m v_Zeno^2 + m |a_N| gap_tol. Impacts slower than v_Zeno are not counted. A corner closed
  within gap_tol above the ground is a rocking mode's pivot exactly at it: the entry projects the state onto
  the ground (`_onto_ground`), so no mode starts with its open corner below it; a loaded state that does and
  whose corner approaches starts with an impact (`_lands_now`).
- Painleve count (``painleve``): each stick-making impulse of a Painleve situation, applied where the uplift LCP
  of a sliding corner has no or several solutions (`_decide`) or made by an impact LCP on a corner that slid
  in Painleve's configuration (`rocking_model.contact.painleve_sticks`).
- Friction demand (``friction_demand``): the maximum of |sum lambda_T| / sum lambda_N along the motion to the
  tolerance (at both limits of every event, at step ends, inside a step where it peaks: `_demand_peak`) and
  of each impact's percussions (`_note_percussions`).
- Overturning (|phi| = pi/2, located as an event) ends the motion: the pose reached is kept at rest.
- ``advance(t_end, ag, samples)`` integrates through the sample times (an output grid) and reads the state
  there from the dense output, so a fine output grid does not shorten the steps.
- Work budget: ``advance(..., max_steps=N)`` counts Runge-Kutta steps plus EVENT_WORK = 30 per event and
  raises `WorkLimitError` when one call (or, with samples, the stretch between two samples) needs more than N.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from ..contact import closed_candidates, impact, inverse_mass, next_mode, painleve_sticks, project_to_ground
from ..lcp import SLIDE_NEG, SLIDE_POS, STICK
from ..models.sliding import shift_of
from ..modes import OVERTURNED, SLIDING, BoundedLog, bounded_log
from ..tolerances import DEFAULT_TOLERANCES, ZENO_TOL, ContactTolerances
from ..validation import WorkLimitError, check_choice, check_real, state_bool, state_float, state_floats, state_int
from .base import Integrator, SolverOptions, register_scheme
from .dop853 import DOP853
from .dopri5 import DOPRI5
from .events import bounce_search, brent_max, dip_search, earliest_root, first_negative, may_dip, parabola_peak, sinks
from .moreau_jean import inexact_message
from .state import check_configuration, check_times

_KIND_IMPACT, _KIND_RELEASE, _KIND_OVERTURN = "impact", "release", "overturn"
#: a sliding mode's slip velocity reaches zero (stop or reversal); a sticking mode reaches its friction cone
_KIND_SLIP, _KIND_CONE = "slip", "cone"

#: [steps] what one event counts in the work budget (``max_steps``): locating it (some 10 to 60 evaluations of
#: the event functions on the dense output) and the impact and uplift LCPs cost about as much as 20 (rigid
#: block) to 35 (flexible oscillator in flight) Runge-Kutta steps (measured: 0.7 ms and 1.9 ms per event
#: against 20 and 55 us per step), so that the budget bounds the time of an event storm as of a long stretch
#: of smooth steps
EVENT_WORK = 30
#: [1] the friction demand's peak inside a step is searched for (`EventDriven._demand_peak`) when the parabola
#: through the demand at the step's ends and middle peaks inside the step above (1 - DEMAND_PEAK_MARGIN) times
#: the largest demand so far: the steps resolve the motion to the tolerance, so the parabola's error on a
#: step's peak is far below 10 %, and a peak it puts lower cannot raise the maximum (the search is skipped)
DEMAND_PEAK_MARGIN = 0.1
#: [1] a step whose ends both need less than this fraction of the largest demand so far is not searched: its
#: peak would have to double within one step, which the steps' resolution of the motion excludes (away from a
#: lift-off, where the ends themselves grow); it keeps the search off most steps of a long record
DEMAND_STEP_GATE = 0.5
#: the Runge-Kutta pairs of the smooth phases, by name
#: [1] steps a segment may refuse (each retried at half its length) because their interpolant sinks an open
#: corner that started the segment at the ground (watched: `dip_search` sees only armed ones) below -gap, the
#: documented event penetration, while the step's end does not fire it (`sinks`): the Runge-Kutta error control
#: bounds a step's end, not its dense output, which at loose tolerances rocks the body through the ground after
#: an uplift, and a landing inside the first step after a bounce went unseen (tests/test_wrong_side.py). A
#: shorter step ends below the ground at a real landing (an event) and has an accurate interpolant otherwise;
#: 8 halvings cut the interpolant's error by 2^-64 (DOP853), past them the step is taken as it is
MAX_SINK_REFUSALS = 8
METHODS = {"DOP853": DOP853, "DOPRI5": DOPRI5}
#: accepted spellings of ``method``
METHOD_CHOICES = {"DOP853": "DOP853", "DOPRI5": "DOPRI5", "RK45": "DOPRI5", 0: "DOP853", 1: "DOPRI5"}


def _inputs(ag, t: float) -> tuple:
    """(ag(t), ag_v(t)) [m/s2] of the GroundMotion ``ag`` at t: the horizontal and the vertical ground
    acceleration (0.0 without a vertical component), what the contact problems at an event take."""
    vert = ag.vertical
    return ag(t), 0.0 if vert is None else vert(t)


@register_scheme
class EventDriven(Integrator):
    """Event-driven integration of ``model`` with relative/absolute tolerance ``tolerance``.

    method: "DOP853" (order 8) or "DOPRI5" (order 5, cheaper at loose tolerances).
    impact_log_size: number of impacts kept in ``impact_times`` / ``impact_log`` (None: all); the counter
    ``impacts`` counts them all. A bound keeps the memory flat over arbitrarily long runs.
    """

    name = "event_driven"
    code = 1
    summary = "event-driven: Runge-Kutta phases in reduced coordinates, LCPs at events (the faster at equal error, see docs/performance.md)"
    STATE_TOKEN = "y"
    LOGS = ("impact_times", "impact_log")
    _live = None            #: the stepper of the last segment, while it may go on (see `_stepper`)
    _max_work = None        #: work budget of the current `advance` (None: unlimited)
    _work_end = math.inf    #: value of n_steps at which the budget runs out
    _demand_end = None      #: (t, y, totals, demand) at the end of the last segment without an event (the same
    #:                         totals: the same mode and input, so a segment that carries on keeps its value)

    @classmethod
    def from_options(cls, model, mode, q, v, t0, options: SolverOptions) -> "EventDriven":
        tol = check_real("tolerance", options.tolerance, lo=1e-14, hi=1e-2)
        zt = check_real("zeno_tol", options.zeno_tol, lo=0.0, hi=1e-2, lo_open=True)
        method = check_choice("method", options.method, METHOD_CHOICES)
        return cls(model, mode, q, v, t0, tolerance=tol, dt_max=options.dt_max or math.inf, zeno_tol=zt,
                   method=method, impact_log_size=options.impact_log_size, tolerances=options.tolerances)

    def __init__(self, model, mode, q: np.ndarray, v: np.ndarray, t0: float,
                 tolerance: float = 1e-8, dt_max: float = math.inf, zeno_tol: float = ZENO_TOL,
                 max_events: int = 100000, method: str = "DOP853", impact_log_size: int | None = None,
                 tolerances: ContactTolerances = DEFAULT_TOLERANCES):
        self.model = model
        self.t = float(t0)
        self.tolerance = tolerance
        self.dt_max = dt_max
        self.method = method
        self.tolerances = tolerances
        scaled = tolerances.for_model(model)
        #: [m] a corner this close to the ground is at the ground (ContactTolerances.gap)
        self.gap_tol = scaled.gap
        #: [m/s] a normal velocity this small is zero (ContactTolerances.rest_velocity)
        self.v_tol = scaled.rest_velocity
        #: [m/s] the Zeno rule's velocity test (`rocking_model.tolerances.ZENO_TOL`)
        self.v_zeno = zeno_tol * scaled.velocity_scale
        #: [1] how far below zero a disarmed (normalised) event function may go before it fires
        self.event_tol = tolerances.event
        #: [s] longest step of a phase without state (ContactTolerances.stateless_step)
        self.stateless_step = scaled.stateless_step
        #: [N] a normal force below this carries no load (ContactTolerances.demand_floor)
        self.force_floor = scaled.force_floor
        self.reports = []
        self.max_events = max_events
        self.impacts = 0
        self.impact_times: BoundedLog = BoundedLog(impact_log_size)
        #: (t, v_minus, v_plus) of the impacts, full velocities (the last 1000 with a bounded log)
        self.impact_log: BoundedLog = BoundedLog(None if impact_log_size is None else min(1000, impact_log_size))
        self.overturned = False
        self.n_steps = 0
        self._h = None
        self._set_state(model.mode_code(int(mode)), np.asarray(q, float), np.asarray(v, float))

    # ------------------------------------------------------------------ state
    def _set_state(self, mode, q, v):
        model = self.model
        old = self.__dict__.get("mode")
        self.mode = mode
        q = self._onto_ground(mode, q, v)
        r, rd = model.reduce_any(self.mode, q, v)
        self.k = len(r)
        self.y = [float(a) for a in r] + [float(a) for a in rd]
        self._full = None
        # a sticking mode on the ground keeps the base's horizontal offset (it has slid, or landed off its rest
        # position) outside its reduced state: unchanged from a sticking mode (the corners did not move), read
        # off the state after flight or sliding (below gap_tol it is round-off of the events)
        shift = 0.0
        if mode not in SLIDING and model.closed_of(mode):
            if old is not None and old not in SLIDING and model.closed_of(old):
                shift = self.shift
            else:
                shift = shift_of(model, mode, q)
                if abs(shift) <= self.gap_tol:
                    shift = 0.0
        self.shift = shift

    def _onto_ground(self, mode, q, v):
        """q, projected onto the ground where entering ``mode`` would otherwise put an open corner below it.

        The reduced coordinates of a mode hold its closed corners exactly at the ground (a rocking mode's pivot),
        while the contact problems close any corner within gap_tol of it: the Zeno rule closes a corner that
        hovers some 1e-9 L up at the end of a chatter. Reducing then lowers the body by that gap and an open corner
        that the impact left at the ground ends below it, its tilt on the far side of the pivot, beyond event_tol:
        its event function never fires and it would sink through the ground unseen. Instead every corner the
        reduction would put below the ground and the closed ones are put exactly onto it (`project_to_ground`, a
        shift of at most gap_tol), so that the open one starts the mode at the ground, watched, and the contact
        problems decide whether it lands."""
        model = self.model
        closed = model.closed_of(mode)
        if not closed or len(closed) == model.n_contacts:
            return q
        g = model.gaps(q)
        rnd = self.tolerances.grazing * self.gap_tol      # [m] round-off of a located event's gap
        if all(g[i] <= rnd for i in closed):
            return q                                      # (the reduction lowers nothing)
        g_in = model.gaps(model.embed_any(mode, *model.reduce_any(mode, q, v))[0])
        sunk = [i for i in range(model.n_contacts) if i not in closed and g_in[i] < -rnd]
        return project_to_ground(model, q, set(closed) | set(sunk)) if sunk else q

    def state(self):
        """Full (q, v) at the current time."""
        if self._full is None:
            k = self.k
            q, v = self.model.embed_any(self.mode, np.array(self.y[:k]), np.array(self.y[k:]))
            if self.shift:
                q = np.array(q, dtype=float)
                q[self.model.slide_index] += self.shift
            self._full = (q, v)
        return self._full

    def outputs(self) -> dict:
        """The model's outputs at the current time."""
        return self.model.outputs_of(self.mode, self.y, self.shift)

    def _functions(self, mode, ag):
        """(rhs, G, totals) of ``mode``: `RockingModel.functions_of` (G the event function vector: contacts,
        the friction events, then the overturning margin) and, with closed corners, `force_totals_of` (the
        friction demand; None in flight); reused while the mode and a constant input stay the same (each
        co-simulation step would otherwise build them twice)."""
        if ag.constant:
            key = (mode, ag.value) if ag.vertical is None else (mode, ag.value, ag.vertical.value)
        else:
            key = (mode, id(ag))
        cached = self.__dict__.get("_fn_cache")
        if cached is not None and cached[0] == key and (ag.constant or cached[1] is ag):
            return cached[2]
        fns = self.model.functions_of(mode, ag)
        self._fn_cache = (key, ag, fns)
        return fns

    # ------------------------------------------------------------------ plain-data state
    #: fields of `get_state` (the Simulator adds the header: version, scheme, model, n_dof)
    STATE_KEYS = ("t", "mode", "y", "impacts", "overturned", "n_steps", "h", "impact_times", "impact_log",
                  "shift", "friction_demand", "painleve")

    def get_state(self) -> dict:
        """What determines the future of this integrator, as plain data (see `Simulator.get_state`).

        The live Runge-Kutta stepper (``_live``) is left out: a restart from (t, y) with the last step size
        ``h`` takes the same steps bit for bit (its FSAL derivative is evaluated at the stored time). The
        impact logs keep their last ``maxlen`` entries (what `BoundedLog.tail` returns); each impact_log row
        (t, v_minus, v_plus) is flattened to 1 + 2 n_dof floats."""
        flat = []
        for t, vm, vp in self.impact_log.tail():
            flat.append(float(t))
            flat.extend(float(a) for a in vm)
            flat.extend(float(a) for a in vp)
        return {"t": float(self.t), "mode": int(self.mode), "y": [float(a) for a in self.y],
                "impacts": int(self.impacts), "overturned": bool(self.overturned), "n_steps": int(self.n_steps),
                "h": math.nan if self._h is None else float(self._h),
                "impact_times": [float(a) for a in self.impact_times.tail()], "impact_log": flat,
                "shift": float(self.shift), "friction_demand": float(self.friction_demand),
                "painleve": int(self.painleve)}

    def set_state(self, state) -> None:
        """Load a `get_state` dict (header and keys checked by the caller): every field is checked for type,
        length, range and consistency with the model (ValueError naming the field); nothing changes on
        error."""
        model = self.model
        t = state_float(state, "t")
        mode = model.mode_code(state_int(state, "mode", 0, model.n_modes - 1))
        k = len(model.dofs_of(mode))
        y = state_floats(state, "y", length=2 * k)
        impacts = state_int(state, "impacts")
        overturned = state_bool(state, "overturned")
        n_steps = state_int(state, "n_steps")
        h = state_float(state, "h", lo=0.0, lo_open=True, nan_ok=True)
        times = check_times(state, "impact_times", state_floats(
            state, "impact_times", max_len=self.impact_times.maxlen), t, impacts)
        n = 1 + 2 * model.n_dof
        flat = state_floats(state, "impact_log", multiple=n,
                            max_len=None if self.impact_log.maxlen is None else n * self.impact_log.maxlen)
        rows = [(flat[i], np.array(flat[i + 1:i + 1 + model.n_dof]), np.array(flat[i + 1 + model.n_dof:i + n]))
                for i in range(0, len(flat), n)]
        check_times(state, "impact_log", [r[0] for r in rows], t, impacts)
        q, v = model.embed_any(mode, np.array(y[:k]), np.array(y[k:]))
        shift = state_float(state, "shift")
        if shift and (mode in SLIDING or not model.closed_of(mode)):
            raise ValueError(f"state field 'shift' = {shift!r} must be 0 in mode {int(mode)} (its reduced state "
                             "holds the base's position)")
        demand = state_float(state, "friction_demand", lo=0.0)
        painleve = state_int(state, "painleve")
        # a corner may sink in flight where the sticking law has no solution (bug 7, a documented model gap:
        # 33 mm measured before an overturning): only junk, a corner a whole length scale down, is refused
        check_configuration(model, state, "y", q, v, overturned, gap_tol=model.length_scale)
        # all checked: assign
        self.t, self.impacts, self.overturned, self.n_steps = t, impacts, overturned, n_steps
        self._h = None if h != h else h
        self.mode, self.k, self.y, self._full, self.shift = mode, k, y, None, shift
        self.friction_demand, self.painleve = demand, painleve
        self._live = None
        self.impact_times = bounded_log(self.impact_times.maxlen, times)
        self.impact_log = bounded_log(self.impact_log.maxlen, rows)

    def rollback(self, snap) -> None:
        super().rollback(snap)
        self._live = None             # it has moved on; a restart from (t, y, _h) is bit-identical

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_fn_cache", None)      # closures: rebuilt on demand
        state.pop("_live", None)          # the stepper holds them too; a restart is bit-identical
        state.pop("_demand_end", None)    # holds a closure; the demand there is recomputed (the same value)
        return state

    def _atol(self, mode):
        cached = self.__dict__.setdefault("_atol_cache", {})
        if mode not in cached:
            cached[mode] = self._atol_of(mode)
        return cached[mode]

    def _atol_of(self, mode):
        dof_scales = self.model.dof_scales
        s = [dof_scales[i] for i in self.model.dofs_of(mode)]
        ts = self.model.time_scale
        return [self.tolerance * a for a in s] + [self.tolerance * a / ts for a in s]

    # ------------------------------------------------------------------ driver
    def advance(self, t_end: float, ag, max_steps: int | None = None) -> None:
        """Integrate to exactly t_end; ``ag`` is a GroundMotion.

        max_steps: work budget (None: unlimited): Runge-Kutta steps plus EVENT_WORK per event; exceeding it
        raises `WorkLimitError` (the state is then partly advanced: `Simulator.advance` restores it)."""
        self._run(t_end, ag, None, max_steps)

    def sample(self, times, ag, max_steps: int | None = None):
        """Outputs at ``times`` in one pass, read from the dense output (a fine output grid does not shorten
        the steps) and evaluated per contact mode on arrays; the work budget applies between consecutive
        times. See `Integrator.sample`."""
        samples = [self._sample_row(self.mode, list(self.y))]
        samples += self._run(float(times[-1]), ag, times, max_steps)
        modes = np.array([int(smp[0]) for smp in samples])
        overturned = np.array([smp[3] for smp in samples], dtype=bool)
        values = {}
        for code in np.unique(modes):
            idx = np.nonzero(modes == code)[0]
            out = self.model.outputs_array_of(self.model.mode_code(int(code)),
                                              np.array([samples[i][1] for i in idx]),
                                              np.array([samples[i][4] for i in idx]))
            for name, arr in out.items():
                values.setdefault(name, np.empty(len(samples)))[idx] = arr
        values["friction_demand"] = np.array([smp[5] for smp in samples])
        values["painleve"] = np.array([smp[6] for smp in samples])
        # (the outputs above are evaluated in the last contact mode; the output contact reads OVERTURNED)
        return (np.where(overturned, OVERTURNED, modes), values, np.array([smp[2] for smp in samples]),
                overturned)

    def _sample_row(self, mode, y, overturned=None):
        """A sample of `sample`: (mode, y, impacts, overturned, shift, friction_demand, painleve)."""
        return (mode, y, self.impacts, self.overturned if overturned is None else overturned, self.shift,
                self.friction_demand, self.painleve)

    def _run(self, t_end: float, ag, samples, max_steps):
        """`advance` to t_end recording (mode, y, impacts, overturned) at the increasing ``samples`` in
        (t, t_end] (None: no samples, returns None); the work budget of ``max_steps`` then applies between two
        samples."""
        self._max_work = max_steps
        self._work_end = math.inf if max_steps is None else self.n_steps + max_steps
        self._span = (self.t, t_end)
        self._impacts0 = self.impacts
        out = None if samples is None else []
        pending = deque(float(s) for s in samples) if samples is not None else None
        if t_end <= self.t or self.overturned:
            if t_end > self.t:
                self.t = t_end
            while pending:
                pending.popleft()
                out.append(self._sample_row(self.mode, list(self.y)))
            return out
        n_events = 0
        kink = False              # the last segment ended at a breakpoint where ag is continuous
        end_tol = 4.0 * math.ulp(max(abs(t_end), 1.0))
        while not self.overturned:
            if t_end - self.t <= end_tol:
                break
            tb = ag.next_breakpoint(self.t)
            t_stop = t_end if t_end < tb else tb
            if self.model.closed_of(self.mode) and not kink:
                self._settle(self.t, ag)
            if self._segment(t_stop, ag, pending, out):
                self._live = None
                kink = False
                n_events += 1
                self._work_end -= EVENT_WORK
                if n_events > self.max_events:
                    raise WorkLimitError(f"event_driven: more than {self.max_events} events in one advance "
                                         f"at t = {self.t:.17g} s; the motion does not settle; the step was "
                                         "refused. Way out: shorter communication steps")
            elif t_stop == tb:
                # a kink of ag (a sample of a record): the contact forces stay continuous, so the mode holds
                # and the step goes on across it; a jump: re-decide the mode and restart
                kink = ag.continuous_at(tb)
                if not kink:
                    self._live = None
        self.t = t_end
        self._full = None
        while pending:                     # samples at t_end (or after overturning: frozen state)
            pending.popleft()
            out.append(self._sample_row(self.mode, list(self.y)))
        return out

    def _settle(self, t, ag):
        """Re-decide the mode of the current state by the acceleration LCP (after an input change)."""
        mode = self.mode
        closed = self.model.closed_of(mode)
        monitors = self._functions(mode, ag)[1]
        e = monitors(t, self.y)
        nc = self.model.n_contacts
        # fast path: closed corners loaded, open corners clearly open, friction within its cone or the slip
        # going on or just starting (then the mode still holds: the boundary between sticking and sliding is
        # crossed by the events, which know the direction)
        clear = self.tolerances.clearly_open
        if all(e[i] >= 0.0 if i >= nc else e[i] > 0.0 if i in closed else e[i] > clear
               for i in range(len(e) - 1)):
            return
        q, v = self.state()
        if all(i in closed for i in closed_candidates(self.model, q, v, self.gap_tol, self.v_tol)):
            if all(e[i] > 0.0 for i in closed) and all(g >= 0.0 for g in e[nc:-1]):
                return
        new, v_new = self._decide(q, v, _inputs(ag, t), t)
        if new != mode or v_new is not v:
            self._set_state(new, q, v_new)

    # ------------------------------------------------------------------ smooth phase
    def _segment(self, t_stop: float, ag, pending, out) -> bool:
        """Integrate the current mode towards t_stop; returns True if an event ended the segment."""
        mode, k = self.mode, self.k
        if pending and pending[0] <= self.t:
            while pending and pending[0] <= self.t:
                pending.popleft()
                out.append(self._sample_row(mode, list(self.y), False))
            if self._max_work is not None:
                self._work_end = self.n_steps + self._max_work
        if k == 0 and ag.constant:
            # nothing moves and the (positive) contact forces cannot change
            totals = self._functions(mode, ag)[2]
            if totals is not None:
                self.note_demand(*totals(self.t, self.y), self.force_floor)
            self.t = t_stop
            while pending and pending[0] <= t_stop:
                pending.popleft()
                out.append(self._sample_row(mode, list(self.y), False))
            self._full = None
            return False
        rhs, G, totals = self._functions(mode, ag)
        kinds = self._kinds(mode)
        # the friction demand |sum lambda_T| / sum lambda_N, continuous along the segment: noted at its start
        # (the right limit after an event), at the end of each step, at its maximum inside a step
        # (`_demand_peak`) and at the event that ends the segment (its left limit: the peak before an impact).
        # A sliding mode's is mu wherever the normal force carries load: its ends suffice
        ratio = self._demand_ratio
        peaks = totals is not None and mode not in SLIDING
        d_prev = None
        if totals is not None:
            last = self._demand_end
            if last is not None and last[0] == self.t and last[1] is self.y and last[2] is totals:
                d_prev = last[3]              # the last step's end (a segment carried on across a kink of ag)
            else:
                d_prev = ratio(totals(self.t, self.y))
                self.note_ratio(d_prev)
        # without state (rigid block in full contact) a step only samples the contact forces under a varying
        # input: keep it short enough for the dip search to see a force that comes and goes
        max_step = self.dt_max if k else min(self.dt_max, self.stateless_step)
        stepper = self._stepper(mode, rhs, max_step)
        g_prev = G(self.t, self.y)
        tol = self.event_tol
        if self._lands_now(kinds, g_prev):
            self._handle(_KIND_IMPACT, self.t, ag)
            return True
        armed = [g > 0.0 for g in g_prev]
        watch = [not a and g > -tol for a, g in zip(armed, g_prev)]
        first = True
        refusals = 0
        while stepper.t < t_stop:
            stepper.step(t_stop)
            self.n_steps += 1
            if stepper.failed:
                stepper.failed = False
                self.report("failed_step", stepper.t, stepper.failure)
            if self.n_steps > self._work_end:
                raise WorkLimitError(self._work_message(stepper))
            g_new = G(stepper.t, stepper.y)
            # the friction demand at the step's end (right after G: models share their work between the two)
            d_new = ratio(totals(stepper.t, stepper.y)) if totals is not None else None
            # a watched open corner sunk by the step's interpolant: the step is refused (MAX_SINK_REFUSALS)
            if refusals < MAX_SINK_REFUSALS and stepper.t > stepper.t_old:
                ids = [i for i, kind in enumerate(kinds) if watch[i] and kind == _KIND_IMPACT and g_new[i] > -tol]
                if ids and sinks(stepper.dense_output(), G, ids, stepper.t_old, stepper.t,
                                 self.tolerances.sub_samples, self.tolerances.gap):
                    refusals += 1
                    stepper.restart(rhs, stepper.t_old, stepper.y_old, 0.5 * (stepper.t - stepper.t_old))
                    continue
            rose = {}
            if first:
                first = False
                rose = self._bounces(stepper, G, kinds, watch, armed, g_new)
            event = self._find_event(stepper, G, armed, watch, rose, g_prev, g_new)
            if event is not None:
                te, i, dense = event
                self._record_samples(pending, out, mode, dense, te, inclusive=False)
                if k and stepper.h_abs > 0:
                    self._h = stepper.h_abs
                self.t = te
                self.y = dense(te)
                self._full = None
                if totals is not None:
                    # the demand up to the event, its left limit included (the mode's forces at the event)
                    d_e = ratio(totals(te, self.y))
                    if peaks:
                        self._demand_peak(totals, lambda: dense, stepper.t_old, d_prev, te, d_e, None)
                    self.note_ratio(d_e)
                self._handle(kinds[i], te, ag)
                return True
            if pending and pending[0] <= stepper.t:
                self._record_samples(pending, out, mode, stepper.dense_output(), stepper.t, inclusive=True)
            if totals is not None:
                # (the ends of the steps without an event: the mode's forces hold there)
                if peaks:
                    self._demand_peak(totals, stepper.dense_output, stepper.t_old, d_prev, stepper.t, d_new,
                                      stepper.hermite_mid)
                self.note_ratio(d_new)
                d_prev = d_new
            for i, g in enumerate(g_new):
                if g > 0.0:
                    armed[i] = True
                    watch[i] = False
            g_prev = g_new
        self.t = stepper.t
        self.y = stepper.y
        if k:
            self._h = stepper.h_abs
        self._full = None
        self._live = stepper
        if totals is not None:
            self._demand_end = (self.t, self.y, totals, d_prev)
        return False

    def _demand_ratio(self, lam):
        """|lam_T| / lam_N of the force totals ``lam`` = (sum lambda_N, sum lambda_T) [N], or None when the normal
        force is below ``force_floor`` (it carries no load: the ratio would be round-off over round-off)."""
        lam_N, lam_T = lam
        return abs(lam_T) / lam_N if lam_N > self.force_floor else None

    def _demand_peak(self, totals, dense_of, t0, d0, t1, d1, mid_of) -> None:
        """Raise ``friction_demand`` to the peak of the continuous demand inside the step [t0, t1] (ends d0, d1
        already noted), to the tolerance: when the parabola through the demand at the ends and at the middle
        (state ``mid_of()``, or the dense output's when None) peaks inside the step near or above the largest
        demand so far (DEMAND_PEAK_MARGIN), Brent's method on the dense output (``dense_of()``) locates the
        peak to sqrt(tolerance) of the step, its value to about the tolerance. Near a lift-off (a normal force
        below ``force_floor`` at an end) the demand grows without bound: the ends are what is reported."""
        if d0 is None or d1 is None or not t1 > t0 or max(d0, d1) < DEMAND_STEP_GATE * self.friction_demand:
            return
        tm = 0.5 * (t0 + t1)
        dense = None
        if mid_of is None:
            dense = dense_of()
            y_mid = dense(tm)
        else:
            y_mid = mid_of()
        dm = self._demand_ratio(totals(tm, y_mid))
        if dm is None:
            return
        vertex = parabola_peak(d0, dm, d1)
        if vertex is None or vertex[1] < (1.0 - DEMAND_PEAK_MARGIN) * self.friction_demand:
            return
        if dense is None:
            dense = dense_of()
        ratio = self._demand_ratio

        def demand(t):
            return ratio(totals(t, dense(t)))
        tv = t0 + vertex[0] * (t1 - t0)
        xtol = max(math.sqrt(self.tolerance) * (t1 - t0), 4.0 * math.ulp(max(abs(t1), 1.0)))
        self.note_ratio(brent_max(demand, t0, t1, tv, demand(tv), xtol)[1])

    def _lands_now(self, kinds, g_prev) -> bool:
        """Whether an open corner starts the segment below the ground beyond the watch margin (its event function
        below -event_tol: neither armed nor watched) while it approaches it (U_N < -v_tol): it is landing now,
        and the impact LCP decides at once (the corner is a candidate, put back onto the ground as a grazing
        landing) rather than letting it go through the ground unseen. Reached from a loaded state; a mode entry
        does not lead there (`_onto_ground`), and an impact leaves no candidate approaching, so this fires once."""
        tol = self.event_tol
        sunk = [i for i, kind in enumerate(kinds) if kind == _KIND_IMPACT and g_prev[i] <= -tol]
        if not sunk:
            return False
        q, v = self.state()
        U = self.model.contact_jacobians(q)[0].T @ v
        return any(U[i] < -self.v_tol for i in sunk)

    def _kinds(self, mode) -> list:
        """What each event function of ``mode`` means: per contact release (closed) or impact (open), then the
        slip's stop (sliding) or the friction cone (sticking with a finite mu), last overturning."""
        cached = self.__dict__.setdefault("_kinds_cache", {})
        kinds = cached.get(mode)
        if kinds is None:
            model = self.model
            closed = model.closed_of(mode)
            kinds = [(_KIND_RELEASE if i in closed else _KIND_IMPACT) for i in range(model.n_contacts)]
            if mode in SLIDING:
                kinds.append(_KIND_SLIP)
            elif closed and not math.isinf(model.mu):
                kinds.append(_KIND_CONE)
            kinds.append(_KIND_OVERTURN)
            cached[mode] = kinds
        return kinds

    def _bounces(self, stepper, G, kinds, watch, armed, g_new) -> dict:
        """After the first step of a segment: an open corner that started at the ground and is back at or
        below it had a short bounce (it left slowly) just after the start, if `bounce_search` finds it above
        zero; it is then armed and lands at zero, not event_tol below. Returns {corner: (t, G(t))} of those
        found (``armed`` and ``watch`` updated)."""
        rose = {}
        dense = None
        level = self.tolerances.rise * self.event_tol
        for i, kind in enumerate(kinds):
            if watch[i] and kind == _KIND_IMPACT and g_new[i] <= 0.0:
                if dense is None:
                    dense = stepper.dense_output()
                found = bounce_search(dense, G, i, stepper.t_old, stepper.t, level)
                if found is not None:
                    armed[i], watch[i] = True, False
                    rose[i] = found
        return rose

    def _find_event(self, stepper, G, armed, watch, rose, g_prev, g_new):
        """(t_event, function index, dense output) of the first event in the last step, or None.

        An armed function fires at zero, a disarmed one (watched) at -event_tol; without a sign change at
        the ends, a dip inside the step is looked for (`dip_search`). Before the event found, another armed
        contact function may dip below zero and come back (the pivot force of a block that lifts off just
        before it overturns): the step up to it is sub-sampled for that (`first_negative`) where the function
        is below zero at the event's time or may dip in between (`may_dip` on the midpoint: one evaluation
        instead of sub_samples on the common impact, where no other function comes near zero)."""
        tol = self.event_tol
        n_sub = self.tolerances.sub_samples
        t0, t_hit = stepper.t_old, stepper.t
        hits = [i for i in range(len(g_new)) if (armed[i] and g_new[i] <= 0.0) or (watch[i] and g_new[i] <= -tol)]
        g_a, g_b = g_prev, g_new
        dense = None
        if not hits:
            hits, t0, t_hit, g_a, g_b, dense = dip_search(stepper, G, armed, g_prev, g_new, n_sub)
            if not hits:
                return None
        if dense is None:
            dense = stepper.dense_output()
        xtol = 4.0 * math.ulp(max(abs(stepper.t), 1.0))
        shifts = [0.0 if a else tol for a in armed]
        te, i = earliest_root(G, dense, hits, shifts, rose, t0, g_a, t_hit, g_b, xtol)
        others = [j for j in range(len(g_new) - 1) if armed[j] and j not in hits]
        if others and te > t0:
            g_te = G(te, dense(te))
            neg = [j for j in others if g_te[j] <= 0.0]
            if neg:
                found = first_negative(G, dense, t0, g_a, te, others, n_sub)
                if found is None:
                    # te itself: a corner that crosses inside the last sub-interval (not sampled) would be found
                    # below the ground at the impact and could start the next mode there, beyond the watch margin
                    ta = t0 + (te - t0) * (n_sub - 1) / float(n_sub)
                    found = neg, ta, G(ta, dense(ta)), te, g_te
            else:
                # above the ground at both ends: sub-sampled only where the midpoint says that it may dip in
                # between (`may_dip`, the test a step without events passes, here on the exact interpolant)
                tm = 0.5 * (t0 + te)
                g_m = G(tm, dense(tm))
                dip = [j for j in others if may_dip(g_a[j], g_m[j], g_te[j])]
                found = first_negative(G, dense, t0, g_a, te, dip, n_sub) if dip else None
            if found is not None:
                neg, ta, ga, tn, gn = found
                te, i = earliest_root(G, dense, neg, shifts, rose, ta, ga, tn, gn, xtol)
        return te, i, dense

    def _stepper(self, mode, rhs, max_step):
        """The Runge-Kutta stepper of a segment starting at the current state: the last segment's, carried
        on when it ended without an event at the current state under the same right-hand side (a co-simulation
        step with an unchanged input, a kink of ag; its FSAL derivative is still valid), else restarted
        with the last accepted step size."""
        st = self._live
        if st is not None and st.t == self.t and st.y is self.y and st.max_step == max_step:
            if st.fun is not rhs:
                st.restart(rhs, self.t, self.y, self._h)
            return st
        return METHODS[self.method](rhs, self.t, self.y, self.tolerance, self._atol(mode),
                                    max_step=max_step, first_step=self._h if self.k else None)

    def _record_samples(self, pending, out, mode, dense, t_last, inclusive):
        if pending and (pending[0] <= t_last if inclusive else pending[0] < t_last):
            while pending and (pending[0] <= t_last if inclusive else pending[0] < t_last):
                out.append(self._sample_row(mode, dense(pending.popleft()), False))
            if self._max_work is not None:
                self._work_end = self.n_steps + self._max_work      # the budget applies per output sample

    def _work_message(self, stepper) -> str:
        """Why the step is refused (`WorkLimitError`) and how to get it through."""
        t0, t_end = self._span
        model = self.model
        stiff = f", {model.work_note}" if model.work_note else ""
        return (f"event_driven: advancing from t = {t0:.17g} s by {t_end - t0:.6g} s needs more than "
                f"max_steps = {self._max_work} internal steps (Runge-Kutta steps, each event counting "
                f"{EVENT_WORK}); {self.impacts - self._impacts0} impacts so far in this step; stopped at "
                f"t = {stepper.t:.17g} s in mode {self.mode.name} with steps of {stepper.h_abs:.3g} s "
                f"(tolerance = {self.tolerance:g}, dt_max = {self.dt_max:g} s, method {self.method}"
                f"{stiff}, time scale 1/p = {model.time_scale:.3g} s); the step was refused and the state kept. "
                "Way out: shorter communication steps, a looser tolerance, a larger dt_max (0: uncapped), or "
                "max_steps=None (unlimited, for trusted batch runs)")

    # ------------------------------------------------------------------ events
    def _handle(self, kind, t, ag):
        q, v = self.state()
        if kind == _KIND_OVERTURN:
            # the motion ends: the pose at |phi| = pi/2 (located to round-off), at rest (the outputs after
            # overturning must not describe a motion that is no longer computed)
            self.overturned = True
            self.y = self.y[:self.k] + [0.0] * self.k
            self._full = None
            return
        if kind == _KIND_IMPACT:
            self._impact(q, v, t, _inputs(ag, t))
            self._note_percussions(q, v)
        elif kind == _KIND_CONE:
            # the friction reached mu lambda_N: the corners slide against it (preferred where sticking is
            # still consistent to round-off, as at the far side of the root it is only marginally)
            lam_T = self._functions(self.mode, ag)[2](t, self.y)[1]
            slide = SLIDE_NEG if lam_T > 0.0 else SLIDE_POS
            self._enter(q, v, _inputs(ag, t), t, prefer=slide)
        else:
            self._enter(q, v, _inputs(ag, t), t)

    def _note_percussions(self, q, v_minus) -> None:
        """Raise ``friction_demand`` to the ratio |sum Lambda_T| / sum Lambda_N of the percussions of the impact
        that led from v_minus to the current velocity: sticking at an impact needs that much friction too (a
        rocking block's impact about its other corner: h b / (R^2/3 + h^2) = 0.1485 for b = 0.2, h = 1, more than
        the forces of its free rocking need). The rows slide_index and lift_index of M (v+ - v-) carry the
        totals; a normal percussion below force_floor * time_scale [N s] carries no load."""
        model = self.model
        P = model.mass_matrix(q) @ (self.state()[1] - v_minus)
        lam_N = float(P[model.lift_index])
        if lam_N > self.force_floor * model.time_scale:
            self.note_ratio(abs(float(P[model.slide_index])) / lam_N)

    def _impact(self, q, v, t, ag_t):
        model = self.model
        g = model.gaps(q)
        cand = [i for i in range(model.n_contacts) if g[i] <= self.gap_tol]
        closed_before = model.closed_of(self.mode)
        # a corner found below the ground beyond round-off fired event_tol below it: a grazing landing (it
        # never rose measurably: the tail of an impact accumulation). It is put back onto the ground (the next
        # segment starts there, its watch margin unused) and closed plastically (the Zeno rule)
        grazing = tuple(i for i in cand if g[i] < -self.tolerances.grazing * self.gap_tol)
        q_found = q
        if grazing:
            q = project_to_ground(model, q, set(cand) | set(closed_before))
        if len(closed_before) == 1 and len(cand) == model.n_contacts == 2:
            # an impact rule of the model (the classical rule) replaces the impact LCP at a rocking impact
            v_plus = model.classical_impact_velocity(q, v, self.mode)
            if v_plus is not None:
                self._record_impact(t, v, v_plus)
                self._count_painleve(q, v, v_plus, cand)
                self._enter(q, v_plus, ag_t, t)
                return
        v_impact = self._impact_velocity(q, v, cand, grazing, ag_t, t)
        mode, v_plus = self._decide(q, v_impact, ag_t, t)
        if any(i not in model.closed_of(mode) for i in grazing):
            # held closed, the corner is still sent into flight: the sticking LCP has no solution (the corner
            # should slide, bug 7); not held (that would be a chatter of grazing landings)
            q = q_found
            v_impact = self._impact_velocity(q, v, cand, (), ag_t, t)
            mode, v_plus = self._decide(q, v_impact, ag_t, t)
        U_minus = model.contact_jacobians(q)[0].T @ v
        if any(U_minus[i] < -self.v_zeno for i in cand):
            self._record_impact(t, v, v_plus)
        # (a Painleve impulse that `_decide` applied after the impact is counted there)
        self._count_painleve(q, v, v_impact, cand)
        self._set_state(mode, q, v_plus)

    def _count_painleve(self, q, v_minus, v_plus, cand):
        """Count in ``painleve`` an impact that made a sliding corner stick in Painleve's configuration
        (`painleve_sticks`): its tangential percussion is the paradox's stick-making impulse, whether the corner
        also collided (then the impact counts in ``impacts`` too) or touched down slower than v_Zeno."""
        if painleve_sticks(self.model, q, v_minus, v_plus, cand, self.v_tol):
            self.painleve += 1

    def _impact_velocity(self, q, v, cand, closed, ag_t, t):
        """Post-impact velocity by the impact LCP under the Zeno rule (module docstring; README, "Impact
        accumulation (Zeno)"): corners of ``closed`` and corners at the ground that would leave slower than
        v_Zeno are closed plastically; while every candidate leaves (flight) and none is closed, the corner
        whose free-flight bounce U_N+^2 / (2 |a_N|) is the lowest is closed if that bounce stays within gap_tol
        of the ground. Each closure re-solves the impact LCP from the pre-impact velocity, and the tests are
        applied again to the new outcome: a corner that leaves while another is closed rotates about it and is
        not in free flight, so only the velocity test applies to it."""
        model = self.model
        W_N, _ = model.contact_jacobians(q)
        forced = [i for i in cand if i in closed]
        sol = impact(model, q, v, cand, forced=tuple(forced), tolerances=self.tolerances)
        while True:
            U_plus = W_N.T @ sol.v
            # velocity test (a corner that takes impulse and stays at rest needs no closure)
            new = [i for i in cand if i not in forced and U_plus[i] < self.v_zeno
                   and (i not in sol.active or U_plus[i] > self.v_tol)]
            if not new and not forced and cand and all(U_plus[i] >= self.v_zeno for i in cand):
                # bounce test, in flight only: a_N the corner's normal acceleration in free flight
                acc = inverse_mass(model, q) @ model.forces(q, sol.v, *ag_t)
                a_N = W_N.T @ acc + model.contact_drift(q, sol.v)[0]
                falling = [i for i in cand if a_N[i] < 0.0]
                if falling:
                    i = min(falling, key=lambda j: U_plus[j] * U_plus[j] / -a_N[j])
                    if U_plus[i] * U_plus[i] < -2.0 * a_N[i] * self.gap_tol:
                        new = [i]
            if not new:
                break
            forced += new
            sol = impact(model, q, v, cand, forced=tuple(forced), tolerances=self.tolerances)
        if not sol.exact:
            self.report("inexact_contact", t, inexact_message(sol, t, "impact LCP"))
        return sol.v

    def _record_impact(self, t, v_minus, v_plus):
        self.impacts += 1
        self.impact_times.append(t)
        self.impact_log.append((t, np.array(v_minus), np.array(v_plus)))

    def _select_mode(self, q, v, ag_t, t, prefer=None):
        """The mode that the acceleration LCP selects at the consistent state (q, v) (`next_mode`) and the LCP's
        solution; with friction ``prefer`` (a sliding state) is tried first for the closed contacts. An inexact
        solve is reported unless it is a Painleve situation (which `_decide` resolves)."""
        ag, ag_v = ag_t
        mode, sol = next_mode(self.model, q, v, ag, self.gap_tol, self.v_tol, prefer=prefer, ag_v=ag_v,
                              tolerances=self.tolerances)
        if sol is not None and not sol.exact and not sol.painleve:
            self.report("inexact_contact", t, inexact_message(sol, t, "uplift LCP"))
        return mode, sol

    def _enter(self, q, v, ag_t, t, prefer=None):
        mode, v = self._decide(q, v, ag_t, t, prefer)
        self._set_state(mode, q, v)

    def _decide(self, q, v, ag_t, t, prefer=None):
        """(mode, v): the mode that follows the consistent state (q, v) under the ground accelerations ag_t =
        (ag(t), ag_v(t)) [m/s2] (`_select_mode`), and v, changed only
        by the impact without collision of a Painleve situation (counted in ``painleve``; the Painleve sticks
        made by an impact LCP are counted by `_count_painleve`)."""
        mode, sol = self._select_mode(q, v, ag_t, t, prefer)
        if sol is not None and sol.painleve:
            # Painleve: sliding with no consistent acceleration (or several): an impact without collision, the
            # tangential impulse that makes the sliding corners stick (Genot & Brogliato 1999), then the
            # acceleration problem at rest tangentially, which has a solution
            self.painleve += 1
            sol_i = impact(self.model, q, v, sol.active or closed_candidates(self.model, q, v, self.gap_tol,
                                                                             self.v_tol), e_N=0.0, e_T=0.0,
                           prefer=STICK, tolerances=self.tolerances)
            if not sol_i.exact:
                self.report("inexact_contact", t, inexact_message(sol_i, t, "Painleve impact LCP"))
            v = sol_i.v
            mode, _ = self._select_mode(q, v, ag_t, t)
        return mode, v
