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
- Zeno rule (end of impact accumulation): after an impact, a corner at the ground whose post-impact
  separation velocity is below v_Zeno = zeno_tol * sqrt(g L) (L the model's length scale), or (all corners
  leaving) whose free-flight bounce U_N^2 / (2 |a_N|) would stay within gap_tol of the ground, is closed
  plastically and the impact LCP is solved again with that corner held closed. The kinetic energy this
  removes is at most of the order of 1/2 m v_Zeno^2 + m |a_N| gap_tol. Impacts slower than v_Zeno are not
  counted.
- ``advance(t_end, ag, samples)`` integrates through the sample times (an output grid) and reads the state
  there from the dense output, so a fine output grid does not shorten the steps.
- Work budget: ``advance(..., max_steps=N)`` counts Runge-Kutta steps plus EVENT_WORK = 30 per event and
  raises `WorkLimitError` when one call (or, with samples, the stretch between two samples) needs more than N.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from ..contact import closed_candidates, impact, inverse_mass, project_to_ground, uplift
from ..modes import CLOSED, BoundedLog, Mode, bounded_log, mode_from_closed
from ..validation import WorkLimitError, state_bool, state_float, state_floats, state_int
from .dop853 import DOP853
from .dopri5 import DOPRI5
from .state import Checkpointed, check_configuration, check_times

_KIND_IMPACT, _KIND_RELEASE, _KIND_OVERTURN = "impact", "release", "overturn"

#: [steps] what one event counts in the work budget (``max_steps``): locating it (some 10 to 60 evaluations of
#: the event functions on the dense output) and the impact and uplift LCPs cost about as much as 20 (rigid
#: block) to 35 (flexible oscillator in flight) Runge-Kutta steps (measured: 0.7 ms and 1.9 ms per event
#: against 20 and 55 us per step), so that the budget bounds the time of an event storm as of a long stretch
#: of smooth steps
EVENT_WORK = 30
METHODS = {"DOP853": DOP853, "DOPRI5": DOPRI5}


def _locate(fun, a: float, ga: float, b: float, gb: float, xtol: float) -> float:
    """Regula falsi with the Anderson-Bjorck modification on a bracket with ga > 0 >= gb; returns a time t
    with fun(t) <= 0 and t - t_root <= xtol.

    Each trial point keeps at least xtol/2 from the ends of the bracket, so that once the estimate has
    converged the next evaluation on the far side of the root closes the bracket: some 6 to 10 evaluations
    from a step-sized bracket to round-off (about 12 to 20 on average in the scenes, against 20 to 25 when
    every iteration also bisects). A bisection follows a trial point that had to be held off an end without
    closing the bracket (a function that starts tangent to zero) and two iterations that did not halve it."""
    side = 0
    half = 0.5 * xtol
    width = b - a
    n_slow = 0
    bisect = False
    while b - a > xtol:
        clamped = False
        if bisect:
            t = 0.5 * (a + b)
        else:
            t = a + (b - a) * (ga / (ga - gb))
            if t < a + half:
                t, clamped = a + half, True
            elif t > b - half:
                t, clamped = b - half, True
        gt = fun(t)
        if gt > 0.0:
            if side == 1:                     # a moved twice in a row: scale down the far value
                m = 1.0 - gt / ga
                gb *= m if m > 0.0 else 0.5
            a, ga = t, gt
            side = 1
        else:
            if side == -1:
                m = 1.0 - gt / gb if gb != 0.0 else 0.5
                ga *= m if m > 0.0 else 0.5
            b, gb = t, gt
            side = -1
        if bisect or b - a <= 0.5 * width:
            width = b - a
            n_slow = 0
        else:
            n_slow += 1
        bisect = clamped or n_slow >= 2
    return b


class EventDriven(Checkpointed):
    """Event-driven integration of ``model`` with relative/absolute tolerance ``tolerance``.

    method: "DOP853" (order 8) or "DOPRI5" (order 5, cheaper at loose tolerances).
    impact_log_size: number of impacts kept in ``impact_times`` / ``impact_log`` (None: all); the counter
    ``impacts`` counts them all. A bound keeps the memory flat over arbitrarily long runs.
    """

    name = "event_driven"
    LOGS = ("impact_times", "impact_log")
    _live = None            #: the stepper of the last segment, while it may go on (see `_stepper`)
    _max_work = None        #: work budget of the current `advance` (None: unlimited)
    _work_end = math.inf    #: value of n_steps at which the budget runs out

    def __init__(self, model, mode: Mode, q: np.ndarray, v: np.ndarray, t0: float,
                 tolerance: float = 1e-8, dt_max: float = math.inf, zeno_tol: float = 1e-6,
                 max_events: int = 100000, method: str = "DOP853", impact_log_size: int | None = None):
        self.model = model
        self.t = float(t0)
        self.tolerance = tolerance
        self.dt_max = dt_max
        self.method = method
        L = model.length_scale
        self.gap_tol = 1e-9 * L
        self.v_tol = 1e-10 * math.sqrt(model.g * L)
        self.v_zeno = zeno_tol * math.sqrt(model.g * L)
        #: [1] how far below zero a disarmed (normalised) event function may go before it fires
        self.event_tol = 1e-10
        self.max_events = max_events
        self.impacts = 0
        self.impact_times: BoundedLog = BoundedLog(impact_log_size)
        #: (t, v_minus, v_plus) of the impacts, full velocities (the last 1000 with a bounded log)
        self.impact_log: BoundedLog = BoundedLog(None if impact_log_size is None else min(1000, impact_log_size))
        self.overturned = False
        self.n_steps = 0
        self._h = None
        self._set_state(Mode(mode), np.asarray(q, float), np.asarray(v, float))

    # ------------------------------------------------------------------ state
    def _set_state(self, mode, q, v):
        self.mode = Mode(mode)
        r, rd = self.model.reduce(self.mode, q, v)
        self.k = len(r)
        self.y = [float(a) for a in r] + [float(a) for a in rd]
        self._full = None

    def state(self):
        """Full (q, v) at the current time."""
        if self._full is None:
            k = self.k
            self._full = self.model.embed(self.mode, np.array(self.y[:k]), np.array(self.y[k:]))
        return self._full

    def outputs(self) -> dict:
        """The model's outputs at the current time."""
        return self.model.mode_outputs(self.mode, self.y)

    def _functions(self, mode, ag):
        """model.mode_functions(mode, ag), reused while the mode and a constant input stay the same (each
        co-simulation step would otherwise build them twice)."""
        key = (mode, ag.value) if ag.constant else (mode, id(ag))
        cached = self.__dict__.get("_fn_cache")
        if cached is not None and cached[0] == key and (ag.constant or cached[1] is ag):
            return cached[2]
        fns = self.model.mode_functions(mode, ag)
        self._fn_cache = (key, ag, fns)
        return fns

    # ------------------------------------------------------------------ plain-data state
    #: fields of `get_state` (the Simulator adds the header: version, scheme, model, n_dof)
    STATE_KEYS = ("t", "mode", "y", "impacts", "overturned", "n_steps", "h", "impact_times", "impact_log")

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
                "impact_times": [float(a) for a in self.impact_times.tail()], "impact_log": flat}

    def set_state(self, state) -> None:
        """Load a `get_state` dict (header and keys checked by the caller): every field is checked for type,
        length, range and consistency with the model (ValueError naming the field); nothing changes on
        error."""
        model = self.model
        t = state_float(state, "t")
        mode = Mode(state_int(state, "mode", 0, 3))
        k = len(model.mode_dofs(mode))
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
        q, v = model.embed(mode, np.array(y[:k]), np.array(y[k:]))
        # a corner may sink in flight where the sticking law has no solution (bug 7, a documented model gap:
        # 33 mm measured before an overturning): only junk, a corner a whole length scale down, is refused
        check_configuration(model, state, "y", q, v, overturned, gap_tol=model.length_scale)
        # all checked: assign
        self.t, self.impacts, self.overturned, self.n_steps = t, impacts, overturned, n_steps
        self._h = None if h != h else h
        self.mode, self.k, self.y, self._full = mode, k, y, None
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
        return state

    def _atol(self, mode):
        cached = self.__dict__.setdefault("_atol_cache", {})
        if mode not in cached:
            cached[mode] = self._atol_of(mode)
        return cached[mode]

    def _atol_of(self, mode):
        dof_scales = getattr(self.model, "dof_scales", None)
        idx = self.model.mode_dofs(mode)
        if dof_scales is None:
            s = [1.0 if i == self.model.phi_index else self.model.length_scale for i in idx]
        else:
            s = [dof_scales[i] for i in idx]
        ts = self.model.time_scale
        return [self.tolerance * a for a in s] + [self.tolerance * a / ts for a in s]

    # ------------------------------------------------------------------ driver
    def advance(self, t_end: float, ag, samples=None, max_steps: int | None = None):
        """Integrate to exactly t_end; ``ag`` is a GroundMotion.

        samples: increasing times in (t, t_end] at which to record the motion; returns the list of
        (mode, y, impacts, overturned) there (None when no samples are asked for).
        max_steps: work budget (None: unlimited): Runge-Kutta steps plus EVENT_WORK per event, of this call
        or, with samples, between two consecutive samples; exceeding it raises `WorkLimitError` (the state is
        then partly advanced: `Simulator.advance` restores it)."""
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
                out.append((self.mode, list(self.y), self.impacts, self.overturned))
            return out
        n_events = 0
        kink = False              # the last segment ended at a breakpoint where ag is continuous
        end_tol = 4.0 * math.ulp(max(abs(t_end), 1.0))
        while not self.overturned:
            if t_end - self.t <= end_tol:
                break
            tb = ag.next_breakpoint(self.t)
            t_stop = t_end if t_end < tb else tb
            if self.mode != Mode.FLIGHT and not kink:
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
            out.append((self.mode, list(self.y), self.impacts, self.overturned))
        return out

    def _settle(self, t, ag):
        """Re-decide the mode of the current state by the acceleration LCP (after an input change)."""
        mode = self.mode
        closed = CLOSED[mode]
        _, monitors = self._functions(mode, ag)
        e = monitors(t, self.y)
        # fast path: closed corners loaded, open corners clearly open (then the active set still holds)
        if all(e[i] > 0.0 if i in closed else e[i] > 1e-9 for i in (0, 1)):
            return
        q, v = self.state()
        if all(i in closed for i in closed_candidates(self.model, q, v, self.gap_tol, self.v_tol)):
            if all(e[i] > 0.0 for i in closed):
                return
        new = self._select_mode(q, v, ag(t))
        if new != mode:
            self._set_state(new, q, v)

    def _segment(self, t_stop: float, ag, pending, out) -> bool:
        """Integrate the current mode towards t_stop; returns True if an event ended the segment."""
        mode, k = self.mode, self.k
        if pending and pending[0] <= self.t:
            while pending and pending[0] <= self.t:
                pending.popleft()
                out.append((mode, list(self.y), self.impacts, False))
            if self._max_work is not None:
                self._work_end = self.n_steps + self._max_work
        if k == 0 and ag.constant:
            # nothing moves and the (positive) contact forces cannot change
            self.t = t_stop
            while pending and pending[0] <= t_stop:
                pending.popleft()
                out.append((mode, list(self.y), self.impacts, False))
            self._full = None
            return False
        rhs, G = self._functions(mode, ag)
        kinds = [(_KIND_RELEASE if i in CLOSED[mode] else _KIND_IMPACT) for i in (0, 1)]
        # without state (rigid block in full contact) a step only samples the contact forces under a varying
        # input: keep it short enough for the dip search to see a force that comes and goes
        max_step = self.dt_max if k else min(self.dt_max, 0.1 * self.model.time_scale)
        stepper = self._stepper(mode, rhs, max_step)
        g_prev = G(self.t, self.y)
        g_prev[2] = 0.5 * math.pi - abs(g_prev[2])
        tol = self.event_tol
        armed = [g > 0.0 for g in g_prev]
        watch = [not a and g > -tol for a, g in zip(armed, g_prev)]
        first = True
        while stepper.t < t_stop:
            stepper.step(t_stop)
            self.n_steps += 1
            if self.n_steps > self._work_end:
                raise WorkLimitError(self._work_message(stepper))
            g_new = G(stepper.t, stepper.y)
            g_new[2] = 0.5 * math.pi - abs(g_new[2])
            dense = None
            t0, t_hit = stepper.t_old, stepper.t
            rose = {}
            if first:
                first = False
                for i in (0, 1):
                    if watch[i] and kinds[i] == _KIND_IMPACT and g_new[i] <= 0.0:
                        # an open corner that starts at the ground and is back at or below it after the first
                        # step: a short bounce (it left slowly) rose above zero just after the start; if so it
                        # is armed and lands at zero, not event_tol below
                        if dense is None:
                            dense = stepper.dense_output()
                        found = self._rise(dense, G, i, t0, t_hit, 1e-3 * tol)
                        if found is not None:
                            armed[i], watch[i] = True, False
                            rose[i] = found
            hits = [i for i in range(3) if (armed[i] and g_new[i] <= 0.0) or (watch[i] and g_new[i] <= -tol)]
            g_a, g_b = g_prev, g_new
            if not hits:
                hits, t0, t_hit, g_a, g_b, dense = self._dips(stepper, G, armed, g_prev, g_new)
            if hits:
                if dense is None:
                    dense = stepper.dense_output()
                xtol = 4.0 * math.ulp(max(abs(stepper.t), 1.0))

                def earliest(ids, ta, ga, tb, gb):
                    best = None
                    for i in ids:
                        shift = 0.0 if armed[i] else tol

                        def gi(t, i=i, shift=shift):
                            val = G(t, dense(t))[i]
                            return (0.5 * math.pi - abs(val) if i == 2 else val) + shift
                        ta_i, ga_i = rose[i] if i in rose and rose[i][0] > ta else (ta, ga)
                        te = _locate(gi, ta_i, ga_i[i] + shift, tb, gb[i] + shift, xtol)
                        if best is None or te < best[0]:
                            best = (te, i)
                    return best
                te, i = earliest(hits, t0, g_a, t_hit, g_b)
                # another contact function may dip below zero and come back before that event (e.g. the
                # pivot force of a block that lifts off just before it overturns)
                others = [j for j in (0, 1) if armed[j] and j not in hits]
                if others and te > t0:
                    ta, ga = t0, g_a
                    for n in range(1, 16):
                        tn = t0 + (te - t0) * n / 16.0
                        gn = G(tn, dense(tn))
                        gn[2] = 0.5 * math.pi - abs(gn[2])
                        neg = [j for j in others if gn[j] <= 0.0]
                        if neg:
                            te, i = earliest(neg, ta, ga, tn, gn)
                            break
                        ta, ga = tn, gn
                self._record_samples(pending, out, mode, dense, te, inclusive=False)
                if k and stepper.h_abs > 0:
                    self._h = stepper.h_abs
                self.t = te
                self.y = dense(te)
                self._full = None
                self._handle(kinds[i] if i < 2 else _KIND_OVERTURN, te, ag)
                return True
            if pending and pending[0] <= stepper.t:
                self._record_samples(pending, out, mode, stepper.dense_output(), stepper.t, inclusive=True)
            for i in range(3):
                if g_new[i] > 0.0:
                    armed[i] = True
                    watch[i] = False
            g_prev = g_new
        self.t = stepper.t
        self.y = stepper.y
        if k:
            self._h = stepper.h_abs
        self._full = None
        self._live = stepper
        return False

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
                out.append((mode, dense(pending.popleft()), self.impacts, False))
            if self._max_work is not None:
                self._work_end = self.n_steps + self._max_work      # the budget applies per output sample

    def _work_message(self, stepper) -> str:
        """Why the step is refused (`WorkLimitError`) and how to get it through."""
        t0, t_end = self._span
        model = self.model
        omega = getattr(model, "omega", None)
        stiff = f", column omega = {omega:.6g} rad/s" if omega is not None else ""
        return (f"event_driven: advancing from t = {t0:.17g} s by {t_end - t0:.6g} s needs more than "
                f"max_steps = {self._max_work} internal steps (Runge-Kutta steps, each event counting "
                f"{EVENT_WORK}); {self.impacts - self._impacts0} impacts so far in this step; stopped at "
                f"t = {stepper.t:.17g} s in mode {self.mode.name} with steps of {stepper.h_abs:.3g} s "
                f"(tolerance = {self.tolerance:g}, dt_max = {self.dt_max:g} s, method {self.method}"
                f"{stiff}, time scale 1/p = {model.time_scale:.3g} s); the step was refused and the state kept. "
                "Way out: shorter communication steps, a looser tolerance, a larger dt_max (0: uncapped), or "
                "max_steps=None (unlimited, for trusted batch runs)")

    @staticmethod
    def _rise(dense, G, i, t0, t1, level):
        """(t, G(t)) of a time in (t0, t1) where function i is above ``level`` (> 0, above round-off), sampled
        at t0 + (t1 - t0) 4^-n down to round-off in time (it starts at zero with a positive slope), or None."""
        d = t1 - t0
        xtol = 4.0 * math.ulp(max(abs(t1), 1.0))
        while d > xtol:
            d *= 0.25
            t = t0 + d
            gt = G(t, dense(t))
            if gt[i] > level:
                gt[2] = 0.5 * math.pi - abs(gt[2])
                return t, gt
        return None

    @staticmethod
    def _may_dip(g0: float, gm: float, g1: float) -> bool:
        """Whether a function positive at both ends of a step may reach zero inside: its midpoint lies
        below both ends, or the parabola through (0, g0), (1/2, gm), (1, g1) has its vertex inside the step
        and comes down to less than half the smaller end value."""
        lo = min(g0, g1)
        if gm < lo:
            return True
        c = 2.0 * (g0 + g1) - 4.0 * gm
        if c <= 0.0:
            return False
        b = g1 - g0 - c
        x = -b / (2.0 * c)
        return 0.0 < x < 1.0 and g0 + 0.5 * b * x < 0.5 * lo

    def _dips(self, stepper, G, armed, g_prev, g_new):
        """A contact function that dips below zero and comes back within the step (a short excursion of
        the base of a vibrating column, the pivot force of a block about to lift off): look inside the
        step when a cubic Hermite estimate of the midpoint value says it may (`_may_dip`). Returns (hits, t_a, t_b, g_a, g_b, dense) of the first sub-interval with a sign change."""
        t0, t1 = stepper.t_old, stepper.t
        tm = 0.5 * (t0 + t1)
        gm = G(tm, stepper.hermite_mid())
        dip = [i for i in (0, 1) if armed[i] and self._may_dip(g_prev[i], gm[i], g_new[i])]
        if not dip:
            return [], t0, t1, g_prev, g_new, None
        dense = stepper.dense_output()
        ga, ta = g_prev, t0
        for j in range(1, 16):
            tj = t0 + (t1 - t0) * j / 16.0
            gj = G(tj, dense(tj))
            gj[2] = 0.5 * math.pi - abs(gj[2])
            neg = [i for i in dip if gj[i] <= 0.0]
            if neg:
                return neg, ta, tj, ga, gj, dense
            ga, ta = gj, tj
        return [], t0, t1, g_prev, g_new, dense

    # ------------------------------------------------------------------ events
    def _handle(self, kind, t, ag):
        q, v = self.state()
        if kind == _KIND_OVERTURN:
            self.overturned = True
            return
        if kind == _KIND_IMPACT:
            self._impact(q, v, t, ag(t))
        else:
            self._enter(q, v, ag(t))

    def _impact(self, q, v, t, ag_t):
        model = self.model
        g = model.gaps(q)
        cand = [i for i in (0, 1) if g[i] <= self.gap_tol]
        # a corner found below the ground beyond round-off fired event_tol below it: a grazing landing (it
        # never rose measurably: the tail of an impact accumulation). It is put back onto the ground (the next
        # segment starts there, its watch margin unused) and closed plastically (the Zeno rule)
        grazing = tuple(i for i in cand if g[i] < -1e-3 * self.gap_tol)
        q_found = q
        if grazing:
            q = project_to_ground(model, q, set(cand) | set(CLOSED[self.mode]))
        classical = getattr(model, "classical_impact_velocity", None)
        if classical is not None and self.mode in (Mode.LEFT, Mode.RIGHT) and len(cand) == 2:
            v_plus = classical(q, v, self.mode)
            if v_plus is not None:
                self._record_impact(t, v, v_plus)
                self._enter(q, v_plus, ag_t)
                return
        v_plus = self._impact_velocity(q, v, cand, grazing, ag_t)
        mode = self._select_mode(q, v_plus, ag_t)
        if any(i not in CLOSED[mode] for i in grazing):
            # held closed, the corner is still sent into flight: the sticking LCP has no solution (the corner
            # should slide, bug 7); not held (that would be a chatter of grazing landings)
            q = q_found
            v_plus = self._impact_velocity(q, v, cand, (), ag_t)
            mode = self._select_mode(q, v_plus, ag_t)
        U_minus = model.contact_jacobians(q)[0].T @ v
        if any(U_minus[i] < -self.v_zeno for i in cand):
            self._record_impact(t, v, v_plus)
        self._set_state(mode, q, v_plus)

    def _impact_velocity(self, q, v, cand, closed, ag_t):
        """Post-impact velocity by the impact LCP; corners of ``closed``, corners that would leave slower
        than v_Zeno and (when all leave) corners whose free-flight bounce would stay within gap_tol of the
        ground are closed plastically (the Zeno rule)."""
        model = self.model
        sol = impact(model, q, v, cand)
        W_N, _ = model.contact_jacobians(q)
        U_plus = W_N.T @ sol.v
        slow = [i for i in cand if U_plus[i] < self.v_zeno]
        # (a corner that takes impulse and stays at rest needs no second solve)
        zeno = [i for i in cand if i in closed or (i in slow and (i not in sol.active or U_plus[i] > self.v_tol))]
        if cand and not slow and not zeno:
            # all leave (flight): apex of a bounce U+^2 / (2 |a_N|), a_N the corner's normal acceleration
            acc = inverse_mass(model, q) @ model.forces(q, sol.v, ag_t)
            a_N = W_N.T @ acc + model.contact_drift(q, sol.v)[0]
            zeno += [i for i in cand if i not in zeno and U_plus[i] ** 2 < -2.0 * a_N[i] * self.gap_tol]
        if zeno:
            sol = impact(model, q, v, cand, forced=tuple(zeno))
        return sol.v

    def _record_impact(self, t, v_minus, v_plus):
        self.impacts += 1
        self.impact_times.append(t)
        self.impact_log.append((t, np.array(v_minus), np.array(v_plus)))

    def _select_mode(self, q, v, ag_t) -> Mode:
        """The mode that the acceleration LCP selects at the consistent state (q, v)."""
        cand = closed_candidates(self.model, q, v, self.gap_tol, self.v_tol)
        return mode_from_closed(uplift(self.model, q, v, ag_t, cand).active) if cand else Mode.FLIGHT

    def _enter(self, q, v, ag_t):
        self._set_state(self._select_mode(q, v, ag_t), q, v)
