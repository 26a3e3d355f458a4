/* rk_ed.c -- the event-driven scheme (part D): a port of rocking_model/integrators/event_driven.py, function
 * by function (the Python names are given in each comment), so that the C takes the same steps, finds the
 * same events and solves the same contact problems as the Python reference (DESIGN.md "Numerics").
 *
 * - Smooth phases: the reduced state y = [r, r_dot] of the current contact mode, integrated by the
 *   Runge-Kutta pair of rk_rk.h; the event functions of rk_mode_monitors located on the dense output.
 * - Events: impact (the impact LCP under the Zeno rule, the classical rule, grazing landings, the Painleve
 *   count), release / slip / cone (the uplift LCP decides the next mode, a Painleve impulse where it has no
 *   solution), overturning (the pose reached is kept at rest).
 * - The friction demand: at both limits of every event, at step ends, at its peak inside a step
 *   (`_demand_peak`), and each impact's percussions (`_note_percussions`).
 * - The work budget (max_steps: Runge-Kutta steps plus EVENT_WORK per event) and max_events.
 *
 * The ground motion is evaluated where the Python evaluates it: a constant input as its value (ag.value),
 * any other at the time of the call (ag(t)); the kernels get values only.
 * No allocation; every work array is on the stack. */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/** [steps] what one event counts in the work budget (event_driven.EVENT_WORK: locating it and its LCPs cost
 *  about as much as 20 to 35 Runge-Kutta steps) */
#define ED_EVENT_WORK 30
/** [1] event_driven.DEMAND_PEAK_MARGIN: the demand's peak inside a step is searched for when the parabola
 *  through its ends and middle peaks above (1 - margin) times the largest demand so far */
#define ED_DEMAND_PEAK_MARGIN 0.1
/** [1] event_driven.DEMAND_STEP_GATE: a step whose ends need less than this fraction of the largest demand so
 *  far is not searched */
#define ED_DEMAND_STEP_GATE 0.5
/** [1] event_driven.MAX_SINK_REFUSALS: steps a segment may refuse (each retried at half its length) because
 *  their interpolant sinks an open corner that started the segment at the ground below -gap (rk_sinks) */
#define ED_MAX_SINK_REFUSALS 8
/** brent_max's max_iter (the Python's default) */
#define ED_BRENT_MAX_ITER 60
/** [1] check_times: an impact time may exceed t by this relative round-off */
#define ED_TIMES_RTOL 1e-12
/** the top bit of a motion key: set for a key taken from rk_motion.identity (never equal to a serial) */
#define ED_KEY_IDENTITY (1ull << 63)

#define ED(e) (&(e)->core.s.ed)

/* event kinds (event_driven._KIND_*) */
enum { ED_IMPACT = 0, ED_RELEASE = 1, ED_OVERTURN = 2, ED_SLIP = 3, ED_CONE = 4, ED_SWITCH = 5 };

/* ------------------------------------------------------------------------------------------ helpers */

/** math.ulp of a finite x >= 0 (the callers pass max(|t|, 1)) */
static double ed_ulp(double x)
{
    return rk_gap_above(x);
}

static int ed_popcount(rk_set s)
{
    int n = 0;
    while (s) {
        n += (int)(s & 1u);
        s >>= 1;
    }
    return n;
}

static const char *ed_mode_name(int mode, char *buf, size_t n)
{
    static const char *const NAMES[] = {"FULL", "LEFT", "RIGHT", "FLIGHT", "FULL_SLIDE_POS", "FULL_SLIDE_NEG",
                                        "LEFT_SLIDE_POS", "LEFT_SLIDE_NEG", "RIGHT_SLIDE_POS",
                                        "RIGHT_SLIDE_NEG"};
    if (mode >= 0 && mode < 10)
        return NAMES[mode];
    snprintf(buf, n, "%d", mode);
    return buf;
}

/** Note the ratio d [1] (NAN: None): Integrator.note_ratio (at most mu) */
static void ed_note_ratio(rk_engine *e, double d)
{
    rk_ed_state *s = ED(e);
    if (d > s->friction_demand)
        s->friction_demand = d < e->model.mu ? d : e->model.mu;
}

/** _demand_ratio: |lam_T| / lam_N, NAN (None) when lam_N carries no load */
static double ed_ratio(const rk_ed_state *s, const double *lam)
{
    return lam[0] > s->force_floor ? fabs(lam[1]) / lam[0] : NAN;
}

/** report an "inexact_contact" (moreau_jean.inexact_message: part B's rk_inexact_message, shared with
 *  Moreau-Jean) */
static void ed_report_inexact(rk_engine *e, const rk_lcp_solution *sol, double t, const char *what)
{
    char msg[RK_MSG_LEN];
    rk_inexact_message(sol, e->model.ops->n_contacts, t, what, msg, sizeof msg);
    rk_report_add(&e->reports, RK_REPORT_INEXACT_CONTACT, t, "%s", msg);
}

/** The ValueError flexible_impact._inputs raises where the classical rule does not apply (the kernel returns
 *  -1): a pivot that is not LEFT / RIGHT (a sliding mode), a non-finite rate, or a rate that does not close the
 *  other corner (the Python's text, as rk_mj.c writes it). */
static rk_status ed_classical_refusal(const rk_model *m, int mode, const double *v, rk_error *err)
{
    static const char *const NAMES[] = {"FULL", "LEFT", "RIGHT", "FLIGHT", "FULL_SLIDE_POS", "FULL_SLIDE_NEG",
                                        "LEFT_SLIDE_POS", "LEFT_SLIDE_NEG", "RIGHT_SLIDE_POS", "RIGHT_SLIDE_NEG"};
    double phi_dot = v[m->ops->phi_index];
    if (mode != RK_MODE_LEFT && mode != RK_MODE_RIGHT)
        return rk_fail(err, RK_ERR_VALUE, "pivot = <Mode.%s: %d> is not supported; allowed values: <Mode.LEFT: 1>, "
                       "<Mode.RIGHT: 2>, 'left', 'right'", (mode >= 0 && mode < 10) ? NAMES[mode] : "?", mode);
    if (!isfinite(phi_dot))
        return rk_fail(err, RK_ERR_VALUE, "phi_dot_minus = %s is not finite; allowed range (-inf, inf)",
                       isnan(phi_dot) ? "nan" : phi_dot > 0 ? "inf" : "-inf");
    return rk_fail(err, RK_ERR_VALUE, "phi_dot_minus = %g does not close the gap of the other corner when rocking "
                   "on the %s corner; allowed range %s", phi_dot, mode == RK_MODE_LEFT ? "left" : "right",
                   mode == RK_MODE_LEFT ? "(-inf, 0)" : "(0, inf)");
}

/* ------------------------------------------------------------------------------------------ the mode's functions
 * `_functions`: (rhs, G, totals) of a mode under the input. The closures of the Python read ag.value of a
 * constant input and ag(t) otherwise. */
typedef struct ed_fn {
    rk_engine *e;
    int mode;
    rk_motion *ag;
    rk_motion *ag_v;            /**< the vertical component (NULL: none) */
    int constant;               /**< both components constant (TwoComponentMotion.constant) */
    double a0;                  /**< ag.value of a constant input */
    double v0;                  /**< ag.vertical.value of a constant input (0 without vertical component) */
    int pure;                   /**< ag(t) (and ag_v(t)) calls no callback: evaluating it or not changes nothing */
    /** the model's own rhs of a non-sliding mode (what rk_mode_rhs calls there; NULL: through rk_mode_rhs) */
    void (*mode_rhs)(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *dy);
    /** the model's mode_acc1 where mode_rhs is set and ag(t) cannot fail (NULL: none): ed_acc1 */
    double (*acc1)(const rk_model *m, int mode, double y0, double y1, double ag, double ag_v);
    rk_error err;               /**< the failure of a callback (a motion callback, a sliding solve) */
    /** memo_n > 0: ed_G computes the totals too and keeps them for the last (t, y[memo_n]) it saw, which ed_totals
     *  reads there (the dip search and the demand peak both evaluate the middle of a step); 0: off */
    int memo_n;
    int memo_valid;
    double memo_t, memo_y[RK_MAX_Y], memo_lam[2];
} ed_fn;

/** a motion evaluated without side effects or failure (no Python callback inside) */
static int ed_motion_pure(const rk_motion *m)
{
    if (m->kind == RK_MOTION_CALLBACK)
        return 0;
    return m->kind != RK_MOTION_SCALED || ed_motion_pure(m->inner);
}

static void ed_fn_init(ed_fn *f, rk_engine *e, int mode, rk_motion *ag, rk_motion *ag_v)
{
    f->e = e;
    f->mode = mode;
    f->ag = ag;
    f->ag_v = ag_v;
    f->constant = rk_motion_pair_constant(ag, ag_v);
    /* (ScaledMotion.value = factor * motion(0.0); ConstantMotion.value = the value) */
    f->a0 = f->constant ? rk_motion_eval(ag, 0.0, NULL, NULL) : 0.0;
    f->v0 = f->constant && ag_v != NULL ? rk_motion_eval(ag_v, 0.0, NULL, NULL) : 0.0;
    f->pure = f->constant || (ed_motion_pure(ag) && (ag_v == NULL || ed_motion_pure(ag_v)));
    f->mode_rhs = rk_mode_sliding(&e->model, mode) ? NULL : e->model.ops->mode_rhs;
    f->acc1 = f->mode_rhs != NULL && f->pure ? e->model.ops->mode_acc1 : NULL;
    rk_error_clear(&f->err);
    f->memo_n = 0;
    f->memo_valid = 0;
}

/** (ag(t), ag_v(t)) called directly (the Python's ag(t) at an event; a callback's failure and message kept);
 *  ag_v NULL: 0. Not inlined: ed_ag's common path keeps no message buffer */
static RK_NOINLINE rk_status ed_ag_call(rk_motion *ag, rk_motion *ag_v, double t, double *a, double *av, rk_error *err)
{
    int failed = 0;
    char msg[RK_MSG_LEN];
    msg[0] = '\0';
    *a = rk_motion_eval(ag, t, &failed, msg);
    *av = ag_v != NULL && !failed ? rk_motion_eval(ag_v, t, &failed, msg) : 0.0;
    if (failed)
        return rk_fail(err, RK_ERR_VALUE, "%s", msg);
    return RK_OK;
}

/** (ag(t), ag_v(t)) as the Python reads them: (a0, v0) for a constant input */
static rk_status ed_ag(ed_fn *f, double t, double *a, double *av)
{
    if (f->constant) {
        *a = f->a0;
        *av = f->v0;
        return RK_OK;
    }
    if (!f->pure)
        return ed_ag_call(f->ag, f->ag_v, t, a, av, &f->err);
    /* a motion without callback neither fails nor writes a message (every rhs stage reads it) */
    if (!rk_motion_sampled_cached(f->ag, t, a))
        *a = rk_motion_eval(f->ag, t, NULL, NULL);
    *av = f->ag_v != NULL ? rk_motion_eval(f->ag_v, t, NULL, NULL) : 0.0;
    return RK_OK;
}

static rk_status ed_rhs(void *ctx, double t, const double *y, double *dy)
{
    ed_fn *f = (ed_fn *)ctx;
    double a, av;
    rk_status st = ed_ag(f, t, &a, &av);
    if (st != RK_OK)
        return st;
    if (f->mode_rhs != NULL) {
        /* every stage: the model's rhs called directly (rk_mode_rhs's own path for such a mode) */
        f->mode_rhs(&f->e->model, f->mode, y, a, av, dy);
        return RK_OK;
    }
    st = rk_mode_rhs(&f->e->model, f->mode, y, a, av, dy);
    if (st != RK_OK)
        return rk_fail(&f->err, st, "the acceleration of mode %d has no solution at t = %.17g s", f->mode, t);
    return RK_OK;
}

/** the switches' event functions of the n functions g: their values times their sides (ED_SWITCH) */
static void ed_orient(const rk_engine *e, double *g, int n)
{
    int nsw = e->model.ops->n_switches, j;
    for (j = 0; j < nsw; j++)
        g[n - 1 - nsw + j] *= ED(e)->switch_side[j];
}

/** ed_rhs's r_ddot of a one-dof mode as an rk_rhs1_fn (f->acc1 set: a motion that cannot fail) */
static double ed_acc1(void *ctx, double t, double y0, double y1)
{
    ed_fn *f = (ed_fn *)ctx;
    double a, av;
    (void)ed_ag(f, t, &a, &av);
    return f->acc1(&f->e->model, f->mode, y0, y1, a, av);
}

static rk_status ed_G(void *ctx, double t, const double *y, double *g)
{
    ed_fn *f = (ed_fn *)ctx;
    double a, av;
    rk_status st = ed_ag(f, t, &a, &av);
    if (st != RK_OK)
        return st;
    if (f->memo_n > 0) {
        /* the totals from the same kernel call (G does not depend on whether they are asked for) */
        int has = 0;
        f->memo_lam[0] = f->memo_lam[1] = NAN;
        ed_orient(f->e, g, rk_mode_monitors(&f->e->model, f->mode, y, a, av, g, f->memo_lam, &has));
        f->memo_valid = 1;
        f->memo_t = t;
        rk_copy(f->memo_y, y, f->memo_n);
        return RK_OK;
    }
    ed_orient(f->e, g, rk_mode_monitors(&f->e->model, f->mode, y, a, av, g, NULL, NULL));
    return RK_OK;
}

/** G(t, y)[i] alone where the model has it without ag and the forces (a corner gap, the overturning margin); a
 *  motion with a callback is still called, as G calls it (the same calls, the same failures) */
static rk_status ed_G_one(void *ctx, int i, double t, const double *y, double *gi, int *done)
{
    ed_fn *f = (ed_fn *)ctx;
    *done = rk_mode_monitor_one(&f->e->model, f->mode, y, i, gi);
    if (*done && !f->pure) {
        double a, av;
        return ed_ag(f, t, &a, &av);
    }
    return RK_OK;
}

/** the functions of G that ed_G_one has in the segment's mode (rk_mode_monitor_one: a property of the mode) */
static unsigned ed_G_one_mask(void *ctx)
{
    ed_fn *f = (ed_fn *)ctx;
    unsigned mask = 0u;
    int i;
    double gi;
    for (i = 0; i < RK_MAX_EVENTS; i++)
        if (rk_mode_monitor_one(&f->e->model, f->mode, ED(f->e)->y, i, &gi))
            mask |= 1u << i;
    return mask;
}

/** totals(t, y): (sum lambda_N, sum lambda_T) [N]; *has 0 in flight (the Python's totals is None) */
static rk_status ed_totals(ed_fn *f, double t, const double *y, double *lam)
{
    double a, av, g[RK_MAX_EVENTS];
    int has = 0;
    rk_status st;
    if (f->memo_valid && t == f->memo_t && rk_same_bits(y, f->memo_y, f->memo_n)) {
        lam[0] = f->memo_lam[0];
        lam[1] = f->memo_lam[1];
        return RK_OK;
    }
    st = ed_ag(f, t, &a, &av);
    if (st != RK_OK)
        return st;
    lam[0] = lam[1] = NAN;
    rk_mode_monitors(&f->e->model, f->mode, y, a, av, g, lam, &has);
    return RK_OK;
}

/** G(t, y) and, when lam is not NULL, the totals at the same (t, y) in one kernel call; n_y: the size of y.
 *  A step's end and the segment that starts there ask for the same values: the engine's g_memo keeps them */
static rk_status ed_G_totals(ed_fn *f, double t, const double *y, int n_y, double *g, double *lam)
{
    double a, av;
    int has = 0, n;
    rk_engine *e = f->e;
    rk_status st = ed_ag(f, t, &a, &av);
    if (st != RK_OK)
        return st;
    if (e->g_memo.valid && e->g_memo.mode == f->mode && e->g_memo.n_y == n_y && (lam == NULL || e->g_memo.has_lam)
        && rk_same_bits(&a, &e->g_memo.a, 1) && rk_same_bits(&av, &e->g_memo.av, 1)
        && rk_same_bits(y, e->g_memo.y, n_y)) {
        memcpy(g, e->g_memo.g, sizeof e->g_memo.g);
        if (lam != NULL) {
            lam[0] = e->g_memo.lam[0];
            lam[1] = e->g_memo.lam[1];
        }
        return RK_OK;
    }
    if (lam != NULL)
        lam[0] = lam[1] = NAN;
    n = rk_mode_monitors(&e->model, f->mode, y, a, av, g, lam, lam != NULL ? &has : NULL);
    ed_orient(e, g, n);
    e->g_memo.valid = 1;
    e->g_memo.mode = f->mode;
    e->g_memo.n_y = n_y;
    e->g_memo.has_lam = lam != NULL;
    e->g_memo.a = a;
    e->g_memo.av = av;
    rk_copy(e->g_memo.y, y, n_y);
    rk_copy(e->g_memo.g, g, n);
    if (lam != NULL) {
        e->g_memo.lam[0] = lam[0];
        e->g_memo.lam[1] = lam[1];
    }
    return RK_OK;
}

/** Copy a callback's failure into err (the status st came back from a call that ran the callbacks) */
static rk_status ed_pass(ed_fn *f, rk_status st, rk_error *err)
{
    if (st != RK_OK && f->err.status != RK_OK && err != NULL)
        *err = f->err;
    return st;
}

#define ED_TRY(x) do { rk_status st_ = (x); if (st_ != RK_OK) return st_; } while (0)
#define ED_TRYF(f, x) do { rk_status st_ = (x); if (st_ != RK_OK) return ed_pass((f), st_, err); } while (0)

/** `_kinds`: the meaning of each event function of mode; returns their number. A pure function of the mode for
 *  an engine: the last mode's are kept (asked at every segment's start and settle) */
static int ed_kinds(rk_engine *e, int mode, int *kinds)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    if (mode != s->kinds_mode) {
        rk_set closed = rk_closed_of(m, mode);
        int nc = m->ops->n_contacts, i, n = 0;
        for (i = 0; i < nc; i++)
            s->kinds[n++] = RK_IN(closed, i) ? ED_RELEASE : ED_IMPACT;
        if (rk_mode_sliding(m, mode))
            s->kinds[n++] = ED_SLIP;
        else if (closed && !isinf(m->mu))
            s->kinds[n++] = ED_CONE;
        for (i = 0; i < m->ops->n_switches; i++)
            s->kinds[n++] = ED_SWITCH;
        s->kinds[n++] = ED_OVERTURN;
        s->kinds_n = n;
        s->kinds_mode = mode;
    }
    memcpy(kinds, s->kinds, (size_t)s->kinds_n * sizeof(int));
    return s->kinds_n;
}

/** the switches' sides from their functions g at a segment's start (kinds of its n functions): each one clearly
 *  away from zero (beyond the event tolerance) gets the side of its value, and g its magnitude */
static void ed_switch_sides(rk_engine *e, const int *kinds, int n, double *g)
{
    rk_ed_state *s = ED(e);
    int i, j = 0, flipped = 0;
    for (i = 0; i < n; i++) {
        if (kinds[i] != ED_SWITCH)
            continue;
        if (g[i] < -s->event_tol) {
            s->switch_side[j] = -s->switch_side[j];
            g[i] = -g[i];
            flipped = 1;
        }
        j++;
    }
    if (flipped)
        e->g_memo.valid = 0;
}

/** whether the mode has force totals (the Python's totals is not None: closed contacts) */
static int ed_has_totals(const rk_model *m, int mode)
{
    return rk_closed_of(m, mode) != 0;
}

/** `_atol_of` */
static void ed_atol(const rk_engine *e, int mode, double *atol)
{
    const rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int idx[RK_MAX_DOF], k, j;
    double ts = m->time_scale;
    k = rk_dofs_of(m, mode, idx);
    for (j = 0; j < k; j++) {
        atol[j] = s->tolerance * m->dof_scales[idx[j]];
        atol[k + j] = s->tolerance * m->dof_scales[idx[j]] / ts;
    }
}

/* ------------------------------------------------------------------------------------------ state */

/** `_onto_ground`: q_out = q, projected onto the ground at the closed corners of ``mode`` and at the open ones
 *  that its reduction would put below it (a closed corner within gap_tol above the ground, closed by the Zeno
 *  rule, lowers the body by its gap); see the Python */
static rk_status ed_onto_ground(rk_engine *e, int mode, const double *q, const double *v, double *q_out,
                                rk_error *err)
{
    const rk_model *m = &e->model;
    int nc = m->ops->n_contacts, n = m->ops->n_dof, i, lowers = 0;
    rk_set closed = rk_closed_of(m, mode), sunk = 0;
    double g[RK_MAX_CONTACTS], y[2 * RK_MAX_DOF], q_in[RK_MAX_DOF], v_in[RK_MAX_DOF];
    double rnd = e->options.tolerances.grazing * ED(e)->gap_tol;     /* [m] round-off of a located gap */
    memcpy(q_out, q, (size_t)n * sizeof(double));
    if (!closed || ed_popcount(closed) == nc)
        return RK_OK;
    m->ops->gaps(m, q, g);
    for (i = 0; i < nc; i++)
        if (RK_IN(closed, i) && g[i] > rnd)
            lowers = 1;
    if (!lowers)
        return RK_OK;
    rk_reduce_any(m, mode, q, v, y);
    rk_embed_any(m, mode, y, q_in, v_in);
    m->ops->gaps(m, q_in, g);
    for (i = 0; i < nc; i++)
        if (!RK_IN(closed, i) && g[i] < -rnd)
            sunk |= 1u << i;
    return sunk ? rk_project_to_ground(m, q, closed | sunk, q_out, err) : RK_OK;
}

/** `_set_state` (has_old 0 at __init__: no previous mode) */
static rk_status ed_set_state(rk_engine *e, int mode, const double *q_given, const double *v, int has_old,
                              rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int old = s->mode;
    double shift = 0.0, q[RK_MAX_DOF];
    ED_TRY(ed_onto_ground(e, mode, q_given, v, q, err));
    s->mode = mode;
    s->k = rk_reduce_any(m, mode, q, v, s->y);
    /* a sticking mode on the ground keeps the base's horizontal offset outside its reduced state: unchanged
     * from a sticking mode, read off the state after flight or sliding (below gap_tol: round-off) */
    if (!rk_mode_sliding(m, mode) && rk_closed_of(m, mode)) {
        if (has_old && !rk_mode_sliding(m, old) && rk_closed_of(m, old)) {
            shift = s->shift;
        } else {
            shift = rk_shift_of(m, mode, q);
            if (fabs(shift) <= s->gap_tol)
                shift = 0.0;
        }
    }
    s->shift = shift;
    e->model.offset = shift;
    s->live = 0;
    e->core.token++;
    return RK_OK;
}

void rk_ed_full_state(rk_engine *e, double *q, double *v)
{
    const rk_ed_state *s = ED(e);
    rk_embed_any(&e->model, s->mode, s->y, q, v);
    if (s->shift != 0.0)
        q[e->model.ops->slide_index] += s->shift;
}

void rk_ed_outputs(rk_engine *e, double *out)
{
    const rk_ed_state *s = ED(e);
    rk_outputs_of(&e->model, s->mode, s->y, s->shift, out);
}

/* ------------------------------------------------------------------------------------------ init */

static rk_status ed_check_real(const char *name, double x, double lo, double hi, int lo_open, rk_error *err)
{
    char rng[96];
    if (isfinite(x) && (x > lo || (!lo_open && x == lo)) && x <= hi)
        return RK_OK;
    snprintf(rng, sizeof rng, "%s%g, %g]", lo_open ? "(" : "[", lo, hi);
    if (!isfinite(x))
        return rk_fail(err, RK_ERR_VALUE, "%s = %.17g is not finite; allowed range %s", name, x, rng);
    return rk_fail(err, RK_ERR_VALUE, "%s = %g is out of range; allowed range %s", name, x, rng);
}

rk_status rk_ed_init(rk_engine *e, int mode, const double *q, const double *v, rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_options *o = &e->options;
    rk_model_tolerances sc;
    int i;
    ED_TRY(ed_check_real("tolerance", o->tolerance, 1e-14, 1e-2, 0, err));
    ED_TRY(ed_check_real("zeno_tol", o->zeno_tol, 0.0, 1e-2, 1, err));
    if (o->method != RK_METHOD_DOP853 && o->method != RK_METHOD_DOPRI5)
        return rk_fail(err, RK_ERR_VALUE, "method = %d is not supported; allowed values: 'DOP853', 'DOPRI5', "
                       "'RK45', 0, 1", (int)o->method);
    if (mode < 0 || mode >= e->model.ops->n_modes)
        return rk_fail(err, RK_ERR_VALUE, "mode = %d is out of range; allowed range [0, %d]", mode,
                       e->model.ops->n_modes - 1);
    memset(s, 0, sizeof(*s));
    rk_model_scale_tolerances(&e->model, &o->tolerances, &sc);
    s->t = o->t0;
    s->tolerance = o->tolerance;
    s->dt_max = o->dt_max > 0.0 ? o->dt_max : INFINITY;     /* options.dt_max or math.inf */
    s->tab = rk_tableau_of(o->method);
    if (s->tab == NULL)
        return rk_fail(err, RK_ERR_INTERNAL, "no Runge-Kutta tableau for method %d", (int)o->method);
    s->gap_tol = sc.gap;
    s->v_tol = sc.rest_velocity;
    s->v_zeno = o->zeno_tol * sc.velocity_scale;
    s->event_tol = o->tolerances.event;
    s->stateless_step = sc.stateless_step;
    s->force_floor = sc.force_floor;
    s->max_events = o->max_events;
    s->impacts = 0;
    s->overturned = 0;
    s->n_steps = 0;
    s->h = NAN;
    s->friction_demand = 0.0;
    s->painleve = 0;
    s->live = 0;
    for (i = 0; i < RK_MAX_SWITCHES; i++)
        s->switch_side[i] = 1.0;
    s->kinds_mode = -1;
    s->rhs_mode = -1;
    s->max_work = -1;
    s->work_end = INFINITY;
    return ed_set_state(e, mode, q, v, 0, err);
}

/* ------------------------------------------------------------------------------------------ samples */

/** The rows of a sample call (the Python's ``pending`` deque and ``out`` list). */
typedef struct ed_out {
    const double *times;
    long long n, next;          /**< pending: times[next .. n) */
    int *modes;
    double *values;
    long long *impacts;
    int *overturned;
    long long row;              /**< rows written */
} ed_out;

static int ed_pending(const ed_out *o)
{
    return o != NULL && o->next < o->n;
}

/** One row's values (the outputs, friction_demand, painleve) into values, one column every cs (cs <= 1: in a
 *  row) */
static inline void ed_row_values(const rk_model *m, int mode, const double *y, double shift, long long cs, double demand,
                                 double painleve, double *values)
{
    int n_out = m->ops->n_outputs, j;
    if (cs > 1) {
        /* the column layout (rk_engine_sample_columns): one value per column, rows count apart */
        double row[RK_MAX_OUTPUTS];
        rk_outputs_of(m, mode, y, shift, row);
        for (j = 0; j < n_out; j++)
            values[j * cs] = row[j];
        values[n_out * cs] = demand;
        values[(n_out + 1) * cs] = painleve;
    } else {
        rk_outputs_of(m, mode, y, shift, values);
        values[n_out] = demand;
        values[n_out + 1] = painleve;
    }
}

void rk_ed_row(rk_engine *e, int mode, const double *y, int overturned, int *modes, double *values,
               long long *impacts, int *over)
{
    const rk_ed_state *s = ED(e);
    ed_row_values(&e->model, mode, y, s->shift, e->sample_cs, s->friction_demand, (double)s->painleve, values);
    *modes = overturned ? 10 : mode;        /* modes.OVERTURNED */
    *impacts = s->impacts;
    *over = overturned;
}

/** the distance from one row's values to the next's: 1 in the column layout, else a row's length */
static long long ed_row_stride(const rk_engine *e)
{
    return e->sample_cs > 1 ? 1 : e->model.ops->n_outputs + 2;
}

/** `_sample_row` appended to out; overturned < 0: the current flag (the Python's None) */
static void ed_row(rk_engine *e, ed_out *o, int mode, const double *y, int overturned)
{
    long long rs = ed_row_stride(e);
    long long r = o->row++;
    o->next++;
    rk_ed_row(e, mode, y, overturned < 0 ? ED(e)->overturned : overturned, o->modes + r,
              o->values + r * rs, o->impacts + r, o->overturned + r);
}

/** `_record_samples`: the pending samples before (or up to, inclusive) t_last, read from the dense output */
static rk_status ed_record_samples(rk_engine *e, ed_out *o, int mode, double t_last, int inclusive, ed_fn *f,
                                   rk_error *err)
{
    rk_ed_state *s = ED(e);
    double y[RK_MAX_Y];
#define ED_BEFORE(t) (inclusive ? (t) <= t_last : (t) < t_last)
    if (ed_pending(o) && ED_BEFORE(o->times[o->next])) {
        /* rk_ed_row's writes (overturned 0), what does not change from row to row read once: a sampled run
         * spends much of its time here (a pulse: a third of it) */
        const rk_model *m = &e->model;
        long long rs = ed_row_stride(e), cs = e->sample_cs, impacts = s->impacts;
        double shift = s->shift, demand = s->friction_demand, painleve = (double)s->painleve;
        while (o->next < o->n && ED_BEFORE(o->times[o->next])) {
            long long r = o->row++;
            ED_TRYF(f, rk_dense_eval(&s->stepper, o->times[o->next++], y, err));
            ed_row_values(m, mode, y, shift, cs, demand, painleve, o->values + r * rs);
            o->modes[r] = mode;
            o->impacts[r] = impacts;
            o->overturned[r] = 0;
        }
        if (s->max_work >= 0)
            s->work_end = (double)s->n_steps + (double)s->max_work;     /* the budget applies per sample */
    }
#undef ED_BEFORE
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ contact events */

static rk_status ed_decide(rk_engine *e, const double *q, const double *v, double ag_t, double av_t, double t,
                           int prefer, int *mode, double *v_out, int *changed, rk_error *err);

/** `_record_impact` */
static rk_status ed_record_impact(rk_engine *e, double t, const double *v_minus, const double *v_plus,
                                  rk_error *err)
{
    rk_ed_state *s = ED(e);
    int n = e->model.ops->n_dof, i;
    double row[1 + 2 * RK_MAX_DOF];
    rk_status st;
    s->impacts++;
    st = rk_log_append(&e->impact_times, &t);
    if (st != RK_OK)
        return rk_fail(err, st, "out of memory growing the impact log (impact_log_size = None)");
    row[0] = t;
    for (i = 0; i < n; i++) {
        row[1 + i] = v_minus[i];
        row[1 + n + i] = v_plus[i];
    }
    st = rk_log_append(&e->impact_log, row);
    if (st != RK_OK)
        return rk_fail(err, st, "out of memory growing the impact log (impact_log_size = None)");
    return RK_OK;
}

/** `_count_painleve` */
static void ed_count_painleve(rk_engine *e, const double *q, const double *v_minus, const double *v_plus,
                              rk_set cand)
{
    rk_ed_state *s = ED(e);
    if (rk_painleve_sticks(&e->model, q, v_minus, v_plus, cand, s->v_tol) != 0)
        s->painleve++;
}

/** W^T x for the columns of W (n_dof x n_contacts) */
static void ed_wtx(const rk_model *m, const double *W, const double *x, double *out)
{
    int n = m->ops->n_dof, nc = m->ops->n_contacts, i, c;
    for (c = 0; c < nc; c++) {
        double acc = 0.0;
        for (i = 0; i < n; i++)
            acc += W[i * nc + c] * x[i];
        out[c] = acc;
    }
}

/** `_impact_velocity`: the impact LCP under the Zeno rule; writes the post-impact velocity */
static rk_status ed_impact_velocity(rk_engine *e, const double *q, const double *v, rk_set cand, rk_set closed,
                                    double ag_t, double av_t, double t, double *v_out, rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int n = m->ops->n_dof, nc = m->ops->n_contacts, i, j;
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS];
    double U_plus[RK_MAX_CONTACTS];
    rk_set forced = cand & closed;
    rk_contact_args a;
    rk_lcp_solution sol;
    m->ops->contact_jacobians(m, q, W_N, W_T);
    rk_contact_args_default(&a);
    a.forced = forced;
    a.tolerances = &e->options.tolerances;
    ED_TRY(rk_impact(m, q, v, cand, &a, &sol, err));
    for (;;) {
        rk_set new_ = 0;
        ed_wtx(m, W_N, sol.v, U_plus);
        /* velocity test (a corner that takes impulse and stays at rest needs no closure) */
        for (i = 0; i < nc; i++) {
            if (RK_IN(cand, i) && !RK_IN(forced, i) && U_plus[i] < s->v_zeno
                && (!RK_IN(sol.active, i) || U_plus[i] > s->v_tol))
                new_ |= 1u << i;
        }
        if (!new_ && !forced && cand) {
            int all = 1;
            for (i = 0; i < nc; i++)
                if (RK_IN(cand, i) && !(U_plus[i] >= s->v_zeno))
                    all = 0;
            if (all) {
                /* bounce test, in flight only: a_N the corner's normal acceleration in free flight */
                double Minv[RK_MAX_DOF * RK_MAX_DOF], f[RK_MAX_DOF], acc[RK_MAX_DOF], a_N[RK_MAX_CONTACTS];
                double d_N[RK_MAX_CONTACTS], d_T[RK_MAX_CONTACTS];
                int best = -1;
                double best_key = 0.0;
                rk_model_inverse_mass(m, q, Minv);
                m->ops->forces(m, q, sol.v, ag_t, av_t, f);
                for (i = 0; i < n; i++) {
                    double sacc = 0.0;
                    for (j = 0; j < n; j++)
                        sacc += Minv[i * n + j] * f[j];
                    acc[i] = sacc;
                }
                ed_wtx(m, W_N, acc, a_N);
                m->ops->contact_drift(m, q, sol.v, d_N, d_T);
                for (i = 0; i < nc; i++)
                    a_N[i] = a_N[i] + d_N[i];
                for (i = 0; i < nc; i++) {
                    if (RK_IN(cand, i) && a_N[i] < 0.0) {
                        double key = U_plus[i] * U_plus[i] / -a_N[i];
                        if (best < 0 || key < best_key) {
                            best = i;
                            best_key = key;
                        }
                    }
                }
                if (best >= 0 && U_plus[best] * U_plus[best] < -2.0 * a_N[best] * s->gap_tol)
                    new_ = 1u << best;
            }
        }
        if (!new_)
            break;
        forced |= new_;
        a.forced = forced;
        ED_TRY(rk_impact(m, q, v, cand, &a, &sol, err));
    }
    if (!sol.exact)
        ed_report_inexact(e, &sol, t, "impact LCP");
    memcpy(v_out, sol.v, (size_t)n * sizeof(double));
    return RK_OK;
}

/** `_select_mode` */
static rk_status ed_select_mode(rk_engine *e, const double *q, const double *v, double ag_t, double av_t, double t,
                                int prefer, int *mode, rk_lcp_solution *sol, int *has_sol, rk_error *err)
{
    rk_ed_state *s = ED(e);
    ED_TRY(rk_next_mode(&e->model, q, v, ag_t, av_t, s->gap_tol, s->v_tol, prefer, &e->options.tolerances, mode, sol,
                        has_sol, err));
    if (*has_sol && !sol->exact && !rk_lcp_painleve(sol))
        ed_report_inexact(e, sol, t, "uplift LCP");
    return RK_OK;
}

/** `_decide`: (mode, v) after the consistent state (q, v); *changed 1 when a Painleve impulse changed v */
static rk_status ed_decide(rk_engine *e, const double *q, const double *v, double ag_t, double av_t, double t,
                           int prefer, int *mode, double *v_out, int *changed, rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    rk_lcp_solution sol;
    int has = 0;
    *changed = 0;
    memcpy(v_out, v, (size_t)m->ops->n_dof * sizeof(double));
    ED_TRY(ed_select_mode(e, q, v, ag_t, av_t, t, prefer, mode, &sol, &has, err));
    if (has && rk_lcp_painleve(&sol)) {
        /* Painleve: an impact without collision makes the sliding corners stick (Genot & Brogliato 1999),
         * then the acceleration problem at rest tangentially */
        rk_contact_args a;
        rk_lcp_solution sol_i;
        rk_set cands = sol.active ? sol.active : rk_closed_candidates(m, q, v, s->gap_tol, s->v_tol);
        s->painleve++;
        rk_contact_args_default(&a);
        a.has_e = 1;
        a.e_N = 0.0;
        a.e_T = 0.0;
        a.prefer = RK_STICK;
        a.tolerances = &e->options.tolerances;
        ED_TRY(rk_impact(m, q, v, cands, &a, &sol_i, err));
        if (!sol_i.exact)
            ed_report_inexact(e, &sol_i, t, "Painleve impact LCP");
        memcpy(v_out, sol_i.v, (size_t)m->ops->n_dof * sizeof(double));
        *changed = 1;
        ED_TRY(ed_select_mode(e, q, v_out, ag_t, av_t, t, -1, mode, &sol, &has, err));
    }
    return RK_OK;
}

/** `_enter` */
static rk_status ed_enter(rk_engine *e, const double *q, const double *v, double ag_t, double av_t, double t,
                          int prefer, rk_error *err)
{
    int mode, changed;
    double v2[RK_MAX_DOF];
    ED_TRY(ed_decide(e, q, v, ag_t, av_t, t, prefer, &mode, v2, &changed, err));
    return ed_set_state(e, mode, q, v2, 1, err);
}

/** The state of contact c that follows the zero of its normal force in a mode that keeps it closed: open where
 *  flight is consistent, else sliding against the tangential force it carried (lam_T; the limit mu -> inf of
 *  the cone rule); the other candidates first tried in their states of the mode. *mode -1: neither is an exact
 *  solution of the acceleration LCP (contact.uplift's problem, solved with these first trials). */
static rk_status ed_released_mode(rk_engine *e, const double *q, const double *v, double ag_t, double av_t, int c,
                                  double lam_T, int *mode, rk_error *err)
{
    const rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int n = m->ops->n_contacts, i, k, trial, n_trials, hint[RK_MAX_CONTACTS];
    rk_set cand = rk_closed_candidates(m, q, v, s->gap_tol, s->v_tol), closed = rk_closed_of(m, s->mode);
    const int *sliding;
    rk_uplift_data d;
    rk_lcp_problem p;
    rk_lcp_solution sol;
    *mode = -1;
    if (!RK_IN(cand, c))
        return RK_OK;
    rk_uplift_data_of(m, q, v, ag_t, av_t, cand, s->v_tol, &d, &p);
    sliding = d.sliding;
    p.candidates = cand;
    p.rtol = e->options.tolerances.lcp_exact;
    p.mu = m->mu;
    p.sliding = sliding;
    p.hint_states = hint;
    /* open first; sliding only from a sticking state (a sliding contact's options are open or its slip) */
    n_trials = rk_mode_sliding(m, s->mode) || sliding[c] ? 1 : 2;
    for (trial = 0; trial < n_trials; trial++) {
        int want = RK_OPEN;
        for (i = 0, k = 0; i < n; i++) {
            if (!RK_IN(cand, i))
                continue;
            if (i == c)
                hint[k] = want = trial == 0 ? RK_OPEN : lam_T > 0.0 ? RK_SLIDE_NEG : RK_SLIDE_POS;
            else if (sliding[i])
                hint[k] = sliding[i] > 0 ? RK_SLIDE_POS : RK_SLIDE_NEG;
            else
                hint[k] = RK_IN(closed, i) ? RK_STICK : RK_OPEN;
            k++;
        }
        ED_TRY(rk_solve_friction_lcp(&p, &sol, err));
        if (sol.exact && sol.states[c] == want && !rk_lcp_painleve(&sol)) {
            *mode = m->ops->mode_of(m, sol.active, rk_solution_sigma(&sol, n));
            return RK_OK;
        }
    }
    return RK_OK;
}

/** `_enter` at the zero of the normal force of the closed contact c (a release event). There every state of c
 *  carries no normal force, so the acceleration LCP is degenerate and its first exact solution may be the
 *  branch that ends there (the friction LCP accepts a normal force down to -lcp_exact of its scale): kept, the
 *  force would go on into tension with its event function at or below -event_tol, neither armed nor watched
 *  by the next segment. The force crossed zero going down, so the continuation is another state of c. */
static rk_status ed_release(rk_engine *e, const double *q, const double *v, double ag_t, double av_t, double t,
                            int c, double lam_T, rk_error *err)
{
    rk_ed_state *s = ED(e);
    int mode, changed, alt;
    double v2[RK_MAX_DOF];
    ED_TRY(ed_decide(e, q, v, ag_t, av_t, t, -1, &mode, v2, &changed, err));
    if (mode == s->mode && !changed) {
        ED_TRY(ed_released_mode(e, q, v, ag_t, av_t, c, lam_T, &alt, err));
        if (alt >= 0)
            mode = alt;
    }
    return ed_set_state(e, mode, q, v2, 1, err);
}

/** `_impact` */
static rk_status ed_impact(rk_engine *e, const double *q_in, const double *v, double t, double ag_t, double av_t,
                           rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int nc = m->ops->n_contacts, n = m->ops->n_dof, i, mode, changed;
    double g[RK_MAX_CONTACTS], q[RK_MAX_DOF], v_plus[RK_MAX_DOF], v_impact[RK_MAX_DOF];
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS], U_minus[RK_MAX_CONTACTS];
    rk_set cand = 0, grazing = 0, closed_before;
    int recorded;
    memcpy(q, q_in, (size_t)n * sizeof(double));
    m->ops->gaps(m, q, g);
    for (i = 0; i < nc; i++)
        if (g[i] <= s->gap_tol)
            cand |= 1u << i;
    closed_before = rk_closed_of(m, s->mode);
    /* a corner found below the ground beyond round-off fired event_tol below it: a grazing landing, put back
     * onto the ground and closed plastically (the Zeno rule) */
    for (i = 0; i < nc; i++)
        if (RK_IN(cand, i) && g[i] < -e->options.tolerances.grazing * s->gap_tol)
            grazing |= 1u << i;
    if (grazing)
        ED_TRY(rk_project_to_ground(m, q_in, cand | closed_before, q, err));
    if (ed_popcount(closed_before) == 1 && ed_popcount(cand) == nc && nc == 2
        && m->ops->classical_impact_velocity != NULL) {
        /* an impact rule of the model (the classical rule) replaces the impact LCP at a rocking impact */
        int rule = m->ops->classical_impact_velocity(m, q, v, s->mode, v_plus);
        if (rule < 0)
            return ed_classical_refusal(m, s->mode, v, err);
        if (rule) {
            ED_TRY(ed_record_impact(e, t, v, v_plus, err));
            ed_count_painleve(e, q, v, v_plus, cand);
            return ed_enter(e, q, v_plus, ag_t, av_t, t, -1, err);
        }
    }
    ED_TRY(ed_impact_velocity(e, q, v, cand, grazing, ag_t, av_t, t, v_impact, err));
    ED_TRY(ed_decide(e, q, v_impact, ag_t, av_t, t, -1, &mode, v_plus, &changed, err));
    if (grazing & ~rk_closed_of(m, mode)) {
        /* held closed, the corner is still sent into flight (the sticking LCP has no solution): not held */
        memcpy(q, q_in, (size_t)n * sizeof(double));
        ED_TRY(ed_impact_velocity(e, q, v, cand, 0, ag_t, av_t, t, v_impact, err));
        ED_TRY(ed_decide(e, q, v_impact, ag_t, av_t, t, -1, &mode, v_plus, &changed, err));
    }
    m->ops->contact_jacobians(m, q, W_N, W_T);
    ed_wtx(m, W_N, v, U_minus);
    recorded = 0;
    for (i = 0; i < nc; i++)
        if (RK_IN(cand, i) && U_minus[i] < -s->v_zeno)
            recorded = 1;
    if (recorded)
        ED_TRY(ed_record_impact(e, t, v, v_plus, err));
    ed_count_painleve(e, q, v, v_impact, cand);
    return ed_set_state(e, mode, q, v_plus, 1, err);
}

/** `_note_percussions`: |sum Lambda_T| / sum Lambda_N of the impact from v_minus to the current velocity */
static void ed_note_percussions(rk_engine *e, const double *q, const double *v_minus)
{
    const rk_model *m = &e->model;
    const rk_ed_state *s = ED(e);
    int n = m->ops->n_dof, i, j;
    double M[RK_MAX_DOF * RK_MAX_DOF], qq[RK_MAX_DOF], v[RK_MAX_DOF], dv[RK_MAX_DOF], P[RK_MAX_DOF];
    double lam_N;
    m->ops->mass_matrix(m, q, M);
    rk_ed_full_state(e, qq, v);
    for (i = 0; i < n; i++)
        dv[i] = v[i] - v_minus[i];
    for (i = 0; i < n; i++) {
        double acc = 0.0;
        for (j = 0; j < n; j++)
            acc += M[i * n + j] * dv[j];
        P[i] = acc;
    }
    lam_N = P[m->ops->lift_index];
    if (lam_N > s->force_floor * m->time_scale)
        ed_note_ratio(e, fabs(P[m->ops->slide_index]) / lam_N);
}

/** `_handle` */
static rk_status ed_handle(rk_engine *e, int kind, int idx, double t, ed_fn *f, rk_error *err)
{
    rk_ed_state *s = ED(e);
    double q[RK_MAX_DOF], v[RK_MAX_DOF], a, av;
    int j;
    rk_ed_full_state(e, q, v);
    if (kind == ED_OVERTURN) {
        /* the motion ends: the pose at |phi| = pi/2, at rest */
        s->overturned = 1;
        for (j = 0; j < s->k; j++)
            s->y[s->k + j] = 0.0;
        e->core.token++;
        return RK_OK;
    }
    if (kind == ED_SWITCH) {
        /* a force law changed (no impulse, the mode holds): the step ends here and the next one starts at the
         * kink; the crossed function's side flips */
        int n_events, kinds[RK_MAX_EVENTS];
        n_events = ed_kinds(e, s->mode, kinds);
        s->switch_side[idx - (n_events - 1 - e->model.ops->n_switches)] *= -1.0;
        e->g_memo.valid = 0;
        e->core.token++;
        return RK_OK;
    }
    if (kind == ED_IMPACT) {
        ED_TRY(ed_ag_call(f->ag, f->ag_v, t, &a, &av, err));
        ED_TRY(ed_impact(e, q, v, t, a, av, err));
        ed_note_percussions(e, q, v);
    } else if (kind == ED_CONE) {
        /* the friction reached mu lambda_N: the corners slide against it */
        double lam[2];
        ED_TRYF(f, ed_totals(f, t, s->y, lam));
        ED_TRY(ed_ag_call(f->ag, f->ag_v, t, &a, &av, err));
        ED_TRY(ed_enter(e, q, v, a, av, t, lam[1] > 0.0 ? RK_SLIDE_NEG : RK_SLIDE_POS, err));
    } else if (kind == ED_RELEASE) {
        double lam[2];
        ED_TRYF(f, ed_totals(f, t, s->y, lam));
        ED_TRY(ed_ag_call(f->ag, f->ag_v, t, &a, &av, err));
        ED_TRY(ed_release(e, q, v, a, av, t, idx, lam[1], err));
    } else {
        ED_TRY(ed_ag_call(f->ag, f->ag_v, t, &a, &av, err));
        ED_TRY(ed_enter(e, q, v, a, av, t, -1, err));
    }
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ demand peak */

/** the demand ratio on the dense output of the last step (NAN: None) */
static rk_status ed_demand_at(rk_engine *e, ed_fn *f, double t, double *d, rk_error *err)
{
    double y[RK_MAX_Y], lam[2];
    ED_TRYF(f, rk_dense_eval(&ED(e)->stepper, t, y, err));
    ED_TRYF(f, ed_totals(f, t, y, lam));
    *d = ed_ratio(ED(e), lam);
    return RK_OK;
}

/** the demand as an rk_scalar_fn for rk_brent_max (the Python's ``demand(t)`` closure) */
static rk_status ed_demand_fn(void *ctx, double t, double *value, int *has)
{
    ed_fn *f = (ed_fn *)ctx;
    rk_status st = ed_demand_at(f->e, f, t, value, &f->err);
    *has = st == RK_OK && !isnan(*value);
    return st;
}

/** `_demand_peak`: raise friction_demand to the peak of the demand inside [t0, t1] (ends d0, d1 noted);
 *  hermite 1: the middle state from the cubic Hermite estimate (mid_of), else from the dense output */
static rk_status ed_demand_peak(rk_engine *e, ed_fn *f, double t0, double d0, double t1, double d1, int hermite,
                                rk_error *err)
{
    rk_ed_state *s = ED(e);
    double tm, y_mid[RK_MAX_Y], lam[2], dm, vx, vv, tv, dv, xtol, best, tb;
    int has = 0;
    if (isnan(d0) || isnan(d1) || !(t1 > t0) || (d0 > d1 ? d0 : d1) < ED_DEMAND_STEP_GATE * s->friction_demand)
        return RK_OK;
    tm = 0.5 * (t0 + t1);
    if (!hermite)
        ED_TRYF(f, rk_dense_eval(&s->stepper, tm, y_mid, err));
    else
        rk_hermite_mid(&s->stepper, y_mid);
    ED_TRYF(f, ed_totals(f, tm, y_mid, lam));
    dm = ed_ratio(s, lam);
    if (isnan(dm))
        return RK_OK;
    if (!rk_parabola_peak(d0, dm, d1, &vx, &vv) || vv < (1.0 - ED_DEMAND_PEAK_MARGIN) * s->friction_demand)
        return RK_OK;
    tv = t0 + vx * (t1 - t0);
    xtol = sqrt(s->tolerance) * (t1 - t0);
    if (4.0 * ed_ulp(fmax(fabs(t1), 1.0)) > xtol)      /* max(a, b): b only when larger */
        xtol = 4.0 * ed_ulp(fmax(fabs(t1), 1.0));
    ED_TRY(ed_demand_at(e, f, tv, &dv, err));
    ED_TRYF(f, rk_brent_max(ed_demand_fn, f, t0, t1, tv, dv, !isnan(dv), xtol, ED_BRENT_MAX_ITER, &tb, &best,
                            &has, err));
    if (has)
        ed_note_ratio(e, best);
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ segment */

/** Per-segment event bookkeeping */
typedef struct ed_ev {
    int n;                              /**< event functions */
    int armed[RK_MAX_EVENTS], watch[RK_MAX_EVENTS];
    int has_start[RK_MAX_EVENTS];       /**< rose: bounce found (start_t, start_g) */
    double start_t[RK_MAX_EVENTS];
    double start_g[RK_MAX_EVENTS * RK_MAX_EVENTS];
} ed_ev;

/** `_bounces` after the first step of a segment */
static rk_status ed_bounces(rk_engine *e, rk_event_ctx *c, const int *kinds, ed_ev *ev, const double *g_new,
                            ed_fn *f, rk_error *err)
{
    rk_ed_state *s = ED(e);
    double level = e->options.tolerances.rise * s->event_tol;
    int i;
    for (i = 0; i < ev->n; i++) {
        if (ev->watch[i] && kinds[i] == ED_IMPACT && g_new[i] <= 0.0) {
            int found = 0;
            double tf, gf[RK_MAX_EVENTS];
            ED_TRYF(f, rk_bounce_search(c, i, s->stepper.t_old, s->stepper.t, level, &found, &tf, gf, err));
            if (found) {
                ev->armed[i] = 1;
                ev->watch[i] = 0;
                ev->has_start[i] = 1;
                ev->start_t[i] = tf;
                memcpy(ev->start_g + i * ev->n, gf, (size_t)ev->n * sizeof(double));
            }
        }
    }
    return RK_OK;
}

/** `_find_event`: *found 1 with (te, index) of the first event in the last step */
static rk_status ed_find_event(rk_engine *e, rk_event_ctx *c, ed_ev *ev, const double *g_prev,
                               const double *g_new, int *found, double *te, int *idx, ed_fn *f, rk_error *err)
{
    rk_ed_state *s = ED(e);
    double tol = s->event_tol, t0 = s->stepper.t_old, t_hit = s->stepper.t, xtol;
    int n_sub = e->options.tolerances.sub_samples, n = ev->n, i;
    int hits[RK_MAX_EVENTS], n_hits = 0, others[RK_MAX_EVENTS], n_others = 0;
    double ga_buf[RK_MAX_EVENTS], gb_buf[RK_MAX_EVENTS], shifts[RK_MAX_EVENTS];
    const double *g_a = g_prev, *g_b = g_new;
    *found = 0;
    for (i = 0; i < n; i++)
        if ((ev->armed[i] && g_new[i] <= 0.0) || (ev->watch[i] && g_new[i] <= -tol))
            hits[n_hits++] = i;
    if (!n_hits) {
        int used_dense = 0;
        ED_TRYF(f, rk_dip_search(c, ev->armed, g_prev, g_new, n_sub, hits, &n_hits, &t0, &t_hit, ga_buf,
                                 gb_buf, &used_dense, err));
        if (!n_hits)
            return RK_OK;
        g_a = ga_buf;
        g_b = gb_buf;
    }
    xtol = 4.0 * ed_ulp(fmax(fabs(s->stepper.t), 1.0));
    for (i = 0; i < n; i++)
        shifts[i] = ev->armed[i] ? 0.0 : tol;
    ED_TRYF(f, rk_earliest_root(c, hits, n_hits, shifts, ev->has_start, ev->start_t, ev->start_g, t0, g_a, t_hit,
                                g_b, xtol, te, idx, err));
    for (i = 0; i < n - 1; i++) {
        int j, in_hits = 0;
        for (j = 0; j < n_hits; j++)
            if (hits[j] == i)
                in_hits = 1;
        if (ev->armed[i] && !in_hits)
            others[n_others++] = i;
    }
    if (n_others && *te > t0) {
        int fn = 0, neg[RK_MAX_EVENTS], n_neg = 0, neg_te[RK_MAX_EVENTS], n_neg_te = 0, dip[RK_MAX_EVENTS], n_dip = 0;
        double ta, tn, ga[RK_MAX_EVENTS], gn[RK_MAX_EVENTS], gm[RK_MAX_EVENTS];
        for (i = 0; i < n_others; i++)
            if (isnan(g_a[others[i]]))
                break;
        if (i < n_others) {
            /* dip_search's sub-samples hold the dipping functions alone (rk_first_negative): all of G at t0, the
             * values the Python's sub-sample holds */
            ED_TRYF(f, rk_event_eval(c, t0, ga_buf, err));
            g_a = ga_buf;
        }
        ED_TRYF(f, rk_event_eval(c, *te, gn, err));
        for (i = 0; i < n_others; i++)
            if (gn[others[i]] <= 0.0)
                neg_te[n_neg_te++] = others[i];
        if (n_neg_te) {
            /* below the ground at te: the first sub-interval where one of them is */
            ED_TRYF(f, rk_first_negative(c, t0, g_a, *te, others, n_others, n_sub, &fn, neg, &n_neg, &ta, ga,
                                         &tn, gm, err));
            if (fn) {
                memcpy(gn, gm, sizeof gm);
            } else {
                /* te itself: a corner that crosses inside the last sub-interval (not sampled) */
                memcpy(neg, neg_te, sizeof neg_te);
                n_neg = n_neg_te;
                fn = 1;
                tn = *te;
                ta = t0 + (*te - t0) * (n_sub - 1) / (double)n_sub;
                ED_TRYF(f, rk_event_eval(c, ta, ga, err));
            }
        } else {
            /* above it at both ends: sub-sampled only where the midpoint says it may dip in between */
            double tm = 0.5 * (t0 + *te);
            ED_TRYF(f, rk_event_eval(c, tm, gm, err));
            for (i = 0; i < n_others; i++)
                if (rk_may_dip(g_a[others[i]], gm[others[i]], gn[others[i]]))
                    dip[n_dip++] = others[i];
            if (n_dip)
                ED_TRYF(f, rk_first_negative(c, t0, g_a, *te, dip, n_dip, n_sub, &fn, neg, &n_neg, &ta, ga, &tn,
                                             gn, err));
        }
        if (fn)
            ED_TRYF(f, rk_earliest_root(c, neg, n_neg, shifts, ev->has_start, ev->start_t, ev->start_g, ta, ga,
                                        tn, gn, xtol, te, idx, err));
    }
    *found = 1;
    return RK_OK;
}

/** `_stepper`: the live stepper carried on, restarted under a new rhs, or a new one */
static rk_status ed_stepper(rk_engine *e, ed_fn *f, double max_step, rk_error *err)
{
    rk_ed_state *s = ED(e);
    rk_stepper *st = &s->stepper;
    int same_rhs = s->rhs_mode == f->mode
                   && (f->constant ? (s->rhs_constant && s->rhs_value == f->a0 && s->rhs_value_v == f->v0)
                                   : (!s->rhs_constant && s->rhs_motion == s->motion_key));
    if (s->live && st->t == s->t && st->max_step == max_step) {
        st->fun = ed_rhs;
        st->ctx = f;
        if (!same_rhs)
            ED_TRYF(f, rk_stepper_restart(st, ed_rhs, f, s->t, s->y, s->h, err));
    } else {
        double atol[RK_MAX_Y];
        ed_atol(e, f->mode, atol);
        ED_TRYF(f, rk_stepper_init(st, s->tab, ed_rhs, f, s->t, s->y, 2 * s->k, s->tolerance, atol, max_step,
                                   s->k ? s->h : NAN, NULL, err));
    }
    st->fun1 = f->acc1 != NULL ? ed_acc1 : NULL;
    /* (ed_acc1 under a constant input is the kernel with f->a0, f->v0) */
    st->acc1 = f->acc1 != NULL && f->constant ? f->acc1 : NULL;
    st->acc1_m = &e->model;
    st->acc1_mode = f->mode;
    st->acc1_ag = f->a0;
    st->acc1_ag_v = f->v0;
    s->rhs_mode = f->mode;
    s->rhs_constant = f->constant;
    s->rhs_value = f->a0;
    s->rhs_value_v = f->v0;
    s->rhs_motion = s->motion_key;
    return RK_OK;
}

/** `_work_message` */
static rk_status ed_work_limit(rk_engine *e, rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    char note[160], stiff[176], nb[16];
    note[0] = '\0';
    stiff[0] = '\0';
    if (m->ops->work_note != NULL)
        m->ops->work_note(m, note, sizeof note);
    if (note[0])
        snprintf(stiff, sizeof stiff, ", %s", note);
    return rk_fail(err, RK_ERR_WORK_LIMIT, "event_driven: advancing from t = %.17g s by %.6g s needs more than "
                   "max_steps = %lld internal steps (Runge-Kutta steps, each event counting %d); %lld impacts so "
                   "far in this step; stopped at t = %.17g s in mode %s with steps of %.3g s (tolerance = %g, "
                   "dt_max = %g s, method %s%s, time scale 1/p = %.3g s); the step was refused and the state kept. "
                   "Way out: shorter communication steps, a looser tolerance, a larger dt_max (0: uncapped), or "
                   "max_steps=None (unlimited, for trusted batch runs)", s->span0, s->span1 - s->span0,
                   s->max_work, ED_EVENT_WORK, s->impacts - s->impacts0, s->stepper.t,
                   ed_mode_name(s->mode, nb, sizeof nb), s->stepper.h_abs, s->tolerance, s->dt_max,
                   rk_tableau_name(s->tab), stiff, m->time_scale);
}

/** `_lands_now`: an open corner starts the segment below -event_tol (neither armed nor watched) approaching the
 *  ground (U_N < -v_tol): the impact LCP decides at once */
static int ed_lands_now(rk_engine *e, const int *kinds, int n_events, const double *g_prev)
{
    const rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int i, any = 0;
    double q[RK_MAX_DOF], v[RK_MAX_DOF], U[RK_MAX_CONTACTS];
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS];
    for (i = 0; i < n_events; i++)
        if (kinds[i] == ED_IMPACT && g_prev[i] <= -s->event_tol)
            any = 1;
    if (!any)
        return 0;
    rk_ed_full_state(e, q, v);
    m->ops->contact_jacobians(m, q, W_N, W_T);
    ed_wtx(m, W_N, v, U);
    for (i = 0; i < n_events; i++)
        if (kinds[i] == ED_IMPACT && g_prev[i] <= -s->event_tol && U[i] < -s->v_tol)
            return 1;
    return 0;
}

/** `_segment`: integrate the current mode towards t_stop; *event 1 if an event ended it */
static rk_status ed_segment(rk_engine *e, double t_stop, ed_fn *f, ed_out *o, int *event, rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int mode = s->mode, k = s->k, kinds[RK_MAX_EVENTS], has_totals, peaks, first, refusals, i;
    ed_ev ev;
    rk_event_ctx c;
    double lam[2], d_prev = NAN, max_step, g_prev[RK_MAX_EVENTS], g_new[RK_MAX_EVENTS];
    *event = 0;
    if (ed_pending(o) && o->times[o->next] <= s->t) {
        while (ed_pending(o) && o->times[o->next] <= s->t)
            ed_row(e, o, mode, s->y, 0);
        if (s->max_work >= 0)
            s->work_end = (double)s->n_steps + (double)s->max_work;
    }
    has_totals = ed_has_totals(m, mode);
    if (k == 0 && f->constant) {
        /* nothing moves and the (positive) contact forces cannot change */
        if (has_totals) {
            /* (through g_memo: the settle before it computed them at an input change) */
            ED_TRYF(f, ed_G_totals(f, s->t, s->y, 0, g_prev, lam));
            if (lam[0] > s->force_floor)
                ed_note_ratio(e, fabs(lam[1]) / lam[0]);
        }
        s->t = t_stop;
        while (ed_pending(o) && o->times[o->next] <= t_stop)
            ed_row(e, o, mode, s->y, 0);
        e->core.token++;
        return RK_OK;
    }
    ev.n = ed_kinds(e, mode, kinds);
    /* the friction demand: at the segment's start, at step ends, at its peak inside a step, at the event
     * (a sliding mode's is mu wherever the normal force carries load: its ends suffice) */
    peaks = has_totals && !rk_mode_sliding(m, mode);
    /* (a motion with a callback is called as often as before: no memo) */
    if (peaks && f->pure && k > 0)
        f->memo_n = 2 * k;
    /* G and the demand at the segment's start, from one kernel call (as at the step ends below) */
    ED_TRYF(f, ed_G_totals(f, s->t, s->y, 2 * k, g_prev, has_totals ? lam : NULL));
    ed_switch_sides(e, kinds, ev.n, g_prev);
    if (has_totals) {
        d_prev = ed_ratio(s, lam);
        ed_note_ratio(e, d_prev);
    }
    if (g_prev[ev.n - 1] <= 0.0) {
        /* at or past |phi| = pi/2 already (a step that jumped over an impact and the overturning at once, from
         * a state whose time or velocity leaves them below its time resolution): the structure has overturned,
         * in the pose at |phi| = pi/2 */
        int idx[RK_MAX_DOF], j, nd = rk_dofs_of(m, mode, idx);
        for (j = 0; j < nd; j++)
            if (idx[j] == m->ops->phi_index)
                s->y[j] = s->y[j] < 0.0 ? -RK_HALF_PI : RK_HALF_PI;
        ED_TRY(ed_handle(e, ED_OVERTURN, ev.n - 1, s->t, f, err));
        *event = 1;
        return RK_OK;
    }
    if (ed_lands_now(e, kinds, ev.n, g_prev)) {
        ED_TRY(ed_handle(e, ED_IMPACT, -1, s->t, f, err));
        *event = 1;
        return RK_OK;
    }
    /* without state a step only samples the contact forces under a varying input: short enough for the dip
     * search to see a force that comes and goes */
    max_step = k ? s->dt_max : (s->dt_max < s->stateless_step ? s->dt_max : s->stateless_step);
    ED_TRY(ed_stepper(e, f, max_step, err));
    c.stepper = &s->stepper;
    c.G = ed_G;
    c.G_ctx = f;
    c.n_events = ev.n;
    c.G_one = ed_G_one;
    c.G_one_mask = ed_G_one_mask;
    c.one_known = 0;
    for (i = 0; i < ev.n; i++) {
        ev.armed[i] = g_prev[i] > 0.0;
        ev.watch[i] = !ev.armed[i] && g_prev[i] > -s->event_tol;
        ev.has_start[i] = 0;
    }
    first = 1;
    refusals = 0;
    while (s->stepper.t < t_stop) {
        double d_new = NAN, te;
        int found, idx;
        ED_TRYF(f, rk_step(&s->stepper, t_stop, err));
        s->n_steps++;
        if (s->stepper.failed) {
            s->stepper.failed = 0;
            rk_report_add(&e->reports, RK_REPORT_FAILED_STEP, s->stepper.t, "%s", s->stepper.failure);
        }
        if ((double)s->n_steps > s->work_end)
            return ed_work_limit(e, err);
        /* G and the demand at the step's end, from one evaluation (the kernels share their work between the
         * two, as the Python's closures do; part A pins the event functions with totals to those without) */
        ED_TRYF(f, ed_G_totals(f, s->stepper.t, s->stepper.y, 2 * k, g_new, has_totals ? lam : NULL));
        if (has_totals)
            d_new = ed_ratio(s, lam);
        if (refusals < ED_MAX_SINK_REFUSALS && s->stepper.t > s->stepper.t_old) {
            /* `MAX_SINK_REFUSALS`: a step whose interpolant sinks a watched open corner is retried at half */
            int ids[RK_MAX_EVENTS], n_ids = 0, sunk = 0;
            for (i = 0; i < ev.n; i++)
                if (ev.watch[i] && kinds[i] == ED_IMPACT && g_new[i] > -s->event_tol)
                    ids[n_ids++] = i;
            if (n_ids > 0)
                ED_TRYF(f, rk_sinks(&c, ids, n_ids, s->stepper.t_old, s->stepper.t,
                                     e->options.tolerances.sub_samples, e->options.tolerances.gap, &sunk, err));
            if (sunk) {
                double h_half = 0.5 * (s->stepper.t - s->stepper.t_old);
                refusals++;
                ED_TRYF(f, rk_stepper_restart(&s->stepper, ed_rhs, f, s->stepper.t_old, s->stepper.y_old,
                                               h_half, err));
                continue;
            }
        }
        for (i = 0; i < ev.n; i++)
            ev.has_start[i] = 0;
        if (first) {
            first = 0;
            ED_TRY(ed_bounces(e, &c, kinds, &ev, g_new, f, err));
        }
        ED_TRY(ed_find_event(e, &c, &ev, g_prev, g_new, &found, &te, &idx, f, err));
        if (found) {
            double t_old = s->stepper.t_old;
            ED_TRY(ed_record_samples(e, o, mode, te, 0, f, err));
            if (k && s->stepper.h_abs > 0)
                s->h = s->stepper.h_abs;
            s->t = te;
            ED_TRYF(f, rk_dense_eval(&s->stepper, te, s->y, err));
            s->live = 0;
            e->core.token++;
            if (has_totals) {
                /* the demand up to the event, its left limit included */
                double d_e;
                ED_TRYF(f, ed_totals(f, te, s->y, lam));
                d_e = ed_ratio(s, lam);
                if (peaks)
                    ED_TRY(ed_demand_peak(e, f, t_old, d_prev, te, d_e, 0, err));
                ed_note_ratio(e, d_e);
            }
            ED_TRY(ed_handle(e, kinds[idx], idx, te, f, err));
            *event = 1;
            return RK_OK;
        }
        if (ed_pending(o) && o->times[o->next] <= s->stepper.t)
            ED_TRY(ed_record_samples(e, o, mode, s->stepper.t, 1, f, err));
        if (has_totals) {
            if (peaks)
                ED_TRY(ed_demand_peak(e, f, s->stepper.t_old, d_prev, s->stepper.t, d_new, 1, err));
            ed_note_ratio(e, d_new);
            d_prev = d_new;
        }
        for (i = 0; i < ev.n; i++) {
            if (g_new[i] > 0.0) {
                ev.armed[i] = 1;
                ev.watch[i] = 0;
            }
        }
        rk_copy(g_prev, g_new, ev.n);
    }
    s->t = s->stepper.t;
    rk_copy(s->y, s->stepper.y, 2 * k);
    if (k)
        s->h = s->stepper.h_abs;
    s->live = 1;
    e->core.token++;
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ settle */

/** `_settle`: re-decide the mode of the current state by the acceleration LCP (after an input change) */
static rk_status ed_settle(rk_engine *e, double t, rk_motion *ag, rk_motion *ag_v, ed_fn *f, rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int mode = s->mode, nc = m->ops->n_contacts, n_e, i, ok, new_mode, changed;
    rk_set closed = rk_closed_of(m, mode), cc;
    double ev[RK_MAX_EVENTS], clear = e->options.tolerances.clearly_open, q[RK_MAX_DOF], v[RK_MAX_DOF];
    double v_new[RK_MAX_DOF], a, av, lam[2];
    int kinds[RK_MAX_EVENTS];
    n_e = ed_kinds(e, mode, kinds);
    /* (with the totals where the segment reads them: the segment that follows starts from the same values, kept
     * in g_memo; G is the same with or without them) */
    ED_TRYF(f, ed_G_totals(f, t, s->y, 2 * s->k, ev, ed_has_totals(m, mode) ? lam : NULL));
    /* fast path: closed corners loaded, open corners clearly open, friction within its cone or the slip going
     * on or just starting */
    ok = 1;
    for (i = 0; i < n_e - 1; i++) {
        int c = kinds[i] == ED_SWITCH || (i >= nc ? ev[i] >= 0.0 : RK_IN(closed, i) ? ev[i] > 0.0 : ev[i] > clear);
        if (!c) {
            ok = 0;
            break;
        }
    }
    if (ok)
        return RK_OK;
    rk_ed_full_state(e, q, v);
    cc = rk_closed_candidates(m, q, v, s->gap_tol, s->v_tol);
    if ((cc & ~closed) == 0) {
        int all = 1;
        for (i = 0; i < nc; i++)
            if (RK_IN(closed, i) && !(ev[i] > 0.0))
                all = 0;
        for (i = nc; i < n_e - 1; i++)
            if (kinds[i] != ED_SWITCH && !(ev[i] >= 0.0))
                all = 0;
        if (all)
            return RK_OK;
    }
    ED_TRY(ed_ag_call(ag, ag_v, t, &a, &av, err));
    ED_TRY(ed_decide(e, q, v, a, av, t, -1, &new_mode, v_new, &changed, err));
    if (new_mode != mode || changed)
        return ed_set_state(e, new_mode, q, v_new, 1, err);
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ run */

rk_status rk_ed_run(rk_engine *e, double t_end, rk_motion *ag, rk_motion *ag_v, const double *samples,
                    long long n_samples,
                    long long max_steps, int *modes, double *values, long long *impacts, int *overturned,
                    unsigned flags, rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    ed_out out, *o = NULL;
    ed_fn f;
    long long n_events = 0;
    int kink, event;
    double end_tol;
    if (samples != NULL) {
        out.times = samples;
        out.n = n_samples;
        out.next = 0;
        out.modes = modes;
        out.values = values;
        out.impacts = impacts;
        out.overturned = overturned;
        out.row = 0;
        o = &out;
    }
    if (!rk_motion_pair_constant(ag, ag_v)) {
        /* the Python's closures of a non-constant input are keyed by id(ag): the same object carries the live
         * stepper on (FSAL, h_abs), a new one restarts it (bit-identically) */
        if (ag->identity != 0)
            s->motion_key = ag->identity | ED_KEY_IDENTITY;
        else
            s->motion_key = ++s->motion_serial & ~ED_KEY_IDENTITY;
    }
    s->max_work = max_steps < 0 ? -1 : max_steps;
    s->work_end = max_steps < 0 ? INFINITY : (double)s->n_steps + (double)max_steps;
    s->span0 = s->t;
    s->span1 = t_end;
    s->impacts0 = s->impacts;
    if (t_end <= s->t || s->overturned) {
        if (t_end > s->t) {
            s->t = t_end;
            e->core.token++;
        }
        while (ed_pending(o))
            ed_row(e, o, s->mode, s->y, -1);
        return RK_OK;
    }
    kink = (flags & RK_ADVANCE_CONTINUOUS) != 0;
    end_tol = 4.0 * ed_ulp(fmax(fabs(t_end), 1.0));
    while (!s->overturned) {
        double tb, t_stop;
        if (t_end - s->t <= end_tol)
            break;
        tb = rk_motion_pair_next_breakpoint(ag, ag_v, s->t);
        t_stop = t_end < tb ? t_end : tb;
        /* (the settle's functions serve the segment unless it changed the mode) */
        ed_fn_init(&f, e, s->mode, ag, ag_v);
        if (rk_closed_of(m, s->mode) && !kink) {
            ED_TRY(ed_settle(e, s->t, ag, ag_v, &f, err));
            if (s->mode != f.mode)
                ed_fn_init(&f, e, s->mode, ag, ag_v);
        }
        ED_TRY(ed_segment(e, t_stop, &f, o, &event, err));
        if (event) {
            s->live = 0;
            kink = 0;
            n_events++;
            s->work_end -= ED_EVENT_WORK;
            if (n_events > s->max_events)
                return rk_fail(err, RK_ERR_WORK_LIMIT, "event_driven: more than %d events in one advance at "
                               "t = %.17g s; the motion does not settle; the step was refused. Way out: shorter "
                               "communication steps", s->max_events, s->t);
        } else if (t_stop == tb) {
            /* a kink of ag (a sample of a record): the mode holds and the step goes on across it; a jump:
             * re-decide the mode and restart */
            kink = rk_motion_pair_continuous_at(ag, ag_v, tb);
            if (!kink)
                s->live = 0;
        }
    }
    s->t = t_end;
    e->core.token++;
    while (ed_pending(o))               /* samples at t_end (or after overturning: frozen state) */
        ed_row(e, o, s->mode, s->y, -1);
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ plain-data state */

static rk_status ed_check_times(const char *key, const double *times, long long n, double t, long long impacts,
                                long long stride, rk_error *err)
{
    double t_max = t + ED_TIMES_RTOL * fmax(1.0, fabs(t));
    long long i;
    if (n > impacts)
        return rk_fail(err, RK_ERR_VALUE, "state field '%s' holds %lld impacts, more than impacts = %lld", key, n,
                       impacts);
    for (i = 0; i < n; i++) {
        double ti = times[i * stride];
        if (!isfinite(ti))
            return rk_fail(err, RK_ERR_VALUE, "state field '%s'[%lld] = %.17g is not finite", key, i * stride, ti);
        if (ti > t_max || (i && ti < times[(i - 1) * stride]))
            return rk_fail(err, RK_ERR_VALUE, "state field '%s': impact time %.17g is after t = %.17g or out of "
                           "order", key, ti, t);
    }
    return RK_OK;
}

rk_status rk_ed_set_state(rk_engine *e, const rk_plain_state *st, const double *impact_times, long long n_times,
                          const double *impact_log, long long n_log_rows, rk_error *err)
{
    rk_ed_state *s = ED(e);
    const rk_model *m = &e->model;
    int k, i, idx[RK_MAX_DOF], row_len = 1 + 2 * m->ops->n_dof;
    double q[RK_MAX_DOF], v[RK_MAX_DOF];
    long long r;
    if (!isfinite(st->t))
        return rk_fail(err, RK_ERR_VALUE, "state field 't' = %.17g is not finite; allowed range [-inf, inf]", st->t);
    if (st->mode < 0 || st->mode >= m->ops->n_modes)
        return rk_fail(err, RK_ERR_VALUE, "state field 'mode' = %d is out of range; allowed range [0, %d]",
                       st->mode, m->ops->n_modes - 1);
    k = rk_dofs_of(m, st->mode, idx);
    if (st->n_y != 2 * k)
        return rk_fail(err, RK_ERR_VALUE, "state field 'y' has %d values; expected %d", st->n_y, 2 * k);
    for (i = 0; i < st->n_y; i++)
        if (!isfinite(st->y[i]))
            return rk_fail(err, RK_ERR_VALUE, "state field 'y'[%d] = %.17g is not finite", i, st->y[i]);
    if (st->impacts < 0)
        return rk_fail(err, RK_ERR_VALUE, "state field 'impacts' = %lld is out of range", st->impacts);
    if (st->n_steps < 0)
        return rk_fail(err, RK_ERR_VALUE, "state field 'n_steps' = %lld is out of range", st->n_steps);
    if (!isnan(st->h) && !(isfinite(st->h) && st->h > 0.0))
        return rk_fail(err, RK_ERR_VALUE, "state field 'h' = %.17g is not in range; allowed range (0, inf) or nan "
                       "(unset)", st->h);
    if (e->impact_times.maxlen >= 0 && n_times > e->impact_times.maxlen)
        return rk_fail(err, RK_ERR_VALUE, "state field 'impact_times' has %lld values; allowed at most %lld",
                       n_times, e->impact_times.maxlen);
    ED_TRY(ed_check_times("impact_times", impact_times, n_times, st->t, st->impacts, 1, err));
    if (e->impact_log.maxlen >= 0 && n_log_rows > e->impact_log.maxlen)
        return rk_fail(err, RK_ERR_VALUE, "state field 'impact_log' has %lld values; allowed at most %lld",
                       n_log_rows * row_len, e->impact_log.maxlen * row_len);
    for (r = 0; r < n_log_rows * row_len; r++)
        if (!isfinite(impact_log[r]))
            return rk_fail(err, RK_ERR_VALUE, "state field 'impact_log'[%lld] = %.17g is not finite", r,
                           impact_log[r]);
    ED_TRY(ed_check_times("impact_log", impact_log, n_log_rows, st->t, st->impacts, row_len, err));
    rk_embed_any(m, st->mode, st->y, q, v);
    if (!isfinite(st->shift))
        return rk_fail(err, RK_ERR_VALUE, "state field 'shift' = %.17g is not finite", st->shift);
    if (st->shift != 0.0 && (rk_mode_sliding(m, st->mode) || !rk_closed_of(m, st->mode)))
        return rk_fail(err, RK_ERR_VALUE, "state field 'shift' = %.17g must be 0 in mode %d (its reduced state "
                       "holds the base's position)", st->shift, st->mode);
    if (!(isfinite(st->friction_demand) && st->friction_demand >= 0.0))
        return rk_fail(err, RK_ERR_VALUE, "state field 'friction_demand' = %.17g is not in range; allowed range "
                       "[0, inf]", st->friction_demand);
    if (st->painleve < 0)
        return rk_fail(err, RK_ERR_VALUE, "state field 'painleve' = %lld is out of range", st->painleve);
    /* check_configuration(model, state, "y", q, v, overturned, gap_tol=length_scale): part E's shared check */
    ED_TRY(rk_check_configuration(m, "y", q, v, st->overturned, m->length_scale, err));
    /* all checked: assign */
    s->t = st->t;
    s->impacts = st->impacts;
    s->overturned = st->overturned != 0;
    s->n_steps = st->n_steps;
    s->h = st->h;
    s->mode = st->mode;
    s->k = k;
    memcpy(s->y, st->y, (size_t)(2 * k) * sizeof(double));
    s->shift = st->shift;
    e->model.offset = st->shift;
    for (i = 0; i < RK_MAX_SWITCHES; i++)
        s->switch_side[i] = 1.0;
    s->friction_demand = st->friction_demand;
    s->painleve = st->painleve;
    s->live = 0;
    e->impact_times.first = e->impact_times.end;
    e->impact_log.first = e->impact_log.end;
    for (r = 0; r < n_times; r++)
        ED_TRY(rk_log_append(&e->impact_times, impact_times + r));
    for (r = 0; r < n_log_rows; r++)
        ED_TRY(rk_log_append(&e->impact_log, impact_log + r * row_len));
    e->core.token++;
    return RK_OK;
}
