/* rk_rk.h -- the Runge-Kutta pairs, their dense output and the event location (part C).
 *
 * Ports of rocking_model/integrators/rk.py (ExplicitRK: step with error control, restart, initial step,
 * hermite_mid, dense_output), dop853.py and dopri5.py (tableaux, error norms, interpolants) and events.py
 * (locate, earliest_root, first_negative, may_dip, dip_search, bounce_search).
 *
 * One source of truth for the tableaux: rk_tableaux.h is GENERATED at build time by
 * rocking_model/engine/gen_rk.py from the lists in dop853.py / dopri5.py (read with ast, no import: the build
 * environment has no numpy), and holds the coefficients plus, per tableau, the nonzero pattern. The stage,
 * error and dense-output sums are evaluated in the Python's order with the Python's zero terms left out
 * (rk._lincomb), so that a step agrees with the Python bit for bit (DESIGN.md "Numerics"). Pinned step by
 * step (tests/test_engine_rk.py).
 *
 * The right-hand side and the event functions are C callbacks with a context pointer (the driver's segment:
 * model, mode, ground motion): never Python. */
#ifndef RK_RK_H
#define RK_RK_H

#include "rk_common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** rk.py's step-size constants. */
#define RK_SAFETY 0.9
#define RK_MIN_FACTOR 0.2
#define RK_MAX_FACTOR 10.0
/** most stages of a pair, dense-output stages included (DOP853: 12 + 4 extra = 16) */
#define RK_MAX_STAGES 16
/** most dense-output coefficient rows per component (DOP853: 7 (y_old, Q rows...), DOPRI5: 5) */
#define RK_MAX_DENSE 8

/** dy = f(t, y) of size n; returns RK_OK, or a status that aborts the step (propagated by rk_step). */
typedef rk_status (*rk_rhs_fn)(void *ctx, double t, const double *y, double *dy);
/** The second component of f(t, y) of a two-component system whose first is y1 (r_ddot of one degree of freedom),
 *  from and to registers; bit for bit what the rk_rhs_fn of the same stepper writes; never fails. */
typedef double (*rk_rhs1_fn)(void *ctx, double t, double y0, double y1);
struct rk_model;
/** A model's own one-dof kernel (rk_model_ops.mode_acc1): r_ddot of mode at (y0, y1) under the inputs ag, ag_v. */
typedef double (*rk_acc1_fn)(const struct rk_model *m, int mode, double y0, double y1, double ag, double ag_v);
/** G(t, y): the event functions (n_events values) of the current mode. */
typedef rk_status (*rk_event_fn)(void *ctx, double t, const double *y, double *g);
/** G(t, y)[i] alone where that is cheaper than all of G and bit for bit the same value: *done = 1 with *gi set, or
 *  *done = 0 (the caller evaluates G). Any work of G that can fail or call back (ag(t)) is done as by G. */
typedef rk_status (*rk_event_one_fn)(void *ctx, int i, double t, const double *y, double *gi, int *done);

/** A tableau with its generated coefficients (rk_tableaux.h, static const data). Layout private to part C. */
typedef struct rk_tableau rk_tableau;
/** The tableau of a method code (RK_METHOD_DOP853, RK_METHOD_DOPRI5); NULL if none. */
const rk_tableau *rk_tableau_of(rk_method method);
/** Its name ("DOP853", "DOPRI5"), order and error order. */
const char *rk_tableau_name(const rk_tableau *tab);

/** ExplicitRK: the stepper of one smooth segment. Plain data (copied with the engine at a checkpoint: the
 *  Python's ``_live`` stepper carries over between advances, so it is part of the state). */
typedef struct rk_stepper {
    const rk_tableau *tab;
    rk_rhs_fn fun;                  /**< set by the driver before every call (not part of the copied state's
                                         meaning: the driver re-binds it after a restore) */
    void *ctx;
    /** optional (NULL: none; bound with fun, by the driver): fun as an rk_rhs1_fn, which rk_step's stages of DOP853 on
     *  two components call instead */
    rk_rhs1_fn fun1;
    /** optional (NULL: none; bound with fun1, by the driver, where the input is constant over the segment): fun1 as
     *  the model's kernel itself, acc1(acc1_m, acc1_mode, y0, y1, acc1_ag, acc1_ag_v), the same bits without
     *  fun1's layer: one call less at each of a step's stages, the cost a communication step of a held input pays
     *  most often */
    rk_acc1_fn acc1;
    const struct rk_model *acc1_m;
    int acc1_mode;
    double acc1_ag, acc1_ag_v;
    int n;                          /**< state size (0: nothing moves, steps only advance t) */
    double t, y[RK_MAX_Y], f[RK_MAX_Y];          /**< current point and its derivative (FSAL) */
    double t_old, y_old[RK_MAX_Y], f_old[RK_MAX_Y];
    double K[RK_MAX_STAGES][RK_MAX_Y];           /**< stages of the last step (dense output) */
    int n_K;                        /**< stages filled (the 3 extra DOP853 dense stages are added lazily) */
    double rtol, atol[RK_MAX_Y];
    double max_step;                /**< [s] (INFINITY: none) */
    double h_abs;                   /**< [s] next step size */
    long long n_steps, n_rejected;
    int failed;                     /**< set by rk_step when it accepted a step at the smallest size above
                                         tolerance; the caller reports failure[] and clears it */
    char failure[RK_MSG_LEN];
    int dense_ready;                /**< 1: Q below holds the interpolant of the last step */
    double Q[RK_MAX_DENSE][RK_MAX_Y];
} rk_stepper;

/** ExplicitRK.__init__: start at (t0, y0) with tolerances rtol, atol[n], max_step; first_step <= 0 or NAN:
 *  the initial-step heuristic (_initial_step); f0 NULL: evaluated. */
rk_status rk_stepper_init(rk_stepper *s, const rk_tableau *tab, rk_rhs_fn fun, void *ctx, double t0,
                          const double *y0, int n, double rtol, const double *atol, double max_step,
                          double first_step, const double *f0, rk_error *err);
/** ExplicitRK.restart: start again at (t0, y0) under a new rhs, same size, tolerances and max_step;
 *  first_step NAN: the heuristic. */
rk_status rk_stepper_restart(rk_stepper *s, rk_rhs_fn fun, void *ctx, double t0, const double *y0,
                             double first_step, rk_error *err);
/** The initial-step heuristic (_initial_step) at the current point [s]. */
rk_status rk_initial_step(rk_stepper *s, double *h, rk_error *err);
/** ExplicitRK.step: one accepted step ending at t_bound at the latest. RK_ERR_NONFINITE with the Python's
 *  FloatingPointError message when even the smallest step is not finite. */
rk_status rk_step(rk_stepper *s, double t_bound, rk_error *err);
/** ExplicitRK.hermite_mid: cubic Hermite estimate of y at the middle of the last step (no evaluation). */
void rk_hermite_mid(const rk_stepper *s, double *y_mid);
/** DenseOutput(t): y at t in [t_old, t] of the last step (exact end values at t == s->t; builds the
 *  interpolant on first use, which may evaluate the rhs: hence non-const and a status). Always the LAST step
 *  of the stepper (a Python DenseOutput object keeps its own step after further steps; the C does not), and
 *  DOP853's extra stages call s->fun / s->ctx as bound at the time of the call. */
rk_status rk_dense_eval(rk_stepper *s, double t, double *y, rk_error *err);

/* ------------------------------------------------------------------------------------------ events.py */
/** The event functions on the dense output of the last step of a stepper: G(t, dense(t)). */
typedef struct rk_event_ctx {
    rk_stepper *stepper;        /**< dense output source */
    rk_event_fn G;
    void *G_ctx;
    int n_events;
    rk_event_one_fn G_one;      /**< optional (NULL: none): one function of G, for locate's iterations */
    /** optional (NULL: none): the functions G_one has (bit i: function i; they depend on the mode only), asked
     *  once per context by the sub-sampling (first_negative, sinks), which then evaluates those functions alone
     *  when they are all it reads */
    unsigned (*G_one_mask)(void *ctx);
    int one_known;              /**< 0: one_mask not asked yet (set 0 with the context) */
    unsigned one_mask;
} rk_event_ctx;

/** G(t, dense(t)) into g. */
rk_status rk_event_eval(rk_event_ctx *c, double t, double *g, rk_error *err);
/** events.locate on function i shifted up by ``shift``: regula falsi with Anderson-Bjorck on a bracket with
 *  ga > 0 >= gb; *t_out = a time with g <= 0 within xtol of the root. ga and gb are values of the SHIFTED
 *  function (the Python's locate(gi, a, ga_i[i] + shift, b, gb[i] + shift, xtol)); shift is added to every
 *  evaluation G(t, dense(t))[i]. */
rk_status rk_locate(rk_event_ctx *c, int i, double shift, double a, double ga, double b, double gb, double xtol,
                    double *t_out, rk_error *err);
/** events.earliest_root over the functions ``ids`` (n_ids of them), shifts per function, starts: per function
 *  has_start[i] with (start_t[i], start_g[i*n_events ...]) a later left end (bounce_search), or NULL.
 *  Writes the earliest time and its function index. */
rk_status rk_earliest_root(rk_event_ctx *c, const int *ids, int n_ids, const double *shifts,
                           const int *has_start, const double *start_t, const double *start_g, double ta,
                           const double *ga, double tb, const double *gb, double xtol, double *t_out, int *i_out,
                           rk_error *err);
/** events.first_negative: *found 0 (None) or 1 with the functions at or below zero (neg, n_neg) and the
 *  sub-interval (ta, ga[n_events], tb, gb[n_events]). Where G_one has all the functions ids, the sub-samples
 *  hold those alone (the others NAN): ga and gb are exact for ids, and ga for all when ta = t0 (g0). */
rk_status rk_first_negative(rk_event_ctx *c, double t0, const double *g0, double t1, const int *ids, int n_ids,
                            int n, int *found, int *neg, int *n_neg, double *ta, double *ga, double *tb,
                            double *gb, rk_error *err);
/** events.may_dip. */
int rk_may_dip(double g0, double gm, double g1);
/** events.dip_search on the last step: armed[n_events]; hits (n_hits, 0: none) with the sub-interval;
 *  *used_dense 1 when the dense output was built (the Python returns ``dense`` rather than None). */
rk_status rk_dip_search(rk_event_ctx *c, const int *armed, const double *g_prev, const double *g_new, int n,
                        int *hits, int *n_hits, double *ta, double *tb, double *ga, double *gb, int *used_dense,
                        rk_error *err);
/** events.sinks: *sunk 1 when one of the functions ids[n_ids] (watched: they start the step at the ground) is
 *  below -level on the interpolant of the last step (n - 1 inner sub-samples, then t0 + (t1 - t0) 4^-k). */
rk_status rk_sinks(rk_event_ctx *c, const int *ids, int n_ids, double t0, double t1, int n, double level,
                   int *sunk, rk_error *err);
/** events.bounce_search: *found 1 with (t, g[n_events]) where function i is above level. */
rk_status rk_bounce_search(rk_event_ctx *c, int i, double t0, double t1, double level, int *found, double *t,
                           double *g, rk_error *err);

/* added by part C (events.py's peak search, used by EventDriven._demand_peak) */
/** events.parabola_peak: 1 with (*x, *value) of the vertex of the parabola through (0, f0), (1/2, fm), (1, f1)
 *  when it is a maximum inside (0, 1); 0 (None) otherwise. */
int rk_parabola_peak(double f0, double fm, double f1, double *x, double *value);
/** A scalar function of time for rk_brent_max: *value, or *has = 0 (the Python's None: no value, below
 *  everything). */
typedef rk_status (*rk_scalar_fn)(void *ctx, double t, double *value, int *has);
/** events.brent_max: Brent's method for the largest value of f on [a, b] from an inner point x with value fx
 *  (has_fx 0: None), abscissa to about xtol, at most max_iter evaluations (the Python's default: 60). Writes
 *  the best point (*t_out, *f_out; *has_out 0 when no point had a value). */
rk_status rk_brent_max(rk_scalar_fn f, void *ctx, double a, double b, double x, double fx, int has_fx, double xtol,
                       int max_iter, double *t_out, double *f_out, int *has_out, rk_error *err);

#ifdef __cplusplus
}
#endif
#endif /* RK_RK_H */
