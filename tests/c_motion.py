"""A test-only entry into the engine's ground motions (rk_motion.c), compiled at test time with cffi from the
package's C sources: `motion_eval(spec, times, vspec=None)` evaluates a motion spec (rocking_model.engine.motion_spec)
as the engine does, rk_motion_eval, next_breakpoint and continuous_at at each time in order on one motion (its interval
cache carried from one time to the next, as the Python object's), with vspec the pair's (TwoComponentMotion)
breakpoints and continuity and a fourth list, the vertical values. Skips the calling test when no C compiler is
available. The shipped extension exposes the engine, not its motions."""
from __future__ import annotations

import hashlib
import math
import sys
import tempfile
from pathlib import Path

import pytest

from rocking_model.engine import cdefs

SRC = Path(__file__).resolve().parent.parent / "rocking_model" / "engine" / "src"

CDEF = cdefs.STATUS + cdefs.MOTION + """
extern "Python" double m_eval(void *ctx, double t, int *failed, char *msg);
extern "Python" double m_breakpoint(void *ctx, double t, int *failed, char *msg);
extern "Python" int m_continuous(void *ctx, double tb);
"""
#: setup.py's flags (no FMA contraction: the motions agree with the Python classes bit for bit)
FLAGS = ["-std=c99", "-O3", "-ffp-contract=off", "-fno-fast-math"]
_MODULE = []


def _lib():
    if _MODULE:
        return _MODULE[0]
    try:
        import cffi
    except ImportError:
        pytest.skip("cffi is not installed (pip install cffi: the test extra has it)")
    sources = [SRC / "rk_motion.c", SRC / "rk_common.c"]
    digest = hashlib.sha256(CDEF.encode() + " ".join(FLAGS).encode()
                            + b"".join(p.read_bytes() for p in sorted(SRC.glob("*.[ch]"))))
    name = f"_rk_motion_{digest.hexdigest()[:12]}"
    build = Path(tempfile.gettempdir()) / name
    build.mkdir(parents=True, exist_ok=True)
    sys.path.insert(0, str(build))
    try:
        try:
            module = __import__(name)
        except ImportError:
            ffi = cffi.FFI()
            ffi.cdef(CDEF)
            ffi.set_source(name, '#include "rk_motion.h"\n', sources=[str(p) for p in sources],
                           include_dirs=[str(SRC)], extra_compile_args=FLAGS, libraries=["m"])
            try:
                ffi.compile(tmpdir=str(build), verbose=False)
            except Exception as exc:          # no compiler, or no Python headers
                pytest.skip(f"the motion harness does not compile here: {exc}")
            module = __import__(name)
    finally:
        sys.path.remove(str(build))
    _bind_callbacks(module.ffi)
    _MODULE.append((module.ffi, module.lib))
    return _MODULE[0]


def _bind_callbacks(ffi):
    """The Python motions called from C: the first exception kept (re-raised by motion_eval), a NaN returned."""

    def store(cb, exc, failed):
        if failed != ffi.NULL:
            failed[0] = 1
        cb.setdefault("exc", exc)

    @ffi.def_extern()
    def m_eval(ctx, t, failed, msg):
        cb = ffi.from_handle(ctx)
        try:
            x = float(cb["motion"](t))
            if not math.isfinite(x):
                raise ValueError(f"ag({t!r}) = {x} is not finite; allowed range [-1000, 1000] m/s2 (AG_MAX)")
            return x
        except Exception as exc:
            store(cb, exc, failed)
            return math.nan

    @ffi.def_extern()
    def m_breakpoint(ctx, t, failed, msg):
        cb = ffi.from_handle(ctx)
        try:
            return float(cb["motion"].next_breakpoint(t))
        except Exception as exc:
            store(cb, exc, failed)
            return math.nan

    @ffi.def_extern()
    def m_continuous(ctx, tb):
        cb = ffi.from_handle(ctx)
        try:
            return 1 if cb["motion"].continuous_at(tb) else 0
        except Exception as exc:
            store(cb, exc, ffi.NULL)
            return 0


_SIMPLE = {("constant", 2), ("linear", 4), ("sine", 4), ("cosine", 4), ("ricker", 4), ("rect", 4)}


def _buffer(ffi, obj, name):
    view = memoryview(obj)
    if view.format != "d" or view.ndim != 1 or not view.c_contiguous:
        raise TypeError(f"{name} must be a 1-D float64 array")
    return ffi.from_buffer("double[]", obj), view.shape[0]


def _parse(ffi, lib, spec, keep, callbacks):
    """The C motion of a spec (the engine's motion spec format)."""
    m = ffi.new("rk_motion *")
    keep.append(m)
    kind, n = spec[0], len(spec)
    err = ffi.new("rk_error *")
    st = lib.RK_OK
    if (kind, n) in _SIMPLE and kind in ("constant", "linear"):
        (lib.rk_motion_constant(m, spec[1]) if kind == "constant" else lib.rk_motion_linear(m, *spec[1:]))
    elif (kind, n) in _SIMPLE:
        st = getattr(lib, "rk_motion_" + kind)(m, *spec[1:], err)
    elif kind == "sampled" and n == 3:
        (t, nt), (ag, na) = _buffer(ffi, spec[1], "t"), _buffer(ffi, spec[2], "ag")
        if nt != na:
            raise ValueError("ground motion: t and ag must be 1-D arrays of equal length >= 2")
        keep += [t, ag]
        st = lib.rk_motion_sampled(m, t, ag, nt, err)
    elif kind == "scaled" and n == 3:
        inner = _parse(ffi, lib, spec[2], keep, callbacks)
        m.kind, m.factor, m.inner = lib.RK_MOTION_SCALED, spec[1], inner
        m.constant, m.value = inner.constant, spec[1] * inner.value
    elif kind == "callback" and n == 4:
        cb = {"motion": spec[1]}
        callbacks.append(cb)
        handle = ffi.new_handle(cb)
        keep.append(handle)
        m.kind, m.fn, m.ctx = lib.RK_MOTION_CALLBACK, lib.m_eval, handle
        m.fn_breakpoint = lib.m_breakpoint if hasattr(spec[1], "next_breakpoint") else ffi.NULL
        m.fn_continuous = lib.m_continuous if hasattr(spec[1], "continuous_at") else ffi.NULL
        m.constant, m.value = bool(spec[2]), float(spec[3])
    else:
        raise ValueError(f"motion spec: unknown kind {kind!r} or wrong length {n}")
    if st != lib.RK_OK:
        raise ValueError(ffi.string(err.message).decode())
    return m


def motion_eval(spec, times, vspec=None) -> tuple:
    """(ag, next_breakpoint, continuous_at) lists at ``times`` (and ag_v with vspec): see the module's doc."""
    ffi, lib = _lib()
    keep, callbacks = [], []
    m = _parse(ffi, lib, spec, keep, callbacks)
    mv = None if vspec is None else _parse(ffi, lib, vspec, keep, callbacks)
    failed, msg = ffi.new("int *"), ffi.new("char[]", 512)

    def check():
        for cb in callbacks:
            if "exc" in cb:
                raise cb["exc"]

    values, bps, cont, vvals = [], [], [], []
    for t in times:
        values.append(lib.rk_motion_eval(m, t, failed, msg))
        check()
        if mv is not None:
            vvals.append(lib.rk_motion_eval(mv, t, failed, msg))
            bps.append(lib.rk_motion_pair_next_breakpoint(m, mv, t))
            cont.append(bool(lib.rk_motion_pair_continuous_at(m, mv, t)))
        else:
            bps.append(lib.rk_motion_next_breakpoint(m, t))
            cont.append(bool(lib.rk_motion_continuous_at(m, t)))
        check()
    return (values, bps, cont, vvals) if mv is not None else (values, bps, cont)
