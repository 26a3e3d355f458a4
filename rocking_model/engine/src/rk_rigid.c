/* rk_rigid.c -- RK_RIGID_BLOCK, the rigid rocking block (part A): the port of
 * rocking_model/models/rigid_block.py (Giouvanidis & Dimitrakopoulos 2017, Sect. 2; Housner 1963).
 *
 * Block of half-width b [m], half-height h [m], mass m [kg] on a rigid ground moving horizontally with
 * acceleration ag [m/s2]. Full coordinates q = [x, y, phi]: centroid position in the ground frame (y absolute,
 * y = h at rest) and rotation phi, positive counter-clockwise; phi > 0 pivots on the left corner. Corner i sits
 * at body coordinates (s_i b, -h), s = (-1, +1).
 *
 * Every expression keeps the Python's operation order (DESIGN.md section 7): the results agree bit for bit
 * (tests/test_engine_model.py). A square is a product on both sides (``x * x``: Python's ``x ** 2`` calls libm's
 * pow, not always x * x rounded, and compilers turn pow(x, 2.0) into x * x), and math.hypot is rk_py_hypot
 * (CPython's own algorithm). */
#include "rk_model.h"

#include <math.h>
#include <string.h>

/* parameters, declared order (RigidBlock's fields) */
enum { P_B, P_H, P_M, P_G, P_EN, P_LAW, P_MU, N_PARAMS };
/* derived constants in m->d */
enum { D_R, D_ALPHA, D_IC, D_P, D_P2 };

static const char *const IMPACT_LAW_ITEMS[] = {"newton", "energy_consistent"};

static const rk_param_decl PARAMS[N_PARAMS] = {
    {"b", "m", 0.2, 1e-6, 1e3, 0, 0, 0, 0, 0, NULL},
    {"h", "m", 1.0, 1e-6, 1e3, 0, 0, 0, 0, 0, NULL},
    {"m", "kg", 1.0, 1e-9, 1e12, 0, 0, 0, 0, 0, NULL},
    {"g", "m/s2", 9.81, 1e-3, 1e3, 0, 0, 0, 0, 0, NULL},
    {"e_N", "1", 0.0, 0.0, 1.0, 0, 0, 0, 0, 0, NULL},
    {"impact_law", "", 0.0, 0.0, 1.0, 0, 0, 0, 1, 2, IMPACT_LAW_ITEMS},
    {"mu", "1", INFINITY, 1e-3, INFINITY, 0, 0, 1, 0, 0, NULL},
};

static const rk_param_decl INITIAL[2] = {
    {"phi_0", "rad", 0.0, -RK_HALF_PI, RK_HALF_PI, 1, 1, 0, 0, 0, NULL},
    {"phi_dot_0", "rad/s", 0.0, -1e4, 1e4, 0, 0, 0, 0, 0, NULL},
};

static const rk_param_decl OUTPUTS[8] = {
    {"phi", "rad", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},
    {"phi_dot", "rad/s", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},
    {"x", "m", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},
    {"y", "m", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},
    {"x_dot", "m/s", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},
    {"y_dot", "m/s", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},
    {"slip", "m", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},
    {"energy", "J", 0.0, -INFINITY, INFINITY, 1, 1, 0, 0, 0, NULL},
};
enum { O_PHI, O_PHI_DOT, O_X, O_Y, O_X_DOT, O_Y_DOT, O_SLIP, O_ENERGY };
static const int SHIFTED[2] = {O_X, O_SLIP};

#define B (m->p[P_B])
#define H (m->p[P_H])
#define MASS (m->p[P_M])
#define G (m->p[P_G])

/* ------------------------------------------------------------------------------------------ construction */
static rk_status rigid_init(rk_model *m, const double *params, rk_error *err)
{
    int i;
    double R;
    for (i = 0; i < N_PARAMS; i++) {
        if (rk_param_check(&PARAMS[i], params[i], &m->p[i], err) != RK_OK)
            return err == NULL ? RK_ERR_VALUE : err->status;
    }
    R = rk_py_hypot(B, H);
    m->d[D_R] = R;
    m->d[D_ALPHA] = atan2(B, H);
    m->d[D_IC] = MASS * (R * R) / 3.0;
    m->d[D_P] = sqrt(3.0 * G / (4.0 * R));
    m->d[D_P2] = m->d[D_P] * m->d[D_P];    /* self._p * self._p of mode_closures and rocking_acceleration */
    m->e_N = m->p[P_EN];
    m->impact_law = (int)m->p[P_LAW];
    m->e_T = m->impact_law == 1 ? m->e_N : 0.0;
    m->mu = m->p[P_MU];
    m->g = G;
    m->length_scale = R;
    m->time_scale = 1.0 / m->d[D_P];
    m->force_scale = MASS * G;
    m->step_limit = INFINITY;
    m->dof_scales[0] = R;
    m->dof_scales[1] = R;
    m->dof_scales[2] = 1.0;
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ dynamical system */
static void rigid_mass_matrix(const rk_model *m, const double *q, double *M)
{
    (void)q;
    memset(M, 0, 9 * sizeof(double));
    M[0] = MASS;
    M[4] = MASS;
    M[8] = m->d[D_IC];
}

static void rigid_inverse_mass_matrix(const rk_model *m, const double *q, double *Minv)
{
    (void)q;
    memset(Minv, 0, 9 * sizeof(double));
    Minv[0] = 1.0 / MASS;
    Minv[4] = 1.0 / MASS;
    Minv[8] = 1.0 / m->d[D_IC];
}

static void rigid_forces(const rk_model *m, const double *q, const double *v, double ag, double ag_v, double *f)
{
    (void)q; (void)v;
    /* ground frame: inertial force -m ag along x, gravity and the inertial force -m ag_v along -y (the
     * effective gravity g + ag_v; g + 0.0 == g: ag_v = 0 rounds as before) */
    f[0] = -MASS * ag;
    f[1] = -MASS * (G + ag_v);
    f[2] = 0.0;
}

/* ------------------------------------------------------------------------------------------ contact relation */
static void rigid_gaps(const rk_model *m, const double *q, double *g)
{
    double y = q[1], phi = q[2];
    double sp = sin(phi), cp = cos(phi);
    g[0] = y + -1.0 * B * sp - H * cp;
    g[1] = y + 1.0 * B * sp - H * cp;
}

static void rigid_contact_jacobians(const rk_model *m, const double *q, double *W_N, double *W_T)
{
    double phi = q[2];
    double sp = sin(phi), cp = cos(phi);
    double b = B, h = H;
    W_N[0] = 0.0; W_N[1] = 0.0;
    W_N[2] = 1.0; W_N[3] = 1.0;
    W_N[4] = -b * cp + h * sp; W_N[5] = b * cp + h * sp;
    W_T[0] = 1.0; W_T[1] = 1.0;
    W_T[2] = 0.0; W_T[3] = 0.0;
    W_T[4] = b * sp + h * cp; W_T[5] = -b * sp + h * cp;
}

static void rigid_contact_abscissae(const rk_model *m, const double *q, double *x)
{
    double bc = B * cos(q[2]), hs = H * sin(q[2]);
    x[0] = q[0] - bc + hs;
    x[1] = q[0] + bc + hs;
}

static void rigid_contact_drift(const rk_model *m, const double *q, const double *v, double *a_N, double *a_T)
{
    double phi = q[2], w = v[2];
    double sp = sin(phi), cp = cos(phi);
    double b = B, h = H;
    int i;
    for (i = 0; i < 2; i++) {
        double s = i == 0 ? -1.0 : 1.0;
        a_N[i] = (-s * b * sp + h * cp) * w * w;
        a_T[i] = (-s * b * cp - h * sp) * w * w;
    }
}

/* ------------------------------------------------------------------------------------------ sticking modes */
static int rigid_mode_dofs(const rk_model *m, int mode, int *idx)
{
    (void)m;
    if (mode == RK_MODE_FULL)
        return 0;
    if (mode == RK_MODE_FLIGHT) {
        idx[0] = 0; idx[1] = 1; idx[2] = 2;
        return 3;
    }
    idx[0] = 2;
    return 1;
}

static void rigid_embed(const rk_model *m, int mode, const double *r, const double *r_dot, double *q, double *v)
{
    double s, phi, w, sp, cp, b = B, h = H;
    if (mode == RK_MODE_FULL) {
        q[0] = 0.0; q[1] = h; q[2] = 0.0;
        v[0] = 0.0; v[1] = 0.0; v[2] = 0.0;
        return;
    }
    if (mode == RK_MODE_FLIGHT) {
        memcpy(q, r, 3 * sizeof(double));
        memcpy(v, r_dot, 3 * sizeof(double));
        return;
    }
    s = (double)rk_pivot_sign(mode);
    phi = r[0];
    w = r_dot[0];
    sp = sin(phi);
    cp = cos(phi);
    q[0] = s * b * (1.0 - cp) - h * sp;
    q[1] = -s * b * sp + h * cp;
    q[2] = phi;
    v[0] = (s * b * sp - h * cp) * w;
    v[1] = (-s * b * cp - h * sp) * w;
    v[2] = w;
}

static void rigid_mode_jacobian(const rk_model *m, int mode, const double *r, const double *r_dot, double *J,
                                double *jd)
{
    double s, phi, w, sp, cp, b = B, h = H;
    jd[0] = 0.0; jd[1] = 0.0; jd[2] = 0.0;
    if (mode == RK_MODE_FULL)
        return;
    if (mode == RK_MODE_FLIGHT) {
        int i;
        for (i = 0; i < 9; i++)
            J[i] = (i % 4 == 0) ? 1.0 : 0.0;
        return;
    }
    s = (double)rk_pivot_sign(mode);
    phi = r[0];
    w = r_dot[0];
    sp = sin(phi);
    cp = cos(phi);
    J[0] = s * b * sp - h * cp;
    J[1] = -s * b * cp - h * sp;
    J[2] = 1.0;
    jd[0] = (s * b * cp + h * sp) * w * w;
    jd[1] = (s * b * sp - h * cp) * w * w;
    jd[2] = 0.0;
}

/* (g + ag_v) / g [1]: 1.0 exactly when ag_v = 0 (the division skipped there: the same bits) */
static inline double rigid_g_ratio(const rk_model *m, double ag_v)
{
    return ag_v == 0.0 ? 1.0 : (G + ag_v) / G;
}

/* mode_closures' rocking_acceleration on the pivot of sign s [rad/s2]:
 * p^2 (ag / g cos(alpha + s phi) + s (g + ag_v) / g sin(alpha + s phi)) */
static inline double rigid_rocking_acc(const rk_model *m, double s, double phi, double ag, double ag_v)
{
    double x = m->d[D_ALPHA] + s * phi;
    return m->d[D_P2] * (ag / G * cos(x) + s * rigid_g_ratio(m, ag_v) * sin(x));
}

/* mode_closures' rhs */
static void rigid_mode_rhs(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *dy)
{
    if (mode == RK_MODE_FULL)
        return;
    if (mode == RK_MODE_FLIGHT) {
        dy[0] = y[3]; dy[1] = y[4]; dy[2] = y[5];
        dy[3] = -ag; dy[4] = -(G + ag_v); dy[5] = 0.0;
        return;
    }
    {
        dy[0] = y[1];
        dy[1] = rigid_rocking_acc(m, (double)rk_pivot_sign(mode), y[0], ag, ag_v);
    }
}

/* mode_closures' monitors and totals (the rocking branch's totals reuse the monitors' acc, sp, cp, lam) */
static void rigid_mode_monitors(const rk_model *m, int mode, const double *y, double ag, double ag_v,
                                double *g, double *totals)
{
    double b = B, h = H, grav = G, ge = G + ag_v;
    if (mode == RK_MODE_FULL) {
        /* the corner forces over the weight m g (not m (g + ag_v), which may vanish or change sign) */
        double d = 0.5 * ag * h / b / grav, gr = rigid_g_ratio(m, ag_v);
        g[0] = 0.5 * gr + d;
        g[1] = 0.5 * gr - d;
        g[2] = RK_HALF_PI;
        if (totals != NULL) {
            /* vertical and horizontal equilibrium: the effective weight, and the sticking force m ag */
            totals[0] = MASS * ge;
            totals[1] = MASS * ag;
        }
        return;
    }
    if (mode == RK_MODE_FLIGHT) {
        double yc = y[1], phi = y[2];
        double bs = b * sin(phi), hc = h * cos(phi);
        double L = m->d[D_R];
        g[0] = (yc - bs - hc) / L;
        g[1] = (yc + bs - hc) / L;
        g[2] = RK_HALF_PI - fabs(phi);
        return;
    }
    {
        double s = (double)rk_pivot_sign(mode);
        double phi = y[0], w = y[1];
        double gr = rigid_g_ratio(m, ag_v);
        double acc = rigid_rocking_acc(m, s, phi, ag, ag_v);
        double sp = sin(phi), cp = cos(phi);
        /* vertical Newton's law of the centroid, divided by the weight: lambda_N / (m g) = y_dd / g + (g + ag_v) / g */
        double lam = ((-s * b * cp - h * sp) * acc + (s * b * sp - h * cp) * w * w) / grav + gr;
        double margin = RK_HALF_PI - fabs(phi);
        if (s < 0) {
            g[0] = lam; g[1] = -s * phi;
        } else {
            g[0] = -s * phi; g[1] = lam;
        }
        g[2] = margin;
        if (totals != NULL) {
            double x_dd = (s * b * sp - h * cp) * acc + (s * b * cp + h * sp) * w * w;
            totals[0] = MASS * grav * lam;
            totals[1] = MASS * (x_dd + ag);
        }
    }
}

/* rigid_mode_monitors' gap of the open corner (-s phi) and overturning margin of a rocking mode, the same
 * expressions, without the pivot's force (its trigonometry and ag): locate's iterations on an impact read these */
static int rigid_mode_monitor_one(const rk_model *m, int mode, const double *y, int i, double *gi)
{
    double s, phi;
    (void)m;
    if (mode == RK_MODE_FULL || mode == RK_MODE_FLIGHT)
        return 0;
    s = (double)rk_pivot_sign(mode);
    phi = y[0];
    if (i == 2) {
        *gi = RK_HALF_PI - fabs(phi);
        return 1;
    }
    if ((s < 0 && i == 1) || (!(s < 0) && i == 0)) {
        *gi = -s * phi;
        return 1;
    }
    return 0;
}

static void rigid_outputs(const rk_model *m, const double *q, const double *v, double *out);

static void rigid_mode_outputs(const rk_model *m, int mode, const double *y, double *out)
{
    double s, phi, w, sp, cp, yc, xd, yd, kin, b = B, h = H;
    if (mode == RK_MODE_FULL) {
        int i;
        for (i = 0; i < 8; i++)
            out[i] = 0.0;
        return;
    }
    if (mode == RK_MODE_FLIGHT) {
        rigid_outputs(m, y, y + 3, out);
        return;
    }
    s = (double)rk_pivot_sign(mode);
    phi = y[0];
    w = y[1];
    sp = sin(phi);
    cp = cos(phi);
    yc = -s * b * sp + h * cp - h;
    xd = (s * b * sp - h * cp) * w;
    yd = (-s * b * cp - h * sp) * w;
    kin = 0.5 * (MASS * (xd * xd + yd * yd) + m->d[D_IC] * w * w);
    out[O_PHI] = phi;
    out[O_PHI_DOT] = w;
    out[O_X] = s * b * (1.0 - cp) - h * sp;
    out[O_Y] = yc;
    out[O_X_DOT] = xd;
    out[O_Y_DOT] = yd;
    out[O_SLIP] = 0.0;
    out[O_ENERGY] = kin + MASS * G * yc;
}

static void rigid_contact_forces(const rk_model *m, int mode, const double *q, const double *v, double ag, double ag_v,
                                 double *lam)
{
    double mass = MASS, ge = G + ag_v;
    if (mode == RK_MODE_FULL) {
        /* vertical and moment equilibrium with the horizontal sticking force m ag at y = -h */
        double d = 0.5 * mass * ag * H / B;
        lam[0] = 0.5 * mass * ge + d;
        lam[1] = 0.5 * mass * ge - d;
        return;
    }
    lam[0] = 0.0;
    lam[1] = 0.0;
    if (mode == RK_MODE_FLIGHT)
        return;
    {
        /* vertical Newton's law of the centroid: lambda_N = m (y_ddot + g + ag_v) */
        double s = (double)rk_pivot_sign(mode);
        double phi = q[2], w = v[2];
        double acc = rigid_rocking_acc(m, s, phi, ag, ag_v);
        double y_dd = (-s * B * cos(phi) - H * sin(phi)) * acc + (s * B * sin(phi) - H * cos(phi)) * w * w;
        lam[s < 0 ? 0 : 1] = mass * (y_dd + ge);
    }
}

/* ------------------------------------------------------------------------------------------ quantities */
static void rigid_rest_position(const rk_model *m, double *q)
{
    q[0] = 0.0;
    q[1] = H;
    q[2] = 0.0;
}

static double rigid_energy(const rk_model *m, const double *q, const double *v)
{
    double kin = 0.5 * (MASS * (v[0] * v[0] + v[1] * v[1]) + m->d[D_IC] * (v[2] * v[2]));
    return kin + MASS * G * (q[1] - H);
}

static void rigid_outputs(const rk_model *m, const double *q, const double *v, double *out)
{
    out[O_PHI] = q[2];
    out[O_PHI_DOT] = v[2];
    out[O_X] = q[0];
    out[O_Y] = q[1] - H;
    out[O_X_DOT] = v[0];
    out[O_Y_DOT] = v[1];
    /* the lower corner's displacement (the left one, s = -1, for phi > 0), as `slip` */
    out[O_SLIP] = q[0] + (q[2] > 0.0 ? -1.0 : 1.0) * B * (cos(q[2]) - 1.0) + H * sin(q[2]);
    out[O_ENERGY] = rigid_energy(m, q, v);
}

static rk_status rigid_initial_state(const rk_model *m, const double *initial, int *mode, double *q, double *v,
                                     rk_error *err)
{
    double phi_0, phi_dot_0;
    if (rk_param_check(&INITIAL[0], initial[0], &phi_0, err) != RK_OK
        || rk_param_check(&INITIAL[1], initial[1], &phi_dot_0, err) != RK_OK)
        return RK_ERR_VALUE;
    *mode = rk_mode_of_initial_state(phi_0, phi_dot_0);
    rigid_embed(m, *mode, &phi_0, &phi_dot_0, q, v);
    return RK_OK;
}

const rk_model_ops RK_RIGID_BLOCK = {
    "rigid", "RigidBlock",
    3, 2, 10,
    2, 0, 1,
    N_PARAMS, PARAMS,
    2, INITIAL,
    8, OUTPUTS,
    2, SHIFTED,
    rigid_init,
    rk_two_corner_mode_of, rk_two_corner_closed_of, rk_two_corner_stick_of,
    rigid_mass_matrix, rigid_inverse_mass_matrix, rigid_forces, NULL,
    rigid_gaps, rigid_contact_jacobians, rigid_contact_drift, rigid_contact_abscissae,
    rigid_mode_dofs, rigid_embed, rigid_mode_jacobian, rigid_mode_rhs, rigid_mode_monitors,
    rigid_mode_outputs, rigid_contact_forces,
    rigid_rest_position, rigid_energy, rigid_outputs, rigid_initial_state,
    NULL, NULL,
    rigid_mode_monitor_one
};
