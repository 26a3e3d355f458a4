/* rk_py_api.h -- the engine functions the cffi binding rocking_model._rk calls, as a table of pointers that the
 * extension rocking_model._engine hands it at import: one copy of the engine library (in _engine, with the
 * hand-written hot calls), whose registry of added models and whose code both bindings share. */
#ifndef RK_PY_API_H
#define RK_PY_API_H

#include "src/rk_engine.h"
#include "src/rk_model.h"

typedef struct rk_py_api {
    size_t size;    /* sizeof(rk_py_api) of the extension: checked by the binding (both built from this header) */
    const char *(*version)(void);
    int (*api_version)(void);
    const char *(*message)(const rk_engine *e);
    rk_status (*status)(const rk_engine *e);
    int (*n_dof)(const rk_engine *e);
    int (*n_contacts)(const rk_engine *e);
    int (*n_modes)(const rk_engine *e);
    rk_scheme (*scheme)(const rk_engine *e);
    void (*get_state)(const rk_engine *e, rk_plain_state *s);
    long long (*impact_times)(const rk_engine *e, double *buf, long long cap);
    long long (*impact_log)(const rk_engine *e, double *buf, long long cap_rows);
    rk_status (*set_state)(rk_engine *e, const rk_plain_state *s, const double *impact_times, long long n_times,
                           const double *impact_log, long long n_log_rows);
    size_t (*snapshot_size)(const rk_engine *e);
    rk_status (*snapshot)(const rk_engine *e, void *buf, size_t size);
    rk_status (*restore)(rk_engine *e, const void *buf, size_t size);
    const rk_reports *(*reports)(const rk_engine *e);
    int (*contacts)(const rk_engine *e, int *states);
    int (*full_state)(rk_engine *e, double *q, double *v);
    const rk_model_ops *const *(*model_kinds)(void);
    rk_status (*model_add)(const rk_model_ops *ops, rk_error *err);
    void (*kind_names)(char *buf, size_t n);
    const rk_model_ops *(*model_find)(const char *kind);
    rk_status (*model_init)(rk_model *m, const rk_model_ops *ops, const double *params, int n_params, rk_error *err);
    void (*model_inverse_mass)(const rk_model *m, const double *q, double *Minv);
    double (*model_slip)(const rk_model *m, const double *q);
} rk_py_api;

#endif /* RK_PY_API_H */
