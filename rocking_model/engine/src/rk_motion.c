/* rk_motion.c -- the ground motions as C data (part E): the formulas of rocking_model/ground_motion.py,
 * expression by expression, so that the driver reads the same ag bit for bit (DESIGN.md "Numerics").
 * Pinned: tests/test_engine_api.py compares every kind with the Python class. */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_motion.h"

#include <math.h>
#include <string.h>

/** math.pi as a double (3.141592653589793) */
#define RK_PI 3.14159265358979323846

static void motion_clear(rk_motion *m, rk_motion_kind kind)
{
    memset(m, 0, sizeof(*m));
    m->kind = kind;
    m->inner = NULL;
    m->t = m->ag = NULL;
    m->fn = NULL;
    m->fn_breakpoint = NULL;
    m->fn_continuous = NULL;
    m->ctx = NULL;
}

void rk_motion_constant(rk_motion *m, double value)
{
    motion_clear(m, RK_MOTION_CONSTANT);
    m->value = value;
    m->constant = 1;
}

void rk_motion_linear(rk_motion *m, double value, double rate, double t_ref)
{
    motion_clear(m, RK_MOTION_LINEAR);
    m->value = value;
    m->rate = rate;
    m->t_ref = t_ref;
}

rk_status rk_motion_sampled(rk_motion *m, const double *t, const double *ag, long long n, rk_error *err)
{
    long long i;
    if (t == NULL || ag == NULL || n < 2)
        return rk_fail(err, RK_ERR_VALUE, "ground motion: t and ag must be 1-D arrays of equal length >= 2, got "
                       "%lld samples", n);
    for (i = 0; i < n; i++) {
        if (!isfinite(t[i]) || !isfinite(ag[i]))
            return rk_fail(err, RK_ERR_VALUE, "ground motion: t and ag must be finite; allowed range (-inf, inf)");
    }
    for (i = 1; i < n; i++) {
        if (!(t[i] - t[i - 1] > 0.0))
            return rk_fail(err, RK_ERR_VALUE, "ground motion: t must be strictly increasing");
    }
    motion_clear(m, RK_MOTION_SAMPLED);
    m->t = t;
    m->ag = ag;
    m->n = n;
    m->i_last = 0;
    return RK_OK;
}

rk_status rk_motion_sine(rk_motion *m, double A, double omega_p, double t0, rk_error *err)
{
    if (!isfinite(A))
        return rk_fail(err, RK_ERR_VALUE, "A = %g is not finite; allowed range (-inf, inf)", A);
    if (!isfinite(omega_p) || !(omega_p > 0.0))
        return rk_fail(err, RK_ERR_VALUE, "omega_p = %g is out of range; allowed range (0, inf)", omega_p);
    if (!isfinite(t0))
        return rk_fail(err, RK_ERR_VALUE, "t0 = %g is not finite; allowed range (-inf, inf)", t0);
    motion_clear(m, RK_MOTION_SINE);
    m->A = A;
    m->omega_p = omega_p;
    m->t0 = t0;
    m->t1 = t0 + 2.0 * RK_PI / omega_p;     /* self.t0 + 2.0 * math.pi / self.omega_p */
    return RK_OK;
}

/** ground_motion.JUMP_SLIVER: [s, relative to max(1, |t|)] the sliver after a jump */
#define RK_JUMP_SLIVER 1e-10

/** _jump_breakpoints((a, b)): a, a + sliver, b, b + sliver, sorted */
static void jump_breakpoints(double a, double b, double *bp)
{
    int i, j;
    bp[0] = a;
    bp[1] = a + RK_JUMP_SLIVER * (fabs(a) > 1.0 ? fabs(a) : 1.0);
    bp[2] = b;
    bp[3] = b + RK_JUMP_SLIVER * (fabs(b) > 1.0 ? fabs(b) : 1.0);
    for (i = 1; i < 4; i++) {       /* insertion sort (sorted() of four finite values) */
        double x = bp[i];
        for (j = i; j > 0 && bp[j - 1] > x; j--)
            bp[j] = bp[j - 1];
        bp[j] = x;
    }
}

static rk_status pulse_checks(double A, double w, const char *w_name, double t0, const char *t0_name, rk_error *err)
{
    if (!isfinite(A))
        return rk_fail(err, RK_ERR_VALUE, "A = %g is not finite; allowed range (-inf, inf)", A);
    if (!isfinite(w) || !(w > 0.0))
        return rk_fail(err, RK_ERR_VALUE, "%s = %g is out of range; allowed range (0, inf)", w_name, w);
    if (!isfinite(t0))
        return rk_fail(err, RK_ERR_VALUE, "%s = %g is not finite; allowed range (-inf, inf)", t0_name, t0);
    return RK_OK;
}

rk_status rk_motion_cosine(rk_motion *m, double A, double omega_p, double t0, rk_error *err)
{
    rk_status st = pulse_checks(A, omega_p, "omega_p", t0, "t0", err);
    if (st != RK_OK)
        return st;
    motion_clear(m, RK_MOTION_COSINE);
    m->A = A;
    m->omega_p = omega_p;
    m->t0 = t0;
    m->t1 = t0 + 2.0 * RK_PI / omega_p;
    jump_breakpoints(m->t0, m->t1, m->bp);
    return RK_OK;
}

rk_status rk_motion_ricker(rk_motion *m, double A, double omega_p, double t_c, rk_error *err)
{
    rk_status st = pulse_checks(A, omega_p, "omega_p", t_c, "t_c", err);
    if (st != RK_OK)
        return st;
    motion_clear(m, RK_MOTION_RICKER);
    m->A = A;
    m->omega_p = omega_p;
    m->t0 = t_c;
    return RK_OK;
}

rk_status rk_motion_rect(rk_motion *m, double A, double duration, double t0, rk_error *err)
{
    rk_status st = pulse_checks(A, duration, "duration", t0, "t0", err);
    if (st != RK_OK)
        return st;
    motion_clear(m, RK_MOTION_RECT);
    m->A = A;
    m->t0 = t0;
    m->t1 = t0 + duration;
    jump_breakpoints(m->t0, m->t1, m->bp);
    return RK_OK;
}

/** bisect.bisect_right(t[0..n-1], x): the first index whose value is > x (n if none); NaN compares false
 *  as in Python (x < a[mid] false: lo moves right). */
static long long bisect_right(const double *t, long long n, double x)
{
    long long lo = 0, hi = n;
    while (lo < hi) {
        long long mid = (lo + hi) / 2;
        if (x < t[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/** SampledMotion.__call__ with the interval cache *i_last (SampledMotion._i). */
static double sampled_eval(const rk_motion *m, double t, long long *i_last)
{
    const double *tl = m->t, *al = m->ag;
    long long n = m->n, i = *i_last;
    if (!(tl[i] <= t && t < tl[i + 1])) {
        if (t < tl[0] || t > tl[n - 1])
            return 0.0;
        /* the neighbouring intervals first: a step's stages and its end at a breakpoint move between adjacent
         * intervals (bisect's answer, bisect_right - 1, is the one interval [t_j, t_j+1) that holds t, so a
         * neighbour that holds it is that interval) */
        if (i + 2 < n && tl[i + 1] <= t && t < tl[i + 2])
            i = i + 1;
        else if (i >= 1 && tl[i - 1] <= t && t < tl[i])
            i = i - 1;
        else
            i = bisect_right(tl, n, t) - 1;
        if (i >= n - 1)
            return al[n - 1];
        *i_last = i;
    }
    return rk_motion_sampled_value(m, i, t);
}

static double eval_const(const rk_motion *m, double t, long long *cache, int *failed, char *msg)
{
    switch (m->kind) {
    case RK_MOTION_CONSTANT:
        return m->value;
    case RK_MOTION_LINEAR:
        return m->value + m->rate * (t - m->t_ref);
    case RK_MOTION_SAMPLED:
        return sampled_eval(m, t, cache);
    case RK_MOTION_SINE:
        if (t < m->t0 || t > m->t1)
            return 0.0;
        return m->A * sin(m->omega_p * (t - m->t0));
    case RK_MOTION_COSINE:
        if (t <= m->t0 || t > m->t1)
            return 0.0;
        return m->A * cos(m->omega_p * (t - m->t0));
    case RK_MOTION_RECT:
        return (m->t0 < t && t <= m->t1) ? m->A : 0.0;
    case RK_MOTION_RICKER: {
        /* 0.25 * (w * w) as RickerPulse.__call__ (a product, not pow: the same rounding on every CPU) */
        double w = m->omega_p * (t - m->t0);
        double x = 0.25 * (w * w);
        return m->A * (1.0 - 2.0 * x) * exp(-x);
    }
    case RK_MOTION_SCALED: {
        long long inner_cache = m->inner->i_last;
        return m->factor * eval_const(m->inner, t, &inner_cache, failed, msg);
    }
    case RK_MOTION_CALLBACK: {
        int bad = 0;
        double value = m->fn(m->ctx, t, &bad, msg);
        if (bad && failed != NULL)
            *failed = 1;
        return value;
    }
    }
    return NAN;
}

double rk_motion_eval(rk_motion *m, double t, int *failed, char *msg)
{
    return eval_const(m, t, &m->i_last, failed, msg);
}

double rk_motion_next_breakpoint(rk_motion *m, double t)
{
    switch (m->kind) {
    case RK_MOTION_CONSTANT:
    case RK_MOTION_LINEAR:
        return INFINITY;
    case RK_MOTION_SAMPLED: {
        /* bisect_right's answer is j + 1 where t[j] <= t < t[j + 1]: the interval of the last evaluation (or the
         * next one) holds t at every communication step of a record; else the bisection */
        long long i = m->i_last, j;
        if (i + 1 < m->n && m->t[i] <= t && t < m->t[i + 1])
            j = i + 1;
        else if (i + 2 < m->n && m->t[i + 1] <= t && t < m->t[i + 2])
            j = i + 2;
        else
            j = bisect_right(m->t, m->n, t);
        return j < m->n ? m->t[j] : INFINITY;
    }
    case RK_MOTION_SINE:
        if (m->t0 > t)
            return m->t0;
        if (m->t1 > t)
            return m->t1;
        return INFINITY;
    case RK_MOTION_COSINE:
    case RK_MOTION_RECT: {
        int i;
        for (i = 0; i < 4; i++) {
            if (m->bp[i] > t)
                return m->bp[i];
        }
        return INFINITY;
    }
    case RK_MOTION_RICKER:
        return INFINITY;
    case RK_MOTION_SCALED:
        return rk_motion_next_breakpoint((rk_motion *)(void *)m->inner, t);
    case RK_MOTION_CALLBACK:
        if (m->fn_breakpoint != NULL) {
            int bad = 0;
            char msg[RK_MSG_LEN];
            double tb = m->fn_breakpoint(m->ctx, t, &bad, msg);
            /* a failed (or NaN) answer is no breakpoint: the call still ends within its work budget, and the
             * extension re-raises the callback's exception with the state restored */
            return (bad || tb != tb) ? INFINITY : tb;
        }
        return INFINITY;
    }
    return INFINITY;
}

int rk_motion_continuous_at(const rk_motion *m, double tb)
{
    switch (m->kind) {
    case RK_MOTION_SAMPLED:
        return m->t[0] < tb && tb < m->t[m->n - 1];
    case RK_MOTION_SCALED:
        return rk_motion_continuous_at(m->inner, tb);
    case RK_MOTION_CALLBACK:
        return m->fn_continuous != NULL ? m->fn_continuous(m->ctx, tb) : 0;
    default:
        return 0;
    }
}

/* ------------------------------------------------------------------------------------------ two components */

int rk_motion_pair_constant(const rk_motion *ag, const rk_motion *ag_v)
{
    return ag->constant && (ag_v == NULL || ag_v->constant);
}

double rk_motion_pair_next_breakpoint(rk_motion *ag, rk_motion *ag_v, double t)
{
    double tb = rk_motion_next_breakpoint(ag, t), tv;
    if (ag_v == NULL)
        return tb;
    tv = rk_motion_next_breakpoint(ag_v, t);
    return tv < tb ? tv : tb;
}

/* continuous at tb, or no breakpoint there (the first breakpoint after the float just below tb is not tb) */
static int component_continuous_at(rk_motion *m, double tb)
{
    if (rk_motion_next_breakpoint(m, nextafter(tb, -INFINITY)) != tb)
        return 1;
    return rk_motion_continuous_at(m, tb);
}

int rk_motion_pair_continuous_at(rk_motion *ag, rk_motion *ag_v, double tb)
{
    if (ag_v == NULL)
        return rk_motion_continuous_at(ag, tb);
    return component_continuous_at(ag, tb) && component_continuous_at(ag_v, tb);
}
