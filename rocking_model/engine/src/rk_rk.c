/* rk_rk.c -- the Runge-Kutta pairs (part C): port of rocking_model/integrators/rk.py (ExplicitRK, DenseOutput)
 * with the tableau-specific error norms and interpolants of dop853.py and dopri5.py.
 *
 * The coefficients come from rk_tableaux.h, generated from the Python lists by gen_rk.py. Every sum adds the
 * nonzero terms in index order, left to right, as the straight-line code of rk._Compiled does, and every
 * expression keeps the Python's parenthesisation, so that a step agrees with the Python bit for bit (with
 * -ffp-contract=off). Python's min(a, b) / max(a, b) are written out (b < a ? b : a), not fmin / fmax: they
 * differ on NaN and the Python's choice decides.
 *
 * Errors of the callbacks: every public function clears err on entry; a callback that fails may write its own
 * message into the error it shares through its context and return its status: that message is kept. A callback
 * that returns a status without a message gets a generic one naming the time. */
/* GCC's straight-line (SLP) vectorizer packs the two components of a one-dof state into vector registers across
 * a step's stages, which costs time here: without it a 40 s record held sample by sample runs 12 % faster
 * (benchmarks/compiled_bench.py, holds_vs_lean), with the same bits (without fast-math a vector operation rounds
 * as its scalar ones). Off for this file alone (the Moreau-Jean and contact code gain from it), before the headers: their inline
 * functions then compile under the same options and inline here. */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-tree-slp-vectorize")
#endif
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_rk.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RK_TABLEAUX_DEFINE_DATA
#include "rk_tableaux.h"

const rk_tableau *rk_tableau_of(rk_method method)
{
    switch (method) {
    case RK_METHOD_DOP853: return &RK_TABLEAU_DOP853;
    case RK_METHOD_DOPRI5: return &RK_TABLEAU_DOPRI5;
    }
    return NULL;
}

const char *rk_tableau_name(const rk_tableau *tab)
{
    return tab != NULL ? tab->name : "";
}

/* Python's min(a, b) and max(a, b) of two floats: the first argument unless the second is strictly smaller
 * (larger) */
static double py_min(double a, double b) { return b < a ? b : a; }
static double py_max(double a, double b) { return b > a ? b : a; }

/* a callback failed with status st at t: keep its message if it wrote one, else a generic one */
static rk_status callback_failed(rk_error *err, rk_status st, const char *what, const char *name, double t)
{
    if (err != NULL && err->status == st && err->message[0] != '\0')
        return st;
    return rk_fail(err, st, "%s: the %s failed (%s) at t = %.17g s", name, what, rk_status_name(st), t);
}

static rk_status call_rhs(const rk_stepper *s, double t, const double *y, double *dy, rk_error *err)
{
    rk_status st = s->fun(s->ctx, t, y, dy);
    if (st != RK_OK)
        return callback_failed(err, st, "right-hand side", s->tab->name, t);
    return RK_OK;
}

/* sum_i c_i K[idx_i][j] over the nonzero terms, left to right (rk._lincomb); 0.0 when there are none */
static double lincomb(const rk_lincomb *lc, double K[][RK_MAX_Y], int j)
{
    double acc;
    int i;
    if (lc->n == 0)
        return 0.0;
    acc = lc->c[0] * K[lc->idx[0]][j];
    for (i = 1; i < lc->n; i++)
        acc = acc + lc->c[i] * K[lc->idx[i]][j];
    return acc;
}

/* Python's repr of a float (the shortest string that reads back to x, repr's fixed / exponent rule), for the
 * FloatingPointError message, which shows the state as a list. */
static int py_repr(double x, char *buf, size_t cap)
{
    char tmp[40], digits[24];
    int p, nd = 0, e10 = 0, decpt, pos = 0, i;
    const char *c;
    if (isnan(x))
        return snprintf(buf, cap, "nan");
    if (isinf(x))
        return snprintf(buf, cap, x > 0 ? "inf" : "-inf");
    if (x == 0.0)
        return snprintf(buf, cap, signbit(x) ? "-0.0" : "0.0");
    for (p = 1; p <= 17; p++) {
        snprintf(tmp, sizeof tmp, "%.*e", p - 1, x);
        if (strtod(tmp, NULL) == x)
            break;
    }
    /* tmp = [-]d[.ddd]e[+-]XX */
    for (c = tmp; *c != '\0' && *c != 'e'; c++)
        if (*c >= '0' && *c <= '9' && nd < 20)
            digits[nd++] = *c;
    if (*c == 'e')
        e10 = (int)strtol(c + 1, NULL, 10);
    while (nd > 1 && digits[nd - 1] == '0')
        nd--;
    digits[nd] = '\0';
    decpt = e10 + 1;
    char out[48];
    if (x < 0)
        out[pos++] = '-';
    if (decpt <= -4 || decpt > 16) {
        out[pos++] = digits[0];
        if (nd > 1) {
            out[pos++] = '.';
            for (i = 1; i < nd; i++)
                out[pos++] = digits[i];
        }
        pos += snprintf(out + pos, sizeof out - (size_t)pos, "e%c%02d", e10 < 0 ? '-' : '+', e10 < 0 ? -e10 : e10);
    } else if (decpt <= 0) {
        out[pos++] = '0';
        out[pos++] = '.';
        for (i = 0; i < -decpt; i++)
            out[pos++] = '0';
        for (i = 0; i < nd; i++)
            out[pos++] = digits[i];
    } else if (decpt >= nd) {
        for (i = 0; i < nd; i++)
            out[pos++] = digits[i];
        for (i = nd; i < decpt; i++)
            out[pos++] = '0';
        out[pos++] = '.';
        out[pos++] = '0';
    } else {
        for (i = 0; i < decpt; i++)
            out[pos++] = digits[i];
        out[pos++] = '.';
        for (i = decpt; i < nd; i++)
            out[pos++] = digits[i];
    }
    out[pos] = '\0';
    return snprintf(buf, cap, "%s", out);
}

/* Python's sum() of n floats from the int start 0: 0 + x_0, then plain addition (CPython < 3.12) or
 * Neumaier's compensated sum (CPython >= 3.12), as the building interpreter does (RK_PY_SUM_COMPENSATED) */
static double py_sum(const double *x, int n)
{
    /* f starts at +0.0: Python's first addition 0 + x_0 is exactly that, and with the compensation c still
     * 0.0 the first compensated step reduces to it too */
    double f = 0.0;
    int i;
#if RK_PY_SUM_COMPENSATED
    double c = 0.0;
    for (i = 0; i < n; i++) {
        double t = f + x[i];
        if (i == 0) {
            f = t;
            continue;
        }
        if (fabs(f) >= fabs(x[i]))
            c += (f - t) + x[i];
        else
            c += (x[i] - t) + f;
        f = t;
    }
    if (c != 0.0 && isfinite(c))
        f += c;
#else
    for (i = 0; i < n; i++)
        f = f + x[i];
#endif
    return f;
}

rk_status rk_initial_step(rk_stepper *s, double *h, rk_error *err)
{
    /* Hairer's heuristic (scipy.integrate._ivp.common.select_initial_step), as ExplicitRK._initial_step */
    /* (y1 initialised: GCC does not see that n >= 1 below, -Wmaybe-uninitialized) */
    double scale[RK_MAX_Y], terms[RK_MAX_Y], y1[RK_MAX_Y] = {0.0}, f1[RK_MAX_Y];
    double d0, d1, d2, h0, h1;
    int j, n = s->n;
    rk_status st;
    rk_error_clear(err);
    if (n == 0) {
        *h = isfinite(s->max_step) ? s->max_step : 1.0;
        return RK_OK;
    }
    for (j = 0; j < n; j++)
        scale[j] = s->atol[j] + fabs(s->y[j]) * s->rtol;
    for (j = 0; j < n; j++)
        terms[j] = (s->y[j] / scale[j]) * (s->y[j] / scale[j]);
    d0 = sqrt(py_sum(terms, n) / n);
    for (j = 0; j < n; j++)
        terms[j] = (s->f[j] / scale[j]) * (s->f[j] / scale[j]);
    d1 = sqrt(py_sum(terms, n) / n);
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    for (j = 0; j < n; j++)
        y1[j] = s->y[j] + h0 * s->f[j];
    st = call_rhs(s, s->t + h0, y1, f1, err);
    if (st != RK_OK)
        return st;
    for (j = 0; j < n; j++)
        terms[j] = ((f1[j] - s->f[j]) / scale[j]) * ((f1[j] - s->f[j]) / scale[j]);
    d2 = sqrt(py_sum(terms, n) / n) / h0;
    if (d1 <= 1e-15 && d2 <= 1e-15)
        h1 = py_max(1e-6, h0 * 1e-3);
    else
        h1 = pow(0.01 / py_max(d1, d2), 1.0 / (s->tab->order + 1.0));
    *h = py_min(100.0 * h0, h1);
    return RK_OK;
}

rk_status rk_stepper_init(rk_stepper *s, const rk_tableau *tab, rk_rhs_fn fun, void *ctx, double t0,
                          const double *y0, int n, double rtol, const double *atol, double max_step,
                          double first_step, const double *f0, rk_error *err)
{
    rk_status st;
    int j;
    rk_error_clear(err);
    if (tab == NULL)
        return rk_fail(err, RK_ERR_VALUE, "Runge-Kutta stepper: no tableau given");
    if (n < 0 || n > RK_MAX_Y)
        return rk_fail(err, RK_ERR_VALUE, "%s: the state size n = %d is out of range; allowed range [0, %d]",
                       tab->name, n, RK_MAX_Y);
    {
        /* y0, atol, f0 may point into *s (a re-init from its own state): copied before the reset */
        double y0c[RK_MAX_Y], atolc[RK_MAX_Y], f0c[RK_MAX_Y];
        for (j = 0; j < n; j++) {
            y0c[j] = y0[j];
            atolc[j] = atol[j];
            f0c[j] = f0 != NULL ? f0[j] : 0.0;
        }
        memset(s, 0, sizeof *s);
        for (j = 0; j < n; j++) {
            s->y[j] = y0c[j];
            s->atol[j] = atolc[j];
            s->f[j] = f0c[j];
        }
    }
    s->tab = tab;
    s->fun = fun;
    s->ctx = ctx;
    s->t = t0;
    s->n = n;
    s->rtol = rtol;
    s->max_step = max_step;
    if (n > 0 && f0 == NULL) {
        st = call_rhs(s, s->t, s->y, s->f, err);
        if (st != RK_OK)
            return st;
    }
    s->n_K = 0;
    s->dense_ready = 0;
    if (!(first_step > 0.0)) {          /* None in the Python (NAN or <= 0 here): the heuristic */
        st = rk_initial_step(s, &s->h_abs, err);
        if (st != RK_OK)
            return st;
    } else {
        s->h_abs = first_step;
    }
    s->h_abs = py_min(s->h_abs, max_step);
    s->t_old = s->t;
    rk_copy(s->y_old, s->y, n);
    rk_copy(s->f_old, s->f, n);
    s->n_steps = 0;
    s->n_rejected = 0;
    s->failed = 0;
    s->failure[0] = '\0';
    return RK_OK;
}

rk_status rk_stepper_restart(rk_stepper *s, rk_rhs_fn fun, void *ctx, double t0, const double *y0,
                             double first_step, rk_error *err)
{
    rk_status st;
    int n = s->n;
    double f[RK_MAX_Y];
    rk_error_clear(err);
    s->fun = fun;
    s->ctx = ctx;
    if (n > 0) {
        /* evaluated before anything changes, so that a failing rhs leaves the stepper as it was */
        st = call_rhs(s, t0, y0, f, err);
        if (st != RK_OK)
            return st;
        rk_copy(s->y, y0, n);       /* y0 may be s->y itself */
        rk_copy(s->f, f, n);
    }
    s->t = t0;
    s->n_K = 0;
    s->dense_ready = 0;
    if (!isnan(first_step)) {
        s->h_abs = py_min(first_step, s->max_step);
    } else if (n > 0) {
        double h;
        st = rk_initial_step(s, &h, err);
        if (st != RK_OK)
            return st;
        s->h_abs = py_min(h, s->max_step);
    }
    s->t_old = s->t;
    rk_copy(s->y_old, s->y, n);
    rk_copy(s->f_old, s->f, n);
    return RK_OK;
}

#if defined(__GNUC__)
#define RK_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define RK_ALWAYS_INLINE inline
#endif
/* loops over a tableau's stages and terms: unrolled in full where the tableau is a constant (step_n) */
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 8
#define RK_UNROLL _Pragma("GCC unroll 16")
#else
#define RK_UNROLL
#endif

/* acc[j] += c row[j], j < n */
static RK_ALWAYS_INLINE void add_term(double *acc, double c, const double *row, int n)
{
    int j;
    for (j = 0; j < n; j++)
        acc[j] = acc[j] + c * row[j];
}

/* sum_i c_i K[idx_i][j] for every component j < n at once (rk._lincomb per component: the same products and
 * left-to-right sums, the terms read once for all components); 0.0 where there are no terms. fixed: lc and n
 * are constants (step_n's DOP853 path), the terms unrolled */
static RK_ALWAYS_INLINE void lincomb_all(const rk_lincomb *lc, double K[][RK_MAX_Y], int n, double *acc, int fixed)
{
    int i, j;
    if (lc->n == 0) {
        for (j = 0; j < n; j++)
            acc[j] = 0.0;
        return;
    }
    for (j = 0; j < n; j++)
        acc[j] = lc->c[0] * K[lc->idx[0]][j];
    if (fixed) {
        RK_UNROLL
        for (i = 1; i < lc->n; i++)
            add_term(acc, lc->c[i], K[lc->idx[i]], n);
    } else {
        for (i = 1; i < lc->n; i++)
            add_term(acc, lc->c[i], K[lc->idx[i]], n);
    }
}

/* stage st_i of a step: K[st_i] = f(t + C h, y + h sum_i A_i K_i) */
static RK_ALWAYS_INLINE rk_status stage(const rk_stepper *s, const rk_tableau *tab, int st_i, int n, int fixed,
                                       double t, double h, double K[][RK_MAX_Y], rk_error *errp)
{
    double arg[RK_MAX_Y], acc[RK_MAX_Y];
    int j;
    lincomb_all(&tab->A[st_i], K, n, acc, fixed);
    for (j = 0; j < n; j++)
        arg[j] = s->y[j] + h * acc[j];
    if (fixed && n == 2 && s->acc1 != NULL) {
        K[st_i][0] = arg[1];
        K[st_i][1] = s->acc1(s->acc1_m, s->acc1_mode, arg[0], arg[1], s->acc1_ag, s->acc1_ag_v);
        return RK_OK;
    }
    if (fixed && n == 2 && s->fun1 != NULL) {
        K[st_i][0] = arg[1];
        K[st_i][1] = s->fun1(s->ctx, t + tab->C[st_i] * h, arg[0], arg[1]);
        return RK_OK;
    }
    return call_rhs(s, t + tab->C[st_i] * h, arg, K[st_i], errp);
}

/* rk._Compiled.rk_step: the stages, y_new, f_new = f(t_new, y_new), the error estimates and the tableau's
 * error norm; K[s][j] receives the n_stages stages. fixed: tab and n are constants (step_n), the loops over
 * the stages and their terms unrolled */
static RK_ALWAYS_INLINE rk_status attempt_n(const rk_stepper *s, const rk_tableau *tab, int n, int fixed, double t,
                                            double h, double t_new, double *y_new, double K[][RK_MAX_Y],
                                            double *err_norm, rk_error *errp)
{
    const double *y = s->y;
    double sc[RK_MAX_Y], er[2][RK_MAX_Y], acc[RK_MAX_Y];
    double err;
    int ns = tab->n_stages, st_i, j, m;
    rk_status st;
    for (j = 0; j < n; j++)
        K[0][j] = s->f[j];
    if (fixed) {
        RK_UNROLL
        for (st_i = 1; st_i < ns - 1; st_i++)
            if ((st = stage(s, tab, st_i, n, 1, t, h, K, errp)) != RK_OK)
                return st;
    } else {
        for (st_i = 1; st_i < ns - 1; st_i++)
            if ((st = stage(s, tab, st_i, n, 0, t, h, K, errp)) != RK_OK)
                return st;
    }
    lincomb_all(&tab->B, K, n, acc, fixed);
    for (j = 0; j < n; j++)
        y_new[j] = y[j] + h * acc[j];
    if (fixed && n == 2 && s->acc1 != NULL) {
        K[ns - 1][0] = y_new[1];
        K[ns - 1][1] = s->acc1(s->acc1_m, s->acc1_mode, y_new[0], y_new[1], s->acc1_ag, s->acc1_ag_v);
    } else if (fixed && n == 2 && s->fun1 != NULL) {
        K[ns - 1][0] = y_new[1];
        K[ns - 1][1] = s->fun1(s->ctx, t_new, y_new[0], y_new[1]);
    } else if ((st = call_rhs(s, t_new, y_new, K[ns - 1], errp)) != RK_OK) {
        return st;
    }
    for (m = 0; m < tab->n_errors; m++)
        lincomb_all(&tab->E[m], K, n, er[m], fixed);
    /* mixed error scale atol_j + rtol max(|y_j|, |y_new_j|) */
    for (j = 0; j < n; j++)
        sc[j] = s->atol[j] + py_max(fabs(y[j]), fabs(y_new[j])) * s->rtol;
    /* the sums start from +0.0: 0.0 + p*p is p*p exactly (a square is never -0.0), so this adds the same
     * terms as the Python's p0*p0 + p1*p1 + ... */
    if (tab->style == RK_STYLE_DOP853) {
        /* Hairer's norm: |h| e5 / sqrt((e5 + 0.01 e3) n) */
        double e5 = 0.0, e3 = 0.0;
        for (j = 0; j < n; j++) {
            double p = er[0][j] / sc[j], q = er[1][j] / sc[j];
            e5 = e5 + p * p;
            e3 = e3 + q * q;
        }
        if (e5 == 0.0 && e3 == 0.0) {
            err = 0.0;
        } else {
            double den = sqrt((e5 + 0.01 * e3) * n);
            /* den == 0.0 only when e5 == 0.0 and 0.01 e3 underflows (estimates near 1e-154 of the scale): the
             * Python raises ZeroDivisionError there; the estimate is zero, so the step is accepted (err = 0.0,
             * the value the Python's formula gives whenever it does not divide by zero) */
            err = (den == 0.0) ? 0.0 : fabs(h) * e5 / den;
        }
    } else {
        /* |h| sqrt(sum p_j^2 / n) */
        double acc2 = 0.0;
        for (j = 0; j < n; j++) {
            double p = er[0][j] / sc[j];
            acc2 = acc2 + p * p;
        }
        err = fabs(h) * sqrt(acc2 / n);
    }
    *err_norm = err;
    return RK_OK;
}

/* One accepted step (rk.ExplicitRK.step) of a stepper with n > 0 components under the tableau tab: inlined with
 * tab and n constants for DOP853 on one degree of freedom (the rigid block's rocking modes), so that the stage
 * loops unroll into straight-line code with the coefficients as constants and the two components side by side
 * (the same operations in the same order: the same bits) */
static RK_ALWAYS_INLINE rk_status step_n(rk_stepper *s, const rk_tableau *tab, int n, int fixed, double t_bound,
                                         rk_error *err)
{
    double K[RK_MAX_STAGES][RK_MAX_Y], y_new[RK_MAX_Y];
    double t = s->t, min_step, h_abs, h, t_new, e, err_exp;
    int rejected = 0, i, j;
    rk_status st;
    err_exp = -1.0 / (tab->error_order + 1.0);
    min_step = 10.0 * fabs(rk_gap_above(t));
    h_abs = py_min(s->h_abs, s->max_step);
    for (;;) {
        if (!(h_abs >= min_step))       /* NaN too (an initial step from an overflowed derivative): the loop
                                         * then ends at the smallest step with the non-finite report */
            h_abs = min_step;
        h = h_abs;
        t_new = t + h;
        if (t_new >= t_bound) {
            t_new = t_bound;
            h = t_new - t;
            h_abs = fabs(h);
        }
        st = attempt_n(s, tab, n, fixed, t, h, t_new, y_new, K, &e, err);
        if (st != RK_OK)
            return st;
        if (e < 1.0 || h_abs <= min_step) {
            double factor;
            if (!(e < 1.0)) {
                if (!isfinite(e)) {
                    /* even the smallest step does not give a finite state: the motion has overflowed */
                    char ys[RK_MSG_LEN];
                    size_t pos = 0;
                    ys[pos++] = '[';
                    for (j = 0; j < n && pos < sizeof ys - 32; j++) {
                        if (j > 0) {
                            ys[pos++] = ',';
                            ys[pos++] = ' ';
                        }
                        pos += (size_t)py_repr(s->y[j], ys + pos, sizeof ys - pos);
                    }
                    ys[pos++] = ']';
                    ys[pos] = '\0';
                    return rk_fail(err, RK_ERR_NONFINITE,
                                   "%s: the state is not finite after a step of %.3g s from t = %.17g s (y = %s)",
                                   tab->name, h, t, ys);
                }
                /* accepted only because no smaller step exists: the caller reports it */
                s->failed = 1;
                snprintf(s->failure, sizeof s->failure,
                         "%s: the step of %.3g s from t = %.17g s was accepted at the smallest step size with its "
                         "error estimate %.3g times the tolerance: the solution may be inaccurate there",
                         tab->name, h, t, e);
            }
            factor = (e == 0.0) ? RK_MAX_FACTOR : py_min(RK_MAX_FACTOR, RK_SAFETY * pow(e, err_exp));
            if (rejected)
                factor = py_min(1.0, factor);
            s->h_abs = h_abs * factor;
            break;
        }
        if (!isfinite(e))
            e = 1e10;
        h_abs *= py_max(RK_MIN_FACTOR, RK_SAFETY * pow(e, err_exp));
        rejected = 1;
        s->n_rejected += 1;
    }
    s->t_old = t;
    s->t = t_new;
    for (j = 0; j < n; j++) {
        s->y_old[j] = s->y[j];
        s->f_old[j] = s->f[j];
        s->y[j] = y_new[j];
        s->f[j] = K[tab->n_stages - 1][j];
    }
    /* the n components of each stage (the rows' unused tails are never read) */
    for (i = 0; i < tab->n_stages; i++)
        for (j = 0; j < n; j++)
            s->K[i][j] = K[i][j];
    s->n_K = tab->n_stages;
    s->dense_ready = 0;
    s->n_steps += 1;
    return RK_OK;
}

rk_status rk_step(rk_stepper *s, double t_bound, rk_error *err)
{
    rk_error_clear(err);
    if (s->n == 0) {
        double t = s->t, h = py_min(s->max_step, t_bound - t);
        s->t_old = t;
        s->t = (h >= t_bound - t) ? t_bound : t + h;
        s->n_steps += 1;
        s->n_K = 0;
        s->dense_ready = 0;
        return RK_OK;
    }
    if (s->n == 2 && s->tab == &RK_TABLEAU_DOP853)
        return step_n(s, &RK_TABLEAU_DOP853, 2, 1, t_bound, err);
    return step_n(s, s->tab, s->n, 0, t_bound, err);
}

void rk_hermite_mid(const rk_stepper *s, double *y_mid)
{
    double h = s->t - s->t_old;
    int j;
    for (j = 0; j < s->n; j++)
        y_mid[j] = 0.5 * (s->y_old[j] + s->y[j]) + 0.125 * h * (s->f_old[j] - s->f[j]);
}

/* rk._Compiled.dense + make_interpolant: the extra stages (DOP853), the coefficient rows h * sum_i D_i k_i,
 * and the end terms of the interpolant (DOP853: Q[n_dense..n_dense+2] = F0, F1, F2) */
/* (not inlined: once per step, against one call of rk_dense_eval per output row and event sample) */
static RK_NOINLINE rk_status build_dense(rk_stepper *s, rk_error *err)
{
    const rk_tableau *tab = s->tab;
    double arg[RK_MAX_Y];
    double h = s->t - s->t_old;
    int n = s->n, st_i, j, r;
    rk_status st;
    if (s->n_K < tab->n_stages)
        return rk_fail(err, RK_ERR_INTERNAL, "%s: dense output requested before a step (no stages to interpolate)",
                       tab->name);
    for (st_i = s->n_K; st_i < tab->n_all; st_i++) {
        for (j = 0; j < n; j++)
            arg[j] = s->y_old[j] + h * lincomb(&tab->A[st_i], s->K, j);
        st = call_rhs(s, s->t_old + tab->C[st_i] * h, arg, s->K[st_i], err);
        if (st != RK_OK)
            return st;
        s->n_K = st_i + 1;
    }
    for (r = 0; r < tab->n_dense; r++)
        for (j = 0; j < n; j++)
            s->Q[r][j] = h * lincomb(&tab->D[r], s->K, j);
    if (tab->style == RK_STYLE_DOP853) {
        for (j = 0; j < n; j++) {
            double y0 = s->y_old[j];
            double F0 = s->y[j] - y0;
            s->Q[4][j] = F0;
            s->Q[5][j] = h * s->f_old[j] - F0;
            s->Q[6][j] = 2.0 * F0 - h * (s->f[j] + s->f_old[j]);
        }
    }
    s->dense_ready = 1;
    return RK_OK;
}

rk_status rk_dense_eval(rk_stepper *s, double t, double *y, rk_error *err)
{
    double h, x;
    int j, n = s->n;
    rk_status st;
    rk_error_clear(err);
    if (t == s->t) {
        rk_copy(y, s->y, n);
        return RK_OK;
    }
    if (n == 0)
        return RK_OK;
    if (!s->dense_ready) {
        st = build_dense(s, err);
        if (st != RK_OK)
            return st;
    }
    h = s->t - s->t_old;
    x = (h != 0.0) ? (t - s->t_old) / h : 0.0;
    if (s->tab->style == RK_STYLE_DOP853) {
        /* Hairer's contd8: y0 + x (F0 + xm (F1 + x (F2 + xm (F3 + ...)))) */
        double xm = 1.0 - x;
        for (j = 0; j < n; j++) {
            double F3 = s->Q[0][j], F4 = s->Q[1][j], F5 = s->Q[2][j], F6 = s->Q[3][j];
            double F0 = s->Q[4][j], F1 = s->Q[5][j], F2 = s->Q[6][j];
            y[j] = s->y_old[j] + (((((((F6 * x + F5) * xm + F4) * x + F3) * xm + F2) * x + F1) * xm + F0) * x);
        }
    } else {
        for (j = 0; j < n; j++) {
            double q0 = s->Q[0][j], q1 = s->Q[1][j], q2 = s->Q[2][j], q3 = s->Q[3][j];
            y[j] = s->y_old[j] + x * (q0 + x * (q1 + x * (q2 + x * q3)));
        }
    }
    return RK_OK;
}
