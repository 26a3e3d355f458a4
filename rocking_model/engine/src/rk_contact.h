/* rk_contact.h -- the one-step contact problems (part B).
 *
 * Ports of rocking_model/lcp.py (solve_contact_lcp: enumeration of active sets up to ENUMERATE_MAX candidates,
 * principal pivoting beyond; solve_friction_lcp: enumeration of the 4^n states up to FRICTION_ENUMERATE_MAX,
 * descent beyond) and rocking_model/contact.py (impact, uplift, solve_with_friction, project_to_ground,
 * closed_candidates, sliding_delassus, painleve_sticks, next_mode, solution_sigma, mode_forces).
 * Same constants (ENUMERATE_MAX 6, MAX_PIVOTS 200, SINGULAR_RTOL 1e-13, PARALLEL_RTOL 1e-12,
 * FRICTION_ENUMERATE_MAX 4), same order of trial of the active sets / states, same tie rules, same small
 * dense solves (lcp._solve_small), so that the chosen active set is the Python's and the values agree to
 * round-off. Pinned on random problems (tests/test_engine_contact.py).
 *
 * No allocation: every work array is on the stack, sized by RK_MAX_DOF / RK_MAX_CONTACTS.
 * Matrices: row-major; W_N, W_T are n_dof x n_contacts (one column per contact), as in rk_model.h. */
#ifndef RK_CONTACT_H
#define RK_CONTACT_H

#include "rk_common.h"
#include "rk_model.h"

#ifdef __cplusplus
extern "C" {
#endif

/** lcp.py's constants (named once here, same values and reasons). */
#define RK_ENUMERATE_MAX 6
#define RK_MAX_PIVOTS 200
#define RK_SINGULAR_RTOL 1e-13
#define RK_PARALLEL_RTOL 1e-12
#define RK_FRICTION_ENUMERATE_MAX 4

/** A contact problem (lcp.py's module docstring): unknown percussions on the candidates act on
 *  v = v_free + Minv (W_N P_N + W_T P_T). Every array is borrowed for the call. */
typedef struct rk_lcp_problem {
    int n_dof;                  /**< m: size of v */
    int n_contacts;             /**< n */
    const double *Minv;         /**< (m, m) */
    const double *W_N, *W_T;    /**< (m, n) */
    const double *v_free;       /**< (m,) velocity (impact) or acceleration (uplift) without percussions */
    const double *b_N, *b_T;    /**< (n,) offsets of the normal / tangential conditions */
    rk_set candidates;          /**< contacts taking part */
    rk_set forced;              /**< candidates closed as equalities w_N = 0 (the Zeno rule) */
    double rtol;                /**< [1] ContactTolerances.lcp_exact: below it the solution is exact */
    /* sticking problem only */
    int has_hint;               /**< 1: ``hint`` is given (Python: hint is not None) */
    rk_set hint;                /**< active set tried first */
    double hint_tol;            /**< [1] ContactTolerances.lcp_hint */
    /* frictional problem only */
    double mu;                  /**< [1] > 0, INFINITY allowed */
    const int *sliding;         /**< NULL (Python None) or per contact 0 (not sliding), +1, -1 (the ``sliding``
                                     dict: contacts that already slide and their direction) */
    int count;                  /**< 1: count the exact solutions (n_solutions) */
    const int *hint_states;     /**< NULL or per CANDIDATE in increasing order, an rk_contact_state tried
                                     first (the ``hint`` list of solve_friction_lcp) */
} rk_lcp_problem;

/** lcp.ContactSolution / FrictionSolution. Arrays beyond n_dof / n_contacts are unused. */
typedef struct rk_lcp_solution {
    double v[RK_MAX_DOF];           /**< solution velocity (impact) or acceleration (uplift) */
    double P_N[RK_MAX_CONTACTS];    /**< normal percussion per contact (0 off the active set) */
    double P_T[RK_MAX_CONTACTS];    /**< tangential percussion per contact */
    double w_N[RK_MAX_CONTACTS];    /**< W_N^T v + b_N (NAN for non-candidates) */
    double w_T[RK_MAX_CONTACTS];    /**< frictional only: W_T^T v + b_T (NAN for non-candidates) */
    rk_set active;                  /**< contacts carrying a normal percussion */
    int exact;                      /**< 0: no active set met every condition; the least-violating one */
    double violation;               /**< [1] largest relative violation */
    int frictional;                 /**< 1: a FrictionSolution (states, n_solutions, sliding meaningful) */
    int states[RK_MAX_CONTACTS];    /**< rk_contact_state per contact (RK_OPEN off the candidates) */
    int n_solutions;                /**< -1: not counted */
    int sliding[RK_MAX_CONTACTS];   /**< the problem's ``sliding`` (all 0 for None) */
    int has_sliding;                /**< 1: the problem's sliding was not NULL and not empty */
} rk_lcp_solution;

/** FrictionSolution.painleve (0 for a sticking solution). */
int rk_lcp_painleve(const rk_lcp_solution *sol);

/** lcp.solve_contact_lcp. RK_ERR_VALUE on an inconsistent problem (a forced contact outside the contacts). */
rk_status rk_solve_contact_lcp(const rk_lcp_problem *p, rk_lcp_solution *out, rk_error *err);
/** lcp.solve_friction_lcp (uses mu, sliding, count, hint_states). */
rk_status rk_solve_friction_lcp(const rk_lcp_problem *p, rk_lcp_solution *out, rk_error *err);

/** Wider variants (added by part B): the same solvers for up to RK_LCP_MAX_CONTACTS contacts, so that the
 *  pivoting (more than RK_ENUMERATE_MAX free candidates) and the frictional descent (more than
 *  RK_FRICTION_ENUMERATE_MAX candidates) can be pinned to the Python although no model of the engine has that
 *  many contacts. rk_solve_contact_lcp / rk_solve_friction_lcp call them and copy the result. */
#define RK_LCP_MAX_CONTACTS 8
typedef struct rk_lcp_wide_solution {
    double v[RK_MAX_DOF];
    double P_N[RK_LCP_MAX_CONTACTS], P_T[RK_LCP_MAX_CONTACTS];
    double w_N[RK_LCP_MAX_CONTACTS], w_T[RK_LCP_MAX_CONTACTS];
    rk_set active;
    int exact;
    double violation;
    int frictional;
    int states[RK_LCP_MAX_CONTACTS];
    int n_solutions;
    int sliding[RK_LCP_MAX_CONTACTS];
    int has_sliding;
} rk_lcp_wide_solution;
rk_status rk_solve_contact_lcp_wide(const rk_lcp_problem *p, rk_lcp_wide_solution *out, rk_error *err);
rk_status rk_solve_friction_lcp_wide(const rk_lcp_problem *p, rk_lcp_wide_solution *out, rk_error *err);

/* ------------------------------------------------------------------------------------------ contact.py */
/** Optional arguments of the contact.py functions: what the Python passes as keywords. */
typedef struct rk_contact_args {
    rk_set forced;              /**< ``forced`` */
    int prefer;                 /**< ``prefer``: an rk_contact_state, or -1 (None) */
    int has_hint;               /**< solve_with_friction ``hint`` given */
    rk_set hint;
    int has_e;                  /**< impact: 1 to override e_N and e_T by the two below */
    double e_N, e_T;
    int count;                  /**< uplift / solve_with_friction ``count`` */
    int has_slip_tol;           /**< uplift: ``slip_tol`` given (not None) */
    double slip_tol;            /**< [m/s] */
    const int *sliding;         /**< solve_with_friction ``sliding`` (NULL: None) */
    const rk_tolerances *tolerances;  /**< impact / uplift / solve_with_friction ``tolerances`` (lcp_exact,
                                           lcp_hint); NULL: RK_DEFAULT_TOLERANCES. Both schemes pass the user's */
} rk_contact_args;

/** The defaults: nothing forced, prefer -1, no hint, no e override, count 0, no slip_tol, no sliding,
 *  tolerances NULL. */
void rk_contact_args_default(rk_contact_args *a);

/** contact.impact: post-impact velocities from the impact LCP (Newton normal, the model's tangential law,
 *  Coulomb with a finite mu). */
rk_status rk_impact(const rk_model *m, const double *q, const double *v_minus, rk_set candidates,
                    const rk_contact_args *a, rk_lcp_solution *out, rk_error *err);
/** contact.uplift: the acceleration-level LCP at (q, v, ag). */
rk_status rk_uplift(const rk_model *m, const double *q, const double *v, double ag, double ag_v, rk_set candidates,
                    const rk_contact_args *a, rk_lcp_solution *out, rk_error *err);
/** The data of rk_uplift's acceleration-level problem at (q, v) under (ag, ag_v). */
typedef struct rk_uplift_data {
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS];
    double Minv[RK_MAX_DOF * RK_MAX_DOF];
    double b_N[RK_MAX_CONTACTS], b_T[RK_MAX_CONTACTS];     /**< the drifts (d/dt W)^T v */
    double acc_free[RK_MAX_DOF];                             /**< M^-1 f */
    int sliding[RK_MAX_CONTACTS];   /**< +-1 where a contact of ``moving`` slides faster than slip_tol, else 0 */
} rk_uplift_data;
/** Fill d and point p at it (p's other fields zero: the caller sets candidates, forced, the solver's options);
 *  slip_tol < 0: no sliding computed (all 0). */
void rk_uplift_data_of(const rk_model *m, const double *q, const double *v, double ag, double ag_v, rk_set moving,
                       double slip_tol, rk_uplift_data *d, rk_lcp_problem *p);
/** contact.solve_with_friction: the friction law picks the problem (p's Minv..b_T, candidates, forced are
 *  used; its rtol / hint / mu / sliding / count / hint_states fields are set from m and a). */
rk_status rk_solve_with_friction(const rk_model *m, const rk_lcp_problem *p, const rk_contact_args *a,
                                 rk_lcp_solution *out, rk_error *err);
/** contact.project_to_ground: q_out = q moved onto g_N = 0 at ``corners``. */
rk_status rk_project_to_ground(const rk_model *m, const double *q, rk_set corners, double *q_out,
                               rk_error *err);
/** contact.closed_candidates: contacts with g_N <= gap_tol [m] and |U_N| <= v_tol [m/s]. */
rk_set rk_closed_candidates(const rk_model *m, const double *q, const double *v, double gap_tol, double v_tol);
/** contact.sliding_delassus [1/kg] (+-INFINITY with mu = inf, as the Python). */
double rk_sliding_delassus(const rk_model *m, const double *q, int i, double sigma);
/** contact.painleve_sticks. */
rk_set rk_painleve_sticks(const rk_model *m, const double *q, const double *v_minus, const double *v_plus,
                          rk_set candidates, double v_tol);
/** contact.next_mode: the mode that follows a consistent state, and whether an uplift solution was computed
 *  (*has_solution 0: no candidate, the mode of no closed contact, sol untouched). prefer: -1 or a state;
 *  tolerances: the uplift LCP's (``tolerances``; NULL: RK_DEFAULT_TOLERANCES). */
rk_status rk_next_mode(const rk_model *m, const double *q, const double *v, double ag, double ag_v, double gap_tol,
                       double v_tol, int prefer, const rk_tolerances *tolerances, int *mode, rk_lcp_solution *sol,
                       int *has_solution, rk_error *err);
/** contact.solution_sigma: +1, -1 or 0. */
int rk_solution_sigma(const rk_lcp_solution *sol, int n_contacts);
/** contact.mode_forces: normal forces [N] of the closed contacts of a sticking mode held closed. */
rk_status rk_mode_forces(const rk_model *m, int mode, const double *q, const double *v, double ag, double ag_v,
                         double *lam, rk_error *err);

/** Added by part B: integrators/moreau_jean.inexact_message, the text of an "inexact_contact" report (shared by
 *  the event-driven scheme and Moreau-Jean): "the <what> at t = <t> s has no exact solution (least violation
 *  <.3g>, closed contacts <tuple>): kept the least-violating one; a corner may sink or lift against the
 *  contact law". n_contacts bounds the contacts listed. */
void rk_inexact_message(const rk_lcp_solution *sol, int n_contacts, double t, const char *what, char *buf,
                        size_t n);
/** Added by part B: np.linalg.lstsq(A, b, rcond=1e-12)[0] for a square A (n x n, row-major, n <= 16): the
 *  minimum-norm least-squares solution (singular values <= 1e-12 * the largest dropped). */
void rk_lstsq_square(int n, const double *A, const double *b, double *x);

#ifdef __cplusplus
}
#endif
#endif /* RK_CONTACT_H */
