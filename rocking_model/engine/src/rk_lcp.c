/* rk_lcp.c -- port of rocking_model/lcp.py (part B): the sticking contact LCP (solve_contact_lcp: enumeration
 * of the active sets in the Python's order, principal pivoting beyond ENUMERATE_MAX free candidates) and the
 * frictional contact LCP (solve_friction_lcp: the 4^n state combinations in itertools.product order, the
 * descent beyond FRICTION_ENUMERATE_MAX candidates).
 *
 * Numerics (DESIGN.md section 7): the pure-Python float code of lcp.py (_solve_small, _Problem.trial,
 * violators, the violation measures) is ported expression by expression, with Python's max() (the first
 * maximal argument wins) as py_max. The numpy products (G^T M^-1 G, G^T v_free, v_free + MG P, w0 + D P) are
 * plain loops in index order; np.linalg.solve and np.linalg.lstsq(rcond=1e-12) are the engine's dense solves
 * rk_la_solve / rk_la_lstsq (rk_model.c: Gaussian elimination with partial pivoting, failing only on an exactly
 * zero pivot as LAPACK's gesv; the minimum-norm least-squares solution from a one-sided Jacobi SVD with LAPACK's
 * cut-off), shared with the kernels. These agree with numpy to round-off (pinned at 1e-13 relative by
 * tests/test_engine_contact.py).
 *
 * No allocation: every work array is on the stack. The Python's _SETS_CACHE becomes an enumeration of the
 * sets in the same order into a local array. */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_contact.h"

#include <math.h>
#include <string.h>

#define NMAX RK_LCP_MAX_CONTACTS
#define UMAX (2 * RK_LCP_MAX_CONTACTS)
/* the dense solves of rk_model.h take up to RK_MAX_Y unknowns */
typedef char rk_lcp_umax_fits[(UMAX <= RK_MAX_Y) ? 1 : -1];
/** [1] rcond of the np.linalg.lstsq fallbacks of lcp.py */
#define LSTSQ_RCOND 1e-12
/** most state combinations of the frictional enumeration (4^FRICTION_ENUMERATE_MAX) */
#define MAX_COMBOS 256

/** Python's max(a, b): a unless b is strictly greater. */
static double py_max(double a, double b)
{
    return (b > a) ? b : a;
}

/* ------------------------------------------------------------------------------------------ dense solves */

/** lcp._solve_small verbatim: Gaussian elimination with partial pivoting on A (n x n, row stride UMAX);
 *  returns 0 (None) if A is singular to round-off. */
static int solve_small(int n, double A[][UMAX], const double *b, double *x)
{
    double M[UMAX][UMAX + 1];
    double big = 0.0;
    int r, c, j;
    for (r = 0; r < n; r++) {
        for (j = 0; j < n; j++)
            M[r][j] = A[r][j];
        M[r][n] = b[r];
    }
    for (r = 0; r < n; r++)
        for (j = 0; j < n; j++)
            if (fabs(A[r][j]) > big)
                big = fabs(A[r][j]);
    if (big == 0.0)
        big = 1.0;
    for (c = 0; c < n; c++) {
        int p = c;
        double best = fabs(M[c][c]);
        for (r = c + 1; r < n; r++)
            if (fabs(M[r][c]) > best) {
                p = r;
                best = fabs(M[r][c]);
            }
        if (best <= RK_SINGULAR_RTOL * big)
            return 0;
        if (p != c)
            for (j = 0; j <= n; j++) {
                double t = M[c][j];
                M[c][j] = M[p][j];
                M[p][j] = t;
            }
        for (r = c + 1; r < n; r++) {
            double f = M[r][c] / M[c][c];
            if (f != 0.0)
                for (j = c; j <= n; j++)
                    M[r][j] -= f * M[c][j];
        }
    }
    for (c = n - 1; c >= 0; c--) {
        double acc = 0.0;
        for (j = c + 1; j < n; j++)
            acc += M[c][j] * x[j];
        x[c] = (M[c][n] - acc) / M[c][c];
    }
    return 1;
}

/** np.linalg.solve of A (n x n, row stride UMAX), and np.linalg.lstsq(A, b, rcond=1e-12)[0] where it fails (an
 *  exactly zero pivot): the engine's dense solves (rk_la_solve, rk_la_lstsq of rk_model.h), shared with the
 *  kernels. */
static void solve_or_lstsq(int n, double A[][UMAX], const double *b, double *x)
{
    double F[UMAX * UMAX];
    int r, c;
    for (r = 0; r < n; r++)
        for (c = 0; c < n; c++)
            F[r * n + c] = A[r][c];
    if (rk_la_solve(n, F, b, x) != RK_OK)
        rk_la_lstsq(n, n, F, b, LSTSQ_RCOND, x);
}

/** np.linalg.lstsq(A, b, rcond=1e-12)[0] of A (n x n, row stride UMAX) (rk_la_lstsq) */
static void lstsq(int n, double A[][UMAX], const double *b, double *x)
{
    double F[UMAX * UMAX];
    int r, c;
    for (r = 0; r < n; r++)
        for (c = 0; c < n; c++)
            F[r * n + c] = A[r][c];
    rk_la_lstsq(n, n, F, b, LSTSQ_RCOND, x);
}

/* ------------------------------------------------------------------------------------------ the problem */

/** One contact LCP on floats (lcp._Problem and what solve_*_lcp computes before solving). */
typedef struct lcp_ctx {
    int n, m;                   /* contacts, dofs */
    double D[UMAX][UMAX];       /* Delassus matrix G^T M^-1 G */
    double MG[RK_MAX_DOF][UMAX];
    double w0[UMAX];            /* residuals without percussions */
    rk_set cand, forced;
    int cand_idx[NMAX], n_cand;
    double scale_v;
    /* frictional */
    double mu, inv_mu;
    int sliding[NMAX];
} lcp_ctx;

typedef struct trial_res {
    double viol;
    rk_set S;                   /* sticking: the active set */
    int states[NMAX];           /* frictional: the state of each candidate (in cand order) */
    double P[UMAX];
    double w[UMAX];
} trial_res;

static rk_status ctx_init(lcp_ctx *x, const rk_lcp_problem *p, rk_error *err)
{
    int n = p->n_contacts, m = p->n_dof, i, k, r, c;
    double G[RK_MAX_DOF][UMAX];
    if (n < 0 || n > NMAX)
        return rk_fail(err, RK_ERR_VALUE, "n_contacts = %d is out of range; allowed range [0, %d]", n, NMAX);
    if (m < 1 || m > RK_MAX_DOF)
        return rk_fail(err, RK_ERR_VALUE, "n_dof = %d is out of range; allowed range [1, %d]", m, RK_MAX_DOF);
    if (((p->candidates | p->forced) >> n) != 0u)
        return rk_fail(err, RK_ERR_VALUE, "candidates and forced must be contacts in 0..%d", n - 1);
    if (!(isfinite(p->rtol) && p->rtol >= 0.0))
        return rk_fail(err, RK_ERR_VALUE, "rtol = %.17g is out of range; allowed range [0, inf)", p->rtol);
    x->n = n;
    x->m = m;
    x->cand = p->candidates | p->forced;
    x->forced = p->forced;
    x->n_cand = 0;
    for (i = 0; i < n; i++)
        if (RK_IN(x->cand, i))
            x->cand_idx[x->n_cand++] = i;
    for (k = 0; k < m; k++)
        for (c = 0; c < n; c++) {
            G[k][c] = p->W_N[k * n + c];
            G[k][n + c] = p->W_T[k * n + c];
        }
    /* MG = Minv @ G, D = G^T @ MG, w0 = G^T v_free + b */
    for (r = 0; r < m; r++)
        for (c = 0; c < 2 * n; c++) {
            double acc = 0.0;
            for (k = 0; k < m; k++)
                acc += p->Minv[r * m + k] * G[k][c];
            x->MG[r][c] = acc;
        }
    for (r = 0; r < 2 * n; r++) {
        double acc = 0.0;
        for (c = 0; c < 2 * n; c++) {
            double a = 0.0;
            for (k = 0; k < m; k++)
                a += G[k][r] * x->MG[k][c];
            x->D[r][c] = a;
        }
        for (k = 0; k < m; k++)
            acc += G[k][r] * p->v_free[k];
        x->w0[r] = acc + (r < n ? p->b_N[r] : p->b_T[r - n]);
    }
    x->scale_v = 1e-300;
    for (k = 0; k < x->n_cand; k++) {
        i = x->cand_idx[k];
        x->scale_v = py_max(x->scale_v, fabs(x->w0[i]));
        x->scale_v = py_max(x->scale_v, fabs(x->w0[n + i]));
    }
    x->mu = p->mu;
    x->inv_mu = isinf(p->mu) ? 0.0 : 1.0 / p->mu;
    for (i = 0; i < NMAX; i++)
        x->sliding[i] = (p->sliding != NULL && i < n) ? p->sliding[i] : 0;
    return RK_OK;
}

/** v = v_free + MG @ P */
static void velocity(const lcp_ctx *x, const double *v_free, const double *P, double *v)
{
    int r, c;
    for (r = 0; r < x->m; r++) {
        double acc = 0.0;
        for (c = 0; c < 2 * x->n; c++)
            acc += x->MG[r][c] * P[c];
        v[r] = v_free[r] + acc;
    }
}

/** _Problem.parallel */
static int parallel(const lcp_ctx *x, int i, int j)
{
    int a = x->n + i, b = x->n + j;
    double dd = x->D[a][a] * x->D[b][b];
    return fabs(dd - x->D[a][b] * x->D[b][a]) <= RK_PARALLEL_RTOL * py_max(dd, 1e-300);
}

/** _Problem.trial */
static void stick_trial(const lcp_ctx *x, rk_set S, trial_res *res)
{
    int n = x->n, m2 = 2 * n, r, c, k;
    int S_idx[NMAX], nS = 0, rows[UMAX], nr = 0, merged = 0;
    double scale_P = 1e-300, viol = 0.0;
    for (c = 0; c < m2; c++)
        res->P[c] = 0.0;
    for (k = 0; k < n; k++)
        if (RK_IN(S, k))
            S_idx[nS++] = k;
    if (nS > 0) {
        double A[UMAX][UMAX], rhs[UMAX], sol[UMAX];
        for (k = 0; k < nS; k++)
            rows[nr++] = S_idx[k];
        for (k = 0; k < nS; k++)
            rows[nr++] = n + S_idx[k];
        merged = nS == 2 && parallel(x, S_idx[0], S_idx[1]);
        if (merged)
            nr = 3;
        for (r = 0; r < nr; r++) {
            for (c = 0; c < nr; c++)
                A[r][c] = x->D[rows[r]][rows[c]];
            rhs[r] = -x->w0[rows[r]];
        }
        if (merged) {
            /* one tangential unknown acting through both contacts, split evenly (minimum-norm split) */
            int t0 = n + S_idx[0], t1 = n + S_idx[1];
            for (r = 0; r < 3; r++)
                A[r][2] = 0.5 * (x->D[rows[r]][t0] + x->D[rows[r]][t1]);
        }
        if (!solve_small(nr, A, rhs, sol))
            lstsq(nr, A, rhs, sol);
        for (r = 0; r < nr; r++)
            res->P[rows[r]] = sol[r];
        if (merged)
            res->P[n + S_idx[0]] = res->P[n + S_idx[1]] = 0.5 * sol[2];
    }
    for (r = 0; r < m2; r++) {
        double acc = 0.0;
        for (c = 0; c < m2; c++)
            if (res->P[c] != 0.0)
                acc += x->D[r][c] * res->P[c];
        res->w[r] = x->w0[r] + acc;
    }
    for (k = 0; k < n; k++)
        scale_P = py_max(scale_P, fabs(res->P[k]));
    for (k = 0; k < x->n_cand; k++) {
        int i = x->cand_idx[k];
        if (RK_IN(S, i)) {
            if (!RK_IN(x->forced, i))
                viol = py_max(viol, -res->P[i] / scale_P);
            viol = py_max(py_max(viol, fabs(res->w[i]) / x->scale_v), fabs(res->w[n + i]) / x->scale_v);
        } else {
            viol = py_max(viol, -res->w[i] / x->scale_v);
        }
    }
    res->viol = viol;
    res->S = S;
}

/** _Problem.violators: the first (lowest-index) violating candidate, or -1. */
static int first_violator(const lcp_ctx *x, const trial_res *res, double rtol)
{
    int n = x->n, k;
    double scale_P = 1e-300;
    for (k = 0; k < n; k++)       /* max([abs(P[i]) ...] + [1e-300]): the same value */
        if (fabs(res->P[k]) > scale_P)
            scale_P = fabs(res->P[k]);
    for (k = 0; k < x->n_cand; k++) {
        int i = x->cand_idx[k];
        if (RK_IN(x->forced, i))
            continue;
        if ((RK_IN(res->S, i) && -res->P[i] / scale_P > rtol) || (!RK_IN(res->S, i) && -res->w[i] / x->scale_v > rtol))
            return i;
    }
    return -1;
}

/** _pivot */
static void pivot(const lcp_ctx *x, rk_set start, double rtol, trial_res *out)
{
    trial_res best, res;
    int have = 0, pass, it, k, improved;
    rk_set S;
    for (pass = 0; pass < 2; pass++) {
        S = (pass == 0 ? start : x->cand) | x->forced;
        for (it = 0; it < RK_MAX_PIVOTS; it++) {
            int i;
            stick_trial(x, S, &res);
            if (!have || res.viol < best.viol) {
                best = res;
                have = 1;
            }
            i = first_violator(x, &res, rtol);
            if (i < 0) {
                *out = res;
                return;
            }
            S ^= 1u << i;
        }
    }
    S = best.S;
    improved = 1;
    while (improved) {
        improved = 0;
        for (k = 0; k < x->n_cand; k++) {
            int i = x->cand_idx[k];
            if (RK_IN(x->forced, i))
                continue;
            stick_trial(x, S ^ (1u << i), &res);
            if (res.viol < best.viol) {
                best = res;
                S = res.S;
                improved = 1;
                if (res.viol <= rtol) {
                    *out = res;
                    return;
                }
            }
        }
    }
    *out = best;
}

static void clear_solution(rk_lcp_wide_solution *out)
{
    int i;
    memset(out, 0, sizeof *out);
    for (i = 0; i < NMAX; i++) {
        out->w_N[i] = NAN;
        out->w_T[i] = NAN;
        out->states[i] = RK_OPEN;
    }
    out->n_solutions = -1;
}

rk_status rk_solve_contact_lcp_wide(const rk_lcp_problem *p, rk_lcp_wide_solution *out, rk_error *err)
{
    lcp_ctx x;
    trial_res best;
    rk_status st = ctx_init(&x, p, err);
    int n_forced = 0, k, i;
    if (st != RK_OK)
        return st;
    for (i = 0; i < x.n; i++)
        n_forced += RK_IN(x.forced, i);
    if (x.n_cand - n_forced <= RK_ENUMERATE_MAX) {
        /* _active_sets: forced plus every subset of the free candidates, smallest first, each size in
         * itertools.combinations order; the hint first when it is one of them */
        rk_set sets[1 << RK_ENUMERATE_MAX];
        int free_idx[NMAX], nf = 0, n_sets = 0, size, comb[NMAX], n_tried = 0, have = 0, hint_in = 0;
        rk_set hint = p->hint;
        trial_res res;
        for (k = 0; k < x.n_cand; k++)
            if (!RK_IN(x.forced, x.cand_idx[k]))
                free_idx[nf++] = x.cand_idx[k];
        for (size = 0; size <= nf; size++) {
            for (k = 0; k < size; k++)
                comb[k] = k;
            for (;;) {
                rk_set S = x.forced;
                for (k = 0; k < size; k++)
                    S |= 1u << free_idx[comb[k]];
                sets[n_sets++] = S;
                /* next combination (lexicographic) */
                k = size - 1;
                while (k >= 0 && comb[k] == nf - size + k)
                    k--;
                if (k < 0)
                    break;
                comb[k]++;
                for (i = k + 1; i < size; i++)
                    comb[i] = comb[i - 1] + 1;
            }
        }
        if (p->has_hint)
            for (k = 0; k < n_sets; k++)
                if (sets[k] == hint)
                    hint_in = 1;
        /* _enumerate */
        for (k = -1; k < n_sets; k++) {
            rk_set S;
            if (k < 0) {
                if (!hint_in)
                    continue;
                S = hint;
            } else {
                S = sets[k];
                if (hint_in && S == hint)
                    continue;
            }
            stick_trial(&x, S, &res);
            if (!have || res.viol < best.viol) {
                best = res;
                have = 1;
                if (res.viol == 0.0 || (n_tried == 0 && p->has_hint && res.viol <= p->hint_tol))
                    break;
            }
            n_tried++;
        }
    } else {
        rk_set start = p->has_hint ? (p->hint & x.cand) : 0u;
        pivot(&x, start, p->rtol, &best);
    }
    clear_solution(out);
    velocity(&x, p->v_free, best.P, out->v);
    for (i = 0; i < x.n; i++) {
        out->P_N[i] = best.P[i];
        out->P_T[i] = best.P[x.n + i];
    }
    for (k = 0; k < x.n_cand; k++)
        out->w_N[x.cand_idx[k]] = best.w[x.cand_idx[k]];
    for (i = 0; i < x.n; i++)   /* w_T: the sticking solution does not return it */
        out->w_T[i] = NAN;
    out->active = best.S;
    out->exact = best.viol <= p->rtol;
    out->violation = best.viol;
    out->frictional = 0;
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ friction */

static double slide_sign(int s)
{
    return s == RK_SLIDE_POS ? 1.0 : -1.0;
}

/** solve_friction_lcp's trial(states) */
static void friction_trial(const lcp_ctx *x, const int *states, trial_res *res)
{
    int n = x->n, m2 = 2 * n, rows[UMAX], nr = 0, nc = 0, r, c, k;
    double cols[UMAX][UMAX];     /* cols[c][r]: column c of the system, over all 2n rows of D */
    double scale_P = 0.0, viol = 0.0, scale_v = x->scale_v;
    for (k = 0; k < x->n_cand; k++) {
        int i = x->cand_idx[k], s = states[k];
        if (s == RK_OPEN)
            continue;
        rows[nr++] = i;
        if (s == RK_STICK) {
            for (r = 0; r < m2; r++) {
                cols[nc][r] = x->D[r][i];
                cols[nc + 1][r] = x->D[r][n + i];
            }
            nc += 2;
            rows[nr++] = n + i;
        } else {
            double sg = slide_sign(s);
            for (r = 0; r < m2; r++)
                cols[nc][r] = x->inv_mu * x->D[r][i] - sg * x->D[r][n + i];
            nc += 1;
        }
    }
    for (c = 0; c < m2; c++)
        res->P[c] = 0.0;
    if (nc > 0) {
        double A[UMAX][UMAX], rhs[UMAX], sol[UMAX];
        int j = 0;
        for (r = 0; r < nr; r++) {
            for (c = 0; c < nc; c++)
                A[r][c] = cols[c][rows[r]];
            rhs[r] = -x->w0[rows[r]];
        }
        solve_or_lstsq(nr, A, rhs, sol);
        for (k = 0; k < x->n_cand; k++) {
            int i = x->cand_idx[k], s = states[k];
            if (s == RK_STICK) {
                res->P[i] = sol[j];
                res->P[n + i] = sol[j + 1];
                j += 2;
            } else if (s != RK_OPEN) {
                res->P[i] = x->inv_mu * sol[j];
                res->P[n + i] = -slide_sign(s) * sol[j];
                j += 1;
            }
        }
    }
    for (r = 0; r < m2; r++) {
        double acc = 0.0;
        for (c = 0; c < m2; c++)
            acc += x->D[r][c] * res->P[c];
        res->w[r] = x->w0[r] + acc;
    }
    for (c = 0; c < m2; c++)
        if (fabs(res->P[c]) > scale_P)
            scale_P = fabs(res->P[c]);
    scale_P = py_max(scale_P, 1e-300);
    for (k = 0; k < x->n_cand; k++) {
        int i = x->cand_idx[k], s = states[k];
        if (s == RK_OPEN) {
            viol = py_max(viol, -res->w[i] / scale_v);
            continue;
        }
        viol = py_max(viol, fabs(res->w[i]) / scale_v);
        if (s == RK_STICK) {
            double cone;
            if (!RK_IN(x->forced, i))
                viol = py_max(viol, -res->P[i] / scale_P);
            cone = x->inv_mu != 0.0 ? fabs(res->P[n + i]) - x->mu * py_max(res->P[i], 0.0) : 0.0;
            viol = py_max(py_max(viol, fabs(res->w[n + i]) / scale_v), cone / scale_P);
        } else {
            double sigma = slide_sign(s);
            if (!RK_IN(x->forced, i))
                viol = py_max(viol, sigma * res->P[n + i] / scale_P);
            if (x->sliding[i] == 0)
                viol = py_max(viol, -sigma * res->w[n + i] / scale_v);
        }
    }
    res->viol = viol;
    res->S = 0u;
    for (k = 0; k < x->n_cand; k++) {
        res->states[k] = states[k];
        if (states[k] != RK_OPEN)
            res->S |= 1u << x->cand_idx[k];
    }
}

/** options(i): the states a candidate may take, in the order they are tried; returns their number. */
static int state_options(const lcp_ctx *x, int i, int *opts)
{
    if (x->sliding[i] != 0) {
        int slide = x->sliding[i] > 0 ? RK_SLIDE_POS : RK_SLIDE_NEG;
        if (RK_IN(x->forced, i)) {
            opts[0] = slide;
            return 1;
        }
        opts[0] = RK_OPEN;
        opts[1] = slide;
        return 2;
    }
    if (RK_IN(x->forced, i)) {
        opts[0] = RK_STICK;
        opts[1] = RK_SLIDE_POS;
        opts[2] = RK_SLIDE_NEG;
        return 3;
    }
    opts[0] = RK_OPEN;
    opts[1] = RK_STICK;
    opts[2] = RK_SLIDE_POS;
    opts[3] = RK_SLIDE_NEG;
    return 4;
}

rk_status rk_solve_friction_lcp_wide(const rk_lcp_problem *p, rk_lcp_wide_solution *out, rk_error *err)
{
    lcp_ctx x;
    trial_res best, res;
    int opts[NMAX][4], n_opts[NMAX], k, j, i, have = 0, n_exact = 0, has_first = 0, first[NMAX];
    double rtol = p->rtol;
    rk_status st;
    if (!(p->mu > 0.0))
        return rk_fail(err, RK_ERR_VALUE, "mu = %.17g is out of range; allowed range (0, inf]", p->mu);
    st = ctx_init(&x, p, err);
    if (st != RK_OK)
        return st;
    k = x.n_cand;
    for (j = 0; j < k; j++)
        n_opts[j] = state_options(&x, x.cand_idx[j], opts[j]);
    if (p->hint_states != NULL) {
        has_first = 1;
        for (j = 0; j < k; j++)
            first[j] = p->hint_states[j];
    }
    if (k <= RK_FRICTION_ENUMERATE_MAX) {
        /* combos = list(product(*opts)) (the last candidate varies fastest), the hint moved to the front */
        int combos[MAX_COMBOS][NMAX], n_combos = 0, idx[NMAX], c, first_at = -1, n_motions = 0;
        double motions[MAX_COMBOS][RK_MAX_DOF];
        for (j = 0; j < k; j++)
            idx[j] = 0;
        for (;;) {
            for (j = 0; j < k; j++)
                combos[n_combos][j] = opts[j][idx[j]];
            n_combos++;
            for (j = k - 1; j >= 0; j--) {
                if (++idx[j] < n_opts[j])
                    break;
                idx[j] = 0;
            }
            if (j < 0)
                break;
        }
        if (has_first)
            for (c = 0; c < n_combos && first_at < 0; c++) {
                int same = 1;
                for (j = 0; j < k; j++)
                    same &= combos[c][j] == first[j];
                if (same)
                    first_at = c;
            }
        for (c = -1; c < n_combos; c++) {
            if (c < 0 && first_at < 0)
                continue;
            if (c == first_at)
                continue;
            friction_trial(&x, c < 0 ? combos[first_at] : combos[c], &res);
            if (p->count && res.viol <= rtol) {
                double v[RK_MAX_DOF], scale = 0.0, sf = 0.0;
                int u, r, dup = 0;
                velocity(&x, p->v_free, res.P, v);
                for (r = 0; r < x.m; r++) {
                    if (fabs(v[r]) > scale)
                        scale = fabs(v[r]);
                    if (fabs(p->v_free[r]) > sf)
                        sf = fabs(p->v_free[r]);
                }
                scale = py_max(py_max(scale, sf), 1e-300);
                for (u = 0; u < n_motions && !dup; u++) {
                    double dmax = 0.0;
                    for (r = 0; r < x.m; r++)
                        if (fabs(v[r] - motions[u][r]) > dmax)
                            dmax = fabs(v[r] - motions[u][r]);
                    dup = dmax <= rtol * scale;
                }
                if (!dup) {
                    memcpy(motions[n_motions], v, sizeof v);
                    n_motions++;
                }
                n_exact = n_motions;
                if (!have || best.viol > rtol) {
                    best = res;     /* the first exact one in the order of preference */
                    have = 1;
                }
                continue;
            }
            if (!have || (res.viol < best.viol && best.viol > rtol)) {
                best = res;         /* an exact one is kept: the first in the order of preference */
                have = 1;
                if (!p->count && res.viol <= rtol)
                    break;
            }
        }
    } else {
        int states[NMAX], improved = 1;
        if (has_first && k > 0)
            memcpy(states, first, sizeof states);
        else
            for (j = 0; j < k; j++)
                states[j] = opts[j][0];
        friction_trial(&x, states, &best);
        have = 1;
        while (improved && best.viol > rtol) {
            improved = 0;
            for (j = 0; j < k; j++) {
                int o;
                for (o = 0; o < n_opts[j]; o++) {
                    int s = opts[j][o];
                    if (s == best.states[j])
                        continue;
                    memcpy(states, best.states, sizeof states);
                    states[j] = s;
                    friction_trial(&x, states, &res);
                    if (res.viol < best.viol) {
                        best = res;
                        improved = 1;
                    }
                }
            }
        }
        n_exact = best.viol <= rtol;
    }
    clear_solution(out);
    velocity(&x, p->v_free, best.P, out->v);
    for (i = 0; i < x.n; i++) {
        out->P_N[i] = best.P[i];
        out->P_T[i] = best.P[x.n + i];
    }
    for (j = 0; j < k; j++) {
        i = x.cand_idx[j];
        out->w_N[i] = best.w[i];
        out->w_T[i] = best.w[x.n + i];
        out->states[i] = best.states[j];
    }
    out->active = best.S;
    out->exact = best.viol <= rtol;
    out->violation = best.viol;
    out->frictional = 1;
    out->n_solutions = p->count ? n_exact : -1;
    for (i = 0; i < x.n; i++) {
        out->sliding[i] = x.sliding[i];
        if (x.sliding[i] != 0)
            out->has_sliding = 1;
    }
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ public */

static rk_status narrow(const rk_lcp_problem *p, const rk_lcp_wide_solution *w, rk_lcp_solution *out)
{
    int i;
    memset(out, 0, sizeof *out);
    memcpy(out->v, w->v, sizeof out->v);
    for (i = 0; i < RK_MAX_CONTACTS; i++) {
        out->P_N[i] = w->P_N[i];
        out->P_T[i] = w->P_T[i];
        out->w_N[i] = w->w_N[i];
        out->w_T[i] = w->w_T[i];
        out->states[i] = w->states[i];
        out->sliding[i] = w->sliding[i];
    }
    out->active = w->active;
    out->exact = w->exact;
    out->violation = w->violation;
    out->frictional = w->frictional;
    out->n_solutions = w->n_solutions;
    out->has_sliding = w->has_sliding;
    (void)p;
    return RK_OK;
}

rk_status rk_solve_contact_lcp(const rk_lcp_problem *p, rk_lcp_solution *out, rk_error *err)
{
    rk_lcp_wide_solution w;
    rk_status st;
    if (p->n_contacts > RK_MAX_CONTACTS)
        return rk_fail(err, RK_ERR_VALUE, "n_contacts = %d is out of range; allowed range [0, %d]",
                       p->n_contacts, RK_MAX_CONTACTS);
    st = rk_solve_contact_lcp_wide(p, &w, err);
    if (st != RK_OK)
        return st;
    return narrow(p, &w, out);
}

rk_status rk_solve_friction_lcp(const rk_lcp_problem *p, rk_lcp_solution *out, rk_error *err)
{
    rk_lcp_wide_solution w;
    rk_status st;
    if (p->n_contacts > RK_MAX_CONTACTS)
        return rk_fail(err, RK_ERR_VALUE, "n_contacts = %d is out of range; allowed range [0, %d]",
                       p->n_contacts, RK_MAX_CONTACTS);
    st = rk_solve_friction_lcp_wide(p, &w, err);
    if (st != RK_OK)
        return st;
    return narrow(p, &w, out);
}

int rk_lcp_painleve(const rk_lcp_solution *sol)
{
    int i, slides = 0;
    if (!sol->frictional || sol->n_solutions == -1 || sol->n_solutions == 1)
        return 0;
    for (i = 0; i < RK_MAX_CONTACTS; i++)
        slides |= sol->states[i] == RK_SLIDE_POS || sol->states[i] == RK_SLIDE_NEG;
    return sol->has_sliding || slides;
}

void rk_lstsq_square(int n, const double *A, const double *b, double *x)
{
    rk_la_lstsq(n, n, A, b, LSTSQ_RCOND, x);
}
