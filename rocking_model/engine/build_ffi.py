"""The cffi binding (API mode, out of line) of the engine's cold calls: setup.py compiles it into the extension module
``rocking_model._rk``, which `rocking_model._engine_cold` wraps. It holds no engine code: its functions call the
engine inside rocking_model._engine through the table of rk_py_api.h, which that module hands over at import
(`rk_py_bind`), so that both bindings share one engine (its registry of added models included).

The hot calls (engine creation, advance, sample, outputs) stay hand-written in _engine.c: see the comment there."""
import cffi

try:
    from . import cdefs
except ImportError:           # setup.py loads this file as a top-level module (nothing installed yet)
    import cdefs

CDEF = r"""
#define RK_MAX_DOF 8
#define RK_MAX_CONTACTS 4
#define RK_MAX_Y 16
#define RK_MAX_REPORTS 16
""" + cdefs.STATUS + cdefs.COMMON + r"""
typedef struct rk_param_decl {
    const char *name; const char *unit; double default_value; double lo, hi; int lo_open, hi_open; int inf_ok;
    int integer; int n_items; ...;
} rk_param_decl;
typedef struct rk_model_ops {
    const char *kind; const char *class_name; int n_dof, n_contacts, n_modes, phi_index, slide_index, lift_index;
    int n_params; const rk_param_decl *param_decls; int n_initial; const rk_param_decl *initial_decls;
    int n_outputs; const rk_param_decl *output_decls; int n_shifted; const int *shifted; ...;
} rk_model_ops;
typedef struct rk_plain_state {
    double t; int mode; int n_y; double y[16]; double q[8], v[8]; rk_set closed; long long impacts;
    int overturned; long long n_steps; double h; double shift; double friction_demand; long long painleve; ...;
} rk_plain_state;
typedef struct rk_engine rk_engine;

int rk_py_bind(const void *api);
const char *c_version(void);
int c_api_version(void);
const char *c_message(const rk_engine *e);
rk_status c_status(const rk_engine *e);
int c_n_dof(const rk_engine *e);
int c_n_contacts(const rk_engine *e);
int c_n_modes(const rk_engine *e);
rk_scheme c_scheme(const rk_engine *e);
void c_get_state(const rk_engine *e, rk_plain_state *s);
long long c_impact_times(const rk_engine *e, double *buf, long long cap);
long long c_impact_log(const rk_engine *e, double *buf, long long cap_rows);
rk_status c_set_state(rk_engine *e, const rk_plain_state *s, const double *impact_times, long long n_times,
                      const double *impact_log, long long n_log_rows);
size_t c_snapshot_size(const rk_engine *e);
rk_status c_snapshot(const rk_engine *e, void *buf, size_t size);
rk_status c_restore(rk_engine *e, const void *buf, size_t size);
const rk_reports *c_reports(const rk_engine *e);
int c_contacts(const rk_engine *e, int *states);
int c_full_state(rk_engine *e, double *q, double *v);
const rk_model_ops *const *c_model_kinds(void);
rk_status c_model_add(const rk_model_ops *ops, rk_error *err);
void c_kind_names(char *buf, size_t n);
int c_model(const char *kind, const double *params, int n_params, const char *fn, int mode, const double *a,
            const double *b, double ag, double ag_v, double *o1, double *o2, int *n2, int *ival, char *msg,
            char *names, int names_len);
"""

PREAMBLE = r"""
#include "rk_py_api.h"

#include <stdio.h>
#include <string.h>

/* the extension's table, set once at import (rk_py_bind; the same table every time) */
static const rk_py_api *API = NULL;

static int rk_py_bind(const void *api)
{
    if (api == NULL || ((const rk_py_api *)api)->size != sizeof(rk_py_api))
        return -1;
    API = (const rk_py_api *)api;
    return 0;
}

static const char *c_version(void) { return API->version(); }
static int c_api_version(void) { return API->api_version(); }
static const char *c_message(const rk_engine *e) { return API->message(e); }
static rk_status c_status(const rk_engine *e) { return API->status(e); }
static int c_n_dof(const rk_engine *e) { return API->n_dof(e); }
static int c_n_contacts(const rk_engine *e) { return API->n_contacts(e); }
static int c_n_modes(const rk_engine *e) { return API->n_modes(e); }
static rk_scheme c_scheme(const rk_engine *e) { return API->scheme(e); }
static void c_get_state(const rk_engine *e, rk_plain_state *s) { API->get_state(e, s); }
static long long c_impact_times(const rk_engine *e, double *buf, long long cap)
{
    return API->impact_times(e, buf, cap);
}
static long long c_impact_log(const rk_engine *e, double *buf, long long cap_rows)
{
    return API->impact_log(e, buf, cap_rows);
}
static rk_status c_set_state(rk_engine *e, const rk_plain_state *s, const double *impact_times, long long n_times,
                             const double *impact_log, long long n_log_rows)
{
    return API->set_state(e, s, impact_times, n_times, impact_log, n_log_rows);
}
static size_t c_snapshot_size(const rk_engine *e) { return API->snapshot_size(e); }
static rk_status c_snapshot(const rk_engine *e, void *buf, size_t size) { return API->snapshot(e, buf, size); }
static rk_status c_restore(rk_engine *e, const void *buf, size_t size) { return API->restore(e, buf, size); }
static const rk_reports *c_reports(const rk_engine *e) { return API->reports(e); }
static int c_contacts(const rk_engine *e, int *states) { return API->contacts(e, states); }
static int c_full_state(rk_engine *e, double *q, double *v) { return API->full_state(e, q, v); }
static const rk_model_ops *const *c_model_kinds(void) { return API->model_kinds(); }
static rk_status c_model_add(const rk_model_ops *ops, rk_error *err) { return API->model_add(ops, err); }
static void c_kind_names(char *buf, size_t n) { API->kind_names(buf, n); }

/* one function of a model's generated kernel on an instance built from params (rocking_model.models.base's
 * analysis methods): the values in o1 (and o2, *n2 of them), an integer result in *ival; returns the count in
 * o1, -2 for "none" (no stiff part, no impact rule of the model's own), -1 with msg on an error. */
static int c_model(const char *kind, const double *params, int n_params, const char *fn, int mode, const double *a,
                   const double *b, double ag, double ag_v, double *o1, double *o2, int *n2, int *ival, char *msg,
                   char *names, int names_len)
{
    rk_model m;
    rk_error err;
    const rk_model_ops *ops = API->model_find(kind);
    int n, nc, k = 0, idx[RK_MAX_DOF], i;
    *n2 = 0;
    *ival = 0;
    memset(&err, 0, sizeof err);
    if (ops == NULL) {
        char kinds[256];
        API->kind_names(kinds, sizeof kinds);
        snprintf(msg, 512, "model kind '%s' is unknown; allowed values %s", kind, kinds);
        return -1;
    }
    if (API->model_init(&m, ops, params, n_params, &err) != RK_OK) {
        snprintf(msg, 512, "%s", err.message);
        return -1;
    }
    n = ops->n_dof;
    nc = ops->n_contacts;
    if (mode < 0 || mode >= ops->n_modes) {
        snprintf(msg, 512, "mode = %d is out of range; allowed range [0, %d]", mode, ops->n_modes - 1);
        return -1;
    }
    if (!strcmp(fn, "info")) {
        size_t pos = 0;
        o1[0] = m.length_scale; o1[1] = m.time_scale; o1[2] = m.force_scale; o1[3] = m.step_limit;
        for (i = 0; i < n; i++)
            o1[4 + i] = m.dof_scales[i];
        names[0] = '\0';
        for (i = 0; i < ops->n_named; i++) {
            int j = ops->named_index[i];
            o2[i] = j >= 0 ? m.d[j] : m.p[-1 - j];
            pos += (size_t)snprintf(names + pos, pos < (size_t)names_len ? (size_t)names_len - pos : 0, "%s%s",
                                    i ? "\n" : "", ops->named[i]);
        }
        *n2 = ops->n_named;
        return 4 + n;
    }
    if (!strcmp(fn, "mass_matrix")) { ops->mass_matrix(&m, a, o1); return n * n; }
    if (!strcmp(fn, "inverse_mass_matrix")) { API->model_inverse_mass(&m, a, o1); return n * n; }
    if (!strcmp(fn, "forces")) { ops->forces(&m, a, b, ag, ag_v, o1); return n; }
    if (!strcmp(fn, "stiff_jacobians")) {
        if (ops->stiff_jacobians == NULL || !ops->stiff_jacobians(&m, a, b, o1, o2))
            return -2;
        *n2 = n * n;
        return n * n;
    }
    if (!strcmp(fn, "gaps")) { ops->gaps(&m, a, o1); return nc; }
    if (!strcmp(fn, "contact_abscissae")) { ops->contact_abscissae(&m, a, o1); return nc; }
    if (!strcmp(fn, "contact_jacobians")) { ops->contact_jacobians(&m, a, o1, o2); *n2 = n * nc; return n * nc; }
    if (!strcmp(fn, "contact_drift")) { ops->contact_drift(&m, a, b, o1, o2); *n2 = nc; return nc; }
    if (!strcmp(fn, "rest_position")) { ops->rest_position(&m, o1); return n; }
    if (!strcmp(fn, "energy")) { o1[0] = ops->energy(&m, a, b); return 1; }
    if (!strcmp(fn, "outputs")) { ops->outputs(&m, a, b, o1); return ops->n_outputs; }
    if (!strcmp(fn, "slip")) { o1[0] = API->model_slip(&m, a); return 1; }
    if (!strcmp(fn, "initial_state")) {
        if (ops->initial_state(&m, a, ival, o1, o2, &err) != RK_OK) {
            snprintf(msg, 512, "%s", err.message);
            return -1;
        }
        *n2 = n;
        return n;
    }
    /* the functions of a sticking mode */
    if (rk_stick_of(&m, mode, NULL) != mode) {
        snprintf(msg, 512, "model(..., %s): mode %d is not a sticking mode", fn, mode);
        return -1;
    }
    k = ops->mode_dofs(&m, mode, idx);
    if (!strcmp(fn, "mode_dofs")) {
        for (i = 0; i < k; i++)
            o1[i] = idx[i];
        return k;
    }
    if (!strcmp(fn, "embed")) { ops->embed(&m, mode, a, b, o1, o2); *n2 = n; return n; }
    if (!strcmp(fn, "mode_jacobian")) { ops->mode_jacobian(&m, mode, a, b, o1, o2); *n2 = n; return n * k; }
    if (!strcmp(fn, "mode_rhs")) { ops->mode_rhs(&m, mode, a, ag, ag_v, o1); return 2 * k; }
    if (!strcmp(fn, "mode_outputs")) { ops->mode_outputs(&m, mode, a, o1); return ops->n_outputs; }
    if (!strcmp(fn, "contact_forces")) { ops->contact_forces(&m, mode, a, b, ag, ag_v, o1); return nc; }
    if (!strcmp(fn, "classical_impact_velocity")) {
        int rule = ops->classical_impact_velocity == NULL ? 0 : ops->classical_impact_velocity(&m, a, b, mode, o1);
        return rule == 0 ? -2 : n;
    }
    snprintf(msg, 512, "model(): unknown function '%s'", fn);
    return -1;
}
"""


def builder(include_dirs=(), extra_compile_args=()):
    """The FFI builder of ``rocking_model._rk`` (include_dirs: the folder of rk_py_api.h and the one of src/)."""
    ffi = cffi.FFI()
    ffi.cdef(CDEF)
    ffi.set_source("rocking_model._rk", PREAMBLE, include_dirs=list(include_dirs),
                   extra_compile_args=list(extra_compile_args))
    return ffi
