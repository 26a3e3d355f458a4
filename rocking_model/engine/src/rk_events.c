/* rk_events.c -- event location on the dense output of a step (part C): port of
 * rocking_model/integrators/events.py (locate, earliest_root, first_negative, may_dip, dip_search,
 * bounce_search, parabola_peak, brent_max), statement by statement, with the same comparisons (strict / non-strict) and the same
 * tie-breaking, so that the C finds the same times and indices as the Python (tests/test_engine_rk.py).
 *
 * The event functions are evaluated as the Python does: G(t, dense(t)) with dense the interpolant of the
 * stepper's last step (rk_dense_eval: exact end values at the step's end), except dip_search's midpoint,
 * G(tm, hermite_mid). Errors of the callbacks: as in rk_rk.c (a message written by the callback is kept). */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_rk.h"

#include <math.h>
#include <string.h>

/* locate's iterations: a bracket halves at least every third iteration (the bisection rule), so some 200
 * iterations take any double bracket down to round-off; the cap only turns a bad xtol (0, NaN) into an error
 * instead of an endless loop */
#define LOCATE_MAX_ITER 10000

/* a failed call of the event functions at t: the callback's own message if it wrote one, else a generic one */
static rk_status callback_failed(rk_status st, double t, rk_error *err)
{
    if (err != NULL && err->status == st && err->message[0] != '\0')
        return st;
    return rk_fail(err, st, "events: the event functions failed (%s) at t = %.17g s", rk_status_name(st), t);
}

rk_status rk_event_eval(rk_event_ctx *c, double t, double *g, rk_error *err)
{
    double y[RK_MAX_Y];
    rk_status st;
    rk_error_clear(err);
    st = rk_dense_eval(c->stepper, t, y, err);
    if (st != RK_OK)
        return st;
    st = c->G(c->G_ctx, t, y, g);
    return st == RK_OK ? RK_OK : callback_failed(st, t, err);
}

/* function i of G on the dense output, shifted up by shift (G_one when it has that function alone: the same value
 * without the others, e.g. a corner gap without the contact force's trigonometry) */
static rk_status eval_one(rk_event_ctx *c, int i, double shift, double t, double *out, rk_error *err)
{
    double g[RK_MAX_EVENTS];
    rk_status st;
    if (c->G_one != NULL) {
        double y[RK_MAX_Y], gi = 0.0;
        int done = 0;
        rk_error_clear(err);
        st = rk_dense_eval(c->stepper, t, y, err);
        if (st != RK_OK)
            return st;
        st = c->G_one(c->G_ctx, i, t, y, &gi, &done);
        if (st != RK_OK)
            return callback_failed(st, t, err);
        if (done) {
            *out = gi + shift;
            return RK_OK;
        }
        st = c->G(c->G_ctx, t, y, g);
        if (st != RK_OK)
            return callback_failed(st, t, err);
        *out = g[i] + shift;
        return RK_OK;
    }
    st = rk_event_eval(c, t, g, err);
    if (st != RK_OK)
        return st;
    *out = g[i] + shift;
    return RK_OK;
}

rk_status rk_locate(rk_event_ctx *c, int i, double shift, double a, double ga, double b, double gb, double xtol,
                    double *t_out, rk_error *err)
{
    /* ga, gb: the values of the shifted function (the Python's locate(gi, a, ga_i[i] + shift, ...)) */
    int side = 0, n_slow = 0, bisect = 0, iter = 0;
    double half = 0.5 * xtol, width = b - a;
    rk_error_clear(err);
    if (i < 0 || i >= c->n_events || c->n_events > RK_MAX_EVENTS)
        return rk_fail(err, RK_ERR_INTERNAL, "events.locate: function index %d out of range [0, %d)", i,
                       c->n_events);
    while (b - a > xtol) {
        int clamped = 0;
        double t, gt = 0.0;
        rk_status st;
        if (++iter > LOCATE_MAX_ITER)
            return rk_fail(err, RK_ERR_INTERNAL,
                           "events.locate: no convergence in %d iterations on [%.17g, %.17g] with xtol = %.17g",
                           LOCATE_MAX_ITER, a, b, xtol);
        if (bisect) {
            t = 0.5 * (a + b);
        } else {
            t = a + (b - a) * (ga / (ga - gb));
            if (t < a + half) {
                t = a + half;
                clamped = 1;
            } else if (t > b - half) {
                t = b - half;
                clamped = 1;
            }
        }
        st = eval_one(c, i, shift, t, &gt, err);
        if (st != RK_OK)
            return st;
        if (gt > 0.0) {
            if (side == 1) {                /* a moved twice in a row: scale down the far value */
                double m = 1.0 - gt / ga;
                gb *= (m > 0.0) ? m : 0.5;
            }
            a = t;
            ga = gt;
            side = 1;
        } else {
            if (side == -1) {
                double m = (gb != 0.0) ? 1.0 - gt / gb : 0.5;
                ga *= (m > 0.0) ? m : 0.5;
            }
            b = t;
            gb = gt;
            side = -1;
        }
        if (bisect || b - a <= 0.5 * width) {
            width = b - a;
            n_slow = 0;
        } else {
            n_slow += 1;
        }
        bisect = clamped || n_slow >= 2;
    }
    *t_out = b;
    return RK_OK;
}

rk_status rk_earliest_root(rk_event_ctx *c, const int *ids, int n_ids, const double *shifts,
                           const int *has_start, const double *start_t, const double *start_g, double ta,
                           const double *ga, double tb, const double *gb, double xtol, double *t_out, int *i_out,
                           rk_error *err)
{
    int k, found = 0, best_i = -1;
    double best_t = 0.0;
    rk_error_clear(err);
    for (k = 0; k < n_ids; k++) {
        int i = ids[k];
        double shift = shifts[i], ta_i = ta, te;
        const double *ga_i = ga;
        rk_status st;
        if (has_start != NULL && has_start[i] && start_t[i] > ta) {
            ta_i = start_t[i];
            ga_i = start_g + (size_t)i * (size_t)c->n_events;
        }
        st = rk_locate(c, i, shift, ta_i, ga_i[i] + shift, tb, gb[i] + shift, xtol, &te, err);
        if (st != RK_OK)
            return st;
        if (!found || te < best_t) {
            best_t = te;
            best_i = i;
            found = 1;
        }
    }
    if (!found)
        return rk_fail(err, RK_ERR_INTERNAL, "events.earliest_root: no function to locate");
    *t_out = best_t;
    *i_out = best_i;
    return RK_OK;
}

/* the functions ids of G on the dense output at t: through G_one alone where it has them all (the same values
 * as G's, without the pivot force's trigonometry and ag), the other entries of g NAN; else all of G */
static rk_status eval_ids(rk_event_ctx *c, double t, const int *ids, int n_ids, double *g, rk_error *err)
{
    double y[RK_MAX_Y];
    int k;
    rk_status st;
    if (c->G_one == NULL || c->G_one_mask == NULL)
        return rk_event_eval(c, t, g, err);
    if (!c->one_known) {
        c->one_mask = c->G_one_mask(c->G_ctx);
        c->one_known = 1;
    }
    for (k = 0; k < n_ids; k++)
        if (!(c->one_mask >> ids[k] & 1u))
            return rk_event_eval(c, t, g, err);
    rk_error_clear(err);
    st = rk_dense_eval(c->stepper, t, y, err);
    if (st != RK_OK)
        return st;
    for (k = 0; k < c->n_events; k++)
        g[k] = NAN;
    for (k = 0; k < n_ids; k++) {
        int done = 0;
        st = c->G_one(c->G_ctx, ids[k], t, y, &g[ids[k]], &done);
        if (st != RK_OK)
            return callback_failed(st, t, err);
        if (!done) {
            /* (a mask that promised too much: all of G, the same values) */
            st = c->G(c->G_ctx, t, y, g);
            return st == RK_OK ? RK_OK : callback_failed(st, t, err);
        }
    }
    return RK_OK;
}

rk_status rk_first_negative(rk_event_ctx *c, double t0, const double *g0, double t1, const int *ids, int n_ids,
                            int n, int *found, int *neg, int *n_neg, double *ta, double *ga, double *tb,
                            double *gb, rk_error *err)
{
    int j, k, ne = c->n_events;
    double a = t0, g_a[RK_MAX_EVENTS], gj[RK_MAX_EVENTS];
    rk_error_clear(err);
    memcpy(g_a, g0, sizeof(double) * (size_t)ne);
    *found = 0;
    *n_neg = 0;
    for (j = 1; j < n; j++) {
        double tj = t0 + (t1 - t0) * j / (double)n;
        int m = 0;
        rk_status st = eval_ids(c, tj, ids, n_ids, gj, err);
        if (st != RK_OK)
            return st;
        for (k = 0; k < n_ids; k++)
            if (gj[ids[k]] <= 0.0)
                neg[m++] = ids[k];
        if (m > 0) {
            *found = 1;
            *n_neg = m;
            *ta = a;
            memcpy(ga, g_a, sizeof(double) * (size_t)ne);
            *tb = tj;
            memcpy(gb, gj, sizeof(double) * (size_t)ne);
            return RK_OK;
        }
        a = tj;
        memcpy(g_a, gj, sizeof(double) * (size_t)ne);
    }
    return RK_OK;
}

int rk_may_dip(double g0, double gm, double g1)
{
    double lo = (g1 < g0) ? g1 : g0;        /* Python's min(g0, g1) */
    double c, b, x;
    if (gm < lo)
        return 1;
    c = 2.0 * (g0 + g1) - 4.0 * gm;
    if (c <= 0.0)
        return 0;
    b = g1 - g0 - c;
    x = -b / (2.0 * c);
    return 0.0 < x && x < 1.0 && g0 + 0.5 * b * x < 0.5 * lo;
}

rk_status rk_dip_search(rk_event_ctx *c, const int *armed, const double *g_prev, const double *g_new, int n,
                        int *hits, int *n_hits, double *ta, double *tb, double *ga, double *gb, int *used_dense,
                        rk_error *err)
{
    rk_stepper *s = c->stepper;
    double t0 = s->t_old, t1 = s->t, tm = 0.5 * (t0 + t1);
    double y_mid[RK_MAX_Y], gm[RK_MAX_EVENTS];
    int dip[RK_MAX_EVENTS], n_dip = 0, i, ne = c->n_events, n_contacts = c->n_events - 1, found = 0;
    rk_status st;
    rk_error_clear(err);
    rk_hermite_mid(s, y_mid);
    st = c->G(c->G_ctx, tm, y_mid, gm);
    if (st != RK_OK) {
        if (err != NULL && err->status == st && err->message[0] != '\0')
            return st;
        return rk_fail(err, st, "events: the event functions failed (%s) at t = %.17g s", rk_status_name(st), tm);
    }
    for (i = 0; i < n_contacts; i++)
        if (armed[i] && rk_may_dip(g_prev[i], gm[i], g_new[i]))
            dip[n_dip++] = i;
    *n_hits = 0;
    *used_dense = 0;
    if (n_dip > 0) {
        *used_dense = 1;
        st = rk_first_negative(c, t0, g_prev, t1, dip, n_dip, n, &found, hits, n_hits, ta, ga, tb, gb, err);
        if (st != RK_OK)
            return st;
        if (found)
            return RK_OK;
        *n_hits = 0;
    }
    *ta = t0;
    *tb = t1;
    rk_copy(ga, g_prev, ne);
    rk_copy(gb, g_new, ne);
    return RK_OK;
}

/* math.ulp(x) */
static double py_ulp(double x)
{
    double up;
    if (isnan(x) || isinf(x))
        return fabs(x);
    x = fabs(x);
    up = nextafter(x, INFINITY);
    if (isinf(up))
        return x - nextafter(x, -INFINITY);
    return up - x;
}

rk_status rk_sinks(rk_event_ctx *c, const int *ids, int n_ids, double t0, double t1, int n, double level,
                   int *sunk, rk_error *err)
{
    double d = t1 - t0, a1 = fabs(t1), g[RK_MAX_EVENTS];
    double xtol = 4.0 * py_ulp(1.0 > a1 ? 1.0 : a1);        /* max(abs(t1), 1.0) */
    int j, k;
    rk_status st;
    rk_error_clear(err);
    *sunk = 0;
    for (j = 1; j < n; j++) {
        st = eval_ids(c, t0 + d * j / (double)n, ids, n_ids, g, err);
        if (st != RK_OK)
            return st;
        for (k = 0; k < n_ids; k++)
            if (g[ids[k]] < -level) {
                *sunk = 1;
                return RK_OK;
            }
    }
    while (d > xtol) {
        d *= 0.25;
        st = eval_ids(c, t0 + d, ids, n_ids, g, err);
        if (st != RK_OK)
            return st;
        for (k = 0; k < n_ids; k++)
            if (g[ids[k]] < -level) {
                *sunk = 1;
                return RK_OK;
            }
    }
    return RK_OK;
}

rk_status rk_bounce_search(rk_event_ctx *c, int i, double t0, double t1, double level, int *found, double *t,
                           double *g, rk_error *err)
{
    double d = t1 - t0, a1 = fabs(t1);
    double xtol = 4.0 * py_ulp(1.0 > a1 ? 1.0 : a1);        /* max(abs(t1), 1.0) */
    rk_error_clear(err);
    *found = 0;
    while (d > xtol) {
        double tt, gt[RK_MAX_EVENTS];
        rk_status st;
        d *= 0.25;
        tt = t0 + d;
        st = rk_event_eval(c, tt, gt, err);
        if (st != RK_OK)
            return st;
        if (gt[i] > level) {
            *found = 1;
            *t = tt;
            memcpy(g, gt, sizeof(double) * (size_t)c->n_events);
            return RK_OK;
        }
        /* (below level: closer to the start) */
    }
    return RK_OK;
}

int rk_parabola_peak(double f0, double fm, double f1, double *x, double *value)
{
    double c = 2.0 * (f0 + f1) - 4.0 * fm, b, xv;
    if (c >= 0.0)
        return 0;
    b = f1 - f0 - c;
    xv = -b / (2.0 * c);
    if (!(0.0 < xv && xv < 1.0))
        return 0;
    *x = xv;
    *value = f0 + (b + c * xv) * xv;
    return 1;
}

/* Brent's golden-section fraction (events._CGOLD) */
#define RK_CGOLD 0.3819660112501051

rk_status rk_brent_max(rk_scalar_fn f, void *ctx, double a, double b, double x, double fx, int has_fx, double xtol,
                       int max_iter, double *t_out, double *f_out, int *has_out, rk_error *err)
{
    /* minimises g = -f; None is +inf */
    double gx = has_fx ? -fx : INFINITY;
    double w = x, v = x, gw = gx, gv = gx, d = 0.0, e = 0.0;
    int it;
    rk_error_clear(err);
    for (it = 0; it < max_iter; it++) {
        double xm = 0.5 * (a + b), tol2 = 2.0 * xtol, u, fu, gu;
        int golden = 1, has_u = 0;
        rk_status st;
        if (fabs(x - xm) <= tol2 - 0.5 * (b - a))
            break;
        if (fabs(e) > xtol) {
            double r = (x - w) * (gx - gv);
            double q = (x - v) * (gx - gw);
            double p = (x - v) * q - (x - w) * r, e_old;
            q = 2.0 * (q - r);
            if (q > 0.0)
                p = -p;
            q = fabs(q);
            e_old = e;
            e = d;
            if (q != 0.0 && fabs(p) < fabs(0.5 * q * e_old) && q * (a - x) < p && p < q * (b - x)) {
                d = p / q;
                golden = 0;
                if ((x + d) - a < tol2 || b - (x + d) < tol2)
                    d = (xm >= x) ? xtol : -xtol;
            }
        }
        if (golden) {
            e = (x >= xm) ? (a - x) : (b - x);
            d = RK_CGOLD * e;
        }
        u = (fabs(d) >= xtol) ? x + d : x + ((d >= 0.0) ? xtol : -xtol);
        fu = 0.0;
        st = f(ctx, u, &fu, &has_u);
        if (st != RK_OK) {
            if (err != NULL && err->status == st && err->message[0] != '\0')
                return st;
            return rk_fail(err, st, "events.brent_max: the function failed (%s) at t = %.17g s", rk_status_name(st), u);
        }
        gu = has_u ? -fu : INFINITY;
        if (gu <= gx) {
            if (u >= x)
                a = x;
            else
                b = x;
            v = w;
            gv = gw;
            w = x;
            gw = gx;
            x = u;
            gx = gu;
        } else {
            if (u < x)
                a = u;
            else
                b = u;
            if (gu <= gw || w == x) {
                v = w;
                gv = gw;
                w = u;
                gw = gu;
            } else if (gu <= gv || v == x || v == w) {
                v = u;
                gv = gu;
            }
        }
    }
    *t_out = x;
    *has_out = gx != INFINITY;
    *f_out = *has_out ? -gx : 0.0;
    return RK_OK;
}
