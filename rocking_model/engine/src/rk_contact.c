/* rk_contact.c -- port of rocking_model/contact.py (part B): the contact problems of a model at a state
 * (impact, uplift, solve_with_friction), the geometry around them (project_to_ground, closed_candidates), the
 * Painleve configuration (sliding_delassus, painleve_sticks), the mode that follows a state (next_mode,
 * solution_sigma) and the forces of a sticking mode held closed (mode_forces).
 *
 * As the Python: impact, uplift and next_mode solve with the caller's tolerances (rk_contact_args.tolerances,
 * rk_next_mode's argument; NULL: RK_DEFAULT_TOLERANCES), both schemes pass the user's; mode_forces needs none
 * (every closed contact forced: one active set, forces independent of lcp_exact and lcp_hint).
 * The numpy products (W^T v, M^-1 f, the Delassus blocks) are plain loops in index order (DESIGN.md 7.4). */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_contact.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/** Python's max(a, b): a unless b is strictly greater. */
static double py_max(double a, double b)
{
    return (b > a) ? b : a;
}

/** M(q)^-1 (contact.inverse_mass = model.inverse_mass_matrix): rk_model_inverse_mass (part A: the kernel's
 *  closed form, else Gauss-Jordan with partial pivoting, pinned to np.linalg.inv). */
static void inverse_mass(const rk_model *m, const double *q, double *Minv)
{
    rk_model_inverse_mass(m, q, Minv);
}

/** out = W^T v for W (n_dof x n_contacts, one column per contact). */
static void columns_dot(int n_dof, int n_c, const double *W, const double *v, double *out)
{
    int i, k;
    for (i = 0; i < n_c; i++) {
        double acc = 0.0;
        for (k = 0; k < n_dof; k++)
            acc += W[k * n_c + i] * v[k];
        out[i] = acc;
    }
}

/** out = A x for a square A (n x n). */
static void mat_vec(int n, const double *A, const double *x, double *out)
{
    int i, k;
    for (i = 0; i < n; i++) {
        double acc = 0.0;
        for (k = 0; k < n; k++)
            acc += A[i * n + k] * x[k];
        out[i] = acc;
    }
}

/** a^T Minv b of two columns (numpy's ``a @ Minv @ b``: (a @ Minv) first). */
static double quad(int n, const double *a, int sa, const double *Minv, const double *b, int sb)
{
    double t[RK_MAX_DOF], acc = 0.0;
    int j, k;
    for (j = 0; j < n; j++) {
        double s = 0.0;
        for (k = 0; k < n; k++)
            s += a[k * sa] * Minv[k * n + j];
        t[j] = s;
    }
    for (j = 0; j < n; j++)
        acc += t[j] * b[j * sb];
    return acc;
}

static int has_any(const int *sliding, int n)
{
    int i;
    if (sliding == NULL)
        return 0;
    for (i = 0; i < n; i++)
        if (sliding[i] != 0)
            return 1;
    return 0;
}

void rk_contact_args_default(rk_contact_args *a)
{
    memset(a, 0, sizeof *a);
    a->forced = 0u;
    a->prefer = -1;
    a->has_hint = 0;
    a->hint = 0u;
    a->has_e = 0;
    a->count = 0;
    a->has_slip_tol = 0;
    a->sliding = NULL;
    a->tolerances = NULL;
}

rk_status rk_solve_with_friction(const rk_model *m, const rk_lcp_problem *p, const rk_contact_args *a,
                                 rk_lcp_solution *out, rk_error *err)
{
    const rk_tolerances *tol = (a != NULL && a->tolerances != NULL) ? a->tolerances : &RK_DEFAULT_TOLERANCES;
    rk_contact_args defaults;
    rk_lcp_problem q = *p;
    int n = p->n_contacts, i, k, hint_states[RK_MAX_CONTACTS];
    rk_status st;
    if (a == NULL) {
        rk_contact_args_default(&defaults);
        a = &defaults;
    }
    q.rtol = tol->lcp_exact;
    q.mu = m->mu;
    q.sliding = NULL;
    q.count = 0;
    q.hint_states = NULL;
    q.has_hint = 0;
    if (isinf(m->mu) && !has_any(a->sliding, n)) {
        rk_lcp_solution limit;
        q.has_hint = a->has_hint;
        q.hint = a->hint;
        q.hint_tol = tol->lcp_hint;
        st = rk_solve_contact_lcp(&q, out, err);
        if (st != RK_OK || out->exact)
            return st;
        q.has_hint = 0;
        st = rk_solve_friction_lcp(&q, &limit, err);
        if (st != RK_OK)
            return st;
        if (limit.violation < out->violation)
            *out = limit;
        return RK_OK;
    }
    if (a->prefer >= 0 || a->has_hint) {
        /* the state tried first per candidate: ``prefer``, or stuck where the hint had it closed; a contact
         * that already slides keeps its direction */
        rk_set cand = p->candidates | p->forced;
        k = 0;
        for (i = 0; i < n; i++) {
            int s;
            if (!RK_IN(cand, i))
                continue;
            s = a->prefer >= 0 ? a->prefer : RK_IN(a->hint, i) ? RK_STICK : RK_OPEN;
            if (s != RK_OPEN && a->sliding != NULL && a->sliding[i] != 0)
                s = a->sliding[i] > 0 ? RK_SLIDE_POS : RK_SLIDE_NEG;
            hint_states[k++] = s;
        }
        q.hint_states = hint_states;
    }
    q.sliding = a->sliding;
    q.count = a->count;
    return rk_solve_friction_lcp(&q, out, err);
}

rk_status rk_impact(const rk_model *m, const double *q, const double *v_minus, rk_set candidates,
                    const rk_contact_args *a, rk_lcp_solution *out, rk_error *err)
{
    int n = m->ops->n_contacts, nd = m->ops->n_dof, i;
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS], Minv[RK_MAX_DOF * RK_MAX_DOF];
    double U_minus[RK_MAX_CONTACTS], U_T[RK_MAX_CONTACTS], b_N[RK_MAX_CONTACTS], b_T[RK_MAX_CONTACTS];
    double e, et;
    rk_contact_args defaults, args;
    rk_lcp_problem p;
    if (a == NULL) {
        rk_contact_args_default(&defaults);
        a = &defaults;
    }
    e = a->has_e ? a->e_N : m->e_N;
    et = a->has_e ? a->e_T : m->e_T;
    m->ops->contact_jacobians(m, q, W_N, W_T);
    columns_dot(nd, n, W_N, v_minus, U_minus);
    for (i = 0; i < n; i++) {
        /* np.minimum(U_minus, 0.0): NaN propagates */
        b_N[i] = e * ((U_minus[i] < 0.0 || isnan(U_minus[i])) ? U_minus[i] : 0.0);
        if (RK_IN(a->forced, i))
            b_N[i] = 0.0;
    }
    if (et != 0.0) {
        /* one coefficient per contact in both directions (Glocker's standard impact): e on the closing
         * contacts, 0 on the forced ones; a contact that separates takes no part in the impact */
        rk_set kept = 0u;
        columns_dot(nd, n, W_T, v_minus, U_T);
        for (i = 0; i < n; i++) {
            b_T[i] = U_minus[i] < 0.0 ? et * U_T[i] : 0.0;
            if (RK_IN(a->forced, i))
                b_T[i] = 0.0;
            if (RK_IN(candidates, i) && (RK_IN(a->forced, i) || U_minus[i] <= 0.0))
                kept |= 1u << i;
        }
        candidates = kept;
    } else {
        for (i = 0; i < n; i++)
            b_T[i] = 0.0;
    }
    inverse_mass(m, q, Minv);
    memset(&p, 0, sizeof p);
    p.n_dof = nd;
    p.n_contacts = n;
    p.Minv = Minv;
    p.W_N = W_N;
    p.W_T = W_T;
    p.v_free = v_minus;
    p.b_N = b_N;
    p.b_T = b_T;
    p.candidates = candidates;
    p.forced = a->forced;
    rk_contact_args_default(&args);
    args.prefer = a->prefer;
    args.tolerances = a->tolerances;
    return rk_solve_with_friction(m, &p, &args, out, err);
}

void rk_uplift_data_of(const rk_model *m, const double *q, const double *v, double ag, double ag_v, rk_set moving,
                       double slip_tol, rk_uplift_data *d, rk_lcp_problem *p)
{
    int n = m->ops->n_contacts, nd = m->ops->n_dof, i;
    double f[RK_MAX_DOF];
    m->ops->contact_jacobians(m, q, d->W_N, d->W_T);
    m->ops->contact_drift(m, q, v, d->b_N, d->b_T);
    inverse_mass(m, q, d->Minv);
    m->ops->forces(m, q, v, ag, ag_v, f);
    mat_vec(nd, d->Minv, f, d->acc_free);
    for (i = 0; i < n; i++)
        d->sliding[i] = 0;
    if (slip_tol >= 0.0) {
        double U_T[RK_MAX_CONTACTS];
        columns_dot(nd, n, d->W_T, v, U_T);
        for (i = 0; i < n; i++)
            d->sliding[i] = (RK_IN(moving, i) && fabs(U_T[i]) > slip_tol) ? (U_T[i] > 0.0 ? 1 : -1) : 0;
    }
    memset(p, 0, sizeof *p);
    p->n_dof = nd;
    p->n_contacts = n;
    p->Minv = d->Minv;
    p->W_N = d->W_N;
    p->W_T = d->W_T;
    p->v_free = d->acc_free;
    p->b_N = d->b_N;
    p->b_T = d->b_T;
}

rk_status rk_uplift(const rk_model *m, const double *q, const double *v, double ag, double ag_v, rk_set candidates,
                    const rk_contact_args *a, rk_lcp_solution *out, rk_error *err)
{
    rk_uplift_data d;
    rk_contact_args defaults, args;
    rk_lcp_problem p;
    if (a == NULL) {
        rk_contact_args_default(&defaults);
        a = &defaults;
    }
    rk_uplift_data_of(m, q, v, ag, ag_v, candidates | a->forced, a->has_slip_tol ? a->slip_tol : -1.0, &d, &p);
    rk_contact_args_default(&args);
    if (a->has_slip_tol)
        args.sliding = d.sliding;
    p.candidates = candidates;
    p.forced = a->forced;
    args.count = a->count;
    args.prefer = a->prefer;
    args.tolerances = a->tolerances;
    return rk_solve_with_friction(m, &p, &args, out, err);
}

rk_status rk_project_to_ground(const rk_model *m, const double *q, rk_set corners, double *q_out, rk_error *err)
{
    int n = m->ops->n_contacts, nd = m->ops->n_dof, idx[RK_MAX_CONTACTS], k = 0, i, j, r;
    double g_all[RK_MAX_CONTACTS], W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS];
    double Minv[RK_MAX_DOF * RK_MAX_DOF], MW[RK_MAX_DOF][RK_MAX_CONTACTS], A[RK_MAX_CONTACTS * RK_MAX_CONTACTS];
    double g[RK_MAX_CONTACTS], mu[RK_MAX_CONTACTS];
    for (i = 0; i < n; i++)
        if (RK_IN(corners, i))
            idx[k++] = i;
    if (k == 0 || (corners >> n) != 0u)
        return rk_fail(err, RK_ERR_VALUE, "project_to_ground: corners must be a non-empty set of contacts in 0..%d",
                       n - 1);
    m->ops->gaps(m, q, g_all);
    m->ops->contact_jacobians(m, q, W_N, W_T);
    inverse_mass(m, q, Minv);
    for (j = 0; j < k; j++)
        g[j] = g_all[idx[j]];
    for (r = 0; r < nd; r++)
        for (j = 0; j < k; j++) {
            double acc = 0.0;
            int c;
            for (c = 0; c < nd; c++)
                acc += Minv[r * nd + c] * W_N[c * n + idx[j]];
            MW[r][j] = acc;
        }
    for (i = 0; i < k; i++)
        for (j = 0; j < k; j++) {
            double acc = 0.0;
            for (r = 0; r < nd; r++)
                acc += W_N[r * n + idx[i]] * MW[r][j];
            A[i * k + j] = acc;
        }
    if (k == 1) {
        mu[0] = -g[0] / A[0];
    } else if (k > 2) {
        double rhs[RK_MAX_CONTACTS];
        for (j = 0; j < k; j++)
            rhs[j] = -g[j];
        rk_lstsq_square(k, A, rhs, mu);
    } else {
        double det = A[0] * A[3] - A[1] * A[2];
        if (fabs(det) > 1e-12 * fabs(A[0] * A[3])) {
            mu[0] = (A[3] * -g[0] - A[1] * -g[1]) / det;
            mu[1] = (A[0] * -g[1] - A[2] * -g[0]) / det;
        } else {
            double rhs[2];
            rhs[0] = -g[0];
            rhs[1] = -g[1];
            rk_lstsq_square(2, A, rhs, mu);
        }
    }
    for (r = 0; r < nd; r++) {
        double acc = 0.0;
        for (j = 0; j < k; j++)
            acc += MW[r][j] * mu[j];
        q_out[r] = q[r] + acc;
    }
    return RK_OK;
}

rk_set rk_closed_candidates(const rk_model *m, const double *q, const double *v, double gap_tol, double v_tol)
{
    int n = m->ops->n_contacts, nd = m->ops->n_dof, i;
    double g[RK_MAX_CONTACTS], W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS];
    double U[RK_MAX_CONTACTS];
    rk_set out = 0u;
    m->ops->gaps(m, q, g);
    m->ops->contact_jacobians(m, q, W_N, W_T);
    columns_dot(nd, n, W_N, v, U);
    for (i = 0; i < n; i++)
        if (g[i] <= gap_tol && fabs(U[i]) <= v_tol)
            out |= 1u << i;
    return out;
}

double rk_sliding_delassus(const rk_model *m, const double *q, int i, double sigma)
{
    int n = m->ops->n_contacts, nd = m->ops->n_dof;
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS], Minv[RK_MAX_DOF * RK_MAX_DOF];
    double a, c;
    m->ops->contact_jacobians(m, q, W_N, W_T);
    inverse_mass(m, q, Minv);
    a = quad(nd, W_N + i, n, Minv, W_N + i, n);
    c = quad(nd, W_N + i, n, Minv, W_T + i, n);
    if (isinf(m->mu))
        return sigma * c > 0.0 ? -INFINITY : c == 0.0 ? a : INFINITY;
    return a - sigma * m->mu * c;
}

rk_set rk_painleve_sticks(const rk_model *m, const double *q, const double *v_minus, const double *v_plus,
                          rk_set candidates, double v_tol)
{
    int n = m->ops->n_contacts, nd = m->ops->n_dof, i;
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS], Minv[RK_MAX_DOF * RK_MAX_DOF];
    double U_N_minus[RK_MAX_CONTACTS], U_T_minus[RK_MAX_CONTACTS], U_T_plus[RK_MAX_CONTACTS];
    double U_N_plus[RK_MAX_CONTACTS];
    rk_set out = 0u;
    m->ops->contact_jacobians(m, q, W_N, W_T);
    inverse_mass(m, q, Minv);
    columns_dot(nd, n, W_N, v_minus, U_N_minus);
    columns_dot(nd, n, W_T, v_minus, U_T_minus);
    columns_dot(nd, n, W_T, v_plus, U_T_plus);
    columns_dot(nd, n, W_N, v_plus, U_N_plus);
    for (i = 0; i < n; i++) {
        double c, d;
        if (!RK_IN(candidates, i))
            continue;
        if (!(fabs(U_T_minus[i]) > v_tol && fabs(U_T_plus[i]) <= v_tol && U_N_plus[i] <= v_tol))
            continue;
        if (rk_sliding_delassus(m, q, i, U_T_minus[i] > 0.0 ? 1.0 : -1.0) > 0.0)
            continue;
        c = quad(nd, W_N + i, n, Minv, W_T + i, n);
        d = quad(nd, W_T + i, n, Minv, W_T + i, n);
        if (c * U_T_minus[i] >= d * (1.0 + m->e_N) * py_max(-U_N_minus[i], 0.0))
            out |= 1u << i;
    }
    return out;
}

int rk_solution_sigma(const rk_lcp_solution *sol, int n_contacts)
{
    int i, first = -1, all_slide = 1;
    if (!sol->frictional)
        return 0;               /* a sticking solution has no states: it sticks */
    for (i = 0; i < n_contacts; i++) {
        int s = sol->states[i];
        if (s == RK_OPEN)
            continue;
        if (first < 0)
            first = s;
        if (s != RK_SLIDE_POS && s != RK_SLIDE_NEG)
            all_slide = 0;
    }
    if (first >= 0 && all_slide)
        return first == RK_SLIDE_POS ? 1 : -1;
    return 0;
}

rk_status rk_next_mode(const rk_model *m, const double *q, const double *v, double ag, double ag_v, double gap_tol,
                       double v_tol, int prefer, const rk_tolerances *tolerances, int *mode, rk_lcp_solution *sol,
                       int *has_solution, rk_error *err)
{
    rk_set cand = rk_closed_candidates(m, q, v, gap_tol, v_tol);
    rk_contact_args a;
    rk_status st;
    if (cand == 0u) {
        *mode = m->ops->mode_of(m, 0u, 0);
        *has_solution = 0;
        return RK_OK;
    }
    rk_contact_args_default(&a);
    a.has_slip_tol = 1;
    a.slip_tol = v_tol;
    a.count = 1;
    a.prefer = prefer;
    a.tolerances = tolerances;
    st = rk_uplift(m, q, v, ag, ag_v, cand, &a, sol, err);
    if (st != RK_OK)
        return st;
    *has_solution = 1;
    *mode = m->ops->mode_of(m, sol->active, rk_solution_sigma(sol, m->ops->n_contacts));
    return RK_OK;
}

rk_status rk_mode_forces(const rk_model *m, int mode, const double *q, const double *v, double ag, double ag_v,
                         double *lam, rk_error *err)
{
    int n = m->ops->n_contacts, nd = m->ops->n_dof, i;
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS], Minv[RK_MAX_DOF * RK_MAX_DOF];
    double a_N[RK_MAX_CONTACTS], a_T[RK_MAX_CONTACTS], f[RK_MAX_DOF], acc_free[RK_MAX_DOF];
    rk_set closed = rk_closed_of(m, mode);
    rk_lcp_problem p;
    rk_lcp_solution sol;
    rk_status st;
    if (closed == 0u) {
        for (i = 0; i < n; i++)
            lam[i] = 0.0;
        return RK_OK;
    }
    m->ops->contact_jacobians(m, q, W_N, W_T);
    m->ops->contact_drift(m, q, v, a_N, a_T);
    inverse_mass(m, q, Minv);
    m->ops->forces(m, q, v, ag, ag_v, f);
    mat_vec(nd, Minv, f, acc_free);
    memset(&p, 0, sizeof p);
    p.n_dof = nd;
    p.n_contacts = n;
    p.Minv = Minv;
    p.W_N = W_N;
    p.W_T = W_T;
    p.v_free = acc_free;
    p.b_N = a_N;
    p.b_T = a_T;
    p.candidates = closed;
    p.forced = closed;
    p.rtol = RK_DEFAULT_TOLERANCES.lcp_exact;   /* sets sol.exact only, not read: one active set (all forced) */
    p.mu = INFINITY;
    st = rk_solve_contact_lcp(&p, &sol, err);
    if (st != RK_OK)
        return st;
    for (i = 0; i < n; i++)
        lam[i] = sol.P_N[i];
    return RK_OK;
}

void rk_inexact_message(const rk_lcp_solution *sol, int n_contacts, double t, const char *what, char *buf,
                        size_t n)
{
    char closed[64];
    size_t len = 0;
    int i, k = 0;
    closed[0] = '(';
    closed[1] = '\0';
    len = 1;
    for (i = 0; i < n_contacts && i < RK_MAX_CONTACTS; i++)
        if (RK_IN(sol->active, i)) {
            int w = snprintf(closed + len, sizeof closed - len, k ? ", %d" : "%d", i);
            if (w > 0)
                len += (size_t)w;
            k++;
        }
    snprintf(closed + len, sizeof closed - len, k == 1 ? ",)" : ")");
    snprintf(buf, n, "the %s at t = %.17g s has no exact solution (least violation %.3g, closed contacts %s): "
             "kept the least-violating one; a corner may sink or lift against the contact law",
             what, t, sol->violation, closed);
}
