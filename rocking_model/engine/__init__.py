"""The compiled engine: C sources in ``src/``, the extension module `rocking_model._engine`.

See ``DESIGN.md`` in this folder for the architecture and the C API.

`CompiledIntegrator` implements the `rocking_model.integrators.base.Integrator` contract on top of
`rocking_model._engine.Engine`, so that `Simulator`, `simulate`, the CLI, the ensembles and the FMUs run the C
engine; `motion_spec` turns a `GroundMotion` into the plain tuple the engine reads.
"""
from __future__ import annotations

import math
import operator
import sys

import numpy as np

from ..ground_motion import (CheckedMotion, ConstantMotion, CosinePulse, GroundMotion, LinearMotion, RectangularPulse,
                             RickerPulse, SampledMotion, ScaledMotion, SinePulse)
from ..integrators.base import SCHEMES, Integrator, Report
from ..modes import ContactState

__all__ = ["CompiledIntegrator", "motion_spec", "vertical_spec", "ENGINES", "available"]

#: the accepted values of ``Simulator(engine=...)``: the compiled engine is the only one
ENGINES = {"c": "c"}


def available() -> bool:
    """Whether the extension module was built (``pip install .`` builds it)."""
    try:
        _extension()
    except ImportError:
        return False
    return True


_EXTENSION = None


def _extension():
    """The extension module `rocking_model._engine` (ImportError if not built), imported once: a relative import
    statement per call goes through importlib's Python code each time."""
    global _EXTENSION
    if _EXTENSION is None:
        from .. import _engine

        _EXTENSION = _engine
    return _EXTENSION


def motion_spec(gm: GroundMotion) -> tuple:
    """The engine's description of a ground motion: the classes the C engine evaluates itself (same formulas,
    bit for bit: rk_motion.c), any other one as a callback into Python (exact, slower). A two-component motion
    (``gm.vertical`` not None) is described by its horizontal component; `vertical_spec` gives the other."""
    if getattr(gm, "vertical", None) is not None:
        return motion_spec(gm.horizontal)
    cls = type(gm)
    if cls is ConstantMotion:
        return ("constant", gm.value)
    if cls is LinearMotion:
        return ("linear", gm.value, gm.rate, gm.t_ref)
    if cls is SampledMotion or _plain_sampled(cls):
        return ("sampled", np.ascontiguousarray(gm.t, dtype=float), np.ascontiguousarray(gm.ag, dtype=float))
    if cls is SinePulse:
        return ("sine", gm.A, gm.omega_p, gm.t0)
    if cls is CosinePulse:
        return ("cosine", gm.A, gm.omega_p, gm.t0)
    if cls is RickerPulse:
        return ("ricker", gm.A, gm.omega_p, gm.t_c)
    if cls is RectangularPulse:
        return ("rect", gm.A, gm.duration, gm.t0)
    if cls is ScaledMotion and gm.motion.peak_bound is not None:
        # (a scaled motion without a known peak is checked value by value: a callback, as the Python runs it)
        return ("scaled", gm.factor, motion_spec(gm.motion))
    if cls is CheckedMotion and (type(gm.motion) in (SampledMotion, SinePulse, LinearMotion, ConstantMotion,
                                                       CosinePulse, RickerPulse, RectangularPulse)
                                 or _plain_sampled(type(gm.motion))):
        return motion_spec(gm.motion)
    constant = bool(getattr(gm, "constant", False))
    return ("callback", gm, constant, float(getattr(gm, "value", 0.0)) if constant else 0.0)


#: what the engine's sampled path evaluates in C in place of a SampledMotion's Python methods
_SAMPLED_METHODS = ("__call__", "next_breakpoint", "continuous_at", "support", "peak_bound")
#: class -> whether it is a SampledMotion subclass that evaluates as one (e.g. records.Record)
_PLAIN_SAMPLED: dict = {}


def _plain_sampled(cls) -> bool:
    """Whether ``cls`` is a SampledMotion subclass that keeps SampledMotion's evaluation (a `Record` adds a name
    and a vertical component only): the C engine evaluates it itself, as a SampledMotion, instead of calling
    back into Python at every evaluation (20 times slower on a 30 s record)."""
    known = _PLAIN_SAMPLED.get(cls)
    if known is None:
        known = _PLAIN_SAMPLED[cls] = issubclass(cls, SampledMotion) and all(
            getattr(cls, name) is getattr(SampledMotion, name) for name in _SAMPLED_METHODS)
    return known


def vertical_spec(gm: GroundMotion):
    """The engine's description of the vertical component of a ground motion, None without one (the engine then
    runs today's path: no vertical acceleration, bit-identical)."""
    vertical = getattr(gm, "vertical", None)
    return None if vertical is None else motion_spec(vertical)


def _sampled(names, modes, values, impacts, overturned) -> tuple:
    """`Integrator.sample`'s (modes, outputs, impacts, overturned) from the arrays the engine wrote (``values``: the
    outputs, friction_demand, painleve, one row each: the engine wrote them in columns; ``modes`` int64 and
    ``overturned`` bool, as the Python scheme returns them): one contiguous array per output (rows of one block: a
    copy per column costs more than the run of a short scene)."""
    cols = list(values)               # the row views, made at once
    out = dict(zip(names, cols))
    out["friction_demand"] = cols[-2]
    out["painleve"] = cols[-1].astype(_I64)
    return modes, out, impacts, overturned


#: Engine's max_events default (engine_init in _engine.c), passed by position with the arguments after it: the
#: keyword parser cost a third of the engine's creation
_MAX_EVENTS = 100000

#: model class -> its output names, as the engine lists them (read once: the engine builds the list per read)
_NAMES: dict = {}

#: numpy's float64 descriptor (an identity test: a dtype's == parses its other side first)
_F64 = np.dtype(np.float64)
_I64 = np.dtype(np.int64)
_BOOL = np.dtype(bool)


def kernel_call(cls, params: list, fn: str, mode: int = 0, a=None, b=None, ag: float = 0.0, ag_v: float = 0.0):
    """One function of the model kernel of ``cls`` (generated from its declaration) on parameters ``params``
    (floats in declared order): `rocking_model._engine.model`; a model declared after the build is compiled
    and added first (`rocking_model.engine.plugin`)."""
    if cls not in _KERNELS_READY:
        from .plugin import ensure
        ensure(cls)
        _KERNELS_READY.add(cls)
    return _extension().model(cls.__name__, params, fn, mode, a, b, ag, ag_v)


#: the model classes whose kernels the engine knows
_KERNELS_READY: set = set()


def _floats(x) -> list | tuple:
    """``x`` as a sequence of floats (a float64 array's tolist(): the same values without a numpy scalar each; a
    tuple of floats, `RockingModel._start_state`'s, as it is)."""
    if type(x) is tuple:
        for a in x:
            if type(a) is not float:
                return [float(a) for a in x]
        return x
    if type(x) is np.ndarray and x.dtype is _F64:
        return x.tolist()
    return [float(a) for a in x]


#: model class -> a getter of its declared parameters in order, as a tuple (declared_parameters is slow to call
#: per run)
_PARAM_GETTERS: dict = {}


class _Log:
    """What the Simulator and the tests read of a `BoundedLog` (tail(), maxlen, len, iteration, indexing): the
    rows the engine holds (impact_times, or impact_log as (t, v_minus, v_plus) rows)."""

    def __init__(self, integ, rows: bool = False):
        self._integ = integ
        self._rows = rows

    @property
    def maxlen(self):
        n = self._integ._options.impact_log_size
        return n if n is None or not self._rows else min(1000, n)

    def tail(self) -> list:
        eng = self._integ._engine
        if not self._rows:
            return eng.impact_times
        flat = eng.get_state()["impact_log"]
        n = self._integ.model.n_dof
        w = 1 + 2 * n
        return [(flat[i], np.array(flat[i + 1:i + 1 + n]), np.array(flat[i + 1 + n:i + w]))
                for i in range(0, len(flat), w)]

    def __len__(self):
        return len(self.tail())

    def __iter__(self):
        return iter(self.tail())

    def __getitem__(self, i):
        return self.tail()[i]

    def __eq__(self, other):
        return self.tail() == list(other)

    def __repr__(self):
        return repr(self.tail())


class CompiledIntegrator(Integrator):
    """An integration scheme (``moreau_jean`` or ``event_driven``, declared in
    `rocking_model.integrators.schemes`) run by the C engine. The checkpoint around an advance is a copy of a C
    struct, the outputs are computed by the engine on demand."""

    engine = "c"

    def __init__(self, model, scheme: str, mode, q, v, t0: float, options, settings: dict):
        try:
            _engine = _extension()
        except ImportError as exc:
            raise ImportError("engine='c' needs the compiled extension rocking_model._engine, which is not built "
                              f"({exc}); `pip install .` builds it (a C compiler is required)") from exc

        ref_cls = SCHEMES[scheme]
        self.name, self.code, self.summary = ref_cls.name, ref_cls.code, ref_cls.summary
        self.STATE_KEYS = ref_cls.STATE_KEYS
        self.model = model
        self._scheme_cls = ref_cls
        self._options = options
        self._settings = settings               # the scheme's checked options (the method's canonical name)
        self._t0 = float(t0)
        self._start = (int(mode), _floats(q), _floats(v))
        self._engine = self._new_engine(_engine)
        names = _NAMES.get(type(model))
        if names is None:
            names = _NAMES[type(model)] = tuple(self._engine.output_names)
        self._names = names
        self._t_fail = None
        self.reports = []

    # the logs as views made on demand (no reference cycle: the engine and its log storage are freed as soon as
    # the integrator is, not at the next cyclic garbage collection)
    @property
    def impact_times(self) -> "_Log":
        return _Log(self)

    @property
    def impact_log(self) -> "_Log":
        if self.name != "event_driven":
            raise AttributeError("impact_log: the moreau_jean scheme keeps impact_times only")
        return _Log(self, rows=True)

    @classmethod
    def from_options(cls, model, mode, q, v, t0, options, scheme: str = "event_driven") -> "CompiledIntegrator":
        # the scheme's checks of its options first (messages naming the option), then the engine's
        settings = SCHEMES[scheme].settings(model, options)
        return cls(model, scheme, mode, q, v, t0, options, settings)

    def __getattr__(self, name):
        # the scheme's settings (dt_max, theta, tolerance, method, tolerances) as checked from the options;
        # never its state (that is the engine's)
        settings = self.__dict__.get("_settings")
        if settings is not None and name in settings:
            return settings[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def _engine_args(self):
        """(model class name, its declared parameters in order): the dataclass fields themselves (checked floats,
        an int choice), read by one attrgetter; the extension converts each with PyFloat_AsDouble, as float()."""
        cls = type(self.model)
        getter = _PARAM_GETTERS.get(cls)
        if getter is None:
            from .plugin import ensure
            ensure(cls)                   # a model declared after the build: its kernels compiled and added
            names = tuple(p.name for p in cls.parameters())
            # (a one-parameter attrgetter returns the value itself: a tuple either way)
            getter = _PARAM_GETTERS[cls] = (operator.attrgetter(*names) if len(names) > 1
                                            else lambda model, _n=names: tuple(getattr(model, n) for n in _n))
        return cls.__name__, getter(self.model)

    def _new_engine(self, _engine):
        """A new `Engine` at the start state: `_engine_args` and `_engine_kwargs` with the options passed by
        position, in the extension's order (a keyword costs it a dictionary lookup each)."""
        o = self._options
        return _engine.Engine(*self._engine_args(), None, self._scheme_cls.code, self._t0, float(o.dt_max),
                              float(o.tolerance), float(o.theta), float(o.zeno_tol), self._settings["method"],
                              o.impact_log_size, _MAX_EVENTS, o.tolerances, self._start)

    def _engine_kwargs(self):
        o = self._options
        return dict(scheme=self._scheme_cls.code, t0=self._t0, dt_max=float(o.dt_max), tolerance=float(o.tolerance),
                    theta=float(o.theta), zeno_tol=float(o.zeno_tol), method=self._settings["method"],
                    impact_log_size=o.impact_log_size, tolerances=o.tolerances)

    # ------------------------------------------------------------------ pickling (ensembles)
    def __getstate__(self):
        state = dict(self.__dict__)
        state["_engine"] = self._engine.snapshot()
        state.pop("_last_motion", None)   # may be a lambda's wrapper (not picklable); a new object restarts
        return state

    def __setstate__(self, state):
        from .. import _engine

        snap = state.pop("_engine")
        self.__dict__.update(state)
        self._engine = self._new_engine(_engine)
        self._engine.restore(snap)

    # ------------------------------------------------------------------ attributes
    @property
    def q(self):
        return self.state()[0]

    @property
    def v(self):
        return self.state()[1]

    @property
    def y(self) -> list:
        return self._engine.get_state()["y"]

    @property
    def k(self) -> int:
        return len(self.y) // 2

    @property
    def shift(self) -> float:
        return self._engine.get_state()["shift"]

    @property
    def t(self) -> float:
        return self._engine.t if self._t_fail is None else self._t_fail

    @property
    def mode(self):
        return self.model.mode_code(self._engine.mode)

    @property
    def impacts(self) -> int:
        return self._engine.impacts

    @property
    def overturned(self) -> bool:
        return self._engine.overturned

    @property
    def n_steps(self) -> int:
        return self._engine.n_steps

    @property
    def friction_demand(self) -> float:
        return self._engine.friction_demand

    @property
    def painleve(self) -> int:
        return self._engine.painleve

    @property
    def contact_code(self) -> int:
        return self._engine.contact_code

    @property
    def contacts(self) -> tuple:
        return tuple(ContactState(s) for s in self._engine.contacts())

    #: the Simulator keys its output cache on the identity of this attribute: a new object every read (the
    #: engine caches the outputs itself, by a state token)
    STATE_TOKEN = "_fresh"

    @property
    def _fresh(self):
        return object()

    # ------------------------------------------------------------------ checkpoint (Checkpointed)
    def checkpoint(self):
        self._engine.checkpoint()
        return None

    def rollback(self, snap) -> None:
        self._t_fail = None
        self._engine.rollback()

    def commit(self, snap) -> None:
        self._engine.commit()

    def forget_failure(self) -> None:
        """After a failed call, which the engine undid itself (every call is guarded in C: rk_engine.h): ``t``
        reads the engine's time again (the failure time was kept for the caller's message)."""
        self._t_fail = None

    # ------------------------------------------------------------------ stepping
    def _run(self, call):
        self._t_fail = None
        try:
            call()
        except BaseException:
            self._run_failed()
            raise
        finally:
            if self._engine.report_count:
                self.reports = [Report(kind, t, msg) for kind, t, msg in self._engine.reports()]

    def _run_failed(self):
        """In the except clause of a failed engine call: the engine is restored; ``t`` says where the scheme had got
        to (Simulator._diverged's "at t = ...", as the Python integrator's t before its rollback) until the
        Simulator rolls back; the engine's NonFiniteError raised as FloatingPointError."""
        self._t_fail = self._engine.fail_time
        exc = sys.exc_info()[1]
        if isinstance(exc, _extension().NonFiniteError):
            raise FloatingPointError(str(exc)) from None

    def advance(self, t_end: float, ag, max_steps: int | None = None) -> None:
        eng = self._engine
        if type(ag) is ConstantMotion:
            self._run(lambda: eng.advance(t_end, ag.value, 0.0, max_steps))
        elif (getattr(ag, "vertical", None) is not None and type(ag.horizontal) is ConstantMotion
              and type(ag.vertical) is ConstantMotion):
            # both components constant: the engine's constant path with the vertical value
            h, v = ag.horizontal.value, ag.vertical.value
            self._run(lambda: eng.advance(t_end, h, 0.0, max_steps, ag_v=v))
        else:
            spec = motion_spec(ag)
            vspec = vertical_spec(ag)
            ident = self._identity(ag)
            self._run(lambda: eng.advance_motion(t_end, spec, max_steps, ident, vspec))

    def _identity(self, ag) -> int:
        """id(ag), the object kept alive while it is the last motion (the Python's closure cache holds it too),
        so that the event-driven scheme carries its stepper on under the same motion object as the Python."""
        if ag.constant:
            return 0
        self._last_motion = ag
        return id(ag)

    def sample(self, times, ag, max_steps: int | None = None, hold: bool = False):
        """`Integrator.sample`; hold: ag (and ag_v) held at each interval's start instead (simulate's
        hold="zoh": the results of a `Simulator.advance` per interval under the number ag(t_k), in one call)."""
        if type(times) is not np.ndarray or times.dtype is not _F64 or not times.flags.c_contiguous:
            times = np.ascontiguousarray(times, dtype=float)
        n = times.size + 1
        names = self._names
        # (the dtypes as descriptors: np.empty converts a type argument on every call)
        ints = np.empty((2, n), _I64)                       # modes and impacts: one block
        values = np.empty((len(names) + 2, n), _F64)       # one row per output (columns=True)
        overturned = np.empty(n, _BOOL)
        spec = motion_spec(ag)
        vspec = None if ag.vertical is None else motion_spec(ag.vertical)
        ident = 0 if ag.constant else self._identity(ag)
        eng = self._engine
        self._t_fail = None
        try:
            eng.sample(times, spec, max_steps, ints[0], values, ints[1], overturned, ident, vspec, True, hold)
        except BaseException:
            self._run_failed()
            raise
        finally:
            if eng.report_count:
                self.reports = [Report(kind, t, msg) for kind, t, msg in eng.reports()]
        return _sampled(names, ints[0], values, ints[1], overturned)

    # ------------------------------------------------------------------ state
    def state(self):
        q, v = self._engine.full_state()
        return np.array(q), np.array(v)

    def outputs(self) -> dict:
        return dict(zip(self._names, self._engine.outputs()))

    def get_state(self) -> dict:
        state = self._engine.get_state()
        h = state.get("h")
        if h is not None and h != h:
            state["h"] = math.nan     # the Python's object: equal states compare equal (nan is nan)
        return {key: state[key] for key in self.STATE_KEYS}

    def set_state(self, state) -> None:
        """Load a `get_state` dict: its fields read with their types checked (`read_state`), then loaded into the
        engine, which checks their ranges and consistency with the model; nothing changes on error."""
        self._engine.set_state(self._scheme_cls.read_state(self.model, state, self._options.impact_log_size))

    def report(self, kind: str, t: float, message: str) -> None:
        self.reports.append(Report(kind, float(t), message))

