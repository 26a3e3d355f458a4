/* rk_motion.h -- the ground acceleration ag(t) as C data (part E).
 *
 * C counterpart of the rocking_model.ground_motion classes the integrators read: ag(t), ``constant``,
 * next_breakpoint(t) and continuous_at(tb). Same formulas and operation order as the Python __call__ of
 * each class, so that the driver sees the same values bit for bit. A motion is borrowed by the engine for
 * the duration of one advance / sample call only (never stored past it).
 * Pinned: tests/test_engine_api.py compares rk_motion_eval / next_breakpoint with the Python classes. */
#ifndef RK_MOTION_H
#define RK_MOTION_H

#include "rk_common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum rk_motion_kind {
    RK_MOTION_CONSTANT = 0,     /**< ConstantMotion: ag = value (constant: the Python's ag.constant path) */
    RK_MOTION_LINEAR = 1,       /**< LinearMotion: ag = value + rate (t - t_ref), no breakpoints */
    RK_MOTION_SAMPLED = 2,      /**< SampledMotion: linear between samples t[i], ag[i]; 0 outside; breakpoints
                                     at the samples, continuous at the inner ones */
    RK_MOTION_SINE = 3,         /**< SinePulse: A sin(omega_p (t - t0)) on [t0, t0 + 2 pi / omega_p] */
    RK_MOTION_CALLBACK = 4,     /**< any other GroundMotion through C callbacks (the extension wraps a Python
                                     callable: slow, exact; a failing call sets *failed and the advance
                                     returns RK_ERR_VALUE with the callback's message) */
    RK_MOTION_SCALED = 5,       /**< ScaledMotion: factor * inner */
    /* (added by part E: the pulses of pulse_from_parameters in C, so that ensembles of pulses never call back) */
    RK_MOTION_COSINE = 6,       /**< CosinePulse: A cos(omega_p (t - t0)) on (t0, t1]; jumps at t0 and t1 */
    RK_MOTION_RICKER = 7,       /**< RickerPulse: A (1 - 2 x) exp(-x), x = (omega_p (t - t_c))^2 / 4 (t_c in t0) */
    RK_MOTION_RECT = 8          /**< RectangularPulse: A on (t0, t1]; jumps at t0 and t1 */
} rk_motion_kind;

typedef struct rk_motion rk_motion;
struct rk_motion {
    rk_motion_kind kind;
    double value, rate, t_ref;          /**< CONSTANT (value), LINEAR */
    const double *t, *ag;               /**< SAMPLED: borrowed arrays of n samples (t strictly increasing) */
    long long n;
    long long i_last;                   /**< SAMPLED: interval of the last evaluation (SampledMotion._i) */
    double A, omega_p, t0, t1;          /**< SINE (t1 = t0 + 2 pi / omega_p, computed as the Python does);
                                             COSINE, RECT (t1 the end); RICKER (t0 = t_c) */
    double bp[4];                       /**< COSINE, RECT: the jump breakpoints (ground_motion._jump_breakpoints:
                                             t0, t0 + sliver, t1, t1 + sliver, sorted) */
    double factor;                      /**< SCALED */
    const rk_motion *inner;             /**< SCALED */
    /** CALLBACK: ag(t); set *failed = 1 and write msg (RK_MSG_LEN) on failure */
    double (*fn)(void *ctx, double t, int *failed, char *msg);
    /** CALLBACK: next breakpoint after t (INFINITY: none); NULL: none. A failure (or a NaN) is read as none by
     *  rk_motion_next_breakpoint (the extension then re-raises the Python exception with the state restored) */
    double (*fn_breakpoint)(void *ctx, double t, int *failed, char *msg);
    /** CALLBACK: continuity at a breakpoint; NULL: not continuous (GroundMotion.continuous_at's default, a
     *  jump) */
    int (*fn_continuous)(void *ctx, double tb);
    void *ctx;
    int constant;                       /**< 1: the Python's ``ag.constant`` (CONSTANT, SCALED of constant) */
    /** (added by part E) the identity of the caller's motion object across calls: 0 = a new motion at every
     *  call; otherwise equal values mean the same GroundMotion object (the extension passes id(gm), the object
     *  kept alive meanwhile). The event-driven scheme keys its stepper's rhs on it as the Python's closure cache
     *  keys on id(ag): the same object in two advances carries the live stepper on (FSAL, h_abs). Set to 0 by
     *  the constructors. */
    unsigned long long identity;
};

/** Constructors (fill every field; no allocation). */
void rk_motion_constant(rk_motion *m, double value);
void rk_motion_linear(rk_motion *m, double value, double rate, double t_ref);
rk_status rk_motion_sampled(rk_motion *m, const double *t, const double *ag, long long n, rk_error *err);
rk_status rk_motion_sine(rk_motion *m, double A, double omega_p, double t0, rk_error *err);
/** CosinePulse(A, omega_p, t0), RickerPulse(A, omega_p, t_c), RectangularPulse(A, duration, t0). (Added.) */
rk_status rk_motion_cosine(rk_motion *m, double A, double omega_p, double t0, rk_error *err);
rk_status rk_motion_ricker(rk_motion *m, double A, double omega_p, double t_c, rk_error *err);
rk_status rk_motion_rect(rk_motion *m, double A, double duration, double t0, rk_error *err);

/** SampledMotion.__call__ on the interval [t[i], t[i + 1]] that holds t: the linear interpolation */
static inline double rk_motion_sampled_value(const rk_motion *m, long long i, double t)
{
    const double *tl = m->t, *al = m->ag;
    return al[i] + (al[i + 1] - al[i]) * (t - tl[i]) / (tl[i + 1] - tl[i]);
}

/** ag(t) of a SAMPLED motion whose cached interval holds t (a step's stages, between two samples): 1 with
 *  *out the value rk_motion_eval gives, 0 for any other motion or t (then call rk_motion_eval). Inline: every
 *  Runge-Kutta stage reads ag. */
static inline int rk_motion_sampled_cached(const rk_motion *m, double t, double *out)
{
    long long i = m->i_last;
    if (m->kind != RK_MOTION_SAMPLED || !(m->t[i] <= t && t < m->t[i + 1]))
        return 0;
    *out = rk_motion_sampled_value(m, i, t);
    return 1;
}

/** ag(t) [m/s2]; a CALLBACK failure sets *failed (may be NULL for the others) and msg. */
double rk_motion_eval(rk_motion *m, double t, int *failed, char *msg);
/** GroundMotion.next_breakpoint: the first breakpoint strictly after t (INFINITY: none). */
double rk_motion_next_breakpoint(rk_motion *m, double t);
/** GroundMotion.continuous_at. */
int rk_motion_continuous_at(const rk_motion *m, double tb);

/* The two-component motion (ground_motion.TwoComponentMotion): the horizontal ag and the vertical ag_v
 * (NULL: none, GroundMotion.vertical is None; every function then reduces to the horizontal one's exactly). */
/** TwoComponentMotion.constant: both components constant. */
int rk_motion_pair_constant(const rk_motion *ag, const rk_motion *ag_v);
/** TwoComponentMotion.next_breakpoint: the earlier of both components' next breakpoints after t. */
double rk_motion_pair_next_breakpoint(rk_motion *ag, rk_motion *ag_v, double t);
/** TwoComponentMotion.continuous_at: both components continuous at tb (a component without a breakpoint at tb
 *  is continuous there). */
int rk_motion_pair_continuous_at(rk_motion *ag, rk_motion *ag_v, double tb);

#ifdef __cplusplus
}
#endif
#endif /* RK_MOTION_H */
