/* rk_flexible.c -- RK_FLEXIBLE_OSCILLATOR, the flexible rocking oscillator (part A): the port of
 * rocking_model/models/flexible_oscillator.py (Giouvanidis & Dimitrakopoulos 2017, appendix, Eqs. 48-55) and of
 * the classical impact rule of rocking_model/models/flexible_impact.py.
 *
 * A cantilever column (height h, flexural rigidity EI, mass m_c) with a top mass m on a rigid base (mass m_b,
 * radius of gyration rho, half-width b). Full coordinates q = [u, x, y, phi]: u the tip deflection, (x, y) the
 * base midpoint in the ground frame (y = 0 at rest), phi the rotation (phi > 0 pivots on the left corner).
 * Shorthands (module docstring of the Python): m_tilde = m + 33/140 m_c, k_tilde = 3 EI/h^3, M_t, D, A_h, C,
 * I_mb, J0, J_eff, c = 2 zeta sqrt(m_tilde k_tilde).
 *
 * The closed forms keep the Python's operation order (bitwise equal, tests/test_engine_model.py); where the
 * Python uses numpy products (contact_forces, kinetic_energy) the C loops agree to round-off. */
#include "rk_model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* parameters, declared order (FlexibleOscillator's fields) */
enum { P_M, P_MC, P_MB, P_RHO, P_H, P_B, P_EI, P_ZETA, P_EN, P_LAW, P_MU, P_RULE, P_G, N_PARAMS };
/* derived constants in m->d */
enum { D_MT, D_KT, D_MTOT, D_D, D_AH, D_C, D_IMB, D_J0, D_JEFF, D_CD, D_OMEGA, D_HCG, D_R, D_ALPHA, D_IO, D_P,
       D_A11, D_K0, D_L };

/** [rad/s] OMEGA_MAX: largest fixed-base circular frequency of the column */
#define OMEGA_MAX 1e4

static const char *const IMPACT_LAW_ITEMS[] = {"newton", "energy_consistent"};
static const char *const IMPACT_RULE_ITEMS[] = {"lcp", "classical"};

static const rk_param_decl PARAMS[N_PARAMS] = {
    {"m", "kg", 500.0, 1e-9, 1e12, 0, 0, 0, 0, 0, NULL},
    {"m_c", "kg", 30.0, 0.0, 1e12, 0, 0, 0, 0, 0, NULL},
    {"m_b", "kg", 100.0, 0.0, 1e12, 0, 0, 0, 0, 0, NULL},
    {"rho", "m", 0.145, 0.0, 1e3, 0, 0, 0, 0, 0, NULL},
    {"h", "m", 1.5, 1e-6, 1e3, 0, 0, 0, 0, 0, NULL},
    {"b", "m", 0.25, 1e-6, 1e3, 0, 0, 0, 0, 0, NULL},
    {"EI", "N.m2", 9.45e5, 0.0, 1e15, 1, 0, 0, 0, 0, NULL},
    {"zeta", "1", 0.02, 0.0, 10.0, 0, 0, 0, 0, 0, NULL},
    {"e_N", "1", 0.0, 0.0, 1.0, 0, 0, 0, 0, 0, NULL},
    {"impact_law", "", 0.0, 0.0, 1.0, 0, 0, 0, 1, 2, IMPACT_LAW_ITEMS},
    {"mu", "1", INFINITY, 1e-3, INFINITY, 0, 0, 1, 0, 0, NULL},
    {"impact_rule", "", 0.0, 0.0, 1.0, 0, 0, 0, 1, 2, IMPACT_RULE_ITEMS},
    {"g", "m/s2", 9.81, 1e-3, 1e3, 0, 0, 0, 0, 0, NULL},
};

static const rk_param_decl INITIAL[4] = {
    {"phi_0", "rad", 0.0, -RK_HALF_PI, RK_HALF_PI, 1, 1, 0, 0, 0, NULL},
    {"phi_dot_0", "rad/s", 0.0, -1e4, 1e4, 0, 0, 0, 0, 0, NULL},
    {"u_0", "m", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},   /* checked against [-h, h] (initial_state) */
    {"u_dot_0", "m/s", 0.0, -1e4, 1e4, 0, 0, 0, 0, 0, NULL},
};

#define OUT(name, unit) {name, unit, 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL}
static const rk_param_decl OUTPUTS[11] = {
    OUT("u", "m"), OUT("u_dot", "m/s"), OUT("phi", "rad"), OUT("phi_dot", "rad/s"), OUT("x", "m"), OUT("y", "m"),
    OUT("x_dot", "m/s"), OUT("y_dot", "m/s"), OUT("slip", "m"), OUT("top_displacement", "m"), OUT("energy", "J"),
};
enum { O_U, O_U_DOT, O_PHI, O_PHI_DOT, O_X, O_Y, O_X_DOT, O_Y_DOT, O_SLIP, O_TOP, O_ENERGY };
static const int SHIFTED[3] = {O_X, O_SLIP, O_TOP};

#define MT (m->d[D_MT])
#define KT (m->d[D_KT])
#define MTOT (m->d[D_MTOT])
#define DD (m->d[D_D])
#define AH (m->d[D_AH])
#define CC (m->d[D_C])
#define J0 (m->d[D_J0])
#define CD (m->d[D_CD])
#define B (m->p[P_B])
#define H (m->p[P_H])
#define G (m->p[P_G])

/* ------------------------------------------------------------------------------------------ construction */
static rk_status flexible_init(rk_model *m, const double *params, rk_error *err)
{
    int i;
    double mm, m_c, h, omega;
    for (i = 0; i < N_PARAMS; i++) {
        if (rk_param_check(&PARAMS[i], params[i], &m->p[i], err) != RK_OK)
            return RK_ERR_VALUE;
    }
    if (m->p[P_MC] == 0.0 && m->p[P_MB] * (m->p[P_RHO] * m->p[P_RHO]) == 0.0) {
        int bad = m->p[P_MB] == 0.0 ? P_MB : P_RHO;   /* rho > 0 can still give m_b*rho^2 = 0 (underflow) */
        return rk_fail(err, RK_ERR_VALUE, "%s = %g is out of range when m_c = 0: the mass matrix is singular unless "
                       "m_c > 0 or m_b*rho^2 > 0; allowed range with m_c = 0: m_b in (0, 1e+12] and rho in (0, 1000]",
                       PARAMS[bad].name, m->p[bad]);
    }
    mm = m->p[P_M];
    m_c = m->p[P_MC];
    h = H;
    m->d[D_MT] = mm + 33.0 / 140.0 * m_c;
    m->d[D_KT] = 3.0 * m->p[P_EI] / pow(h, 3.0);
    m->d[D_MTOT] = mm + m->p[P_MB] + m_c;
    m->d[D_D] = mm + 3.0 / 8.0 * m_c;
    m->d[D_AH] = (mm + 0.5 * m_c) * h;
    m->d[D_C] = (mm + 11.0 / 40.0 * m_c) * h;
    m->d[D_IMB] = m->p[P_MB] * (m->p[P_RHO] * m->p[P_RHO]);
    m->d[D_J0] = m->d[D_IMB] + mm * (h * h) + m_c * (h * h) / 3.0;
    m->d[D_JEFF] = m->d[D_J0] - m->d[D_C] * m->d[D_C] / m->d[D_MT];
    m->d[D_CD] = 2.0 * m->p[P_ZETA] * sqrt(m->d[D_MT] * m->d[D_KT]);
    omega = sqrt(m->d[D_KT] / m->d[D_MT]);
    if (omega > OMEGA_MAX) {
        double EI_max = OMEGA_MAX * OMEGA_MAX * m->d[D_MT] * pow(h, 3.0) / 3.0;
        return rk_fail(err, RK_ERR_VALUE, "EI = %g is out of range for m = %g, m_c = %g, h = %g; allowed range "
                       "(0, %.6g] N m2: the column's circular frequency omega = sqrt(3 EI/(h^3 m_tilde)) = %.4g rad/s "
                       "exceeds OMEGA_MAX = %g rad/s; a column this stiff rocks as a rigid body: use RigidBlock",
                       m->p[P_EI], mm, m_c, h, EI_max, omega, OMEGA_MAX);
    }
    m->d[D_OMEGA] = omega;
    m->d[D_HCG] = m->d[D_AH] / m->d[D_MTOT];
    m->d[D_R] = rk_py_hypot(B, m->d[D_HCG]);
    m->d[D_ALPHA] = atan2(B, m->d[D_HCG]);
    m->d[D_IO] = m->d[D_J0] + m->d[D_MTOT] * (B * B);
    m->d[D_P] = sqrt(m->d[D_MTOT] * G * m->d[D_R] / m->d[D_IO]);
    m->d[D_A11] = m->d[D_MT] - m->d[D_D] * m->d[D_D] / m->d[D_MTOT];       /* mode_closures' flight a11 */
    m->d[D_K0] = m->d[D_J0] + m->d[D_MTOT] * B * B;                         /* mode_closures' rocking K0 */
    m->d[D_L] = rk_py_hypot(B, h);
    m->e_N = m->p[P_EN];
    m->impact_law = (int)m->p[P_LAW];
    m->e_T = m->impact_law == 1 ? m->e_N : 0.0;
    m->mu = m->p[P_MU];
    m->g = G;
    m->length_scale = m->d[D_L];
    m->time_scale = 1.0 / m->d[D_P];
    m->force_scale = m->d[D_MTOT] * G;
    m->step_limit = 0.25 / sqrt(m->d[D_KT] / m->d[D_MT]);
    for (i = 0; i < 3; i++)
        m->dof_scales[i] = m->d[D_L];
    m->dof_scales[3] = 1.0;
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ dynamical system */
static void flexible_mass_matrix(const rk_model *m, const double *q, double *M)
{
    double u = q[0], phi = q[3], sp = sin(phi), cp = cos(phi), D = DD, Mt = MTOT;
    double Mxp = -(AH * cp + D * u * sp), Myp = -AH * sp + D * u * cp;
    double row[16];
    row[0] = MT; row[1] = D * cp; row[2] = D * sp; row[3] = -CC;
    row[4] = D * cp; row[5] = Mt; row[6] = 0.0; row[7] = Mxp;
    row[8] = D * sp; row[9] = 0.0; row[10] = Mt; row[11] = Myp;
    row[12] = -CC; row[13] = Mxp; row[14] = Myp; row[15] = J0 + MT * u * u;
    memcpy(M, row, sizeof row);
}

static void flexible_forces(const rk_model *m, const double *q, const double *v, double ag, double ag_v, double *f)
{
    /* right-hand sides of Eq. (55): damping, elastic, centrifugal/Coriolis, ground inertia, gravity; the
     * vertical ground acceleration adds to gravity (g + 0.0 == g: ag_v = 0 rounds as before) */
    double u = q[0], phi = q[3], ud = v[0], w = v[3], sp = sin(phi), cp = cos(phi), D = DD, Mt = MTOT, g = G + ag_v;
    double Mxp = -(AH * cp + D * u * sp), Myp = -AH * sp + D * u * cp;
    f[0] = -CD * ud - KT * u + MT * u * w * w - D * cp * ag - D * sp * g;
    f[1] = Myp * w * w + 2.0 * D * sp * ud * w - Mt * ag;
    f[2] = -Mxp * w * w - 2.0 * D * cp * ud * w - Mt * g;
    f[3] = -2.0 * MT * u * ud * w - Mxp * ag - g * Myp;
}

static int flexible_stiff_jacobians(const rk_model *m, const double *q, const double *v, double *K, double *C)
{
    (void)q; (void)v;
    memset(K, 0, 16 * sizeof(double));
    memset(C, 0, 16 * sizeof(double));
    K[0] = KT;
    C[0] = CD;
    return 1;
}

/* ------------------------------------------------------------------------------------------ contact relation */
static void flexible_gaps(const rk_model *m, const double *q, double *g)
{
    double y = q[2], sp = sin(q[3]);
    g[0] = y - B * sp;
    g[1] = y + B * sp;
}

static void flexible_contact_jacobians(const rk_model *m, const double *q, double *W_N, double *W_T)
{
    double phi = q[3], bs = B * sin(phi), bc = B * cos(phi);
    W_N[0] = 0.0; W_N[1] = 0.0; W_N[2] = 0.0; W_N[3] = 0.0;
    W_N[4] = 1.0; W_N[5] = 1.0; W_N[6] = -bc; W_N[7] = bc;
    W_T[0] = 0.0; W_T[1] = 0.0; W_T[2] = 1.0; W_T[3] = 1.0;
    W_T[4] = 0.0; W_T[5] = 0.0; W_T[6] = bs; W_T[7] = -bs;
}

static void flexible_contact_abscissae(const rk_model *m, const double *q, double *x)
{
    double bc = B * cos(q[3]);
    x[0] = q[1] - bc;
    x[1] = q[1] + bc;
}

static void flexible_contact_drift(const rk_model *m, const double *q, const double *v, double *a_N, double *a_T)
{
    double phi = q[3], w = v[3];
    double bs = B * sin(phi) * w * w, bc = B * cos(phi) * w * w;
    a_N[0] = bs;
    a_N[1] = -bs;
    a_T[0] = bc;
    a_T[1] = -bc;
}

/* ------------------------------------------------------------------------------------------ sticking modes */
static int flexible_mode_dofs(const rk_model *m, int mode, int *idx)
{
    (void)m;
    if (mode == RK_MODE_FULL) {
        idx[0] = 0;
        return 1;
    }
    if (mode == RK_MODE_FLIGHT) {
        idx[0] = 0; idx[1] = 1; idx[2] = 2; idx[3] = 3;
        return 4;
    }
    idx[0] = 0;
    idx[1] = 3;
    return 2;
}

static void flexible_embed(const rk_model *m, int mode, const double *r, const double *r_dot, double *q, double *v)
{
    double s, u, phi, ud, w, sp, cp, b = B;
    if (mode == RK_MODE_FULL) {
        q[0] = r[0]; q[1] = 0.0; q[2] = 0.0; q[3] = 0.0;
        v[0] = r_dot[0]; v[1] = 0.0; v[2] = 0.0; v[3] = 0.0;
        return;
    }
    if (mode == RK_MODE_FLIGHT) {
        memcpy(q, r, 4 * sizeof(double));
        memcpy(v, r_dot, 4 * sizeof(double));
        return;
    }
    s = (double)rk_pivot_sign(mode);
    u = r[0]; phi = r[1]; ud = r_dot[0]; w = r_dot[1];
    sp = sin(phi);
    cp = cos(phi);
    q[0] = u; q[1] = s * b * (1.0 - cp); q[2] = -s * b * sp; q[3] = phi;
    v[0] = ud; v[1] = s * b * sp * w; v[2] = -s * b * cp * w; v[3] = w;
}

static void flexible_mode_jacobian(const rk_model *m, int mode, const double *r, const double *r_dot, double *J,
                                   double *jd)
{
    double s, phi, w, sp, cp, b = B;
    int i;
    for (i = 0; i < 4; i++)
        jd[i] = 0.0;
    if (mode == RK_MODE_FULL) {
        J[0] = 1.0; J[1] = 0.0; J[2] = 0.0; J[3] = 0.0;
        return;
    }
    if (mode == RK_MODE_FLIGHT) {
        for (i = 0; i < 16; i++)
            J[i] = (i % 5 == 0) ? 1.0 : 0.0;
        return;
    }
    s = (double)rk_pivot_sign(mode);
    phi = r[1];
    w = r_dot[1];
    sp = sin(phi);
    cp = cos(phi);
    J[0] = 1.0; J[1] = 0.0;
    J[2] = 0.0; J[3] = s * b * sp;
    J[4] = 0.0; J[5] = -s * b * cp;
    J[6] = 0.0; J[7] = 1.0;
    jd[1] = s * b * cp * w * w;
    jd[2] = s * b * sp * w * w;
}

/* mode_closures' rocking accel(u, phi, ud, w, a) */
static void rocking_accel(const rk_model *m, double s, double u, double phi, double ud, double w, double a,
                          double a_v, double *udd, double *wd, double *sp_out, double *cp_out)
{
    double mt = MT, kt = KT, c = CD, C = CC, D = DD, g = G + a_v, A_h = AH;
    double sb = s * B, sbM = sb * MTOT;
    double sp = sin(phi), cp = cos(phi);
    double K = m->d[D_K0] + mt * u * u - 2.0 * sb * D * u;
    double E = mt * u - sb * D;
    double f_u = -c * ud - kt * u - g * D * sp - D * cp * a + E * w * w;
    double f_p = -2.0 * E * ud * w - g * (D * u - sbM) * cp + g * A_h * sp + a * (A_h * cp + (D * u - sbM) * sp);
    double det = mt * K - C * C;
    *udd = (K * f_u + C * f_p) / det;
    *wd = (C * f_u + mt * f_p) / det;
    *sp_out = sp;
    *cp_out = cp;
}

static void flexible_mode_rhs(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *dy)
{
    double mt = MT, kt = KT, c = CD, C = CC, D = DD, g = G + ag_v, A_h = AH, Mt = MTOT, J0v = J0;
    if (mode == RK_MODE_FLIGHT) {
        /* M(q) v_dot = f: x and y condensed out (Schur complement), the (u, phi) system by Cramer's rule */
        double u = y[0], phi = y[3], ud = y[4], xd = y[5], yd = y[6], w = y[7], a = ag;
        double sp = sin(phi), cp = cos(phi);
        double Mxp = -(A_h * cp + D * u * sp), Myp = -A_h * sp + D * u * cp;
        double ww = w * w;
        double f_u = -c * ud - kt * u + mt * u * ww - D * cp * a - D * sp * g;
        double f_x = Myp * ww + 2.0 * D * sp * ud * w - Mt * a;
        double f_y = -Mxp * ww - 2.0 * D * cp * ud * w - Mt * g;
        double f_p = -2.0 * mt * u * ud * w - Mxp * a - g * Myp;
        double a11 = m->d[D_A11];
        double a12 = -C - D * (cp * Mxp + sp * Myp) / Mt;
        double a22 = J0v + mt * u * u - (Mxp * Mxp + Myp * Myp) / Mt;
        double r1 = f_u - D * (cp * f_x + sp * f_y) / Mt;
        double r2 = f_p - (Mxp * f_x + Myp * f_y) / Mt;
        double det = a11 * a22 - a12 * a12;
        double udd = (a22 * r1 - a12 * r2) / det;
        double wd = (a11 * r2 - a12 * r1) / det;
        dy[0] = ud; dy[1] = xd; dy[2] = yd; dy[3] = w;
        dy[4] = udd;
        dy[5] = (f_x - D * cp * udd - Mxp * wd) / Mt;
        dy[6] = (f_y - D * sp * udd - Myp * wd) / Mt;
        dy[7] = wd;
        return;
    }
    if (mode == RK_MODE_FULL) {
        double u = y[0], ud = y[1];
        dy[0] = ud;
        dy[1] = (-c * ud - kt * u - D * ag) / mt;
        return;
    }
    {
        double udd, wd, sp, cp;
        rocking_accel(m, (double)rk_pivot_sign(mode), y[0], y[1], y[2], y[3], ag, ag_v, &udd, &wd, &sp, &cp);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = udd;
        dy[3] = wd;
    }
}

static void flexible_mode_monitors(const rk_model *m, int mode, const double *y, double ag, double ag_v,
                                   double *g, double *totals)
{
    double mt = MT, kt = KT, c = CD, C = CC, D = DD, grav = G, A_h = AH, Mt = MTOT, b = B;
    /* W the weight (the monitors' scale, always > 0), We = M_t (g + ag_v) the effective weight (== W at
     * ag_v = 0) that the contacts carry */
    double ge = grav + ag_v, W = Mt * grav, We = Mt * ge;
    if (mode == RK_MODE_FLIGHT) {
        double yc = y[2], phi = y[3], L = m->d[D_L];
        double bs = b * sin(phi);
        g[0] = (yc - bs) / L;
        g[1] = (yc + bs) / L;
        g[2] = RK_HALF_PI - fabs(phi);
        return;
    }
    if (mode == RK_MODE_FULL) {
        double u = y[0], ud = y[1], a = ag;
        double udd = (-c * ud - kt * u - D * a) / mt;
        /* phi row of M v_dot - f at phi = 0: b (lambda_R - lambda_L) = -C u_dd - (A_h ag - (g + ag_v) D u) */
        double d = (-C * udd - A_h * a + ge * D * u) / b;
        g[0] = 0.5 * (We - d) / W;
        g[1] = 0.5 * (We + d) / W;
        g[2] = RK_HALF_PI;
        if (totals != NULL) {
            totals[0] = We;
            totals[1] = D * (-c * ud - kt * u - D * a) / mt + Mt * a;
        }
        return;
    }
    {
        double s = (double)rk_pivot_sign(mode), sb = s * b;
        double u = y[0], phi = y[1], ud = y[2], w = y[3], a = ag, udd, wd, sp, cp, ydd, Mxp, Myp, lam, margin;
        rocking_accel(m, s, u, phi, ud, w, a, ag_v, &udd, &wd, &sp, &cp);
        /* pivot force = y row of M v_dot - f (the tangential direction is horizontal) */
        ydd = -sb * cp * wd + sb * sp * w * w;
        Mxp = -(A_h * cp + D * u * sp);
        Myp = -A_h * sp + D * u * cp;
        lam = D * sp * udd + Mt * ydd + Myp * wd + Mxp * w * w + 2.0 * D * cp * ud * w + We;
        margin = RK_HALF_PI - fabs(phi);
        if (s < 0) {
            g[0] = lam / W; g[1] = -s * phi;
        } else {
            g[0] = -s * phi; g[1] = lam / W;
        }
        g[2] = margin;
        if (totals != NULL) {
            double ww = w * w;
            double xdd = sb * sp * wd + sb * cp * ww;
            totals[0] = lam;
            totals[1] = D * cp * udd + Mt * xdd + Mxp * wd - Myp * ww - 2.0 * D * sp * ud * w + Mt * a;
        }
    }
}

/* _outputs(u, x, y, phi, ud, xd, yd, w) */
static void outputs8(const rk_model *m, double u, double x, double y, double phi, double ud, double xd, double yd,
                     double w, double *out)
{
    double sp = sin(phi), cp = cos(phi), D = DD, mt = MT, Mt = MTOT;
    double Mxp = -(AH * cp + D * u * sp), Myp = -AH * sp + D * u * cp;
    /* 1/2 v^T M v written out */
    double kin = 0.5 * (mt * ud * ud + Mt * (xd * xd + yd * yd) + (J0 + mt * u * u) * w * w)
        + D * cp * ud * xd + D * sp * ud * yd - CC * ud * w + Mxp * xd * w + Myp * yd * w;
    double pot = 0.5 * KT * u * u + G * (Mt * y + AH * (cp - 1.0) + D * u * sp);
    out[O_U] = u;
    out[O_U_DOT] = ud;
    out[O_PHI] = phi;
    out[O_PHI_DOT] = w;
    out[O_X] = x;
    out[O_Y] = y;
    out[O_X_DOT] = xd;
    out[O_Y_DOT] = yd;
    /* the lower corner's displacement (s = -1, the left one, for phi > 0): exactly 0 while rocking */
    out[O_SLIP] = x + ((phi > 0.0) ? -1.0 : 1.0) * B * (cp - 1.0);
    out[O_TOP] = x - H * sp + u * cp;
    out[O_ENERGY] = kin + pot;
}

static void flexible_outputs(const rk_model *m, const double *q, const double *v, double *out)
{
    outputs8(m, q[0], q[1], q[2], q[3], v[0], v[1], v[2], v[3], out);
}

static void flexible_mode_outputs(const rk_model *m, int mode, const double *y, double *out)
{
    double s, u, phi, ud, w, sp, cp, b = B;
    if (mode == RK_MODE_FULL) {
        outputs8(m, y[0], 0.0, 0.0, 0.0, y[1], 0.0, 0.0, 0.0, out);
        return;
    }
    if (mode == RK_MODE_FLIGHT) {
        outputs8(m, y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7], out);
        return;
    }
    s = (double)rk_pivot_sign(mode);
    u = y[0]; phi = y[1]; ud = y[2]; w = y[3];
    sp = sin(phi);
    cp = cos(phi);
    outputs8(m, u, s * b * (1.0 - cp), -s * b * sp, phi, ud, s * b * sp * w, -s * b * cp * w, w, out);
}

/* FlexibleOscillator.reduced_acceleration of the sticking modes with closed corners (FULL, rocking): its own
 * closed forms (operation order differs from mode_closures' accel: K = J0 + m_tilde u^2 + M_t b^2 - ...) */
static void reduced_acceleration(const rk_model *m, int mode, const double *r, const double *r_dot, double ag,
                                 double ag_v, double *rdd)
{
    if (mode == RK_MODE_FULL) {
        rdd[0] = (-CD * r_dot[0] - KT * r[0] - DD * ag) / MT;
        return;
    }
    {
        double s = (double)rk_pivot_sign(mode);
        double u = r[0], phi = r[1], ud = r_dot[0], w = r_dot[1], sp = sin(phi), cp = cos(phi);
        double mt = MT, C = CC, D = DD, g = G + ag_v;
        double sbM = s * B * MTOT;
        double K = J0 + mt * u * u + MTOT * (B * B) - 2.0 * s * B * D * u;
        double E = mt * u - s * B * D;
        double f_u = -CD * ud - KT * u - g * D * sp - D * cp * ag + E * w * w;
        double f_p = (-2.0 * E * ud * w - g * (D * u - sbM) * cp + g * AH * sp + ag * (AH * cp + (D * u - sbM) * sp));
        double det = mt * K - C * C;
        rdd[0] = (K * f_u + C * f_p) / det;
        rdd[1] = (C * f_u + mt * f_p) / det;
    }
}

static void flexible_contact_forces(const rk_model *m, int mode, const double *q, const double *v, double ag,
                                    double ag_v, double *lam)
{
    int idx[4], k, i, j;
    double r[4], rd[4], J[16], jd[4], rdd[4], a[4], M[16], f[4], resid[4];
    lam[0] = 0.0;
    lam[1] = 0.0;
    if (mode == RK_MODE_FLIGHT)
        return;
    k = flexible_mode_dofs(m, mode, idx);
    for (i = 0; i < k; i++) {
        r[i] = q[idx[i]];
        rd[i] = v[idx[i]];
    }
    flexible_mode_jacobian(m, mode, r, rd, J, jd);
    reduced_acceleration(m, mode, r, rd, ag, ag_v, rdd);
    for (i = 0; i < 4; i++) {
        double s = 0.0;
        for (j = 0; j < k; j++)
            s += J[i * k + j] * rdd[j];
        a[i] = s + jd[i];
    }
    flexible_mass_matrix(m, q, M);
    flexible_forces(m, q, v, ag, ag_v, f);
    for (i = 0; i < 4; i++) {
        double s = 0.0;
        for (j = 0; j < 4; j++)
            s += M[i * 4 + j] * a[j];
        resid[i] = s - f[i];
    }
    if (mode == RK_MODE_FULL) {
        double d = resid[3] / B;
        lam[0] = 0.5 * (resid[2] - d);
        lam[1] = 0.5 * (resid[2] + d);
        return;
    }
    lam[mode == RK_MODE_LEFT ? 0 : 1] = resid[2];
}

/* ------------------------------------------------------------------------------------------ quantities */
static void flexible_rest_position(const rk_model *m, double *q)
{
    (void)m;
    q[0] = 0.0; q[1] = 0.0; q[2] = 0.0; q[3] = 0.0;
}

/** potential_energy: Eq. (53) minus its rest value [J] */
static double potential_energy(const rk_model *m, const double *q)
{
    double u = q[0], y = q[2], phi = q[3], sp = sin(phi), cp = cos(phi);
    return (0.5 * KT * u * u + G * (MTOT * y + AH * (cp - 1.0) + DD * u * sp));
}

/** kinetic_energy: 1/2 v^T M(q) v (numpy's (v @ M) @ v) [J] */
static double kinetic_energy(const rk_model *m, const double *q, const double *v)
{
    double M[16], vm[4], s = 0.0;
    int i, j;
    flexible_mass_matrix(m, q, M);
    for (j = 0; j < 4; j++) {
        double t = 0.0;
        for (i = 0; i < 4; i++)
            t += v[i] * M[i * 4 + j];
        vm[j] = t;
    }
    for (j = 0; j < 4; j++)
        s += vm[j] * v[j];
    return 0.5 * s;
}

static double flexible_energy(const rk_model *m, const double *q, const double *v)
{
    return kinetic_energy(m, q, v) + potential_energy(m, q);
}

static rk_status flexible_initial_state(const rk_model *m, const double *initial, int *mode, double *q, double *v,
                                        rk_error *err)
{
    double phi_0, phi_dot_0, u_0, u_dot_0, r[2], rd[2];
    rk_param_decl u_range = INITIAL[2];
    if (rk_param_check(&INITIAL[0], initial[0], &phi_0, err) != RK_OK
        || rk_param_check(&INITIAL[1], initial[1], &phi_dot_0, err) != RK_OK
        || rk_param_check(&INITIAL[3], initial[3], &u_dot_0, err) != RK_OK)
        return RK_ERR_VALUE;
    /* tip deflection at most the column height */
    u_range.lo = -H;
    u_range.hi = H;
    u_range.lo_open = 0;
    u_range.hi_open = 0;
    if (rk_param_check(&u_range, initial[2], &u_0, err) != RK_OK)
        return RK_ERR_VALUE;
    *mode = rk_mode_of_initial_state(phi_0, phi_dot_0);
    if (*mode == RK_MODE_FULL) {
        flexible_embed(m, *mode, &u_0, &u_dot_0, q, v);
    } else {
        r[0] = u_0; r[1] = phi_0;
        rd[0] = u_dot_0; rd[1] = phi_dot_0;
        flexible_embed(m, *mode, r, rd, q, v);
    }
    return RK_OK;
}

/* flexible_impact.classical_impact(model, u, u_dot, phi_dot_minus, pivot).v_plus, with its _inputs checks:
 * angular momentum about the impacting corner conserved, u_dot continuous, rocking on about the new corner */
static int flexible_classical_impact_velocity(const rk_model *m, const double *q, const double *v_minus, int mode,
                                              double *v_plus)
{
    double u = q[0], u_dot = v_minus[0], phi_dot_minus = v_minus[3], s_o, s_n, b = B, mt = MT, D = DD, Mt = MTOT;
    double a0, ratio, w_plus;
    if ((int)m->p[P_RULE] == 0)
        return 0;
    /* where the Python's _inputs raise ValueError: -1 and a NaN velocity (a caller that only tests for
     * non-zero then stops on the non-finite state instead of going on with a wrong one) */
    v_plus[0] = v_plus[1] = v_plus[2] = v_plus[3] = NAN;
    if (mode != RK_MODE_LEFT && mode != RK_MODE_RIGHT)
        return -1;          /* check_choice("pivot", ...): a sliding mode is not a pivot */
    if (!isfinite(u) || !isfinite(u_dot) || !isfinite(phi_dot_minus))
        return -1;          /* check_real */
    s_o = (double)rk_pivot_sign(mode);
    s_n = -s_o;
    if (!(s_n * phi_dot_minus < 0.0))
        return -1;          /* phi_dot_minus does not close the gap of the other corner */
    a0 = J0 + mt * u * u;
    ratio = (a0 - Mt * b * b) / (a0 + Mt * b * b - 2.0 * s_n * b * D * u);
    w_plus = ratio * phi_dot_minus;
    v_plus[0] = u_dot;
    v_plus[1] = 0.0;
    v_plus[2] = -s_n * b * w_plus;
    v_plus[3] = w_plus;
    return 1;
}

static void flexible_work_note(const rk_model *m, char *buf, size_t n)
{
    snprintf(buf, n, "column omega = %.6g rad/s", sqrt(KT / MT));
}

const rk_model_ops RK_FLEXIBLE_OSCILLATOR = {
    "flexible", "FlexibleOscillator",
    4, 2, 10,
    3, 1, 2,
    N_PARAMS, PARAMS,
    4, INITIAL,
    11, OUTPUTS,
    3, SHIFTED,
    flexible_init,
    rk_two_corner_mode_of, rk_two_corner_closed_of, rk_two_corner_stick_of,
    flexible_mass_matrix, NULL, flexible_forces, flexible_stiff_jacobians,
    flexible_gaps, flexible_contact_jacobians, flexible_contact_drift, flexible_contact_abscissae,
    flexible_mode_dofs, flexible_embed, flexible_mode_jacobian, flexible_mode_rhs, flexible_mode_monitors,
    flexible_mode_outputs, flexible_contact_forces,
    flexible_rest_position, flexible_energy, flexible_outputs, flexible_initial_state,
    flexible_classical_impact_velocity, flexible_work_note,
    NULL        /* mode_monitor_one: none (locate evaluates all of G) */
};
