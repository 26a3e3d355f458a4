"""The C engine bound with cffi (API mode, out of line) for the binding A/B (`compiled_bench.binding_ab`): the
extension module ``_rk_ab`` (``ffi`` and ``lib``) compiled from the engine's sources with setup.py's flags, wrapped by
`benchmarks.ffi_engine` (the `Engine` API of rocking_model._engine). Not part of the package.

The declarations below are the public C API (src/rk_engine.h, rk_motion.h, rk_common.h) as the package calls it;
API mode checks them against the headers at compile time (``...`` leaves a struct's layout to the compiler).
The few C helpers of the preamble fold what would otherwise be several calls and Python statements per engine
creation or sample into one call (each costs about 0.1 us from Python)."""
import glob
import hashlib
import importlib
import os
import re
import sys

import cffi

from rocking_model.engine import cdefs

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SRC = os.path.join(ROOT, "rocking_model", "engine", "src")
MODULE = "_rk_ab"

CDEF = r"""
#define RK_MAX_DOF 8
#define RK_MAX_CONTACTS 4
#define RK_MAX_Y 16
#define RK_MAX_PARAMS 24
#define RK_MAX_INITIAL 8
#define RK_MAX_OUTPUTS 16
#define RK_MAX_REPORTS 16
#define RK_MSG_LEN 512
#define RK_ADVANCE_CONTINUOUS 1
#define RK_ADVANCE_LINEAR 2
#define RK_ADVANCE_LINEAR_V 4

""" + cdefs.STATUS + cdefs.COMMON + r"""
typedef enum rk_method { RK_METHOD_DOP853 = 0, RK_METHOD_DOPRI5 = 1 } rk_method;
typedef struct rk_tolerances {
    double gap, step_gap, grazing, rest_velocity, step_rest_velocity, event, rise, clearly_open, stateless_step;
    int sub_samples;
    double lcp_exact, lcp_hint, demand_floor;
} rk_tolerances;
typedef struct rk_options {
    rk_scheme scheme; double t0, dt_max, tolerance, theta, zeno_tol; rk_method method;
    long long impact_log_size; int max_events; rk_tolerances tolerances;
} rk_options;
void rk_options_default(rk_options *opt);
""" + cdefs.MOTION + r"""
extern "Python" double rk_py_eval(void *ctx, double t, int *failed, char *msg);
extern "Python" double rk_py_breakpoint(void *ctx, double t, int *failed, char *msg);
extern "Python" int rk_py_continuous(void *ctx, double tb);

typedef struct rk_engine rk_engine;
rk_engine *rk_engine_create(const char *kind, const double *params, int n_params, const double *initial,
                            int n_initial, const rk_options *options, rk_error *err);
rk_engine *rk_engine_create_state(const char *kind, const double *params, int n_params, int mode,
                                  const double *q, const double *v, int n_dof, const rk_options *options,
                                  rk_error *err);
double rk_engine_fail_time(const rk_engine *e);
int rk_engine_contact_code(const rk_engine *e);
void rk_engine_free(rk_engine *e);
const char *rk_engine_message(const rk_engine *e);
rk_status rk_engine_status(const rk_engine *e);
rk_status rk_engine_advance(rk_engine *e, double t_end, double ag0, double slope, double ag_v0, double ag_v_slope,
                            long long max_steps, unsigned flags);
rk_status rk_engine_advance_motion(rk_engine *e, double t_end, rk_motion *ag, rk_motion *ag_v,
                                   long long max_steps);
rk_status rk_engine_sample(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n_times,
                           long long max_steps, int *modes, double *values, long long *impacts, int *overturned);
rk_status rk_engine_sample_columns(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times,
                                   long long n_times, long long max_steps, int *modes, double *values,
                                   long long *impacts, int *overturned);
rk_status rk_engine_sample_held(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n_times,
                                long long max_steps, int columns, int *modes, double *values, long long *impacts,
                                int *overturned);
int rk_engine_n_outputs(const rk_engine *e);
const char *rk_engine_output_name(const rk_engine *e, int i);
void rk_engine_outputs(rk_engine *e, double *out);
double rk_engine_time(const rk_engine *e);
int rk_engine_mode(const rk_engine *e);
long long rk_engine_impacts(const rk_engine *e);
int rk_engine_overturned(const rk_engine *e);
long long rk_engine_n_steps(const rk_engine *e);
double rk_engine_friction_demand(const rk_engine *e);
long long rk_engine_painleve(const rk_engine *e);
const char *rk_engine_model_class(const rk_engine *e);
int rk_engine_n_dof(const rk_engine *e);
int rk_engine_n_contacts(const rk_engine *e);
int rk_engine_n_modes(const rk_engine *e);
rk_scheme rk_engine_scheme(const rk_engine *e);
const rk_reports *rk_engine_reports(const rk_engine *e);

long long rk_engine_impact_times(const rk_engine *e, double *buf, long long cap);
void rk_engine_checkpoint(rk_engine *e);
rk_status rk_engine_rollback(rk_engine *e);
void rk_engine_commit(rk_engine *e);

int rk_py_row(rk_engine *e, double *out);
rk_status rk_py_motion(rk_motion *m, int kind, double a, double b, double c, rk_error *err);
rk_engine *rk_py_create(const char *kind, const double *params, int n_params, const double *initial, int n_initial,
                        int mode, const double *q, const double *v, int n_dof, int scheme, double t0, double dt_max,
                        double tolerance, double theta, double zeno_tol, int method, long long impact_log_size,
                        int max_events, const rk_tolerances *tol, rk_error *err);
rk_status rk_py_sample(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n,
                       long long max_steps, int columns, int hold, void *modes, int modes_wide, void *values,
                       void *impacts, void *overturned, int overturned_bool);
"""

#: C helpers of the binding: loops over rows and a row of scalars that would cost more in Python than a short run
PREAMBLE = r"""
#include "rk_engine.h"
#include "rk_model.h"

#include <stdlib.h>

/* output_row(): the outputs, then contact, impacts, overturned, friction_demand, painleve as doubles (exact);
 * returns the number of outputs */
static int rk_py_row(rk_engine *e, double *out)
{
    int n = rk_engine_n_outputs(e);
    rk_engine_outputs(e, out);
    out[n] = (double)rk_engine_contact_code(e);
    out[n + 1] = (double)rk_engine_impacts(e);
    out[n + 2] = (double)rk_engine_overturned(e);
    out[n + 3] = rk_engine_friction_demand(e);
    out[n + 4] = (double)rk_engine_painleve(e);
    return n;
}

/* a motion of three numbers at most by its kind (rk_motion_kind): one call from Python */
static rk_status rk_py_motion(rk_motion *m, int kind, double a, double b, double c, rk_error *err)
{
    switch (kind) {
    case RK_MOTION_CONSTANT: rk_motion_constant(m, a); return RK_OK;
    case RK_MOTION_LINEAR: rk_motion_linear(m, a, b, c); return RK_OK;
    case RK_MOTION_SINE: return rk_motion_sine(m, a, b, c, err);
    case RK_MOTION_COSINE: return rk_motion_cosine(m, a, b, c, err);
    case RK_MOTION_RICKER: return rk_motion_ricker(m, a, b, c, err);
    case RK_MOTION_RECT: return rk_motion_rect(m, a, b, c, err);
    default: return rk_fail(err, RK_ERR_VALUE, "motion kind %d has no parameters of its own", kind);
    }
}

/* Engine(...): the options as arguments (one call: no options struct to fill from Python field by field);
 * n_dof < 0: at the initial values, else at the state (mode, q, v); tol NULL: the defaults */
static rk_engine *rk_py_create(const char *kind, const double *params, int n_params, const double *initial,
                               int n_initial, int mode, const double *q, const double *v, int n_dof, int scheme,
                               double t0, double dt_max, double tolerance, double theta, double zeno_tol, int method,
                               long long impact_log_size, int max_events, const rk_tolerances *tol, rk_error *err)
{
    rk_options o;
    rk_options_default(&o);
    o.scheme = (rk_scheme)scheme;
    o.t0 = t0;
    o.dt_max = dt_max;
    o.tolerance = tolerance;
    o.theta = theta;
    o.zeno_tol = zeno_tol;
    o.method = (rk_method)method;
    o.impact_log_size = impact_log_size;
    o.max_events = max_events;
    if (tol != NULL)
        o.tolerances = *tol;
    if (n_dof >= 0)
        return rk_engine_create_state(kind, params, n_params, mode, q, v, n_dof, &o, err);
    return rk_engine_create(kind, params, n_params, initial, n_initial, &o, err);
}

/* Engine.sample: rk_engine_sample (rows or columns) or, hold, rk_engine_sample_held; int64 modes (modes_wide) and
 * bool overturned (overturned_bool), the arrays Integrator.sample returns, written through int rows */
static rk_status rk_py_sample(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n,
                              long long max_steps, int columns, int hold, void *modes, int modes_wide, void *values,
                              void *impacts, void *overturned, int overturned_bool)
{
    int *m = (int *)modes, *o = (int *)overturned, *scratch = NULL;
    long long i, rows = n + 1;
    rk_status st;
    if (modes_wide || overturned_bool) {
        scratch = (int *)malloc(2 * (size_t)rows * sizeof(int));
        if (scratch == NULL)
            return RK_ERR_MEMORY;
        if (modes_wide)
            m = scratch;
        if (overturned_bool)
            o = scratch + rows;
    }
    if (hold)
        st = rk_engine_sample_held(e, ag, ag_v, times, n, max_steps, columns, m, (double *)values,
                                   (long long *)impacts, o);
    else
        st = (columns ? rk_engine_sample_columns : rk_engine_sample)(e, ag, ag_v, times, n, max_steps, m,
                                                                     (double *)values, (long long *)impacts, o);
    if (modes_wide)
        for (i = 0; i < rows; i++)
            ((long long *)modes)[i] = m[i];
    if (overturned_bool)
        for (i = 0; i < rows; i++)
            ((unsigned char *)overturned)[i] = o[i] != 0;
    free(scratch);
    return st;
}
"""


def setup_flags() -> list:
    """setup.py's compiler flags (the non-Windows list), read from its text: the same flags as the extension."""
    with open(os.path.join(ROOT, "setup.py"), encoding="utf-8") as fh:
        text = fh.read()
    return re.findall(r'"([^"]+)"', re.search(r'CFLAGS = (\[[^\]]*"-std=c99"[^\]]*\])', text).group(1))


def load(build_dir: str | None = None):
    """(ffi, lib) of the module ``_rk_ab``, compiled on first use into ``build_dir`` (default
    benchmarks/results/ffi_build), rebuilt when a source, the flags or this file change."""
    import rocking_model

    sources = sorted(glob.glob(os.path.join(SRC, "*.c")))
    flags = setup_flags()
    h = hashlib.sha256(CDEF.encode() + PREAMBLE.encode() + " ".join(flags).encode() + rocking_model.__version__.encode())
    for path in sources + sorted(glob.glob(os.path.join(SRC, "*.h"))):
        with open(path, "rb") as fh:
            h.update(fh.read())
    folder = os.path.join(build_dir or os.path.join(ROOT, "benchmarks", "results", "ffi_build"), h.hexdigest()[:16])
    if folder not in sys.path:
        sys.path.insert(0, folder)
    try:
        mod = importlib.import_module(MODULE)
        return mod.ffi, mod.lib
    except ImportError:
        pass
    os.makedirs(folder, exist_ok=True)
    ffi = cffi.FFI()
    ffi.cdef(CDEF)
    ffi.set_source(MODULE, PREAMBLE, sources=sources, include_dirs=[SRC],
                   define_macros=[("RK_ENGINE_VERSION_STRING", '"%s"' % rocking_model.__version__)],
                   extra_compile_args=flags, libraries=["m"])
    ffi.compile(tmpdir=folder, verbose=False)
    importlib.invalidate_caches()
    mod = importlib.import_module(MODULE)
    return mod.ffi, mod.lib
