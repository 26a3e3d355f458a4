"""Python API: a stepwise `Simulator` (what the FMUs call) and `simulate()` for whole time histories."""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

import warnings

from .engine import ENGINES, CompiledIntegrator
from .ground_motion import ConstantMotion, GroundMotion, TwoComponentMotion, as_ground_motion, checked_motion
from .integrators import SCHEMES as SCHEME_CLASSES
from .integrators import Report, SolverOptions, scheme_choices
from .models.base import RockingModel
from .params import Param
from .tolerances import DEFAULT_TOLERANCES, ZENO_TOL, ContactTolerances
from .validation import MAX_STEPS, WorkLimitError, check_choice, check_real, check_state_keys, state_int, state_str


#: the engine of `Simulator` and `simulate`: the compiled one, the only one (``engine="c"`` is accepted)
DEFAULT_ENGINE = "c"

class SolverWarning(UserWarning):
    """An advance completed, but something in it needs the user's attention (a `Report`): a contact LCP
    without an exact solution under the sticking law, or an adaptive step accepted at the smallest step size
    with its error above tolerance. ``reports`` lists them."""

    def __init__(self, message: str, reports=()):
        super().__init__(message)
        self.reports = list(reports)


class SolverFailure(ValueError):
    """Raised instead of a `SolverWarning` by a Simulator built with ``on_report="raise"`` (the FMUs): the
    advance is refused with the state kept."""


#: accepted spellings of a scheme: names and integer codes of the registered schemes
SCHEMES = scheme_choices()

#: the solver options the FMUs expose (and the command line), declared once
SOLVER_PARAMETERS = (
    Param("scheme", "event_driven", None, "Integration scheme", items=tuple(
        (name, cls.code, cls.summary) for name, cls in sorted(SCHEME_CLASSES.items(), key=lambda kv: kv[1].code))),
    Param("dt_max", 0.0, "s", "Moreau-Jean time step (largest; each communication step is split evenly) or "
          "largest event-driven step; 0: the scheme's default (Moreau-Jean 1e-3 s, event-driven uncapped)",
          lo=0.0),
    Param("tolerance", 1e-8, "1", "Relative tolerance of the event-driven scheme", lo=1e-14, hi=1e-2),
)

#: [1] smallest dt_max (other than 0, the scheme's default) relative to the model's time scale 1/p: a
#: Moreau-Jean step of 1e-6/p has a first-order error of ~1e-6 of the motion (finer than any rocking study
#: resolves), while the work per second of motion grows as 1/dt_max: 1e6 steps per time scale would make one
#: second of a typical block (1/p ~ 0.2-0.5 s) cost minutes. The same bound holds for the event-driven cap.
DT_MIN_REL = 1e-6


#: the types of a number that `Simulator.advance` passes to the compiled engine as is (a non-finite numpy float
#: takes the checked path: its message names it as the Python does, np.float64(nan))
_NUMBERS = (float, int, np.float64)


def _vertical_or_none(ag_v):
    """``ag_v`` as given, None for a numeric zero (no vertical motion: today's code path, bit for bit)."""
    return None if ag_v is not None and type(ag_v) in _NUMBERS and ag_v == 0.0 else ag_v


def _with_vertical(horizontal: GroundMotion, ag_v) -> TwoComponentMotion:
    """The ground motion ``horizontal`` with the vertical ground acceleration ``ag_v``; ValueError naming ag_v
    when ``horizontal`` already carries one (it is given once: in the ground motion or as ag_v)."""
    if horizontal.vertical is not None:
        raise ValueError("ag_v: the ground motion already has a vertical component (a TwoComponentMotion, a pair "
                         "of callables or (t, ag, ag_v) arrays); give the vertical ground acceleration once, "
                         "either in the ground motion or as ag_v, not both")
    return TwoComponentMotion(horizontal, ag_v)
#: the accepted values of ``Simulator(on_report=...)``
_ON_REPORT = {"warn": "warn", "raise": "raise", "ignore": "ignore"}

#: the model classes already seen to be RockingModel subclasses (a set lookup instead of the ABC's isinstance)
_MODEL_TYPES: set = set()

#: version of the `Simulator.get_state` dict (2: Coulomb friction added the friction demand, the Painleve count and,
#: event-driven, the base's offset; states of version 1 are refused by their version)
STATE_VERSION = 2
_HEADER = ("version", "scheme", "model", "n_dof")


class Simulator:
    """One simulation run of ``model`` with the chosen scheme, advanced step by step.

    Parameters
    ----------
    model : RigidBlock or FlexibleOscillator.
    scheme : "moreau_jean" (0) or "event_driven" (1).
    dt_max : [s] Moreau-Jean step (the largest; each `advance` is split in equal steps; default 1e-3 s,
        and at most 0.25/omega for the flexible oscillator), or the largest step of the event-driven scheme
        (default: none). None or 0 selects the scheme's default (0 is how the FMUs spell it); otherwise at
        least DT_MIN_REL * model.time_scale (1e-6/p).
    tolerance : [1] relative (and scaled absolute) tolerance of the event-driven scheme, in [1e-14, 1e-2].
    theta : [1] Moreau-Jean theta in [0.5, 1].
    zeno_tol : [1] event-driven Zeno rule, v_Zeno = zeno_tol * sqrt(g L).
    method : event-driven Runge-Kutta scheme, "DOP853" (order 8, default) or "DOPRI5" (order 5, cheaper
        at tolerances of 1e-6 and looser; scipy's name "RK45" is accepted for it).
    impact_log_size : number of impact times kept in ``impact_times`` (None: all; the FMUs keep a bounded
        log so that memory stays flat); ``outputs()["impacts"]`` counts every impact.
    max_steps : work budget of one `advance` call: internal steps (Moreau-Jean steps, or Runge-Kutta steps
        with each event counting EVENT_WORK = 30), default MAX_STEPS = 10000; None = unlimited (trusted batch
        use). An advance that needs more raises `WorkLimitError` (Moreau-Jean before any work) and leaves the
        simulator as it was.
    tolerances : `ContactTolerances` of both schemes (default: the documented defaults).
    on_report : what an advance does with its `Report`s (an inexact contact solve, a failed adaptive step):
        "warn" (default: one `SolverWarning` per advance), "raise" (a failed step raises `SolverFailure`, the
        advance refused and the state kept; the other reports, inexact contact solves, which have no better
        answer, are only kept in ``last_reports`` for the caller: the FMUs log them), or "ignore".
        ``last_reports`` keeps the reports of the last advance in every case.
    t0 : [s] start time.
    engine : "c", the compiled engine of `rocking_model.engine` (the only one; the keyword is kept for
        existing callers).
    **initial : initial state, passed to ``model.initial_state`` (phi_0 [rad], phi_dot_0 [rad/s], and
        u_0 [m], u_dot_0 [m/s] for the flexible oscillator).

    Ground motion: `advance` and `sample` take the horizontal ground acceleration ``ag`` [m/s2] (positive along
    +x) and optionally the vertical one ``ag_v`` [m/s2] (positive UPWARD: in the ground frame of the states and
    outputs the inertial force -m_i ag_v along +y on every mass, an effective gravity g + ag_v; where
    g + ag_v < 0 the body leaves the ground). The energy output keeps g: it changes by the work of -m_i ag_v.

    Every `advance` either completes with finite outputs or raises (ValueError for bad input or a motion
    that overflows, WorkLimitError for too much work) with the state exactly as before the call.
    `get_state` / `set_state` save and load the state as a flat dict of plain values.
    """

    #: the engine that runs the simulation: "c", the compiled one
    engine = "c"

    def __init__(self, model: RockingModel, scheme="event_driven", *, dt_max: float | None = None,
                 tolerance: float = 1e-8, theta: float = 0.5, zeno_tol: float = ZENO_TOL, t0: float = 0.0,
                 method: str = "DOP853", impact_log_size: int | None = 10000,
                 max_steps: int | None = MAX_STEPS, tolerances: ContactTolerances = DEFAULT_TOLERANCES,
                 on_report: str = "warn", engine: str = DEFAULT_ENGINE, **initial):
        if type(model) not in _MODEL_TYPES:
            if not isinstance(model, RockingModel):
                raise ValueError(f"model must be a RockingModel (RigidBlock, FlexibleOscillator), got {model!r}")
            _MODEL_TYPES.add(type(model))
        self.model = model
        self.scheme = check_choice("scheme", scheme, SCHEMES)
        t0 = check_real("t0", t0)
        mode, q, v = model._start_state(**initial)
        if impact_log_size is not None:
            impact_log_size = int(check_real("impact_log_size", impact_log_size, lo=0.0))
        if max_steps is not None:
            n = check_real("max_steps", max_steps, lo=1.0, hi=2.0 ** 53)
            if n != int(n):
                raise ValueError(f"max_steps = {max_steps!r} must be a whole number; allowed range [1, 2^53] "
                                 "or None (unlimited)")
            max_steps = int(n)
        self.max_steps = max_steps
        dt = check_real("dt_max", dt_max, lo=0.0) if dt_max is not None else 0.0   # 0: the scheme's default
        dt_min = DT_MIN_REL * model.time_scale
        if 0.0 < dt < dt_min:
            raise ValueError(f"dt_max = {dt:g} is out of range; allowed values 0 (the scheme's default) or "
                             f"[{dt_min:.3g}, inf) s: at least {DT_MIN_REL:g} times the model's time scale "
                             f"1/p = {model.time_scale:.3g} s")
        if not isinstance(tolerances, ContactTolerances):
            raise ValueError(f"tolerances must be a ContactTolerances, got {tolerances!r}")
        self.on_report = check_choice("on_report", on_report, _ON_REPORT)
        options = SolverOptions.of(dt, tolerance, theta, zeno_tol, method, impact_log_size, tolerances)
        if isinstance(engine, str) and engine == "python":
            raise ValueError("engine = 'python' is not supported: the Python reference engine was removed; "
                             "allowed values: 'c' (the compiled engine, the default)")
        self.engine = check_choice("engine", engine, ENGINES)
        self.integrator = CompiledIntegrator.from_options(model, mode, q, v, t0, options, scheme=self.scheme)
        # the attribute replaced (never mutated) whenever the state changes: caches key on its identity
        self._token = self.integrator.STATE_TOKEN
        #: `Report`s of the last advance
        self.last_reports: list[Report] = []
        self._out = None              # (state token, model outputs) of the last checked state
        self._motion = None           # (motion, vertical motion or None, checked motion) of the last non-constant input

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_motion"] = None       # a cache of the caller's input (may be a lambda: not picklable)
        return state

    @property
    def t(self) -> float:
        """Current time [s]."""
        return self.integrator.t

    @property
    def impact_times(self) -> list[float]:
        """Times of the (last ``impact_log_size``) impacts [s]."""
        return self.integrator.impact_times.tail()

    def _ground_motion(self, ag, ag_v=None) -> GroundMotion:
        """``ag`` (and the vertical ``ag_v``, None: none or the one ``ag`` holds) as a GroundMotion ready for the
        integrator: |ag|, |ag_v| <= AG_MAX checked (constant, known peak) or checked value by value
        (`rocking_model.ground_motion.checked_motion`)."""
        if ag_v is None:
            if type(ag) is float or type(ag) is int:
                return ConstantMotion(ag)         # checks |ag| <= AG_MAX
            last = self._motion
            if last is not None and last[0] is ag and last[1] is None:
                return last[2]
            gm = checked_motion(as_ground_motion(ag))
            if not gm.constant:
                self._motion = (ag, None, gm)     # the same object each step: keep its integrator caches
            return gm
        last = self._motion
        if last is not None and last[0] is ag and last[1] is ag_v:
            return last[2]
        gm = checked_motion(_with_vertical(as_ground_motion(ag), ag_v))
        if not gm.constant:
            self._motion = (ag, ag_v, gm)
        return gm

    def advance(self, t_end: float, ag, ag_v=None) -> None:
        """Integrate to exactly ``t_end`` [s] under ground acceleration ``ag``: a number [m/s2] held
        constant, a callable ag(t), a (t, ag) pair of arrays or a GroundMotion; |ag| <= AG_MAX. Positive ag
        acts along +x.

        ag_v: the vertical ground acceleration [m/s2], positive UPWARD (in the ground frame an effective gravity
        g + ag_v on every mass), in whatever form ``ag`` takes (number, callable, (t, ag_v) arrays,
        GroundMotion); |ag_v| <= AG_MAX. None (default) or 0: no vertical motion, exactly today's results.
        ``ag`` may instead carry it (a `TwoComponentMotion`, a pair of callables, (t, ag, ag_v) arrays); both
        at once is a ValueError naming ag_v.

        Raises ValueError (bad t_end, ag or ag_v, or a motion that overflows: the message names the likely
        cause) or `WorkLimitError` (more than max_steps internal steps); either way the simulator is left
        exactly as before the call."""
        if ag_v is not None:                  # (the per-step path without a vertical component stays a test)
            ag_v = _vertical_or_none(ag_v)
        if ag_v is None and type(ag) in _NUMBERS and type(t_end) in _NUMBERS \
                and self.on_report != "raise" \
                and (type(ag) is not np.float64 or math.isfinite(ag)) \
                and (type(t_end) is not np.float64 or math.isfinite(t_end)):
            # the lean path: one call into C (checks, checkpoint, outputs check in C)
            eng = self.integrator._engine
            try:
                eng.advance(t_end, ag, 0.0, self.max_steps)
            except BaseException as exc:
                self._c_failed(exc, t_end, ag)
            if eng.report_count:
                self._c_reports(eng)
            else:
                self.last_reports = []
            return
        t_end = check_real("t_end", t_end)
        integ = self.integrator
        if t_end < integ.t:
            raise ValueError(f"t_end = {t_end:.17g} is before the current time; allowed range "
                             f"[{integ.t:.17g}, inf)")
        # (a nonzero vertical component on the compiled engine goes through CompiledIntegrator.advance with the
        # TwoComponentMotion: the C engine's two-component motion reads its vertical component there)
        gm = self._ground_motion(ag, ag_v)
        self._guarded(t_end, gm, lambda: integ.advance(t_end, gm, max_steps=self.max_steps))

    def _c_failed(self, exc, t_end, ag) -> None:
        """The errors of the lean path as `_guarded` raises them (the engine has restored its state)."""
        from . import _engine

        if isinstance(exc, (_engine.NonFiniteError, np.linalg.LinAlgError)):
            if isinstance(exc, _engine.NonFiniteError):
                exc = FloatingPointError(str(exc))
            raise ValueError(self._diverged(exc, t_end, ConstantMotion(ag), self.integrator._engine.fail_time)) \
                from exc
        raise exc

    def _c_reports(self, eng) -> None:
        integ = self.integrator
        integ.reports = [Report(kind, t, msg) for kind, t, msg in eng.reports()]
        self._check_reports(integ.reports)

    def sample(self, times, ag, ag_v=None) -> tuple:
        """Advance through the increasing ``times`` [s] under ``ag`` (and the vertical ``ag_v`` [m/s2], positive
        upward, as in `advance`) and return the outputs there:
        (contact codes, {output name: array}, impacts, overturned), arrays of len(times) + 1 that start with
        the current state. The same guarantees as `advance` (the work budget applies between consecutive
        times); the event-driven scheme reads its dense output, so the times do not shorten its steps."""
        if ag_v is not None:                  # (the per-step path without a vertical component stays a test)
            ag_v = _vertical_or_none(ag_v)
        integ = self.integrator
        if isinstance(times, np.ndarray) and times.dtype == np.float64 and times.ndim == 1:
            # the compiled engine reads the array as is: checked at once (the first bad value named as below)
            arr = times
            bad = ~(np.isfinite(arr) & (arr >= integ.t))
            if bad.any():
                check_real("times", arr[int(np.argmax(bad))], lo=integ.t)
            times = arr
        else:
            times = [check_real("times", t, lo=integ.t) for t in times]
        if not len(times):
            raise ValueError("times must hold at least one time after the current one")
        if (bool(np.any(times[1:] < times[:-1])) if isinstance(times, np.ndarray)
                else any(b < a for a, b in zip(times, times[1:]))):
            raise ValueError("times must be increasing")
        return self._sample(times, self._ground_motion(ag, ag_v))

    def _sample(self, times, gm, hold: bool = False) -> tuple:
        """`sample` of checked ``times`` (increasing, from the current time on) under a checked motion ``gm``;
        hold (compiled engine, on_report not "raise"): gm(t_k) (and gm.vertical(t_k)) held over each interval
        [t_k, t_k+1), t_0 the current time, as one `advance` per interval under those numbers does."""
        integ = self.integrator
        if self.on_report != "raise":
            # the lean path, as advance's: the engine checkpoints, checks the outputs and restores itself on any
            # error (rk_engine_sample); the same exceptions and reports as _guarded
            try:
                result = integ.sample(times, gm, max_steps=self.max_steps, hold=hold)
            except BaseException as exc:
                t_fail = integ.t
                integ.forget_failure()
                if hold and integ._engine.callback_raised:
                    raise         # ag(t_k) raised: as the number ag(t_k) of an advance would, unwrapped
                err = self._failure(exc, times[-1], gm, t_fail)
                if err is exc:
                    raise
                raise err from exc
            eng = integ._engine
            if eng.report_count:
                self._c_reports(eng)
            else:
                integ.reports, self.last_reports = [], []
            return result
        return self._guarded(times[-1], gm, lambda: integ.sample(times, gm, max_steps=self.max_steps))

    def _guarded(self, t_end: float, gm, action):
        """Run ``action`` (an advance of the integrator to t_end under gm) with the checkpoint / rollback,
        the reports and the check of the outputs that `advance` promises; returns what action returns."""
        integ = self.integrator
        snap = integ.checkpoint()
        integ.reports = []
        try:
            result = action()
            self._check_reports(integ.reports)
            out = integ.outputs()
            if not math.isfinite(sum(out.values())):
                bad = {k: v for k, v in out.items() if not math.isfinite(v)}
                if bad:
                    raise FloatingPointError("non-finite outputs " + ", ".join(f"{k} = {v!r}"
                                                                              for k, v in bad.items()))
        except BaseException as exc:
            t_fail = integ.t
            integ.rollback(snap)
            err = self._failure(exc, t_end, gm, t_fail)
            if err is exc:
                raise
            raise err from exc
        integ.commit(snap)
        self._out = (getattr(integ, self._token), out)
        return result

    def _failure(self, exc: BaseException, t_end: float, gm, t_fail: float) -> BaseException:
        """What an advance (or sample) to ``t_end`` under ``gm`` that failed with ``exc`` at ``t_fail`` raises, the
        state already restored: a work limit, a refused step, a checked input (its message names it: ag of a
        callable, ...) or any other exception as it is; an arithmetic failure as a ValueError that says where and
        the likely cause."""
        if isinstance(exc, (WorkLimitError, SolverFailure)) or \
                not isinstance(exc, (ArithmeticError, ValueError, np.linalg.LinAlgError)):
            return exc
        msg = str(exc)
        if isinstance(exc, ValueError) and (" = " in msg or msg.startswith("ag")):
            return exc
        return ValueError(self._diverged(exc, t_end, gm, t_fail))

    def _check_reports(self, reports) -> None:
        """Act on the `Report`s of an advance as ``on_report`` says (see the class docstring)."""
        self.last_reports = list(reports)
        if not reports or self.on_report == "ignore":
            return
        if self.on_report == "raise":
            failures = [r for r in reports if r.kind in Report.FAILURES]
            if failures:
                raise SolverFailure(f"{len(failures)} failed step(s) in this advance, the first: "
                                    f"{failures[0].message}")
            return                    # the caller reads last_reports (the FMUs log them)
        msg = report_summary(reports)
        warnings.warn(SolverWarning(msg, reports), stacklevel=_user_stacklevel())

    def _diverged(self, exc, t_end, gm, t_fail) -> str:
        """Message of an advance whose motion overflowed: where, and the likely cause."""
        model = self.model
        q, v = self.integrator.state()
        peak = gm.peak_bound
        causes = []
        if peak is not None and peak > 10.0 * model.g:
            causes.append(f"the ground acceleration (|ag| up to {peak:g} m/s2, {peak / model.g:.3g} g)")
        peak_v = None if gm.vertical is None else gm.vertical.peak_bound
        if peak_v is not None and peak_v > 10.0 * model.g:
            causes.append(f"the vertical ground acceleration (|ag_v| up to {peak_v:g} m/s2, {peak_v / model.g:.3g} g)")
        if model.e_N > 0.0:
            causes.append(f"energy created at impacts by e_N = {model.e_N:g} with sticking (physics notes, "
                          "section 6)")
        causes.append(f"a state far outside the model's range (|q| up to {float(np.max(np.abs(q))):.3g}, "
                      f"|v| up to {float(np.max(np.abs(v))):.3g} at t = {self.t:.17g} s)")
        return (f"the motion is not finite in the step from t = {self.t:.17g} s to t_end = {t_end:.17g} s "
                f"(at t = {t_fail:.17g} s: {type(exc).__name__}: {exc}); the step was refused and the state "
                f"kept. Likely cause: {'; or '.join(causes)}")

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Full generalized coordinates and velocities (q, v)."""
        return self.integrator.state()

    def outputs(self) -> dict:
        """Model outputs plus contact (int: the contact mode, `rocking_model.modes.OVERTURNED` = 10 once
        overturned), impacts (int), overturned (bool), friction_demand (float: the largest |lambda_T| / lambda_N
        the contacts needed so far) and painleve (int: Painleve situations resolved so far).

        Once overturned the outputs are those of the pose reached at |phi| = pi/2 at rest: every velocity 0,
        energy the potential (and strain) energy of that pose relative to rest; they no longer change."""
        return self.integrator._engine.output_dict()    # computed on demand by the engine (cached by its state)

    # ------------------------------------------------------------------ plain-data state
    def get_state(self) -> dict:
        """The state that determines all future outputs, as a flat dict of plain values (`json.dumps`
        works; floats may be nan only where a field means "unset").

        Header: version (int, STATE_VERSION), scheme ("moreau_jean" / "event_driven"), model (class name),
        n_dof (full dimension). Event-driven: t [s], mode (0-9, `Mode`: the last contact mode once
        overturned, the state then at rest), y (reduced state of the mode:
        coordinates then velocities), impacts, overturned, n_steps, h (last step size [s], nan before the
        first), impact_times [s], impact_log (rows t, v_minus, v_plus flattened, 1 + 2 n_dof floats each),
        shift (horizontal offset [m] of the base of a sticking mode on the ground), friction_demand,
        painleve. Moreau-Jean: t, q, v (full coordinates and velocities), mode, closed (corners that carried
        impulse in the last step), impacts, overturned, n_steps, impact_times, friction_demand, painleve. The logs hold at most
        impact_log_size entries (impact_log at most min(1000, impact_log_size) rows).

        The model, its parameters and the solver settings are not in it: rebuild the Simulator from the same
        parameters, then `set_state`; both then give bit-identical outputs for the same inputs."""
        integ = self.integrator
        state = {"version": STATE_VERSION, "scheme": self.scheme, "model": type(self.model).__name__,
                 "n_dof": self.model.n_dof}
        state.update(integ.get_state())
        return state

    def set_state(self, state) -> None:
        """Load a `get_state` dict into this simulator (built with the same model and settings). Every field
        is checked (presence, no extra field, type, length for the mode, finite values, ranges, consistency
        of phi and the corners with the mode); a bad one raises ValueError naming it and nothing changes."""
        integ = self.integrator
        if not isinstance(state, Mapping):
            raise ValueError(f"state must be a mapping (dict) of plain values, got {type(state).__name__}")
        # the header first: a state of another version, scheme or model is named as such
        state_int(state, "version", STATE_VERSION, STATE_VERSION)
        state_str(state, "scheme", self.scheme)
        state_str(state, "model", type(self.model).__name__)
        state_int(state, "n_dof", self.model.n_dof, self.model.n_dof)
        check_state_keys(state, _HEADER + integ.STATE_KEYS)
        integ.set_state(state)
        self._out = None


@dataclass
class Result:
    """Time histories on the output grid: ``t`` and one array per output name; impact times [s]."""

    t: np.ndarray
    values: dict
    impact_times: np.ndarray
    scheme: str
    n_steps: int = 0
    info: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.t if name == "t" else self.values[name]

    def __contains__(self, name) -> bool:
        # (without it, ``in`` would iterate through __getitem__ with integer keys)
        return name == "t" or name in self.values

    def __getattr__(self, name):
        values = self.__dict__.get("values", {})
        if name in values:
            return values[name]
        raise AttributeError(name)

    def to_csv(self, path) -> None:
        names = list(self.values)
        data = np.column_stack([self.t] + [np.asarray(self.values[n], dtype=float) for n in names])
        np.savetxt(path, data, delimiter=",", header=",".join(["time"] + names), comments="")


#: (t0, dt, n, t_end) and the output grid of the last simulate (a run repeated over many models or motions, an
#: ensemble's, builds the same grid each time: a copy of it costs a third of building it)
_LAST_GRID = None


def _grid(t0: float, dt: float, n: int, t_end: float) -> np.ndarray:
    """The output grid as fmpy builds it: t_k = t0 + k dt (k = 0..n), the last one clipped to t_end; a new array."""
    global _LAST_GRID
    key = (t0, dt, n, t_end)
    last = _LAST_GRID
    if last is not None and last[0] == key:
        return last[1].copy()
    # (0 + x is x; k dt in place: the same products as dt * np.arange(n + 1), without two temporaries)
    times = np.arange(n + 1, dtype=float)
    times *= dt
    end = n * dt                      # times[n] as a float: the same product (n < 2^53 converts exactly)
    if t0:
        times += t0
        end += t0
    if end > t_end:                   # (the grid increases: only when its last time is past t_end is any)
        np.minimum(times, t_end, out=times)
    _LAST_GRID = (key, times.copy())
    return times


#: the accepted values of ``simulate(hold=...)``
_HOLDS = {"exact": "exact", "zoh": "zoh"}


def simulate(model: RockingModel, ground_motion=None, t_end: float = 10.0, *, scheme="event_driven",
             output_interval: float = 0.01, hold: str = "exact", ag_v=None, **kwargs) -> Result:
    """Simulate ``model`` from t0 to ``t_end`` [s] and return the outputs every ``output_interval`` [s].

    ground_motion: the horizontal ground acceleration ag [m/s2], positive along +x: number, callable ag(t),
        (t, ag) arrays (linear interpolation) or GroundMotion; or both components: a `TwoComponentMotion`, a
        pair of callables (ag(t), ag_v(t)) or three arrays (t, ag, ag_v).
    ag_v: the vertical ground acceleration [m/s2], positive UPWARD (an effective gravity g + ag_v), in any
        form ground_motion takes for one component; None (default) or 0: none. Giving it both here and in
        ground_motion is a ValueError naming ag_v.
    hold: "exact" integrates the ground motion as given; "zoh" holds ag(t_k) (and ag_v(t_k)) constant over
        each output interval, as a co-simulation master (fmpy) does with the FMU.
    Other keyword arguments go to `Simulator` (dt_max, tolerance, theta, zeno_tol, max_steps, t0, engine,
    phi_0, ...); the work budget max_steps applies to each output interval.
    """
    ag_v = _vertical_or_none(ag_v)
    gm = as_ground_motion(ground_motion)
    gm = checked_motion(gm if ag_v is None else _with_vertical(gm, ag_v))
    vert = gm.vertical
    hold = check_choice("hold", hold, _HOLDS)
    kwargs.setdefault("impact_log_size", None)
    sim = Simulator(model, scheme, **kwargs)
    t0 = sim.t
    t_end = check_real("t_end", t_end, lo=t0)
    dt = check_real("output_interval", output_interval, lo=0.0, lo_open=True)
    n = max(1, int(math.ceil((t_end - t0) / dt - 1e-9)))
    times = _grid(t0, dt, n, t_end)
    if hold == "exact":
        # one pass through the output grid (the event-driven scheme reads its dense output there); the work
        # budget applies between consecutive output samples
        # (the grid is finite and increasing from t0 by construction: the compiled engine reads it unchecked)
        modes, values, impacts, overturned = sim._sample(times[1:], gm)
        values["contact"] = modes
        values["impacts"] = impacts
        values["overturned"] = overturned
    elif sim.on_report != "raise":
        # one call into C: the advances of the loop below (ag(t_k) held over each output interval), in C
        modes, values, impacts, overturned = sim._sample(times[1:], gm, hold=True)
        # (the keys in the order of Simulator.outputs(), as the loop below records them)
        tail = values.pop("friction_demand"), values.pop("painleve")
        values["contact"] = modes
        values["impacts"] = impacts
        values["overturned"] = overturned
        values["friction_demand"], values["painleve"] = tail
    else:
        records = [sim.outputs()]
        for k in range(n):
            if vert is None:
                sim.advance(times[k + 1], ConstantMotion(gm(times[k])))
            else:
                sim.advance(times[k + 1], ConstantMotion(gm(times[k])), ag_v=ConstantMotion(vert(times[k]), "ag_v"))
            records.append(sim.outputs())
        values = {name: np.array([r[name] for r in records]) for name in records[0]}
    integ = sim.integrator
    # (the compiled engine's impact times read from it directly: the same list sim.impact_times returns)
    impact_times = integ._engine.impact_times
    return Result(t=times, values=values, impact_times=np.array(impact_times), scheme=sim.scheme,
                  n_steps=integ.n_steps)


def report_summary(reports) -> str:
    """One message for the `Report`s of an advance: how many of each kind, and the first of each."""
    kinds: dict = {}
    for r in reports:
        kinds.setdefault(r.kind, []).append(r)
    return "; ".join(f"{len(rs)} {kind.replace('_', ' ')} report(s), the first: {rs[0].message}"
                     for kind, rs in kinds.items())


def _user_stacklevel() -> int:
    """The stacklevel of `warnings.warn` that names the first caller outside this package."""
    import os
    import sys
    package = os.path.dirname(os.path.abspath(__file__))
    frame, level = sys._getframe(1), 1
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(package + os.sep):
        frame, level = frame.f_back, level + 1
    return level
