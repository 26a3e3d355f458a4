/* rk_model.c -- the model registry and the generic functions of rk_model.h (part A).
 *
 * Skeleton by the architect: the registry lists the kernels that exist. Part A adds &RK_RIGID_BLOCK and
 * &RK_FLEXIBLE_OSCILLATOR to KINDS when rk_rigid.c / rk_flexible.c are written, and implements the rest of
 * rk_model.h here and in rk_sliding.c. */
#include "rk_model.h"

#include <string.h>

static const rk_model_ops *const KINDS[] = {
    NULL     /* part A: &RK_RIGID_BLOCK, &RK_FLEXIBLE_OSCILLATOR, then NULL */
};

const rk_model_ops *const *rk_model_kinds(void)
{
    return KINDS;
}

const rk_model_ops *rk_model_find(const char *kind)
{
    const rk_model_ops *const *k;
    if (kind == NULL)
        return NULL;
    for (k = KINDS; *k != NULL; k++) {
        if (strcmp((*k)->kind, kind) == 0 || strcmp((*k)->class_name, kind) == 0)
            return *k;
    }
    return NULL;
}

rk_status rk_model_init(rk_model *m, const rk_model_ops *ops, const double *params, int n_params,
                        rk_error *err)
{
    if (ops == NULL || n_params != ops->n_params)
        return rk_fail(err, RK_ERR_VALUE, "model parameters: expected %d values, got %d",
                       ops == NULL ? 0 : ops->n_params, n_params);
    memset(m, 0, sizeof(*m));
    m->ops = ops;
    /* part A: ops->init(m, params, err), then rest_abscissae from rest_position and contact_abscissae */
    (void)params;
    return rk_fail(err, RK_ERR_NOT_IMPLEMENTED, "rk_model_init: the model kernels are not implemented yet "
                   "(issue 21, part A)");
}
