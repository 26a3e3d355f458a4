"""The cold part of `rocking_model._engine`, bound with cffi (``rocking_model._rk``, rocking_model/engine/build_ffi.py):
the Engine's state dicts, snapshots, reports, contacts and full state, and the module's version(), api_version(),
model_kinds(), kinds(), add_model(). `install` adds them to the extension module at its import; the hot calls
(creation, advance, sample, outputs) are hand-written in _engine.c (see the comment there for why). Imports neither
numpy nor the rest of the package."""
from ._rk import ffi, lib

#: the package ("rocking_model", or an FMU's bundled copy "rocking_model_<digest>"): its validation.WorkLimitError is
#: the class the package's callers catch
_PACKAGE = __name__.rpartition(".")[0] or "rocking_model"
_NON_FINITE = ValueError      # the extension's NonFiniteError, set by install


def _text(p) -> str:
    return ffi.string(p).decode("utf-8", "replace")


def _error_type(status):
    """The Python exception of a C status (DESIGN.md "Error handling")."""
    if status == lib.RK_ERR_VALUE:
        return ValueError
    if status == lib.RK_ERR_NONFINITE:
        return _NON_FINITE
    if status == lib.RK_ERR_NOT_IMPLEMENTED:
        return NotImplementedError
    if status == lib.RK_ERR_MEMORY:
        return MemoryError
    if status == lib.RK_ERR_WORK_LIMIT:
        import importlib

        return importlib.import_module(_PACKAGE + ".validation").WorkLimitError
    if status == lib.RK_ERR_SOLVER:
        from numpy.linalg import LinAlgError

        return LinAlgError
    return RuntimeError


def _ptr(engine):
    return ffi.cast("rk_engine *", engine._address)


def _raise(e):
    raise _error_type(lib.c_status(e))(_text(lib.c_message(e)))


# ---------------------------------------------------------------------------------------------- Engine methods
def contacts(self) -> tuple:
    """contacts() -> tuple of ContactState codes."""
    states = ffi.new("int[]", lib.RK_MAX_CONTACTS)
    return tuple(ffi.unpack(states, lib.c_contacts(_ptr(self), states)))


def full_state(self):
    """full_state() -> (q, v) lists."""
    q, v = ffi.new("double[]", lib.RK_MAX_DOF), ffi.new("double[]", lib.RK_MAX_DOF)
    n = lib.c_full_state(_ptr(self), q, v)
    return ffi.unpack(q, n), ffi.unpack(v, n)


def reports(self) -> list:
    """reports() -> [(kind, t, message)] of the last call."""
    r = lib.c_reports(_ptr(self))
    return [("inexact_contact" if it.kind == lib.RK_REPORT_INEXACT_CONTACT else "failed_step", it.t,
             _text(it.message)) for it in r.items[0:min(r.count, lib.RK_MAX_REPORTS)]]


def _impact_times(e) -> list:
    n = lib.c_impact_times(e, ffi.NULL, 0)
    if not n:
        return []
    buf = ffi.new("double[]", n)
    lib.c_impact_times(e, buf, n)
    return ffi.unpack(buf, n)


def get_state(self) -> dict:
    """get_state() -> dict of the scheme's STATE_KEYS."""
    e = _ptr(self)
    s = ffi.new("rk_plain_state *")
    lib.c_get_state(e, s)
    n_dof = lib.c_n_dof(e)
    if lib.c_scheme(e) == lib.RK_SCHEME_MOREAU_JEAN:
        closed = [i for i in range(lib.c_n_contacts(e)) if (s.closed >> i) & 1]
        return {"t": s.t, "q": ffi.unpack(s.q, n_dof), "v": ffi.unpack(s.v, n_dof), "mode": s.mode, "closed": closed,
                "impacts": s.impacts, "overturned": bool(s.overturned), "n_steps": s.n_steps,
                "impact_times": _impact_times(e), "friction_demand": s.friction_demand, "painleve": s.painleve}
    rows = lib.c_impact_log(e, ffi.NULL, 0)
    width = 1 + 2 * n_dof
    log = []
    if rows:
        buf = ffi.new("double[]", rows * width)
        lib.c_impact_log(e, buf, rows)
        log = ffi.unpack(buf, rows * width)
    return {"t": s.t, "mode": s.mode, "y": ffi.unpack(s.y, s.n_y), "impacts": s.impacts,
            "overturned": bool(s.overturned), "n_steps": s.n_steps, "h": s.h, "impact_times": _impact_times(e),
            "impact_log": log, "shift": s.shift, "friction_demand": s.friction_demand, "painleve": s.painleve}


def _field(d, key):
    try:
        return d[key]
    except KeyError:
        raise ValueError(f"state field '{key}' is missing") from None


def _field_float(d, key) -> float:
    try:
        return ffi.new("double *", _field(d, key))[0]
    except TypeError:
        raise ValueError(f"state field '{key}' must be a float") from None


def _field_int(d, key) -> int:
    try:
        return ffi.new("long long *", _field(d, key))[0]
    except (TypeError, OverflowError):
        raise ValueError(f"state field '{key}' must be an int") from None


def _field_floats(d, key):
    """A list of floats as (double[] or NULL, length)."""
    try:
        items = list(_field(d, key))
    except TypeError:
        raise ValueError(f"state field '{key}' must be a list of floats") from None
    out = ffi.new("double[]", max(1, len(items)))
    for i, v in enumerate(items):
        try:
            out[i] = v
        except TypeError:
            raise ValueError(f"state field '{key}'[{i}] must be a float") from None
    return out, len(items)


def _field_fixed(d, key, dest, want) -> None:
    buf, n = _field_floats(d, key)
    if n != want:
        raise ValueError(f"state field '{key}' has {n} values; expected {want}")
    ffi.memmove(dest, buf, n * ffi.sizeof("double"))


def set_state(self, d) -> None:
    """set_state(dict): load get_state's fields; the consistency checks run in C with the Python's messages,
    nothing changes on error."""
    from collections.abc import Mapping

    if not isinstance(d, Mapping):
        raise ValueError("state must be a mapping (dict) of plain values")
    e = _ptr(self)
    n_dof = lib.c_n_dof(e)
    s = ffi.new("rk_plain_state *")
    s.h = float("nan")
    s.t = _field_float(d, "t")
    mode = _field_int(d, "mode")
    if mode < -1 or mode > 1000:
        raise ValueError(f"state field 'mode' = {mode} is out of range; allowed range [0, {lib.c_n_modes(e) - 1}]")
    s.mode = mode
    s.impacts = _field_int(d, "impacts")
    s.n_steps = _field_int(d, "n_steps")
    s.friction_demand = _field_float(d, "friction_demand")
    s.painleve = _field_int(d, "painleve")
    s.overturned = bool(_field(d, "overturned"))
    log, n_log = ffi.NULL, 0
    if lib.c_scheme(e) == lib.RK_SCHEME_MOREAU_JEAN:
        _field_fixed(d, "q", s.q, n_dof)
        _field_fixed(d, "v", s.v, n_dof)
        nc = lib.c_n_contacts(e)
        try:
            closed = list(_field(d, "closed"))
        except TypeError:
            raise ValueError("state field 'closed' must be a list of ints") from None
        mask = 0
        for i, c in enumerate(closed):
            try:
                c = ffi.new("long *", c)[0]
            except (TypeError, OverflowError):
                c = -1
            if not 0 <= c < nc:
                raise ValueError(f"state field 'closed'[{i}] must be an int in [0, {nc - 1}]")
            mask |= 1 << c
        s.closed = mask
    else:
        y, ny = _field_floats(d, "y")
        if ny > lib.RK_MAX_Y:
            raise ValueError(f"state field 'y' has {ny} values; allowed at most {lib.RK_MAX_Y}")
        ffi.memmove(s.y, y, ny * ffi.sizeof("double"))
        s.n_y = ny
        s.h = _field_float(d, "h")
        s.shift = _field_float(d, "shift")
        log, n_log = _field_floats(d, "impact_log")
        width = 1 + 2 * n_dof
        if n_log % width:
            raise ValueError(f"state field 'impact_log' has {n_log} values; expected a multiple of {width}")
        n_log //= width
    times, n_times = _field_floats(d, "impact_times")
    if lib.c_set_state(e, s, times, n_times, log, n_log) != lib.RK_OK:
        _raise(e)


def snapshot(self) -> bytes:
    """snapshot() -> bytes of the whole state."""
    e = _ptr(self)
    n = lib.c_snapshot_size(e)
    buf = ffi.new("char[]", n)
    if lib.c_snapshot(e, buf, n) != lib.RK_OK:
        raise RuntimeError("snapshot failed")
    return ffi.buffer(buf, n)[:]


def restore(self, data) -> None:
    """restore(bytes): load a snapshot of an engine built alike."""
    e = _ptr(self)
    buf = ffi.from_buffer(data)
    if lib.c_restore(e, buf, len(buf)) != lib.RK_OK:
        _raise(e)


# ---------------------------------------------------------------------------------------------- module functions
def version() -> str:
    """version() -> str: the version the C engine was built with."""
    return _text(lib.c_version())


def api_version() -> int:
    """api_version() -> int: RK_ENGINE_API_VERSION of rk_engine.h."""
    return lib.c_api_version()


def _decls(d, n) -> list:
    return [(_text(x.name), _text(x.unit), x.default_value, x.lo, x.hi, x.lo_open, x.hi_open, x.inf_ok, x.integer,
             x.n_items) for x in d[0:n]]


def model_kinds() -> list:
    """model_kinds() -> the registered model kernels and their declarations (parameters, initial values, outputs),
    so that a caller of the low-level Engine can build its parameter list without the package."""
    out = []
    k = lib.c_model_kinds()
    i = 0
    while k[i] != ffi.NULL:
        o = k[i]
        out.append({"kind": _text(o.kind), "class_name": _text(o.class_name), "n_dof": o.n_dof,
                    "n_contacts": o.n_contacts, "n_modes": o.n_modes, "phi_index": o.phi_index,
                    "slide_index": o.slide_index, "lift_index": o.lift_index,
                    "params": _decls(o.param_decls, o.n_params), "initial": _decls(o.initial_decls, o.n_initial),
                    "outputs": _decls(o.output_decls, o.n_outputs), "shifted": ffi.unpack(o.shifted, o.n_shifted)})
        i += 1
    return out


def kinds() -> str:
    """kinds() -> str: the model kinds the engine knows (built in, then added), quoted and comma-separated."""
    buf = ffi.new("char[]", 4096)
    lib.c_kind_names(buf, 4096)
    return _text(buf)


def add_model(address: int) -> None:
    """add_model(address): add the kernel (rk_model_ops *) of a model declared after the build
    (rocking_model.engine.plugin compiles it into a library of its own and passes its address)."""
    if not address:
        raise ValueError("add_model: the kernel's address is NULL")
    err = ffi.new("rk_error *")
    if lib.c_model_add(ffi.cast("const rk_model_ops *", address), err) != lib.RK_OK:
        raise ValueError(_text(err.message))


#: the size of `model`'s result buffers (the largest result: a mass matrix of the engine's RK_MAX_Y)
_BUF = 256
_VECTOR = ("forces", "gaps", "contact_abscissae", "rest_position", "outputs", "mass_matrix", "inverse_mass_matrix",
           "mode_rhs", "mode_outputs", "contact_forces", "classical_impact_velocity")
_PAIR = ("stiff_jacobians", "contact_jacobians", "contact_drift", "embed", "mode_jacobian")


def _doubles(x):
    if x is None:
        return ffi.NULL
    return ffi.new("double[]", [float(v) for v in x] or [0.0])


def model(kind, params, fn, mode=0, a=None, b=None, ag=0.0, ag_v=0.0):
    """model(kind, params, fn, mode=0, a=None, b=None, ag=0.0, ag_v=0.0): one function of a model's generated
    kernel on an instance built from ``params`` (ValueError with the model's own message on bad parameters):
    info, mass_matrix, inverse_mass_matrix, forces, stiff_jacobians, gaps, contact_jacobians, contact_drift,
    contact_abscissae, rest_position, energy, outputs, slip, initial_state, and of a sticking mode mode_dofs,
    embed, mode_jacobian, mode_rhs, mode_outputs, contact_forces, classical_impact_velocity."""
    p = [float(v) for v in params]
    # buffers per call: cffi releases the GIL in the call, and Dask workers analyse models in threads
    _O1, _O2 = ffi.new("double[]", _BUF), ffi.new("double[]", _BUF)
    _N2, _IVAL, _MSG = ffi.new("int *"), ffi.new("int *"), ffi.new("char[]", 512)
    _NAMES = ffi.new("char[]", 4096) if fn == "info" else ffi.new("char[]", 1)
    n1 = lib.c_model(kind.encode(), ffi.new("double[]", p or [0.0]), len(p), fn.encode(), int(mode), _doubles(a),
                     _doubles(b), float(ag), float(ag_v), _O1, _O2, _N2, _IVAL, _MSG, _NAMES, len(_NAMES))
    if n1 == -1:
        raise ValueError(_text(_MSG))
    if n1 == -2:
        return None
    n2 = _N2[0]
    if fn == "info":
        names = _text(_NAMES).split("\n") if n2 else []
        return {"length_scale": _O1[0], "time_scale": _O1[1], "force_scale": _O1[2], "step_limit": _O1[3],
                "dof_scales": ffi.unpack(_O1 + 4, n1 - 4), "derived": dict(zip(names, ffi.unpack(_O2, n2)))}
    if fn in ("energy", "slip"):
        return _O1[0]
    if fn == "mode_dofs":
        return [int(x) for x in ffi.unpack(_O1, n1)]
    if fn == "initial_state":
        return _IVAL[0], ffi.unpack(_O1, n1), ffi.unpack(_O2, n2)
    if fn in _PAIR:
        return ffi.unpack(_O1, n1), ffi.unpack(_O2, n2)
    return ffi.unpack(_O1, n1)


_METHODS = (contacts, full_state, reports, get_state, set_state, snapshot, restore)
_FUNCTIONS = (version, api_version, model_kinds, kinds, add_model, model)


def install(module) -> None:
    """Bind to the engine of the extension ``module`` (its rk_py_api table) and add the methods above to its Engine
    and the functions to it."""
    global _NON_FINITE
    if lib.rk_py_bind(ffi.cast("void *", module._API)) != 0:
        raise ImportError(f"{module.__name__} and {__name__} were built from different versions of rk_py_api.h")
    _NON_FINITE = module.NonFiniteError
    for fn in _METHODS:
        setattr(module.Engine, fn.__name__, fn)
    for fn in _FUNCTIONS:
        fn.__module__ = module.__name__
        setattr(module, fn.__name__, fn)
