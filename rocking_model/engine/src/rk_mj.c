/* rk_mj.c -- the Moreau-Jean time-stepper (part E): a verbatim port of
 * rocking_model/integrators/moreau_jean.py (MoreauJean.from_options / __init__, advance, work_message,
 * _step, _project, set_state, outputs).
 *
 * Per step of size dt (Acary & Brogliato 2008, Ch. 10):
 *     W_hat (v+ - v) = dt [(1 - theta) f(q, v, t) + theta f(q, v, t + dt)] - dt^2 theta K v + W_N P_N + W_T P_T
 *     W_hat = M(q) + dt theta C + dt^2 theta^2 K
 *     q+ = q + dt [(1 - theta) v + theta v+]
 * with the velocity-level contact LCP of rk_solve_with_friction on the corners that close within the step,
 * the projection of the closed corners onto the ground and the snap onto the full-contact manifold at rest.
 * Same operation order as the Python (DESIGN.md "Numerics"); the products numpy does with BLAS (K @ v,
 * W_N.T @ v, Winv @ rhs) are plain loops in index order, np.linalg.inv an LU with partial pivoting: pinned
 * to the Python at 1e-13 (tests/test_engine_moreau_jean.py). */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/** [s] default step (moreau_jean.DT_DEFAULT) */
#define RK_MJ_DT_DEFAULT 1e-3
/** [rad] pi/2 as the Python computes it (0.5 * math.pi) */
#define RK_MJ_HALF_PI (0.5 * 3.14159265358979323846)
/** steps beyond which a count is no longer exact in a double (2^53): refused even without a budget */
#define RK_MJ_STEPS_MAX 9007199254740992.0

static int popcount(rk_set s)
{
    int n = 0;
    while (s) {
        n += (int)(s & 1u);
        s >>= 1;
    }
    return n;
}

rk_status rk_mj_init(rk_engine *e, int mode, const double *q, const double *v, rk_error *err)
{
    rk_mj_state *s = &e->core.s.mj;
    const rk_model *m = &e->model;
    double theta = e->options.theta, dt_max;
    int n = m->ops->n_dof;
    /* check_real("theta", options.theta, lo=0.5, hi=1.0) */
    if (!isfinite(theta))
        return rk_fail(err, RK_ERR_VALUE, "theta = %s is not finite; allowed range [0.5, 1]",
                       isnan(theta) ? "nan" : theta > 0 ? "inf" : "-inf");
    if (theta < 0.5 || theta > 1.0)
        return rk_fail(err, RK_ERR_VALUE, "theta = %g is out of range; allowed range [0.5, 1]", theta);
    memset(s, 0, sizeof(*s));
    s->gap_margin = e->scaled.step_gap;
    s->v_rest = e->scaled.step_rest_velocity;
    s->force_floor = e->scaled.force_floor;
    memcpy(s->q, q, (size_t)n * sizeof(double));
    memcpy(s->v, v, (size_t)n * sizeof(double));
    s->t = e->options.t0;
    dt_max = e->options.dt_max != 0.0 ? e->options.dt_max : RK_MJ_DT_DEFAULT;   /* options.dt_max or DT_DEFAULT */
    s->dt_max = m->step_limit < dt_max ? m->step_limit : dt_max;                /* min(dt_max, step_limit) */
    s->theta = theta;
    s->mode = mode;
    s->impacts = 0;
    s->overturned = 0;
    s->n_steps = 0;
    s->friction_demand = 0.0;
    s->painleve = 0;
    s->closed = rk_closed_of(m, mode);
    return RK_OK;
}

/** MoreauJean.work_message. */
static rk_status work_refusal(rk_engine *e, double span, double steps, long long max_steps, rk_error *err)
{
    const rk_mj_state *s = &e->core.s.mj;
    double limit = e->model.step_limit;
    char why[200];
    if (limit <= s->dt_max)
        snprintf(why, sizeof(why), "dt = min(dt_max, 0.25/omega) = %.6g s (the column's omega = %.6g rad/s)",
                 s->dt_max, 0.25 / limit);
    else
        snprintf(why, sizeof(why), "dt_max = %.6g s", s->dt_max);
    return rk_fail(err, RK_ERR_WORK_LIMIT, "moreau_jean: advancing from t = %.17g s by %.6g s needs %.6g steps of "
                   "%s, more than max_steps = %lld per advance; the step was refused and the state kept. Way out: "
                   "communication steps of at most %.6g s, a larger dt_max, or max_steps=None (unlimited, for "
                   "trusted batch runs)", s->t, span, isfinite(steps) ? ceil(steps) : steps, why, max_steps,
                   (double)max_steps * s->dt_max);
}

/** np.linalg.inv of a small dense matrix (n x n, row-major): LU with partial pivoting (LAPACK's getrf
 *  choice of pivot: the first largest |entry|), then the columns of the identity solved. Returns 0 when
 *  singular (numpy raises LinAlgError "Singular matrix"). */
static int invert(int n, const double *A, double *Ainv)
{
    double lu[RK_MAX_DOF * RK_MAX_DOF];
    int piv[RK_MAX_DOF], i, j, k;
    memcpy(lu, A, (size_t)(n * n) * sizeof(double));
    for (i = 0; i < n; i++)
        piv[i] = i;
    for (k = 0; k < n; k++) {
        int p = k;
        double big = fabs(lu[k * n + k]);
        for (i = k + 1; i < n; i++) {
            if (fabs(lu[i * n + k]) > big) {
                big = fabs(lu[i * n + k]);
                p = i;
            }
        }
        if (big == 0.0)
            return 0;
        if (p != k) {
            int t = piv[k];
            piv[k] = piv[p];
            piv[p] = t;
            for (j = 0; j < n; j++) {
                double x = lu[k * n + j];
                lu[k * n + j] = lu[p * n + j];
                lu[p * n + j] = x;
            }
        }
        for (i = k + 1; i < n; i++) {
            double l = lu[i * n + k] / lu[k * n + k];
            lu[i * n + k] = l;
            for (j = k + 1; j < n; j++)
                lu[i * n + j] -= l * lu[k * n + j];
        }
    }
    for (j = 0; j < n; j++) {       /* column j of the inverse: L U x = P e_j */
        double x[RK_MAX_DOF];
        for (i = 0; i < n; i++) {
            double sum = piv[i] == j ? 1.0 : 0.0;
            for (k = 0; k < i; k++)
                sum -= lu[i * n + k] * x[k];
            x[i] = sum;
        }
        for (i = n - 1; i >= 0; i--) {
            double sum = x[i];
            for (k = i + 1; k < n; k++)
                sum -= lu[i * n + k] * x[k];
            x[i] = sum / lu[i * n + i];
        }
        for (i = 0; i < n; i++)
            Ainv[i * n + j] = x[i];
    }
    return 1;
}

/** y = A x (n x n row-major), sums in index order. */
static void matvec(int n, const double *A, const double *x, double *y)
{
    int i, j;
    for (i = 0; i < n; i++) {
        double s = 0.0;
        for (j = 0; j < n; j++)
            s += A[i * n + j] * x[j];
        y[i] = s;
    }
}

/** u = W^T x for W (n_dof x nc, one column per contact). */
static void tmatvec(int n, int nc, const double *W, const double *x, double *u)
{
    int c, i;
    for (c = 0; c < nc; c++) {
        double s = 0.0;
        for (i = 0; i < n; i++)
            s += W[i * nc + c] * x[i];
        u[c] = s;
    }
}

/** ag(t), or RK_ERR_VALUE with the callback's message. */
static rk_status ag_at(rk_motion *ag, double t, double *out, rk_error *err)
{
    int failed = 0;
    char msg[RK_MSG_LEN];
    msg[0] = '\0';
    *out = rk_motion_eval(ag, t, &failed, msg);
    if (failed)
        return rk_fail(err, RK_ERR_VALUE, "%s", msg[0] ? msg : "ag: the ground motion failed");
    return RK_OK;
}

/** ag_v(t) of the vertical component (0 without one), or RK_ERR_VALUE with the callback's message. */
static rk_status ag_v_at(rk_motion *ag_v, double t, double *out, rk_error *err)
{
    int failed = 0;
    char msg[RK_MSG_LEN];
    if (ag_v == NULL) {
        *out = 0.0;
        return RK_OK;
    }
    msg[0] = '\0';
    *out = rk_motion_eval(ag_v, t, &failed, msg);
    if (failed)
        return rk_fail(err, RK_ERR_VALUE, "%s", msg[0] ? msg : "ag_v: the ground motion failed");
    return RK_OK;
}

/** The ValueError flexible_impact._inputs raises where the classical rule does not apply (A's kernel returns
 *  -1): a pivot that is not LEFT / RIGHT (a sliding mode), a non-finite input, or a rate that does not close
 *  the other corner. The Python's text (Mode reprs as Python prints them). */
static rk_status classical_refusal(const rk_model *model, int mode, const double *v, rk_error *err)
{
    static const char *const names[] = {"FULL", "LEFT", "RIGHT", "FLIGHT", "FULL_SLIDE_POS", "FULL_SLIDE_NEG",
                                        "LEFT_SLIDE_POS", "LEFT_SLIDE_NEG", "RIGHT_SLIDE_POS", "RIGHT_SLIDE_NEG"};
    double phi_dot = v[model->ops->phi_index];
    if (mode != RK_MODE_LEFT && mode != RK_MODE_RIGHT)
        return rk_fail(err, RK_ERR_VALUE, "pivot = <Mode.%s: %d> is not supported; allowed values: <Mode.LEFT: 1>, "
                       "<Mode.RIGHT: 2>, 'left', 'right'", (mode >= 0 && mode < 10) ? names[mode] : "?", mode);
    if (!isfinite(phi_dot))
        return rk_fail(err, RK_ERR_VALUE, "phi_dot_minus = %s is not finite; allowed range (-inf, inf)",
                       isnan(phi_dot) ? "nan" : phi_dot > 0 ? "inf" : "-inf");
    return rk_fail(err, RK_ERR_VALUE, "phi_dot_minus = %g does not close the gap of the other corner when rocking "
                   "on the %s corner; allowed range %s", phi_dot, mode == RK_MODE_LEFT ? "left" : "right",
                   mode == RK_MODE_LEFT ? "(-inf, 0)" : "(0, inf)");
}

/** MoreauJean._step. */
static rk_status mj_step(rk_engine *e, double t, double dt, rk_motion *ag, rk_motion *ag_v, rk_error *err)
{
    rk_mj_state *s = &e->core.s.mj;
    const rk_model *model = &e->model;
    const rk_model_ops *ops = model->ops;
    const int n = ops->n_dof, nc = ops->n_contacts;
    const double theta = s->theta;
    const double *q = s->q;
    double v[RK_MAX_DOF], M[RK_MAX_DOF * RK_MAX_DOF], f0[RK_MAX_DOF], f1[RK_MAX_DOF], rhs[RK_MAX_DOF];
    double K[RK_MAX_DOF * RK_MAX_DOF], C[RK_MAX_DOF * RK_MAX_DOF], Winv[RK_MAX_DOF * RK_MAX_DOF];
    double v_free[RK_MAX_DOF], g[RK_MAX_CONTACTS], W_N[RK_MAX_DOF * RK_MAX_CONTACTS];
    double W_T[RK_MAX_DOF * RK_MAX_CONTACTS], U[RK_MAX_CONTACTS], Uf[RK_MAX_CONTACTS];
    double v_new[RK_MAX_DOF], q_new[RK_MAX_DOF], tmp[RK_MAX_DOF], ag0, ag1, av0, av1;
    double margin, v_scale;
    int i, j, rule_impact = 0, sigma = 0, stiff = 0;
    rk_set closed_now, active = 0u, closed = 0u, newly;
    rk_status st;

    memcpy(v, s->v, (size_t)n * sizeof(double));
    ops->mass_matrix(model, q, M);
    if ((st = ag_at(ag, t, &ag0, err)) != RK_OK || (st = ag_v_at(ag_v, t, &av0, err)) != RK_OK)
        return st;
    ops->forces(model, q, v, ag0, av0, f0);
    if (rk_motion_pair_constant(ag, ag_v)) {
        memcpy(f1, f0, (size_t)n * sizeof(double));
    } else {
        if ((st = ag_at(ag, t + dt, &ag1, err)) != RK_OK || (st = ag_v_at(ag_v, t + dt, &av1, err)) != RK_OK)
            return st;
        ops->forces(model, q, v, ag1, av1, f1);
    }
    for (i = 0; i < n; i++)
        rhs[i] = dt * ((1.0 - theta) * f0[i] + theta * f1[i]);
    if (ops->stiff_jacobians != NULL)
        stiff = ops->stiff_jacobians(model, q, v, K, C);
    if (!stiff) {
        rk_model_inverse_mass(model, q, Winv);
    } else {
        double W[RK_MAX_DOF * RK_MAX_DOF], Kv[RK_MAX_DOF];
        double c1 = dt * dt * theta, c2 = dt * theta, c3 = dt * dt * theta * theta;
        matvec(n, K, v, Kv);
        for (i = 0; i < n; i++)
            rhs[i] = rhs[i] - c1 * Kv[i];
        for (i = 0; i < n * n; i++)
            W[i] = M[i] + c2 * C[i] + c3 * K[i];
        if (!invert(n, W, Winv))
            return rk_fail(err, RK_ERR_SOLVER, "Singular matrix");
    }
    matvec(n, Winv, rhs, tmp);
    for (i = 0; i < n; i++)
        v_free[i] = v[i] + tmp[i];
    ops->gaps(model, q, g);
    ops->contact_jacobians(model, q, W_N, W_T);
    tmatvec(n, nc, W_N, v, U);
    closed_now = rk_closed_of(model, s->mode);
    if (popcount(closed_now) == 1 && nc == 2) {
        int hitting = RK_IN(closed_now, 0) ? 1 : 0;      /* 1 - closed_now[0] */
        if (g[hitting] + dt * U[hitting] <= 0.0 && U[hitting] < 0.0 && ops->classical_impact_velocity != NULL) {
            /* an impact rule of the model (the classical rule): replace the pre-impact velocity by the rule's
             * post-impact one; the step's LCP then keeps the contacts closed */
            double v_rule[RK_MAX_DOF];
            int rule = ops->classical_impact_velocity(model, q, v, s->mode, v_rule);
            if (rule < 0)
                return classical_refusal(model, s->mode, v, err);
            if (rule) {
                for (i = 0; i < n; i++) {
                    v_free[i] = v_rule[i] + (v_free[i] - s->v[i]);
                    v[i] = v_rule[i];
                }
                tmatvec(n, nc, W_N, v, U);
                rule_impact = 1;
            }
        }
    }
    /* candidates: closing by the classical prediction g + dt/2 U (with the round-off margin), or by the free
     * motion within the step */
    tmatvec(n, nc, W_N, v_free, Uf);
    margin = s->gap_margin;
    for (i = 0; i < nc; i++) {
        double g_half = g[i] + 0.5 * dt * U[i];
        double g_free = g[i] + dt * ((1.0 - theta) * U[i] + theta * Uf[i]);
        if (g_half <= margin || g_free <= 0.0)
            active |= 1u << i;
    }
    if (active) {
        double b_N[RK_MAX_CONTACTS], b_T[RK_MAX_CONTACTS], lam_N = 0.0, lam_T = 0.0;
        rk_lcp_problem p;
        rk_contact_args a;
        rk_lcp_solution sol;
        for (i = 0; i < nc; i++) {
            double u = U[i];
            b_N[i] = model->e_N * ((u < 0.0 || u != u) ? u : 0.0);     /* e_N * np.minimum(U, 0.0) */
        }
        if (model->e_T != 0.0) {
            double WTv[RK_MAX_CONTACTS];
            tmatvec(n, nc, W_T, v, WTv);
            for (i = 0; i < nc; i++)
                b_T[i] = U[i] < 0.0 ? model->e_T * WTv[i] : 0.0;
        } else {
            for (i = 0; i < nc; i++)
                b_T[i] = 0.0;
        }
        memset(&p, 0, sizeof(p));
        p.n_dof = n;
        p.n_contacts = nc;
        p.Minv = Winv;
        p.W_N = W_N;
        p.W_T = W_T;
        p.v_free = v_free;
        p.b_N = b_N;
        p.b_T = b_T;
        p.candidates = active;
        p.forced = 0u;
        rk_contact_args_default(&a);
        a.has_hint = 1;                         /* the last step's closed contacts, tried first */
        a.hint = s->closed & active;
        a.tolerances = &e->options.tolerances;
        if ((st = rk_solve_with_friction(model, &p, &a, &sol, err)) != RK_OK)
            return st;
        if (!sol.exact) {
            char msg[RK_MSG_LEN];
            rk_inexact_message(&sol, nc, t + dt, "step LCP", msg, sizeof(msg));
            rk_report_add(&e->reports, RK_REPORT_INEXACT_CONTACT, t + dt, "%s", msg);
        }
        memcpy(v_new, sol.v, (size_t)n * sizeof(double));
        closed = sol.active;
        sigma = rk_solution_sigma(&sol, nc);
        for (i = 0; i < nc; i++)
            lam_N += sol.P_N[i];
        for (i = 0; i < nc; i++)
            lam_T += sol.P_T[i];
        rk_note_demand(&s->friction_demand, model->mu, lam_N, lam_T, s->force_floor * dt);
    } else {
        memcpy(v_new, v_free, (size_t)n * sizeof(double));
    }
    v_scale = s->v_rest;
    newly = 0u;
    for (i = 0; i < nc; i++) {
        if (RK_IN(closed, i) && !RK_IN(s->closed, i) && U[i] < -v_scale)
            newly |= 1u << i;
    }
    if (newly || rule_impact) {
        double row = t + dt;
        s->impacts++;
        if ((st = rk_log_append(&e->impact_times, &row)) != RK_OK)
            return rk_fail(err, st, "out of memory growing the impact log");
    }
    s->closed = closed;
    for (i = 0; i < n; i++)
        q_new[i] = q[i] + dt * ((1.0 - theta) * v[i] + theta * v_new[i]);
    if (closed) {
        /* _project: the corners that carried impulse back onto the ground */
        if ((st = rk_project_to_ground(model, q_new, closed, tmp, err)) != RK_OK)
            return st;
        memcpy(q_new, tmp, (size_t)n * sizeof(double));
    }
    if (popcount(closed) == nc) {
        double Un[RK_MAX_CONTACTS];
        int at_rest = 1;
        tmatvec(n, nc, W_N, v_new, Un);
        for (i = 0; i < nc; i++) {
            if (!(fabs(Un[i]) <= v_scale))
                at_rest = 0;
        }
        if (at_rest) {
            /* all corners stuck and at rest in the normal direction: put the state exactly on the
             * full-contact manifold (phi stays 0 at rest) */
            int full = ops->mode_of(model, closed, 0), idx[RK_MAX_DOF], k;
            int si = ops->slide_index;
            double x = q_new[si], x_dot = v_new[si], r[RK_MAX_DOF], r_dot[RK_MAX_DOF];
            k = ops->mode_dofs(model, full, idx);
            for (j = 0; j < k; j++) {
                r[j] = q_new[idx[j]];
                r_dot[j] = v_new[idx[j]];
            }
            ops->embed(model, full, r, r_dot, q_new, v_new);
            /* keep a velocity where the base slides, and an offset where it has slid (the last step's where
             * it was already at rest: no drift by round-off) */
            if (fabs(x_dot - v_new[si]) > v_scale) {
                q_new[si] = x;
                v_new[si] = x_dot;
            } else if (fabs(x - q_new[si]) > margin) {
                q_new[si] = s->mode == full ? q[si] : x;
            }
        }
    }
    memcpy(s->q, q_new, (size_t)n * sizeof(double));
    memcpy(s->v, v_new, (size_t)n * sizeof(double));
    s->mode = ops->mode_of(model, closed, sigma);
    s->n_steps++;
    if (fabs(s->q[ops->phi_index]) >= RK_MJ_HALF_PI) {
        /* the motion ends: the pose at the end of this step, at rest */
        s->overturned = 1;
        for (i = 0; i < n; i++)
            s->v[i] = 0.0;
    }
    return RK_OK;
}

rk_status rk_mj_advance(rk_engine *e, double t_end, rk_motion *ag, rk_motion *ag_v, long long max_steps,
                        rk_error *err)
{
    rk_mj_state *s = &e->core.s.mj;
    double span = t_end - s->t, steps, t0, dt;
    long long n, k;
    rk_status st;
    if (span <= 0.0)
        return RK_OK;
    if (s->overturned) {
        s->t = t_end;
        return RK_OK;
    }
    steps = span / s->dt_max * (1.0 - 1e-12);
    if (max_steps >= 0 && steps > (double)max_steps)
        return work_refusal(e, span, steps, max_steps, err);
    if (!(steps <= RK_MJ_STEPS_MAX))
        return rk_fail(err, RK_ERR_WORK_LIMIT, "moreau_jean: advancing from t = %.17g s by %.6g s needs %.6g steps "
                       "of dt_max = %.6g s, more than can be counted; the step was refused and the state kept. Way "
                       "out: shorter communication steps or a larger dt_max", s->t, span, steps, s->dt_max);
    n = (long long)ceil(steps);
    if (n < 1)
        n = 1;
    t0 = s->t;
    dt = span / (double)n;
    for (k = 0; k < n; k++) {
        double t_next = k == n - 1 ? t_end : t0 + (double)(k + 1) * dt;
        if ((st = mj_step(e, s->t, t_next - s->t, ag, ag_v, err)) != RK_OK) {
            e->fail_t = s->t;
            return st;
        }
        s->t = t_next;
        if (s->overturned) {
            s->t = t_end;
            return RK_OK;
        }
    }
    return RK_OK;
}

void rk_mj_outputs(rk_engine *e, double *out)
{
    e->model.ops->outputs(&e->model, e->core.s.mj.q, e->core.s.mj.v, out);
}

/** "[0, 1]": a closed set as the Python's list repr. */
static void set_text(char *buf, size_t size, rk_set set, int n)
{
    size_t len = 1;
    int i, count = 0;
    buf[0] = '[';
    buf[1] = '\0';
    for (i = 0; i < n; i++) {
        if (RK_IN(set, i)) {
            int w = snprintf(buf + len, size - len, "%s%d", count ? ", " : "", i);
            if (w > 0 && (size_t)w < size - len)
                len += (size_t)w;
            count++;
        }
    }
    snprintf(buf + len, size - len, "]");
}

rk_status rk_mj_set_state(rk_engine *e, const rk_plain_state *st, const double *impact_times, long long n_times,
                          rk_error *err)
{
    rk_mj_state *s = &e->core.s.mj;
    const rk_model *model = &e->model;
    const rk_model_ops *ops = model->ops;
    int i, n = ops->n_dof, nc = ops->n_contacts;
    rk_status r;
    if (!isfinite(st->t))
        return rk_fail(err, RK_ERR_VALUE, "state field 't' = %g is not finite; allowed range (-inf, inf)", st->t);
    for (i = 0; i < n; i++) {
        if (!isfinite(st->q[i]))
            return rk_fail(err, RK_ERR_VALUE, "state field 'q'[%d] = %g is not finite", i, st->q[i]);
    }
    for (i = 0; i < n; i++) {
        if (!isfinite(st->v[i]))
            return rk_fail(err, RK_ERR_VALUE, "state field 'v'[%d] = %g is not finite", i, st->v[i]);
    }
    if (st->mode < 0 || st->mode > ops->n_modes - 1)
        return rk_fail(err, RK_ERR_VALUE, "state field 'mode' = %d is out of range; allowed range [0, %d]",
                       st->mode, ops->n_modes - 1);
    if ((st->closed >> nc) != 0u)
        return rk_fail(err, RK_ERR_VALUE, "state field 'closed' must list corners in [0, %d]", nc - 1);
    if (rk_closed_of(model, st->mode) != st->closed) {
        char text[64];
        set_text(text, sizeof(text), st->closed, nc);
        return rk_fail(err, RK_ERR_VALUE, "state field 'mode' = %d does not match 'closed' = %s; expected one of "
                       "the modes with these closed corners, e.g. %d", st->mode, text,
                       ops->mode_of(model, st->closed, 0));
    }
    if (st->impacts < 0)
        return rk_fail(err, RK_ERR_VALUE, "state field 'impacts' = %lld is out of range; allowed range [0, "
                       "9223372036854775807]", st->impacts);
    if (st->n_steps < 0)
        return rk_fail(err, RK_ERR_VALUE, "state field 'n_steps' = %lld is out of range; allowed range [0, "
                       "9223372036854775807]", st->n_steps);
    for (i = 0; i < n_times; i++) {
        if (!isfinite(impact_times[i]))
            return rk_fail(err, RK_ERR_VALUE, "state field 'impact_times'[%d] = %g is not finite", i,
                           impact_times[i]);
    }
    if ((r = rk_check_times("impact_times", impact_times, n_times, st->t, st->impacts, err)) != RK_OK)
        return r;
    /* the time-stepper lets corners sink by O(dt |v|): only junk (a length scale below the ground) is refused */
    if ((r = rk_check_configuration(model, "q", st->q, st->v, st->overturned, model->length_scale, err)) != RK_OK)
        return r;
    if (!(isfinite(st->friction_demand) && st->friction_demand >= 0.0))
        return rk_fail(err, RK_ERR_VALUE, "state field 'friction_demand' = %g is not %s; allowed range [0, inf)",
                       st->friction_demand, isfinite(st->friction_demand) ? "in range" : "finite");
    if (st->painleve < 0)
        return rk_fail(err, RK_ERR_VALUE, "state field 'painleve' = %lld is out of range; allowed range [0, "
                       "9223372036854775807]", st->painleve);
    s->t = st->t;
    memcpy(s->q, st->q, (size_t)n * sizeof(double));
    memcpy(s->v, st->v, (size_t)n * sizeof(double));
    s->mode = st->mode;
    s->closed = st->closed;
    s->friction_demand = st->friction_demand;
    s->painleve = st->painleve;
    s->impacts = st->impacts;
    s->overturned = st->overturned != 0;
    s->n_steps = st->n_steps;
    return RK_OK;
}
