"""A test-only entry into the engine's model kernels, compiled at test time from the package's C sources (cffi).

The shipped extension module exposes the engine, not its internals; the tests that check a kernel function
by function build this small module instead: `kernels()` returns (ffi, lib) with

    int k_init(const char *kind, const double *params, int n, char *msg)       -> instance slot (0) or -1
    int k_call(const char *fn, int mode, const double *a, const double *b, double ag, double ag_v,
               double *out, double *out2)                                      -> a count / status

on one model instance held by the module; ``int k_set_offset(double x)`` sets its base offset m->offset [m],
which the mode kernels of a model with ground-anchored forces read (the event-driven driver's shift). Skips the
calling test when no C compiler is available.
"""
from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parent.parent / "rocking_model" / "engine" / "src"

CDEF = """
int k_init(const char *kind, const double *params, int n, char *msg);
int k_call(const char *fn, int mode, const double *a, const double *b, double ag, double ag_v, double *out,
           double *out2);
int k_info(int *n_dof, int *n_contacts, int *n_outputs);
int k_set_offset(double offset);
"""

SHIM = r"""
#include "rk_model.h"
#include <string.h>

static rk_model K;

int k_init(const char *kind, const double *params, int n, char *msg)
{
    rk_error err;
    const rk_model_ops *ops = rk_model_find(kind);
    memset(&err, 0, sizeof err);
    if (ops == NULL) {
        strcpy(msg, "unknown kind");
        return -1;
    }
    if (rk_model_init(&K, ops, params, n, &err) != RK_OK) {
        strncpy(msg, err.message, 511);
        msg[511] = 0;
        return -1;
    }
    return 0;
}

int k_set_offset(double offset)
{
    K.offset = offset;
    return 0;
}

int k_info(int *n_dof, int *n_contacts, int *n_outputs)
{
    *n_dof = K.ops->n_dof;
    *n_contacts = K.ops->n_contacts;
    *n_outputs = K.ops->n_outputs;
    return 0;
}

int k_call(const char *fn, int mode, const double *a, const double *b, double ag, double ag_v, double *out,
           double *out2)
{
    const rk_model_ops *o = K.ops;
    if (!strcmp(fn, "mass_matrix")) { o->mass_matrix(&K, a, out); return 0; }
    if (!strcmp(fn, "inverse_mass_matrix")) {
        if (o->inverse_mass_matrix == NULL) return -1;
        o->inverse_mass_matrix(&K, a, out); return 0;
    }
    if (!strcmp(fn, "forces")) { o->forces(&K, a, b, ag, ag_v, out); return 0; }
    if (!strcmp(fn, "stiff_jacobians")) {
        if (o->stiff_jacobians == NULL) return -1;
        return o->stiff_jacobians(&K, a, b, out, out2);
    }
    if (!strcmp(fn, "gaps")) { o->gaps(&K, a, out); return 0; }
    if (!strcmp(fn, "contact_jacobians")) { o->contact_jacobians(&K, a, out, out2); return 0; }
    if (!strcmp(fn, "contact_drift")) { o->contact_drift(&K, a, b, out, out2); return 0; }
    if (!strcmp(fn, "contact_abscissae")) { o->contact_abscissae(&K, a, out); return 0; }
    if (!strcmp(fn, "energy")) { out[0] = o->energy(&K, a, b); return 0; }
    if (!strcmp(fn, "outputs")) { o->outputs(&K, a, b, out); return 0; }
    if (!strcmp(fn, "rest_position")) { o->rest_position(&K, out); return 0; }
    if (!strcmp(fn, "mode_dofs")) {
        int idx[RK_MAX_DOF], k = o->mode_dofs(&K, mode, idx), i;
        for (i = 0; i < k; i++) out[i] = idx[i];
        return k;
    }
    if (!strcmp(fn, "embed")) { o->embed(&K, mode, a, b, out, out2); return 0; }
    if (!strcmp(fn, "mode_jacobian")) { o->mode_jacobian(&K, mode, a, b, out, out2); return 0; }
    if (!strcmp(fn, "mode_rhs")) { o->mode_rhs(&K, mode, a, ag, ag_v, out); return 0; }
    if (!strcmp(fn, "mode_monitors")) { o->mode_monitors(&K, mode, a, ag, ag_v, out, out2); return 0; }
    if (!strcmp(fn, "mode_outputs")) { o->mode_outputs(&K, mode, a, out); return 0; }
    if (!strcmp(fn, "contact_forces")) { o->contact_forces(&K, mode, a, b, ag, ag_v, out); return 0; }
    if (!strcmp(fn, "mode_monitor_one")) {
        int i = (int)ag;
        return o->mode_monitor_one == NULL ? 0 : o->mode_monitor_one(&K, mode, a, i, out);
    }
    if (!strcmp(fn, "classical_impact_velocity")) {
        if (o->classical_impact_velocity == NULL) return -2;
        return o->classical_impact_velocity(&K, a, b, mode, out);
    }
    if (!strcmp(fn, "derived")) {
        int i;
        for (i = 0; i < RK_MAX_DERIVED; i++) out[i] = K.d[i];
        out2[0] = K.length_scale; out2[1] = K.time_scale; out2[2] = K.force_scale; out2[3] = K.step_limit;
        return 0;
    }
    return -99;
}
"""

_CACHE: dict = {}


def kernels(tmp_root: Path):
    """(ffi, lib) of the kernel harness, built once per source state under ``tmp_root``."""
    try:
        import cffi
    except ImportError:
        pytest.skip("cffi is not installed (pip install cffi: the test extra has it)")
    from rocking_model.engine import gen_models

    gen_models.main()          # the generated kernels of the current declarations
    sources = sorted(SRC.glob("*.c"))
    digest = hashlib.sha256(SHIM.encode() + b"".join(p.read_bytes() for p in sorted(SRC.glob("*.[ch]"))))
    name = f"_rk_kernels_{digest.hexdigest()[:12]}"
    if name in _CACHE:
        return _CACHE[name]
    build = tmp_root / name
    build.mkdir(parents=True, exist_ok=True)
    ffi = cffi.FFI()
    ffi.cdef(CDEF)
    ffi.set_source(name, SHIM, sources=[str(p) for p in sources], include_dirs=[str(SRC)],
                   extra_compile_args=["-std=c99", "-O1", "-ffp-contract=off"], libraries=["m"])
    try:
        ffi.compile(tmpdir=str(build), verbose=False)
    except Exception as exc:              # no compiler, or no Python headers
        pytest.skip(f"the kernel harness does not compile here: {exc}")
    sys.path.insert(0, str(build))
    try:
        module = __import__(name)
    finally:
        sys.path.remove(str(build))
    _CACHE[name] = (module.ffi, module.lib)
    return _CACHE[name]


def cache_root(config) -> Path:
    """A folder that survives between tests of one run (pytest's cache dir, else a temporary one)."""
    root = Path(os.environ.get("RK_KERNEL_CACHE", "") or config.cache.mkdir("rk_kernels"))
    return root
