/* rk_model.c -- the model registry and the generic functions of rk_model.h (part A).
 *
 * The registry lists the kernels generated from the models' declarations (gen_models.py: a model is one
 * Python declaration, no C of its own). The any-mode
 * functions dispatch to the kernel for the sticking modes and to rk_sliding.c for the sliding ones, as
 * RockingModel.dofs_of / embed_any / reduce_any / functions_of / outputs_of do. The generic fallbacks are the
 * ports of RockingModel's numpy defaults (reduced_acceleration, mode_functions, sliding.force_totals): a
 * kernel that leaves an optional pointer NULL gets them. Helpers shared by the kernels: the Python's parameter
 * checks and messages (Param.check / check_real / check_choice), repr() of a float, math.hypot, the modes of
 * the two-corner models. */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_model.h"
#include "rk_contact.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the kernels generated from the model declarations (rk_models_gen.c, written at build time by gen_models.py),
 * and those of models declared after the build, added at run time (rk_model_add: a kernel generated from a
 * declaration and compiled into a library of its own). The added table is the one mutable static of the
 * engine: it is written only by rk_model_add, which the binding calls with the interpreter's lock held and
 * before any engine of that kind exists; engines keep their ops pointer, so an entry is never removed. */
static const rk_model_ops *ADDED[RK_MAX_ADDED_KINDS + 1];

const rk_model_ops *const *rk_model_kinds(void)
{
    return rk_generated_models;
}

const rk_model_ops *rk_model_find(const char *kind)
{
    const rk_model_ops *const *k;
    int i;
    if (kind == NULL)
        return NULL;
    for (k = rk_generated_models; *k != NULL; k++) {
        if (strcmp((*k)->kind, kind) == 0 || strcmp((*k)->class_name, kind) == 0)
            return *k;
    }
    for (i = RK_MAX_ADDED_KINDS - 1; i >= 0; i--) {        /* the latest declaration of a kind first */
        if (ADDED[i] != NULL && (strcmp(ADDED[i]->kind, kind) == 0 || strcmp(ADDED[i]->class_name, kind) == 0))
            return ADDED[i];
    }
    return NULL;
}

rk_status rk_model_add(const rk_model_ops *ops, rk_error *err)
{
    const rk_model_ops *const *k;
    int i;
    if (ops == NULL || ops->kind == NULL || ops->class_name == NULL)
        return rk_fail(err, RK_ERR_VALUE, "model kernel is missing its kind");
    if (ops->n_dof < 1 || ops->n_dof > RK_MAX_DOF || ops->n_contacts < 1 || ops->n_contacts > RK_MAX_CONTACTS
        || ops->n_params > RK_MAX_PARAMS || ops->n_initial > RK_MAX_INITIAL || ops->n_outputs > RK_MAX_OUTPUTS
        || ops->n_switches < 0 || ops->n_switches > RK_MAX_SWITCHES || (ops->n_switches > 0 && ops->switches == NULL))
        return rk_fail(err, RK_ERR_VALUE, "model '%s' exceeds the engine's limits (at most %d coordinates, %d "
                       "contacts, %d parameters, %d initial values, %d outputs, %d switches)", ops->kind, RK_MAX_DOF,
                       RK_MAX_CONTACTS, RK_MAX_PARAMS, RK_MAX_INITIAL, RK_MAX_OUTPUTS, RK_MAX_SWITCHES);
    for (k = rk_generated_models; *k != NULL; k++) {
        if (strcmp((*k)->kind, ops->kind) == 0)
            return rk_fail(err, RK_ERR_VALUE, "model kind '%s' is built into the engine; declare a new kind",
                           ops->kind);
    }
    for (i = 0; i < RK_MAX_ADDED_KINDS; i++) {
        if (ADDED[i] == ops)
            return RK_OK;
        if (ADDED[i] == NULL) {
            ADDED[i] = ops;
            return RK_OK;
        }
    }
    return rk_fail(err, RK_ERR_VALUE, "too many models added at run time (at most %d)", RK_MAX_ADDED_KINDS);
}

void rk_model_kind_names(char *buf, size_t n)
{
    const rk_model_ops *const *k;
    size_t pos = 0;
    int i;
    if (n == 0)
        return;
    buf[0] = '\0';
    for (k = rk_generated_models; *k != NULL && pos < n; k++)
        pos += (size_t)snprintf(buf + pos, n - pos, "%s'%s'", pos ? ", " : "", (*k)->kind);
    for (i = 0; i < RK_MAX_ADDED_KINDS && ADDED[i] != NULL && pos < n; i++)
        pos += (size_t)snprintf(buf + pos, n - pos, "%s'%s'", pos ? ", " : "", ADDED[i]->kind);
}

rk_status rk_model_init(rk_model *m, const rk_model_ops *ops, const double *params, int n_params,
                        rk_error *err)
{
    double q[RK_MAX_DOF];
    rk_status st;
    if (ops == NULL || n_params != ops->n_params)
        return rk_fail(err, RK_ERR_VALUE, "model parameters: expected %d values, got %d",
                       ops == NULL ? 0 : ops->n_params, n_params);
    memset(m, 0, sizeof(*m));
    m->ops = ops;
    st = ops->init(m, params, err);
    if (st != RK_OK)
        return st;
    /* RockingModel._rest_abscissae: the contacts' abscissae at rest (slip) */
    ops->rest_position(m, q);
    ops->contact_abscissae(m, q, m->rest_abscissae);
    rk_model_tabulate_modes(m);
    return RK_OK;
}

void rk_model_tabulate_modes(rk_model *m)
{
    const rk_model_ops *ops = m->ops;
    int mode;
    for (mode = 0; mode < RK_MAX_MODES; mode++) {
        int sigma = 0, stick = ops->stick_of != NULL ? ops->stick_of(m, mode, &sigma) : mode;
        m->mode_closed[mode] = ops->closed_of != NULL ? ops->closed_of(m, mode) : 0u;
        m->mode_stick[mode] = (signed char)stick;
        m->mode_sigma[mode] = (signed char)sigma;
    }
}

void rk_model_scale_tolerances(const rk_model *m, const rk_tolerances *tol, rk_model_tolerances *out)
{
    double L = m->length_scale;
    double V = sqrt(m->g * L);
    out->gap = tol->gap * L;
    out->step_gap = tol->step_gap * L;
    out->rest_velocity = tol->rest_velocity * V;
    out->step_rest_velocity = tol->step_rest_velocity * V;
    out->stateless_step = tol->stateless_step * m->time_scale;
    out->velocity_scale = V;
    out->force_floor = tol->demand_floor * m->force_scale;
}

/* ------------------------------------------------------------------------------------------ helpers */
void rk_float_repr(double x, char *buf, size_t n)
{
    char tmp[40], digits[24];
    int prec, e, nd, decpt, i;
    size_t pos = 0;
    char out[64];
    if (isnan(x)) {
        snprintf(buf, n, "nan");
        return;
    }
    if (isinf(x)) {
        snprintf(buf, n, x > 0 ? "inf" : "-inf");
        return;
    }
    if (x == 0.0) {
        snprintf(buf, n, signbit(x) ? "-0.0" : "0.0");
        return;
    }
    /* the shortest correctly rounded digits that read back as x (repr's 'r' mode) */
    for (prec = 1; prec <= 17; prec++) {
        snprintf(tmp, sizeof tmp, "%.*e", prec - 1, x);
        if (strtod(tmp, NULL) == x)
            break;
    }
    {
        const char *p = tmp;
        char *ep;
        nd = 0;
        if (*p == '-')
            p++;
        for (; *p != 'e'; p++)
            if (*p >= '0' && *p <= '9')
                digits[nd++] = *p;
        e = (int)strtol(p + 1, &ep, 10);
        while (nd > 1 && digits[nd - 1] == '0')
            nd--;
        digits[nd] = '\0';
    }
    decpt = e + 1;
    if (x < 0)
        out[pos++] = '-';
    if (decpt <= -4 || decpt > 16) {
        out[pos++] = digits[0];
        if (nd > 1) {
            out[pos++] = '.';
            for (i = 1; i < nd; i++)
                out[pos++] = digits[i];
        }
        pos += (size_t)snprintf(out + pos, sizeof out - pos, "e%c%02d", e < 0 ? '-' : '+', e < 0 ? -e : e);
    } else if (decpt <= 0) {
        out[pos++] = '0';
        out[pos++] = '.';
        for (i = 0; i < -decpt; i++)
            out[pos++] = '0';
        for (i = 0; i < nd; i++)
            out[pos++] = digits[i];
        out[pos] = '\0';
    } else if (decpt >= nd) {
        for (i = 0; i < nd; i++)
            out[pos++] = digits[i];
        for (i = nd; i < decpt; i++)
            out[pos++] = '0';
        out[pos++] = '.';
        out[pos++] = '0';
        out[pos] = '\0';
    } else {
        for (i = 0; i < nd; i++) {
            if (i == decpt)
                out[pos++] = '.';
            out[pos++] = digits[i];
        }
        out[pos] = '\0';
    }
    snprintf(buf, n, "%s", out);
}

rk_status rk_param_check(const rk_param_decl *decl, double value, double *out, rk_error *err)
{
    char rep[40], rng[96], lo_s[40], hi_s[40];
    int lo_none = decl->lo == -INFINITY, hi_none = decl->hi == INFINITY;
    double x = value;
    if (decl->integer) {
        /* check_choice: the codes 0 .. n_items-1, then the names (a float equal to a code is that code) */
        char names[RK_MSG_LEN];
        size_t pos = 0;
        int i;
        for (i = 0; i < decl->n_items; i++) {
            if (value == (double)i) {
                *out = (double)i;
                return RK_OK;
            }
        }
        names[0] = '\0';
        for (i = 0; i < decl->n_items; i++)
            pos += (size_t)snprintf(names + pos, sizeof names - pos, "%s%d", i ? ", " : "", i);
        for (i = 0; i < decl->n_items && pos < sizeof names; i++)
            pos += (size_t)snprintf(names + pos, sizeof names - pos, ", '%s'", decl->items[i]);
        rk_float_repr(value, rep, sizeof rep);
        return rk_fail(err, RK_ERR_VALUE, "%s = %s is not supported; allowed values: %s", decl->name, rep, names);
    }
    if (decl->inf_ok && value == INFINITY) {
        *out = INFINITY;
        return RK_OK;
    }
    if (isfinite(x) && (lo_none || x > decl->lo || (!decl->lo_open && x == decl->lo))
        && (hi_none || x < decl->hi || (!decl->hi_open && x == decl->hi))) {
        *out = x;
        return RK_OK;
    }
    if (lo_none)
        snprintf(lo_s, sizeof lo_s, "-inf");
    else
        snprintf(lo_s, sizeof lo_s, "%g", decl->lo);
    if (hi_none)
        snprintf(hi_s, sizeof hi_s, "inf");
    else
        snprintf(hi_s, sizeof hi_s, "%g", decl->hi);
    snprintf(rng, sizeof rng, "%c%s, %s%c", decl->lo_open || lo_none ? '(' : '[', lo_s, hi_s,
             decl->hi_open || hi_none ? ')' : ']');
    if (decl->inf_ok && hi_none)            /* the range includes +inf (Param.check's replace) */
        rng[strlen(rng) - 1] = ']';
    if (!isfinite(x)) {
        rk_float_repr(value, rep, sizeof rep);
        return rk_fail(err, RK_ERR_VALUE, "%s = %s is not finite; allowed range %s", decl->name, rep, rng);
    }
    return rk_fail(err, RK_ERR_VALUE, "%s = %g is out of range; allowed range %s", decl->name, x, rng);
}

/* CPython's math.hypot (Modules/mathmodule.c, vector_norm with n = 2): lossless scaling, Dekker products and a
 * differential correction; libm's hypot rounds differently in the last bit on some arguments. */
typedef struct { double hi, lo; } rk_dl;

static rk_dl dl_fast_sum(double a, double b)
{
    rk_dl r;
    double x = a + b;
    r.hi = x;
    r.lo = (a - x) + b;
    return r;
}

static rk_dl dl_split(double x)
{
    rk_dl r;
    double t = x * 134217729.0;         /* Veltkamp's constant 2^27 + 1 */
    r.hi = t - (t - x);
    r.lo = x - r.hi;
    return r;
}

static rk_dl dl_mul(double x, double y)
{
    rk_dl xx = dl_split(x), yy = dl_split(y), r;
    double p = xx.hi * yy.hi;
    double q = xx.hi * yy.lo + xx.lo * yy.hi;
    double z = p + q;
    r.hi = z;
    r.lo = p - z + q + xx.lo * yy.lo;
    return r;
}

static double vector_norm2(double *vec, double max, int found_nan)
{
    double x, h, scale, csum = 1.0, frac1 = 0.0, frac2 = 0.0;
    rk_dl pr, sm;
    int max_e, i;
    if (isinf(max))
        return max;
    if (found_nan)
        return NAN;
    if (max == 0.0)
        return max;
    frexp(max, &max_e);
    if (max_e < -1023) {
        for (i = 0; i < 2; i++)
            vec[i] /= DBL_MIN;
        return DBL_MIN * vector_norm2(vec, max / DBL_MIN, found_nan);
    }
    scale = ldexp(1.0, -max_e);
    for (i = 0; i < 2; i++) {
        x = vec[i] * scale;
        pr = dl_mul(x, x);
        sm = dl_fast_sum(csum, pr.hi);
        csum = sm.hi;
        frac1 += pr.lo;
        frac2 += sm.lo;
    }
    h = sqrt(csum - 1.0 + (frac1 + frac2));
    pr = dl_mul(-h, h);
    sm = dl_fast_sum(csum, pr.hi);
    csum = sm.hi;
    frac1 += pr.lo;
    frac2 += sm.lo;
    x = csum - 1.0 + (frac1 + frac2);
    h += x / (2.0 * h);
    return h / scale;
}

double rk_py_hypot(double a, double b)
{
    double v[2], max = 0.0;
    int found_nan;
    v[0] = fabs(a);
    v[1] = fabs(b);
    found_nan = isnan(v[0]) || isnan(v[1]);
    if (v[0] > max)
        max = v[0];
    if (v[1] > max)
        max = v[1];
    return vector_norm2(v, max, found_nan);
}

int rk_two_corner_mode_of(const rk_model *m, rk_set closed, int sigma)
{
    int mode;
    (void)m;
    if (closed == 3u)
        mode = RK_MODE_FULL;
    else if (closed == 1u)
        mode = RK_MODE_LEFT;
    else if (closed == 2u)
        mode = RK_MODE_RIGHT;
    else
        return RK_MODE_FLIGHT;
    if (sigma == 0)
        return mode;
    return RK_MODE_FULL_SLIDE_POS + 2 * mode + (sigma > 0 ? 0 : 1);
}

int rk_two_corner_stick_of(const rk_model *m, int mode, int *sigma)
{
    (void)m;
    if (mode >= RK_MODE_FULL_SLIDE_POS && mode <= RK_MODE_RIGHT_SLIDE_NEG) {
        if (sigma != NULL)
            *sigma = (mode - RK_MODE_FULL_SLIDE_POS) % 2 == 0 ? 1 : -1;
        return (mode - RK_MODE_FULL_SLIDE_POS) / 2;
    }
    if (sigma != NULL)
        *sigma = 0;
    return mode;
}

rk_set rk_two_corner_closed_of(const rk_model *m, int mode)
{
    switch (rk_two_corner_stick_of(m, mode, NULL)) {
    case RK_MODE_FULL: return 3u;
    case RK_MODE_LEFT: return 1u;
    case RK_MODE_RIGHT: return 2u;
    default: return 0u;
    }
}

int rk_mode_of_initial_state(double phi_0, double phi_dot_0)
{
    if (phi_0 > 0.0 || (phi_0 == 0.0 && phi_dot_0 > 0.0))
        return RK_MODE_LEFT;
    if (phi_0 < 0.0 || (phi_0 == 0.0 && phi_dot_0 < 0.0))
        return RK_MODE_RIGHT;
    return RK_MODE_FULL;
}

/* ------------------------------------------------------------------------------------------ linear algebra */
rk_status rk_la_solve(int n, const double *A, const double *b, double *x)
{
    double LU[RK_MAX_Y * RK_MAX_Y], y[RK_MAX_Y];      /* (the contact problems solve up to 2 x 8 unknowns) */
    int i, j, k;
    if (n > RK_MAX_Y)
        return RK_ERR_INTERNAL;
    memcpy(LU, A, (size_t)(n * n) * sizeof(double));
    memcpy(y, b, (size_t)n * sizeof(double));
    for (k = 0; k < n; k++) {
        int p = k;
        double best = fabs(LU[k * n + k]);
        for (i = k + 1; i < n; i++) {
            if (fabs(LU[i * n + k]) > best) {
                best = fabs(LU[i * n + k]);
                p = i;
            }
        }
        if (p != k) {
            for (j = 0; j < n; j++) {
                double t = LU[k * n + j];
                LU[k * n + j] = LU[p * n + j];
                LU[p * n + j] = t;
            }
            {
                double t = y[k];
                y[k] = y[p];
                y[p] = t;
            }
        }
        if (LU[k * n + k] == 0.0)
            return RK_ERR_SOLVER;           /* exactly singular: LAPACK's info > 0, numpy's LinAlgError */
        for (i = k + 1; i < n; i++) {
            double l = LU[i * n + k] / LU[k * n + k];
            LU[i * n + k] = l;
            for (j = k + 1; j < n; j++)
                LU[i * n + j] -= l * LU[k * n + j];
            y[i] -= l * y[k];
        }
    }
    for (i = n - 1; i >= 0; i--) {
        double s = y[i];
        for (j = i + 1; j < n; j++)
            s -= LU[i * n + j] * x[j];
        x[i] = s / LU[i * n + i];
    }
    return RK_OK;
}

rk_status rk_la_lstsq(int rows, int cols, const double *A, const double *b, double rcond, double *x)
{
    /* minimum-norm least squares through a one-sided Jacobi SVD (numpy's lstsq: singular values at most
     * rcond * s_max are dropped; rcond < 0: eps * max(rows, cols)) */
    double U[RK_MAX_Y * RK_MAX_Y], V[RK_MAX_Y * RK_MAX_Y], s[RK_MAX_Y], smax = 0.0;
    int i, j, k, sweep;
    if (rows > RK_MAX_Y || cols > RK_MAX_Y)
        return RK_ERR_INTERNAL;
    if (rcond < 0.0)
        rcond = DBL_EPSILON * (rows > cols ? rows : cols);
    memcpy(U, A, (size_t)(rows * cols) * sizeof(double));
    for (i = 0; i < cols; i++)
        for (j = 0; j < cols; j++)
            V[i * cols + j] = i == j ? 1.0 : 0.0;
    for (sweep = 0; sweep < 60; sweep++) {
        int rotated = 0;
        for (j = 0; j < cols - 1; j++) {
            for (k = j + 1; k < cols; k++) {
                double alpha = 0.0, beta = 0.0, gamma = 0.0, zeta, t, c, sn;
                for (i = 0; i < rows; i++) {
                    alpha += U[i * cols + j] * U[i * cols + j];
                    beta += U[i * cols + k] * U[i * cols + k];
                    gamma += U[i * cols + j] * U[i * cols + k];
                }
                if (gamma == 0.0 || fabs(gamma) <= DBL_EPSILON * sqrt(alpha * beta))
                    continue;
                rotated = 1;
                zeta = (beta - alpha) / (2.0 * gamma);
                t = (zeta >= 0.0 ? 1.0 : -1.0) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                c = 1.0 / sqrt(1.0 + t * t);
                sn = c * t;
                for (i = 0; i < rows; i++) {
                    double u1 = U[i * cols + j], u2 = U[i * cols + k];
                    U[i * cols + j] = c * u1 - sn * u2;
                    U[i * cols + k] = sn * u1 + c * u2;
                }
                for (i = 0; i < cols; i++) {
                    double v1 = V[i * cols + j], v2 = V[i * cols + k];
                    V[i * cols + j] = c * v1 - sn * v2;
                    V[i * cols + k] = sn * v1 + c * v2;
                }
            }
        }
        if (!rotated)
            break;
    }
    for (j = 0; j < cols; j++) {
        double nrm = 0.0;
        for (i = 0; i < rows; i++)
            nrm += U[i * cols + j] * U[i * cols + j];
        s[j] = sqrt(nrm);
        if (s[j] > smax)
            smax = s[j];
    }
    for (j = 0; j < cols; j++)
        x[j] = 0.0;
    for (j = 0; j < cols; j++) {
        double ub = 0.0;
        if (!(s[j] > rcond * smax) || s[j] == 0.0)
            continue;
        for (i = 0; i < rows; i++)
            ub += U[i * cols + j] * b[i];
        ub /= s[j] * s[j];                  /* U's column j is s_j times the unit singular vector */
        for (i = 0; i < cols; i++)
            x[i] += V[i * cols + j] * ub;
    }
    return RK_OK;
}

void rk_model_inverse_mass(const rk_model *m, const double *q, double *Minv)
{
    int n = m->ops->n_dof, i, j, k;
    double A[RK_MAX_DOF * RK_MAX_DOF];
    if (m->ops->inverse_mass_matrix != NULL) {
        m->ops->inverse_mass_matrix(m, q, Minv);
        return;
    }
    /* Gauss-Jordan with partial pivoting (np.linalg.inv) */
    m->ops->mass_matrix(m, q, A);
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++)
            Minv[i * n + j] = i == j ? 1.0 : 0.0;
    for (k = 0; k < n; k++) {
        int p = k;
        double piv;
        for (i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[p * n + k]))
                p = i;
        if (p != k) {
            for (j = 0; j < n; j++) {
                double t = A[k * n + j];
                A[k * n + j] = A[p * n + j];
                A[p * n + j] = t;
                t = Minv[k * n + j];
                Minv[k * n + j] = Minv[p * n + j];
                Minv[p * n + j] = t;
            }
        }
        piv = A[k * n + k];
        for (j = 0; j < n; j++) {
            A[k * n + j] /= piv;
            Minv[k * n + j] /= piv;
        }
        for (i = 0; i < n; i++) {
            double f;
            if (i == k)
                continue;
            f = A[i * n + k];
            for (j = 0; j < n; j++) {
                A[i * n + j] -= f * A[k * n + j];
                Minv[i * n + j] -= f * Minv[k * n + j];
            }
        }
    }
}

/* ------------------------------------------------------------------------------------------ any mode */
int rk_dofs_of(const rk_model *m, int mode, int *idx)
{
    return rk_mode_sliding(m, mode) ? rk_slide_dofs(m, mode, idx) : m->ops->mode_dofs(m, mode, idx);
}

void rk_embed_any(const rk_model *m, int mode, const double *y, double *q, double *v)
{
    int idx[RK_MAX_DOF];
    int k = rk_dofs_of(m, mode, idx);
    if (rk_mode_sliding(m, mode))
        rk_slide_embed(m, mode, y, y + k, q, v);
    else
        m->ops->embed(m, mode, y, y + k, q, v);
}

int rk_reduce_any(const rk_model *m, int mode, const double *q, const double *v, double *y)
{
    int idx[RK_MAX_DOF], k, i;
    if (rk_mode_sliding(m, mode))
        return rk_slide_reduce(m, mode, q, v, y);
    k = m->ops->mode_dofs(m, mode, idx);
    for (i = 0; i < k; i++) {
        y[i] = q[idx[i]];
        y[k + i] = v[idx[i]];
    }
    return k;
}

rk_status rk_mode_rhs(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *dy)
{
    int idx[RK_MAX_DOF], k, i;
    if (rk_mode_sliding(m, mode)) {
        k = rk_slide_dofs(m, mode, idx);
        for (i = 0; i < k; i++)
            dy[i] = y[k + i];
        return rk_slide_acceleration(m, mode, y, y + k, ag, ag_v, dy + k);
    }
    if (m->ops->mode_rhs != NULL)
        m->ops->mode_rhs(m, mode, y, ag, ag_v, dy);
    else
        rk_model_generic_rhs(m, mode, y, ag, ag_v, dy);
    return RK_OK;
}

/* the monitors of a sticking mode without the friction cone (mode_closures' / mode_functions') */
static void stick_monitors(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *g,
                           double *totals)
{
    if (m->ops->mode_monitors != NULL)
        m->ops->mode_monitors(m, mode, y, ag, ag_v, g, totals);
    else
        rk_model_generic_monitors(m, mode, y, ag, ag_v, g, totals);
}

/* the switches of the force laws on the reduced state y of mode, before the overturning margin g[n - 1]: the
 * margin moves to the end (n + n_switches functions) */
static RK_NOINLINE int add_switches(const rk_model *m, int mode, const double *y, double *g, int n)
{
    int nsw = m->ops->n_switches;
    double q[RK_MAX_DOF], v[RK_MAX_DOF];
    rk_embed_any(m, mode, y, q, v);
    if (!rk_mode_sliding(m, mode) && rk_closed_of(m, mode))
        q[m->ops->slide_index] += m->offset;
    g[n - 1 + nsw] = g[n - 1];
    m->ops->switches(m, q, v, g + n - 1);
    return n + nsw;
}

/* (a model without switches pays one test: the event functions are evaluated at every step) */
static inline int with_switches(const rk_model *m, int mode, const double *y, double *g, int n)
{
    return m->ops->n_switches == 0 ? n : add_switches(m, mode, y, g, n);
}

int rk_mode_monitors(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *g, double *totals,
                     int *has_totals)
{
    int nc = m->ops->n_contacts;
    double tot[2] = {0.0, 0.0};
    if (rk_mode_sliding(m, mode)) {
        /* sliding.slide_functions' monitors and force_totals_of's slide_totals */
        int sigma = 0, stick = rk_stick_of(m, mode, &sigma);
        rk_set closed = rk_closed_of(m, stick);
        int idx[RK_MAX_DOF], k = rk_slide_dofs(m, mode, idx), i, c = 0;
        double q[RK_MAX_DOF], v[RK_MAX_DOF], a[RK_MAX_DOF], tau[RK_MAX_CONTACTS], ys[RK_MAX_Y];
        double base[RK_MAX_EVENTS], F = m->force_scale, V = sqrt(m->g * m->length_scale), tau_sum = 0.0;
        double inv_mu = isinf(m->mu) ? 0.0 : 1.0 / m->mu;
        rk_slide_embed(m, mode, y, y + k, q, v);
        if (rk_slide_motion(m, mode, q, v, ag, ag_v, a, tau) != RK_OK)
            for (i = 0; i < RK_MAX_CONTACTS; i++)
                tau[i] = NAN;       /* numpy's lstsq failed too: non-finite event functions stop the driver */
        for (i = 0; i < k - 1; i++) {
            ys[i] = y[i];
            ys[k - 1 + i] = y[k + i];
        }
        stick_monitors(m, stick, ys, ag, ag_v, base, NULL);
        for (i = 0; i < nc; i++)
            g[i] = RK_IN(closed, i) ? tau[c++] / F : base[i];
        g[nc] = (double)sigma * y[2 * k - 1] / V;
        g[nc + 1] = base[nc];
        for (i = 0; i < c; i++)
            tau_sum += tau[i];
        if (totals != NULL) {
            totals[0] = inv_mu * tau_sum;
            totals[1] = (double)(-sigma) * tau_sum;
        }
        if (has_totals != NULL)
            *has_totals = 1;
        return with_switches(m, mode, y, g, nc + 2);
    }
    {
        rk_set closed = rk_closed_of(m, mode);
        int cone = closed && !isinf(m->mu);
        /* the totals only where someone reads them: the caller, or the friction cone */
        stick_monitors(m, mode, y, ag, ag_v, g, closed && (totals != NULL || cone) ? tot : NULL);
        if (has_totals != NULL)
            *has_totals = closed != 0u;
        if (closed && totals != NULL) {
            totals[0] = tot[0];
            totals[1] = tot[1];
        }
        if (!cone)
            return with_switches(m, mode, y, g, nc + 1);
        /* the friction cone before the overturning margin: positive while the corners stick */
        g[nc + 1] = g[nc];
        g[nc] = (m->mu * tot[0] - fabs(tot[1])) / m->force_scale;
        return with_switches(m, mode, y, g, nc + 2);
    }
}

int rk_mode_monitor_one(const rk_model *m, int mode, const double *y, int i, double *gi)
{
    int nc = m->ops->n_contacts, cone;
    if (m->ops->mode_monitor_one == NULL || m->ops->mode_monitors == NULL || rk_mode_sliding(m, mode))
        return 0;
    /* rk_mode_monitors' layout: the contacts' functions, [the friction cone,] [the switches,] the overturning
     * margin */
    cone = rk_closed_of(m, mode) != 0u && !isinf(m->mu);
    if (i < nc)
        return m->ops->mode_monitor_one(m, mode, y, i, gi);
    if (i == nc + cone + m->ops->n_switches)
        return m->ops->mode_monitor_one(m, mode, y, nc, gi);
    return 0;
}

void rk_outputs_of_general(const rk_model *m, int mode, const double *y, double shift, double *out)
{
    double q[RK_MAX_DOF], v[RK_MAX_DOF];
    int i;
    if (rk_mode_sliding(m, mode)) {
        rk_embed_any(m, mode, y, q, v);
        m->ops->outputs(m, q, v, out);
        return;
    }
    if (m->ops->mode_outputs != NULL) {
        m->ops->mode_outputs(m, mode, y, out);
    } else {
        rk_embed_any(m, mode, y, q, v);
        m->ops->outputs(m, q, v, out);
    }
    if (shift != 0.0) {
        for (i = 0; i < m->ops->n_shifted; i++)
            out[m->ops->shifted[i]] += shift;
    }
}

double rk_model_slip(const rk_model *m, const double *q)
{
    double g[RK_MAX_CONTACTS], x[RK_MAX_CONTACTS];
    int i, best = 0, nc = m->ops->n_contacts;
    m->ops->gaps(m, q, g);
    /* np.argmin: the first minimum (the first NaN if any) */
    for (i = 0; i < nc; i++) {
        if (isnan(g[i])) {
            best = i;
            break;
        }
        if (g[i] < g[best])
            best = i;
    }
    m->ops->contact_abscissae(m, q, x);
    return x[best] - m->rest_abscissae[best];
}

double rk_shift_of(const rk_model *m, int mode, const double *q)
{
    double zeros[RK_MAX_DOF], y[RK_MAX_Y], q0[RK_MAX_DOF], v0[RK_MAX_DOF];
    int k, i = m->ops->slide_index;
    memset(zeros, 0, sizeof zeros);
    k = rk_reduce_any(m, mode, q, zeros, y);
    m->ops->embed(m, mode, y, y + k, q0, v0);
    return q[i] - q0[i];
}

/* r_ddot of a sticking mode (RockingModel.reduced_acceleration: the kernel's closed form, else Lagrange) */
static void reduced_acceleration(const rk_model *m, int mode, const double *y, int k, double ag, double ag_v,
                                 double *r_ddot)
{
    double dy[RK_MAX_Y];
    int i;
    if (m->ops->mode_rhs != NULL)
        m->ops->mode_rhs(m, mode, y, ag, ag_v, dy);
    else
        rk_model_generic_rhs(m, mode, y, ag, ag_v, dy);
    for (i = 0; i < k; i++)
        r_ddot[i] = dy[k + i];
}

void rk_force_totals(const rk_model *m, int mode, const double *q, const double *v, double ag, double ag_v,
                     double *totals)
{
    int n = m->ops->n_dof, idx[RK_MAX_DOF], k, i, j;
    double y[RK_MAX_Y], J[RK_MAX_DOF * RK_MAX_DOF], jd[RK_MAX_DOF], a[RK_MAX_DOF], rdd[RK_MAX_DOF];
    double M[RK_MAX_DOF * RK_MAX_DOF], f[RK_MAX_DOF], resid[RK_MAX_DOF];
    k = m->ops->mode_dofs(m, mode, idx);
    for (i = 0; i < k; i++) {
        y[i] = q[idx[i]];
        y[k + i] = v[idx[i]];
    }
    m->ops->mode_jacobian(m, mode, y, y + k, J, jd);
    if (k > 0) {
        reduced_acceleration(m, mode, y, k, ag, ag_v, rdd);
        for (i = 0; i < n; i++) {
            double s = 0.0;
            for (j = 0; j < k; j++)
                s += J[i * k + j] * rdd[j];
            a[i] = s + jd[i];
        }
    } else {
        for (i = 0; i < n; i++)
            a[i] = jd[i];
    }
    m->ops->mass_matrix(m, q, M);
    m->ops->forces(m, q, v, ag, ag_v, f);
    for (i = 0; i < n; i++) {
        double s = 0.0;
        for (j = 0; j < n; j++)
            s += M[i * n + j] * a[j];
        resid[i] = s - f[i];
    }
    totals[0] = resid[m->ops->lift_index];
    totals[1] = resid[m->ops->slide_index];
}

void rk_model_generic_rhs(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *dy)
{
    int n = m->ops->n_dof, idx[RK_MAX_DOF], k, i, j, l;
    double q[RK_MAX_DOF], v[RK_MAX_DOF], J[RK_MAX_DOF * RK_MAX_DOF], jd[RK_MAX_DOF], M[RK_MAX_DOF * RK_MAX_DOF];
    double f[RK_MAX_DOF], fm[RK_MAX_DOF], rhs[RK_MAX_DOF], A[RK_MAX_DOF * RK_MAX_DOF], MJ[RK_MAX_DOF * RK_MAX_DOF];
    k = m->ops->mode_dofs(m, mode, idx);
    if (k == 0)
        return;
    for (i = 0; i < k; i++)
        dy[i] = y[k + i];
    m->ops->embed(m, mode, y, y + k, q, v);
    m->ops->mode_jacobian(m, mode, y, y + k, J, jd);
    m->ops->mass_matrix(m, q, M);
    m->ops->forces(m, q, v, ag, ag_v, f);
    /* (J^T M J) r_ddot = J^T (f - M jd) */
    for (i = 0; i < n; i++) {
        double s = 0.0;
        for (j = 0; j < n; j++)
            s += M[i * n + j] * jd[j];
        fm[i] = f[i] - s;
    }
    for (j = 0; j < k; j++) {
        double s = 0.0;
        for (i = 0; i < n; i++)
            s += J[i * k + j] * fm[i];
        rhs[j] = s;
    }
    for (i = 0; i < n; i++)
        for (j = 0; j < k; j++) {
            double s = 0.0;
            for (l = 0; l < n; l++)
                s += M[i * n + l] * J[l * k + j];
            MJ[i * k + j] = s;
        }
    for (i = 0; i < k; i++)
        for (j = 0; j < k; j++) {
            double s = 0.0;
            for (l = 0; l < n; l++)
                s += J[l * k + i] * MJ[l * k + j];
            A[i * k + j] = s;
        }
    if (rk_la_solve(k, A, rhs, dy + k) != RK_OK) {
        for (i = 0; i < k; i++)
            dy[k + i] = NAN;        /* numpy raises LinAlgError: the driver sees a non-finite rhs */
    }
}

void rk_model_generic_monitors(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *g,
                               double *totals)
{
    int nc = m->ops->n_contacts, idx[RK_MAX_DOF], k, i;
    rk_set closed = rk_closed_of(m, mode);
    double q[RK_MAX_DOF], v[RK_MAX_DOF], lam[RK_MAX_CONTACTS], gap[RK_MAX_CONTACTS], phi;
    double F = m->force_scale, L = m->length_scale;
    k = m->ops->mode_dofs(m, mode, idx);
    m->ops->embed(m, mode, y, y + k, q, v);
    if (closed) {
        if (m->ops->contact_forces != NULL) {
            m->ops->contact_forces(m, mode, q, v, ag, ag_v, lam);
        } else {
            /* RockingModel.contact_forces: contact.mode_forces, the contact LCP with the closed set forced */
            rk_error err;
            if (rk_mode_forces(m, mode, q, v, ag, ag_v, lam, &err) != RK_OK)
                for (i = 0; i < nc; i++)
                    lam[i] = NAN;   /* where numpy raises: the driver sees non-finite event functions */
        }
    }
    m->ops->gaps(m, q, gap);
    phi = q[m->ops->phi_index];
    for (i = 0; i < nc; i++) {
        if (RK_IN(closed, i))
            g[i] = lam[i] / F;
        else if (!closed)
            g[i] = gap[i] / L;
        else
            g[i] = mode == RK_MODE_RIGHT ? -phi : phi;
    }
    g[nc] = RK_HALF_PI - fabs(phi);
    if (totals != NULL && closed)
        rk_force_totals(m, mode, q, v, ag, ag_v, totals);
}
