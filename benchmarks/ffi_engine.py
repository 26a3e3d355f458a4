"""The hot calls of the compiled engine's `Engine` (creation, advance, sample, outputs, checkpoint, attributes: same
arguments, results and exceptions as rocking_model._engine's) as a thin layer over the cffi binding
`benchmarks.ffi_binding`: the B side of the binding A/B (`compiled_bench.binding_ab`), written for speed (no
per-call dict, one C call per creation and per sample). The cold calls are the package's own cffi binding
(rocking_model._engine_cold) and are not measured.

cffi releases the GIL around every C call (Dask workers run engines in threads); a ground motion written in
Python is called back through ``extern "Python"`` functions, which take the GIL again."""
from benchmarks.ffi_binding import load
# the exception of each C status: the package's own mapping (its NonFiniteError is the extension's)
from rocking_model._engine_cold import _error_type

ffi, lib = load()

__all__ = ["Engine"]


def _text(p) -> str:
    return ffi.string(p).decode("utf-8", "replace")


def _fail(status, message):
    """Raise the exception of ``status`` with ``message`` (a char array or pointer)."""
    raise _error_type(status)(_text(message))


# ---------------------------------------------------------------------------------------------- motions
# A motion spec (rocking_model.engine.motion_spec) is a tuple: ("constant", value) | ("linear", value, rate, t_ref) |
# ("sampled", t, ag) with float64 buffers | ("sine" | "cosine" | "ricker" | "rect", A, omega_p, t0) |
# ("scaled", factor, inner_spec) | ("callback", motion, constant, value), a callback being any Python GroundMotion.

_MAX_MOTIONS = 8
#: (kind, length of the spec) -> rk_motion_kind of the motions of three numbers at most (rk_py_motion)
_SIMPLE = {("constant", 2): 0, ("linear", 4): 1, ("sine", 4): 3, ("cosine", 4): 6, ("ricker", 4): 7, ("rect", 4): 8}


class _Callback:
    """A Python ground motion called from C, and the first exception it raised."""

    __slots__ = ("motion", "exc")

    def __init__(self, motion):
        self.motion = motion
        self.exc = None

    def store(self, exc, msg):
        if msg != ffi.NULL:
            text = str(exc).encode("utf-8", "replace")[:511] or b"ag: the ground motion raised an exception"
            ffi.memmove(msg, text + b"\0", len(text) + 1)
        if self.exc is None:
            self.exc = exc


@ffi.def_extern()
def rk_py_eval(ctx, t, failed, msg):
    cb = ffi.from_handle(ctx)
    try:
        x = float(cb.motion(t))
        if x != x or x in (float("inf"), -float("inf")):   # checked_value's refusal
            raise ValueError(f"ag({t!r}) = {'nan' if x != x else 'inf' if x > 0 else '-inf'} is not finite; "
                             "allowed range [-1000, 1000] m/s2 (AG_MAX)")
        return x
    except BaseException as exc:   # (re-raised by the caller once the engine returns)
        cb.store(exc, msg)
        failed[0] = 1
        return float("nan")


@ffi.def_extern()
def rk_py_breakpoint(ctx, t, failed, msg):
    cb = ffi.from_handle(ctx)
    try:
        return float(cb.motion.next_breakpoint(t))
    except BaseException as exc:
        cb.store(exc, msg)
        failed[0] = 1
        return float("nan")


@ffi.def_extern()
def rk_py_continuous(ctx, tb):
    cb = ffi.from_handle(ctx)
    try:
        return 1 if cb.motion.continuous_at(tb) else 0
    except BaseException as exc:
        cb.store(exc, ffi.NULL)
        return 0


def _buffer(obj, name):
    """A 1-D C-contiguous float64 buffer as (double *, n)."""
    try:
        view = memoryview(obj)
    except TypeError:
        raise TypeError(f"{name} must be a contiguous float64 array") from None
    if view.format != "d" or view.ndim != 1 or not view.c_contiguous:
        raise TypeError(f"{name} must be a 1-D float64 array")
    return ffi.from_buffer("double[]", obj), view.shape[0]


class _Motions:
    """The C motions of one call: parsed specs, the buffers and callbacks they borrow (kept alive here)."""

    __slots__ = ("m", "n", "keep", "callbacks")

    def __init__(self):
        self.m = ffi.new("rk_motion[]", _MAX_MOTIONS)
        self.n = 0
        self.keep = None
        self.callbacks = None

    def _check(self, make, *args):
        """Run a motion constructor; its error raised (the rk_error allocated only then)."""
        if make(*args, ffi.NULL) != lib.RK_OK:
            err = ffi.new("rk_error *")
            make(*args, err)
            _fail(err.status, err.message)

    def parse(self, spec, depth=0):
        """The C motion of ``spec`` (a pointer into self.m)."""
        if depth > 4 or self.n >= _MAX_MOTIONS:
            raise ValueError("motion spec: nested too deep")
        if type(spec) is not tuple or len(spec) < 2:
            raise TypeError("motion spec must be a tuple (kind, ...)")
        kind, n = spec[0], len(spec)
        if type(kind) is not str:
            raise TypeError("motion spec: the kind must be a str")
        m = self.m + self.n
        self.n += 1
        code = _SIMPLE.get((kind, n))
        if code is not None:
            _simple(m, code, spec)
        elif kind == "sampled" and n == 3:
            t, nt = _buffer(spec[1], "t")
            ag, na = _buffer(spec[2], "ag")
            if nt != na:
                raise ValueError("ground motion: t and ag must be 1-D arrays of equal length >= 2")
            self.keep = (self.keep or []) + [t, ag]
            self._check(lib.rk_motion_sampled, m, t, ag, nt)
        elif kind == "scaled" and n == 3:
            factor = float(spec[1])
            inner = self.parse(spec[2], depth + 1)
            m.kind = lib.RK_MOTION_SCALED
            m.factor = factor
            m.inner = inner
            m.constant = inner.constant
            m.value = factor * inner.value
        elif kind == "callback" and n == 4:
            motion, constant, value = spec[1], bool(spec[2]), float(spec[3])
            if not callable(motion):
                raise TypeError("motion spec: a callback motion must be callable")
            cb = _Callback(motion)
            handle = ffi.new_handle(cb)
            self.keep = (self.keep or []) + [handle]
            if self.callbacks is None:
                self.callbacks = []
            self.callbacks.append(cb)
            m.kind = lib.RK_MOTION_CALLBACK
            m.fn = lib.rk_py_eval
            # a plain callable (no GroundMotion methods): no breakpoints, not continuous (GroundMotion's defaults)
            m.fn_breakpoint = lib.rk_py_breakpoint if hasattr(motion, "next_breakpoint") else ffi.NULL
            m.fn_continuous = lib.rk_py_continuous if hasattr(motion, "continuous_at") else ffi.NULL
            m.ctx = handle
            m.constant = constant
            m.value = value
        else:
            raise ValueError(f"motion spec: unknown kind {kind!r} or wrong length {n}")
        return m

    @staticmethod
    def single(spec):
        """The C motion of a spec of three numbers at most, alone (the hot path: no _Motions), or None."""
        if type(spec) is tuple:
            code = _SIMPLE.get((spec[0], len(spec)))
            if code is not None:
                m = ffi.new("rk_motion *")
                _simple(m, code, spec)
                return m
        return None

    def raised(self):
        """The first exception a callback raised, or None."""
        if self.callbacks:
            for cb in self.callbacks:
                if cb.exc is not None:
                    return cb.exc
        return None


def _simple(m, code, spec):
    """Fill ``m`` from a spec of three numbers at most (its errors raised, the rk_error allocated only then)."""
    a, b, c = (spec[1], 0.0, 0.0) if len(spec) == 2 else spec[1:]
    if lib.rk_py_motion(m, code, a, b, c, ffi.NULL) != lib.RK_OK:
        err = ffi.new("rk_error *")
        lib.rk_py_motion(m, code, a, b, c, err)
        _fail(err.status, err.message)


def _max_steps(max_steps) -> int:
    if max_steps is None:
        return -1
    if max_steps < 0:
        raise ValueError(f"max_steps = {max_steps} is out of range; allowed range [1, 2^53] or None (unlimited)")
    return max_steps


def _doubles(seq, name, cap):
    """A sequence of numbers as a new double[] and its length."""
    if seq is None:
        return ffi.NULL, 0
    try:
        items = list(seq)
    except TypeError:
        raise TypeError(f"{name} must be a sequence of numbers") from None
    if len(items) > cap:
        raise ValueError(f"{name} holds {len(items)} values, more than {cap}")
    try:
        return ffi.new("double[]", items) if items else ffi.NULL, len(items)
    except TypeError:
        for i, x in enumerate(items):
            try:
                ffi.new("double *", x)
            except TypeError:
                raise TypeError(f"{name}[{i}] must be a number") from None
        raise


# ---------------------------------------------------------------------------------------------- options
_TOL_FIELDS = ("gap", "step_gap", "grazing", "rest_velocity", "step_rest_velocity", "event", "rise", "clearly_open",
               "stateless_step", "lcp_exact", "lcp_hint", "demand_floor", "sub_samples")
#: the last frozen tolerances object read and its C struct: every run reads the same DEFAULT_TOLERANCES (13
#: attribute reads otherwise); only a frozen dataclass is kept (its fields cannot change)
_tol_cache = (None, None)


def _tolerances(tol):
    global _tol_cache
    if tol is _tol_cache[0]:
        return _tol_cache[1]
    c = ffi.new("rk_tolerances *")
    for name in _TOL_FIELDS:
        setattr(c, name, getattr(tol, name))
    params = getattr(type(tol), "__dataclass_params__", None)
    if params is not None and getattr(params, "frozen", False):
        _tol_cache = (tol, c)
    return c


def _choice(value, name, names):
    if type(value) is str:
        if value not in names:
            allowed = ", ".join(repr(n) for n in names)
            extra = ", 0, 1" if name == "scheme" else ""
            raise ValueError(f"{name} = {value!r} is not supported; allowed values: {allowed}{extra}")
        return names.index(value)
    return value


#: model kind -> the keys of output_dict() (output names, contact, impacts, overturned, friction_demand,
#: painleve), made once
_KEYS: dict = {}
_EXTRA = ("contact", "impacts", "overturned", "friction_demand", "painleve")


# ---------------------------------------------------------------------------------------------- Engine
class Engine:
    """Engine(kind, params, initial=None, scheme=1, t0=0.0, dt_max=0.0, tolerance=1e-8, theta=0.5, zeno_tol=1e-6,
    method=0, impact_log_size=None, max_events=100000, tolerances=None, state=None): one simulation in the C
    engine (rk_engine.h). state = (mode, q, v) starts there instead of at the initial values."""

    __slots__ = ("_e", "_keys", "_n", "_buf", "callback_raised", "__weakref__")

    def __init__(self, kind, params, initial=None, scheme=None, t0=0.0, dt_max=0.0, tolerance=1e-8, theta=0.5,
                 zeno_tol=1e-6, method=None, impact_log_size=None, max_events=100000, tolerances=None, state=None):
        if type(kind) is not str:
            raise TypeError(f"Engine() argument 'kind' must be str, not {type(kind).__name__}")
        if scheme.__class__ is not int:
            scheme = 1 if scheme is None else _choice(scheme, "scheme", ("moreau_jean", "event_driven"))
        if method.__class__ is not int:
            method = 0 if method is None else _choice(method, "method", ("DOP853", "DOPRI5"))
        if impact_log_size is None:
            impact_log_size = -1
        elif impact_log_size < 0:
            raise ValueError(f"impact_log_size = {impact_log_size} is out of range; allowed range [0, inf) or None "
                             "(keep all)")
        tol = ffi.NULL if tolerances is None else _tolerances(tolerances)
        err = ffi.new("rk_error *")
        # (lists and tuples go to the double * arguments as they are: cffi converts them in C)
        if state is None:
            init = ffi.NULL if initial is None else initial
            args = [kind.encode(), params, len(params), init, 0 if initial is None else len(initial), 0, ffi.NULL,
                    ffi.NULL, -1, scheme, t0, dt_max, tolerance, theta, zeno_tol, method, impact_log_size,
                    max_events, tol, err]
        else:
            mode, q, v = state
            args = [kind.encode(), params, len(params), ffi.NULL, 0, mode, q, v, len(q), scheme, t0, dt_max,
                    tolerance, theta, zeno_tol, method, impact_log_size, max_events, tol, err]
            if len(q) != len(v):
                raise ValueError("state: q and v must have the same length")
        try:
            if len(params) > lib.RK_MAX_PARAMS:
                raise ValueError(f"params holds {len(params)} values, more than {lib.RK_MAX_PARAMS}")
            e = lib.rk_py_create(*args)
        except TypeError:
            # another sequence than a list or a tuple, or a bad item: converted (and named) one by one
            args[1], args[2] = _doubles(params, "params", lib.RK_MAX_PARAMS)
            if state is None:
                args[3], args[4] = _doubles(initial, "initial", lib.RK_MAX_INITIAL)
            else:
                args[6], args[8] = _doubles(q, "q", lib.RK_MAX_DOF)
                args[7], _ = _doubles(v, "v", lib.RK_MAX_DOF)
            e = lib.rk_py_create(*args)
        self._ready(kind, e, err)

    def _ready(self, kind, e, err):
        if e == ffi.NULL:
            _fail(err.status, err.message)
        self._e = ffi.gc(e, lib.rk_engine_free)
        n = self._n = lib.rk_engine_n_outputs(e)
        keys = _KEYS.get(kind)
        if keys is None:
            keys = _KEYS[kind] = tuple([_text(lib.rk_engine_output_name(e, i)) for i in range(n)]) + _EXTRA
        self._keys = keys
        self._buf = None
        self.callback_raised = False

    def _raise(self):
        e = self._e
        _fail(lib.rk_engine_status(e), lib.rk_engine_message(e))

    # ------------------------------------------------------------------ stepping
    def advance(self, t_end=None, ag0=0.0, slope=0.0, max_steps=None, continuous=False, linear=False, ag_v=0.0,
                ag_v_slope=0.0, linear_v=False, *more):
        """advance(t_end, ag0=0.0, slope=0.0, max_steps=None, continuous=False, linear=False, ag_v=0.0,
        ag_v_slope=0.0, linear_v=False): integrate to t_end under ag(t) = ag0 + slope (t - t0) and the vertical
        ag_v(t) = ag_v + ag_v_slope (t - t0); the state is unchanged on any error."""
        if t_end is None or more:
            if more:
                raise TypeError(f"advance() takes at most 9 arguments ({9 + len(more)} given)")
            raise TypeError("advance() missing required argument 't_end' (pos 1)")
        flags = (1 if continuous else 0) | (2 if linear else 0) | (4 if linear_v else 0)
        try:
            st = lib.rk_engine_advance(self._e, t_end, ag0, slope, ag_v, ag_v_slope,
                                       -1 if max_steps is None else _max_steps(max_steps), flags)
        except TypeError:
            for name, x in (("t_end", t_end), ("ag0", ag0), ("slope", slope), ("ag_v", ag_v),
                            ("ag_v_slope", ag_v_slope)):
                try:
                    ffi.new("double *", x)
                except TypeError:
                    raise TypeError(f"advance() argument '{name}' must be a real number, not "
                                    f"{type(x).__name__}") from None
            raise
        if st:
            self._raise()

    def _run(self, motions, call):
        """Run ``call`` (the C call under parsed motions); a motion callback's exception re-raised with the state
        restored."""
        self.callback_raised = False
        if motions.callbacks is None:
            st = call()
        else:
            snap = self.snapshot()
            st = call()
            exc = motions.raised()
            if exc is not None:
                self.callback_raised = True
                if st == lib.RK_OK:
                    self.restore(snap)     # the call went on past the exception: undo it
                raise exc
        if st:
            self._raise()

    def advance_motion(self, t_end, motion, max_steps=None, identity=0, vspec=None):
        """advance_motion(t_end, motion, max_steps=None, identity=0, vspec=None): integrate to t_end under a
        motion spec (vspec: the vertical component's, None: none)."""
        t_end = float(t_end)
        ms = _max_steps(max_steps)
        mo = _Motions()
        m = mo.parse(motion)
        mv = ffi.NULL if vspec is None else mo.parse(vspec)
        m.identity = identity
        self._run(mo, lambda: lib.rk_engine_advance_motion(self._e, t_end, m, mv, ms))

    def sample(self, times, motion, max_steps, modes, values, impacts, overturned, identity=0, vspec=None,
               columns=False, hold=False):
        """sample(times, motion, max_steps, modes, values, impacts, overturned, identity=0, vspec=None,
        columns=False, hold=False): Integrator.sample into the given arrays (modes: int32 or int64 n+1, values:
        float64 (n+1) x (n_outputs+2), impacts: int64 n+1, overturned: int32 or bool n+1; columns=True: values
        (n_outputs+2) x (n+1), one row per output). hold=True: ag (and ag_v) held at each interval's start
        (simulate's hold="zoh", rk_engine_sample_held)."""
        ms = -1 if max_steps is None else _max_steps(max_steps)
        ct, n = _times(times)
        m = _Motions.single(motion) if vspec is None else None
        if m is None:
            mo = _Motions()
            m = mo.parse(motion)
            mv = ffi.NULL if vspec is None else mo.parse(vspec)
        else:
            mo, mv = None, ffi.NULL
        m.identity = identity
        cm, wide, cv, ci, co, bools = _arrays(modes, values, impacts, overturned, n + 1, self._n + 2)
        e, c, h = self._e, 1 if columns else 0, 1 if hold else 0
        self.callback_raised = False
        if mo is None or mo.callbacks is None:
            st = lib.rk_py_sample(e, m, mv, ct, n, ms, c, h, cm, wide, cv, ci, co, bools)
            if st:
                self._raise()
        else:
            self._run(mo, lambda: lib.rk_py_sample(e, m, mv, ct, n, ms, c, h, cm, wide, cv, ci, co, bools))

    # ------------------------------------------------------------------ outputs
    def _row(self):
        buf = self._buf
        if buf is None:
            buf = self._buf = ffi.new("double[]", lib.RK_MAX_OUTPUTS + 5)
        lib.rk_py_row(self._e, buf)
        return buf

    def outputs(self) -> tuple:
        """outputs() -> tuple in the declared order."""
        buf = self._buf
        if buf is None:
            buf = self._buf = ffi.new("double[]", lib.RK_MAX_OUTPUTS + 5)
        lib.rk_engine_outputs(self._e, buf)
        return tuple(ffi.unpack(buf, self._n))

    def output_row(self) -> tuple:
        """output_row() -> the values of output_dict() as a tuple of floats, in the same order."""
        return tuple(ffi.unpack(self._row(), self._n + 5))

    def output_dict(self) -> dict:
        """output_dict() -> Simulator.outputs(): the outputs by name, contact, impacts, overturned,
        friction_demand, painleve."""
        vals = ffi.unpack(self._row(), self._n + 5)
        n = self._n
        vals[n] = int(vals[n])
        vals[n + 1] = int(vals[n + 1])
        vals[n + 2] = vals[n + 2] != 0.0
        vals[n + 4] = int(vals[n + 4])
        return dict(zip(self._keys, vals))

    @property
    def output_names(self) -> tuple:
        """output names in order"""
        return self._keys[:self._n]

    @property
    def n_outputs(self) -> int:
        return self._n

    def reports(self) -> list:
        """reports() -> [(kind, t, message)] of the last call."""
        r = lib.rk_engine_reports(self._e)
        return [("inexact_contact" if it.kind == lib.RK_REPORT_INEXACT_CONTACT else "failed_step", it.t,
                 _text(it.message)) for it in r.items[0:min(r.count, lib.RK_MAX_REPORTS)]]

    # ------------------------------------------------------------------ attributes
    t = property(lambda self: lib.rk_engine_time(self._e), doc="time [s]")
    mode = property(lambda self: lib.rk_engine_mode(self._e), doc="contact mode")
    contact_code = property(lambda self: lib.rk_engine_contact_code(self._e), doc="mode, or 10 once overturned")
    impacts = property(lambda self: lib.rk_engine_impacts(self._e), doc="impacts so far")
    overturned = property(lambda self: bool(lib.rk_engine_overturned(self._e)), doc="overturned")
    n_steps = property(lambda self: lib.rk_engine_n_steps(self._e), doc="internal steps")
    friction_demand = property(lambda self: lib.rk_engine_friction_demand(self._e),
                               doc="largest |lambda_T| / lambda_N so far")
    painleve = property(lambda self: lib.rk_engine_painleve(self._e), doc="Painleve situations so far")
    fail_time = property(lambda self: lib.rk_engine_fail_time(self._e),
                         doc="time reached when the last call failed [s]")
    n_dof = property(lambda self: lib.rk_engine_n_dof(self._e), doc="full coordinates")
    n_contacts = property(lambda self: lib.rk_engine_n_contacts(self._e), doc="contacts")
    n_modes = property(lambda self: lib.rk_engine_n_modes(self._e), doc="contact modes")
    scheme = property(lambda self: int(lib.rk_engine_scheme(self._e)), doc="0 moreau_jean, 1 event_driven")
    model_class = property(lambda self: _text(lib.rk_engine_model_class(self._e)),
                           doc="the Python class name of the model")
    report_count = property(lambda self: lib.rk_engine_reports(self._e).count,
                            doc="reports of the last call (all counted)")

    @property
    def impact_times(self) -> list:
        """the last impact_log_size impact times [s]"""
        e = self._e
        n = lib.rk_engine_impact_times(e, ffi.NULL, 0)
        if not n:
            return []
        buf = ffi.new("double[]", n)
        lib.rk_engine_impact_times(e, buf, n)
        return ffi.unpack(buf, n)

    # ------------------------------------------------------------------ state
    # ------------------------------------------------------------------ checkpoint, snapshots
    def checkpoint(self) -> None:
        """checkpoint(): save the state in the slot."""
        lib.rk_engine_checkpoint(self._e)

    def rollback(self) -> None:
        """rollback(): restore the slot exactly."""
        if lib.rk_engine_rollback(self._e) != lib.RK_OK:
            self._raise()

    def commit(self) -> None:
        """commit(): drop the slot."""
        lib.rk_engine_commit(self._e)

def _times(obj):
    """A 1-D C-contiguous float64 buffer as (double[], n), a numpy array's checked by its attributes (a memoryview
    costs more)."""
    try:
        ok = obj.dtype.char == "d" and obj.ndim == 1
    except AttributeError:
        return _buffer(obj, "times")
    if not ok:
        raise TypeError("times must be a 1-D float64 array")
    try:
        c = ffi.from_buffer("double[]", obj)
    except (TypeError, BufferError):
        raise TypeError("times must be a contiguous float64 array") from None
    return c, len(c)


def _arrays(modes, values, impacts, overturned, rows, stride):
    """Engine.sample's arrays as (modes, modes int64, values, impacts, overturned, overturned bool): numpy arrays
    read by their attributes (one call: a check per array costs about as much as the C loop of a short run)."""
    try:
        ok = modes.flags.writeable and values.flags.writeable and impacts.flags.writeable \
            and overturned.flags.writeable
        sm, so = modes.itemsize, overturned.itemsize
        cm, cv = ffi.from_buffer("char[]", modes, True), ffi.from_buffer("char[]", values, True)
        ci, co = ffi.from_buffer("char[]", impacts, True), ffi.from_buffer("char[]", overturned, True)
    except (AttributeError, TypeError, BufferError):
        ok = False
    if not ok or len(cm) != rows * sm or sm not in (4, 8) or len(cv) != 8 * rows * stride or len(ci) != 8 * rows \
            or len(co) != rows * so or so not in (4, 1) or values.itemsize != 8 or impacts.itemsize != 8:
        cm, wide = _array(modes, "modes", rows, 4, 8)
        cv, _ = _array(values, "values", rows * stride, 8, 8)
        ci, _ = _array(impacts, "impacts", rows, 8, 8)
        co, bools = _array(overturned, "overturned", rows, 4, 1)
        return cm, wide, cv, ci, co, bools
    return cm, 1 if sm == 8 else 0, cv, ci, co, 1 if so == 1 else 0


def _array(obj, name, n, size, alt):
    """A writable C-contiguous buffer of n items of ``size`` or ``alt`` bytes: (char[], 1 if of alt bytes)."""
    try:
        itemsize = obj.itemsize if obj.flags.writeable else 0
        c = ffi.from_buffer(obj)
    except AttributeError:
        try:
            view = memoryview(obj)
        except TypeError:
            view = None
        if view is None or view.readonly or not view.c_contiguous:
            raise TypeError(f"{name} must be a writable contiguous array") from None
        itemsize = view.itemsize
        view.release()
        c = ffi.from_buffer(obj, require_writable=True)
    except (TypeError, BufferError):
        itemsize = 0
    if not itemsize:
        raise TypeError(f"{name} must be a writable contiguous array")
    if (itemsize != size and itemsize != alt) or len(c) != n * itemsize:
        if size == alt:
            raise ValueError(f"{name} must hold {n} items of {size} bytes")
        raise ValueError(f"{name} must hold {n} items of {size} or {alt} bytes")
    return c, 1 if itemsize != size else 0


# ---------------------------------------------------------------------------------------------- module functions