/* rk_sliding.c -- the sliding modes of any rocking model (part A): the port of rocking_model/models/sliding.py.
 *
 * A sliding mode has the closed corners of its stick mode and a base that moves along the ground with them:
 * its coordinates are the stick mode's reduced coordinates r plus the horizontal offset x_s of the base
 * (slide_index of q). The closed corners carry lambda_N and the friction -sigma mu lambda_N; the unknown of
 * each closed corner is tau = mu lambda_N >= 0 (force direction W_N / mu - sigma W_T), so mu = inf is the limit
 * of the finite-mu motion:
 *
 *     M a = f + sum_i (W_N,i / mu - sigma W_T,i) tau_i,   W_N,i . a + a_N,i = 0   (i closed)
 *
 * and r_ddot follows from a = J r_ddot + J_dot r_dot (J = [J_stick, e_x]). numpy's products and solves are
 * plain loops in index order and the small solves of rk_model.c: pinned to the Python at 1e-13 relative. */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_model.h"

#include <math.h>
#include <string.h>

int rk_slide_dofs(const rk_model *m, int mode, int *idx)
{
    int k = m->ops->mode_dofs(m, rk_stick_of(m, mode, NULL), idx);
    idx[k] = m->ops->slide_index;
    return k + 1;
}

void rk_slide_embed(const rk_model *m, int mode, const double *r, const double *r_dot, double *q, double *v)
{
    int idx[RK_MAX_DOF], k = rk_slide_dofs(m, mode, idx), i = m->ops->slide_index;
    m->ops->embed(m, rk_stick_of(m, mode, NULL), r, r_dot, q, v);
    q[i] += r[k - 1];
    v[i] += r_dot[k - 1];
}

int rk_slide_reduce(const rk_model *m, int mode, const double *q, const double *v, double *y)
{
    int stick = rk_stick_of(m, mode, NULL), idx[RK_MAX_DOF], k0, j, i = m->ops->slide_index;
    double r[RK_MAX_DOF], rd[RK_MAX_DOF], q0[RK_MAX_DOF], v0[RK_MAX_DOF];
    k0 = m->ops->mode_dofs(m, stick, idx);
    for (j = 0; j < k0; j++) {
        r[j] = q[idx[j]];
        rd[j] = v[idx[j]];
    }
    m->ops->embed(m, stick, r, rd, q0, v0);
    for (j = 0; j < k0; j++) {
        y[j] = r[j];
        y[k0 + 1 + j] = rd[j];
    }
    y[k0] = q[i] - q0[i];
    y[2 * k0 + 1] = v[i] - v0[i];
    return k0 + 1;
}

rk_status rk_slide_motion(const rk_model *m, int mode, const double *q, const double *v, double ag,
                          double ag_v, double *a, double *tau)
{
    int n = m->ops->n_dof, nc = m->ops->n_contacts, sigma = 0, stick, closed[RK_MAX_CONTACTS], kc = 0, i, j, l;
    double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS], a_N[RK_MAX_CONTACTS],
        a_T[RK_MAX_CONTACTS], Minv[RK_MAX_DOF * RK_MAX_DOF], f[RK_MAX_DOF], C[RK_MAX_DOF * RK_MAX_CONTACTS],
        a_free[RK_MAX_DOF], MC[RK_MAX_DOF * RK_MAX_CONTACTS], A[RK_MAX_CONTACTS * RK_MAX_CONTACTS],
        rhs[RK_MAX_CONTACTS], inv_mu;
    rk_set cs;
    stick = rk_stick_of(m, mode, &sigma);
    cs = rk_closed_of(m, stick);
    for (i = 0; i < nc; i++)
        if (RK_IN(cs, i))
            closed[kc++] = i;
    m->ops->contact_jacobians(m, q, W_N, W_T);
    m->ops->contact_drift(m, q, v, a_N, a_T);
    rk_model_inverse_mass(m, q, Minv);
    inv_mu = isinf(m->mu) ? 0.0 : 1.0 / m->mu;
    for (i = 0; i < n; i++)
        for (j = 0; j < kc; j++)
            C[i * kc + j] = inv_mu * W_N[i * nc + closed[j]] - (double)sigma * W_T[i * nc + closed[j]];
    m->ops->forces(m, q, v, ag, ag_v, f);
    for (i = 0; i < n; i++) {
        double s = 0.0;
        for (l = 0; l < n; l++)
            s += Minv[i * n + l] * f[l];
        a_free[i] = s;
    }
    for (i = 0; i < n; i++)
        for (j = 0; j < kc; j++) {
            double s = 0.0;
            for (l = 0; l < n; l++)
                s += Minv[i * n + l] * C[l * kc + j];
            MC[i * kc + j] = s;
        }
    for (i = 0; i < kc; i++) {
        double s = 0.0;
        for (j = 0; j < kc; j++) {
            double t = 0.0;
            for (l = 0; l < n; l++)
                t += W_N[l * nc + closed[i]] * MC[l * kc + j];
            A[i * kc + j] = t;
        }
        for (l = 0; l < n; l++)
            s += W_N[l * nc + closed[i]] * a_free[l];
        rhs[i] = -(s + a_N[closed[i]]);
    }
    if (rk_la_solve(kc, A, rhs, tau) != RK_OK) {
        if (rk_la_lstsq(kc, kc, A, rhs, 1e-12, tau) != RK_OK)
            return RK_ERR_SOLVER;
    }
    for (i = 0; i < n; i++) {
        double s = 0.0;
        for (j = 0; j < kc; j++)
            s += MC[i * kc + j] * tau[j];
        a[i] = a_free[i] + s;
    }
    return RK_OK;
}

void rk_slide_jacobian(const rk_model *m, int mode, const double *r, const double *r_dot, double *J, double *jd)
{
    int n = m->ops->n_dof, idx[RK_MAX_DOF], k = rk_slide_dofs(m, mode, idx), i, j;
    double Js[RK_MAX_DOF * RK_MAX_DOF];
    m->ops->mode_jacobian(m, rk_stick_of(m, mode, NULL), r, r_dot, Js, jd);
    for (i = 0; i < n; i++) {
        for (j = 0; j < k - 1; j++)
            J[i * k + j] = Js[i * (k - 1) + j];
        J[i * k + k - 1] = i == m->ops->slide_index ? 1.0 : 0.0;
    }
}

rk_status rk_slide_acceleration(const rk_model *m, int mode, const double *r, const double *r_dot, double ag,
                                double ag_v, double *r_ddot)
{
    int n = m->ops->n_dof, idx[RK_MAX_DOF], k = rk_slide_dofs(m, mode, idx), i;
    double q[RK_MAX_DOF], v[RK_MAX_DOF], a[RK_MAX_DOF], tau[RK_MAX_CONTACTS], J[RK_MAX_DOF * RK_MAX_DOF],
        jd[RK_MAX_DOF], rhs[RK_MAX_DOF];
    rk_status st;
    rk_slide_embed(m, mode, r, r_dot, q, v);
    st = rk_slide_motion(m, mode, q, v, ag, ag_v, a, tau);
    if (st != RK_OK)
        return st;
    rk_slide_jacobian(m, mode, r, r_dot, J, jd);
    for (i = 0; i < n; i++)
        rhs[i] = a[i] - jd[i];
    return rk_la_lstsq(n, k, J, rhs, -1.0, r_ddot);
}
