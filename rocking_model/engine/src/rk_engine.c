/* rk_engine.c -- the public API (part E). Skeleton by the architect: version, create (checks the options,
 * finds the kernel) and free. Everything else of rk_engine.h is part E's task list (DESIGN.md). */
#include "rk_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef RK_ENGINE_VERSION_STRING
#define RK_ENGINE_VERSION_STRING "unknown"
#endif

const char *rk_engine_version(void)
{
    return RK_ENGINE_VERSION_STRING;
}

int rk_engine_api_version(void)
{
    return RK_ENGINE_API_VERSION;
}

static rk_status check_options(const rk_options *o, rk_error *err)
{
    if (o->scheme != RK_SCHEME_MOREAU_JEAN && o->scheme != RK_SCHEME_EVENT_DRIVEN)
        return rk_fail(err, RK_ERR_VALUE, "scheme = %d is out of range; allowed values 0 (moreau_jean) or 1 "
                       "(event_driven)", (int)o->scheme);
    if (!isfinite(o->t0))
        return rk_fail(err, RK_ERR_VALUE, "t0 = %.17g is out of range; allowed range (-inf, inf)", o->t0);
    if (!(o->dt_max >= 0.0) || isnan(o->dt_max))
        return rk_fail(err, RK_ERR_VALUE, "dt_max = %.17g is out of range; allowed range [0, inf]", o->dt_max);
    if (o->method != RK_METHOD_DOP853 && o->method != RK_METHOD_DOPRI5)
        return rk_fail(err, RK_ERR_VALUE, "method = %d is out of range; allowed values 0 (DOP853) or 1 (DOPRI5)",
                       (int)o->method);
    if (o->impact_log_size < -1)
        return rk_fail(err, RK_ERR_VALUE, "impact_log_size = %lld is out of range; allowed range [0, inf) or -1 "
                       "(keep all)", o->impact_log_size);
    if (o->max_events < 1)
        return rk_fail(err, RK_ERR_VALUE, "max_events = %d is out of range; allowed range [1, inf)",
                       o->max_events);
    return rk_tolerances_check(&o->tolerances, err);
}

rk_engine *rk_engine_create(const char *kind, const double *params, int n_params, const double *initial,
                            int n_initial, const rk_options *options, rk_error *err)
{
    rk_options opt;
    const rk_model_ops *ops;
    rk_engine *e;
    (void)initial;
    rk_error_clear(err);
    if (options == NULL)
        rk_options_default(&opt);
    else
        opt = *options;
    if (check_options(&opt, err) != RK_OK)
        return NULL;
    if (kind == NULL) {
        rk_fail(err, RK_ERR_VALUE, "model kind is missing; allowed values 'rigid', 'flexible'");
        return NULL;
    }
    ops = rk_model_find(kind);
    if (ops == NULL) {
        if (strcmp(kind, "rigid") == 0 || strcmp(kind, "flexible") == 0 || strcmp(kind, "RigidBlock") == 0
            || strcmp(kind, "FlexibleOscillator") == 0)
            rk_fail(err, RK_ERR_NOT_IMPLEMENTED, "the C kernel of model '%s' is not implemented yet (issue 21, "
                    "part A); use engine=\"python\"", kind);
        else
            rk_fail(err, RK_ERR_VALUE, "model kind '%s' is unknown; allowed values 'rigid', 'flexible'", kind);
        return NULL;
    }
    if (n_params != ops->n_params) {
        rk_fail(err, RK_ERR_VALUE, "model '%s' takes %d parameters, got %d", ops->kind, ops->n_params, n_params);
        return NULL;
    }
    if (n_initial < 0 || n_initial > ops->n_initial) {
        rk_fail(err, RK_ERR_VALUE, "model '%s' takes at most %d initial values, got %d", ops->kind,
                ops->n_initial, n_initial);
        return NULL;
    }
    e = (rk_engine *)calloc(1, sizeof(rk_engine));
    if (e == NULL) {
        rk_fail(err, RK_ERR_MEMORY, "out of memory creating an engine (%lu bytes)", (unsigned long)sizeof(rk_engine));
        return NULL;
    }
    e->options = opt;
    if (rk_model_init(&e->model, ops, params, n_params, err) != RK_OK) {
        rk_engine_free(e);
        return NULL;
    }
    /* part E: initial state (ops->initial_state), logs (rk_log storage), scheme init (rk_ed_init / rk_mj_init) */
    rk_fail(err, RK_ERR_NOT_IMPLEMENTED, "the C engine's schemes are not implemented yet (issue 21, parts D and "
            "E); use engine=\"python\"");
    rk_engine_free(e);
    return NULL;
}

void rk_engine_free(rk_engine *e)
{
    if (e == NULL)
        return;
    free(e->impact_times.data);
    free(e->impact_log.data);
    free(e);
}

const char *rk_engine_message(const rk_engine *e)
{
    return e->error.message;
}

rk_status rk_engine_status(const rk_engine *e)
{
    return e->error.status;
}
