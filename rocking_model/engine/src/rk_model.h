/* rk_model.h -- the model kernel interface: what a model provides to the engine.
 *
 * A model kind is one constant rk_model_ops (a struct of function pointers plus its static description),
 * generated at build time from the model's Python declaration (rocking_model/engine/gen_models.py writes
 * rk_models_gen.c); an instance is an rk_model (its parameters and derived constants, plain data, copyable by
 * assignment). Adding a model = declaring it in one Python file; nothing in the engine names a model.
 *
 * rk_model.c holds the generic functions below, rk_sliding.c the sliding modes (any kernel). The generated
 * kernels are checked against the sympy expressions they come from, evaluated in high precision
 * (tests/test_generated_kernels.py).
 *
 * Conventions
 * - q, v: full coordinates in the order of dof_names (rigid: x, y, phi; flexible: u, x, y, phi), SI units.
 * - Matrices are row-major arrays: M[i * n_dof + j]; W_N, W_T have one COLUMN per contact:
 *   W[i * n_contacts + c] (i the coordinate, c the contact), as the Python's (n, n_contacts) arrays;
 *   a mode Jacobian J is n_dof x k: J[i * k + j].
 * - y = [r_0..r_{k-1}, r_dot_0..r_dot_{k-1}] is the reduced state of a mode (k = its number of dofs).
 * - ag [m/s2] is always a VALUE (the caller evaluates the ground motion at t); no callbacks into Python. Every
 *   function taking ag takes the vertical ground acceleration ag_v [m/s2, positive upward] right after it: the
 *   effective gravity g + ag_v on every mass (DESIGN.md section 3a); ag_v = 0 must round as without it.
 * - The kernel functions of the "sticking modes" section are called only with modes m where
 *   stick_of(m) == m; the generic rk_* functions of this header reach every mode (sliding ones through
 *   rk_sliding.c), as RockingModel.dofs_of / embed_any / reduce_any / functions_of do.
 * - Kernel functions never fail on finite input: they return non-finite values where the Python would
 *   (the driver checks). Functions that can fail return rk_status. */
#ifndef RK_MODEL_H
#define RK_MODEL_H

#include "rk_common.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct rk_model rk_model;

/** A declared parameter, initial value or output (rocking_model.params.Param): name, unit, range. */
typedef struct rk_param_decl {
    const char *name;
    const char *unit;           /**< "" for none */
    double default_value;
    double lo, hi;              /**< allowed range (+-INFINITY: unbounded) */
    int lo_open, hi_open;       /**< 1: the bound itself is excluded */
    int inf_ok;                 /**< 1: +inf is allowed (mu) */
    int integer;                /**< 1: an integer choice (impact_law, impact_rule) */
    /* added by part A (at the end, DESIGN.md section 1): the names of an integer choice's items, codes
     * 0 .. n_items-1 (Param.items), for the message of a value that is not a code */
    int n_items;
    const char *const *items;
} rk_param_decl;

/** The kernel of one model kind. All function pointers are required unless marked "optional (NULL: ...)". */
typedef struct rk_model_ops {
    /* ---------------------------------------------------------------- static description */
    const char *kind;                /**< registry name: "rigid", "flexible" (rocking_model.models.MODELS) */
    const char *class_name;          /**< the Python class name: "RigidBlock" (the state header's "model") */
    int n_dof;                       /**< len(dof_names) */
    int n_contacts;                  /**< contacts (columns of W_N, W_T) */
    int n_modes;                     /**< contact modes, codes 0 .. n_modes-1 */
    int phi_index, slide_index, lift_index;   /**< as RockingModel */
    int n_params;                    /**< declared parameters, in constructor order (Model.parameters()) */
    const rk_param_decl *param_decls;
    int n_initial;                   /**< declared initial values (Model.INITIAL) */
    const rk_param_decl *initial_decls;
    int n_outputs;                   /**< declared outputs (Model.OUTPUTS), the order of every output array */
    const rk_param_decl *output_decls;
    int n_shifted;                   /**< SHIFTED_OUTPUTS, as indices into output_decls */
    const int *shifted;

    /* ---------------------------------------------------------------- construction */
    /** Check params[0..n_params-1] (declared order) with the Python's ranges and messages (check_parameters
     *  and __post_init__: e.g. the flexible oscillator's singular mass matrix, OMEGA_MAX), then fill m->p,
     *  m->d (kernel-private derived constants, same formulas and operation order as __post_init__) and the
     *  common fields of rk_model (e_N, e_T, mu, g, impact_law, length_scale, time_scale, force_scale,
     *  step_limit, dof_scales). RK_ERR_VALUE with the Python message on a bad value. */
    rk_status (*init)(rk_model *m, const double *params, rk_error *err);

    /* ---------------------------------------------------------------- modes (sticking and sliding) */
    /** The mode of a closed set, sliding with sigma (+1, -1; 0 stuck): RockingModel.mode_of. */
    int (*mode_of)(const rk_model *m, rk_set closed, int sigma);
    /** The closed contacts of any mode: RockingModel.closed_of. */
    rk_set (*closed_of)(const rk_model *m, int mode);
    /** The stick mode of a sliding mode (the mode itself if not sliding), and its sigma (0 if not sliding):
     *  rocking_model.modes.SLIDING / stick_mode / slide_sign. */
    int (*stick_of)(const rk_model *m, int mode, int *sigma);

    /* ---------------------------------------------------------------- dynamical system */
    void (*mass_matrix)(const rk_model *m, const double *q, double *M);
    /** optional (NULL: the generic inverse of rk_model_inverse_mass) */
    void (*inverse_mass_matrix)(const rk_model *m, const double *q, double *Minv);
    /** f(q, v, ag, ag_v) [N, N m]: non-contact generalized forces (ag_v: gravity g + ag_v). */
    void (*forces)(const rk_model *m, const double *q, const double *v, double ag, double ag_v, double *f);
    /** optional (NULL: no stiff part, returns 0): K = -df/dq, C = -df/dv of the stiff linear part; returns 1
     *  when filled (RockingModel.stiff_jacobians not None). */
    int (*stiff_jacobians)(const rk_model *m, const double *q, const double *v, double *K, double *C);

    /* ---------------------------------------------------------------- contact relation */
    void (*gaps)(const rk_model *m, const double *q, double *g);                          /**< [m] */
    void (*contact_jacobians)(const rk_model *m, const double *q, double *W_N, double *W_T);
    void (*contact_drift)(const rk_model *m, const double *q, const double *v, double *a_N, double *a_T);
    void (*contact_abscissae)(const rk_model *m, const double *q, double *x);            /**< [m] */

    /* ---------------------------------------------------------------- sticking modes */
    /** Indices in q of the reduced coordinates of a sticking mode (idx has room for RK_MAX_DOF); returns k. */
    int (*mode_dofs)(const rk_model *m, int mode, int *idx);
    /** Full (q, v) of the reduced state (r, r_dot) of a sticking mode: RockingModel.embed. */
    void (*embed)(const rk_model *m, int mode, const double *r, const double *r_dot, double *q, double *v);
    /** (J, J_dot r_dot) of a sticking mode: RockingModel.mode_jacobian (J is n_dof x k). */
    void (*mode_jacobian)(const rk_model *m, int mode, const double *r, const double *r_dot, double *J,
                          double *jd);
    /** dy = [r_dot, r_ddot] of a sticking mode at y under (ag, ag_v): the rhs of mode_closures, SAME operation order
     *  as the Python closed form (DESIGN.md "Numerics"). optional (NULL: rk_model_generic_rhs, Lagrange on the
     *  constrained system as RockingModel.reduced_acceleration). */
    void (*mode_rhs)(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *dy);
    /** The event functions of a sticking mode at (y, ag, ag_v), in the order of mode_closures' monitors (one per
     *  contact, then the overturning margin HALF_PI - |phi|): writes n_contacts + 1 values into g; when totals
     *  is not NULL and the mode has closed contacts, also (sum lambda_N, sum lambda_T) [N] into totals[0..1]
     *  computed from the same intermediates (mode_closures' totals). optional (NULL: rk_model_generic_monitors,
     *  RockingModel.mode_functions' generic monitors and sliding.force_totals). */
    void (*mode_monitors)(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *g,
                          double *totals);
    /** Outputs of the reduced state of a sticking mode (mode_outputs, out in the order of outputs).
     *  optional (NULL: outputs(embed(y))). */
    void (*mode_outputs)(const rk_model *m, int mode, const double *y, double *out);
    /** Normal contact forces [N] of the closed contacts of a sticking mode held closed (contact_forces).
     *  optional (NULL: rk_mode_forces of rk_contact.h). */
    void (*contact_forces)(const rk_model *m, int mode, const double *q, const double *v, double ag, double ag_v,
                           double *lam);

    /* ---------------------------------------------------------------- quantities */
    void (*rest_position)(const rk_model *m, double *q);
    double (*energy)(const rk_model *m, const double *q, const double *v);                 /**< [J] */
    /** outputs(q, v), in the order of ops->output_decls. */
    void (*outputs)(const rk_model *m, const double *q, const double *v, double *out);
    /** (mode, q, v) of the initial values initial[0..n_initial-1] (declared order), checked with the Python's
     *  ranges and messages (initial_state). */
    rk_status (*initial_state)(const rk_model *m, const double *initial, int *mode, double *q, double *v,
                               rk_error *err);
    /** optional (NULL: none): the classical impact rule (FlexibleOscillator.classical_impact_velocity with
     *  impact_rule = 1): writes v_plus and returns 1 when the rule replaces the impact LCP at an impact of
     *  the open contact of the rocking ``mode``; returns 0 when the LCP decides. (Part A: returns -1 and NaN
     *  velocities where the Python raises ValueError: ``mode`` not LEFT/RIGHT (e.g. a sliding mode), a
     *  non-finite input, or phi_dot that does not close the other corner's gap.) */
    int (*classical_impact_velocity)(const rk_model *m, const double *q, const double *v_minus, int mode,
                                     double *v_plus);
    /** optional (NULL: ""): RockingModel.work_note, what drives the cost of a step (the flexible column's
     *  omega), written into buf (size n, NUL-terminated) for the work-limit messages. */
    void (*work_note)(const rk_model *m, char *buf, size_t n);
    /** optional (NULL: none): the event function i of a sticking mode alone where it needs neither ag nor the
     *  contact forces (i < n_contacts: a gap; i == n_contacts: the overturning margin), bit for bit the value
     *  mode_monitors writes; returns 1 with *gi set, 0 where only mode_monitors has it. */
    int (*mode_monitor_one)(const rk_model *m, int mode, const double *y, int i, double *gi);
    /* ---------------------------------------------------------------- named derived quantities */
    int n_named;                     /**< the declaration's derived quantities (R, alpha, p, ...) */
    const char *const *named;        /**< their names */
    const int *named_index;          /**< their places in rk_model.d */
    /* ---------------------------------------------------------------- switches of the force laws */
    /** the points where a smooth force law changes (a tendon slackens): n_switches values, each crossing zero
     *  there, over its scale, of the full state (q, v); the event-driven scheme ends its steps at each
     *  crossing. optional (n_switches 0, NULL). */
    int n_switches;
    void (*switches)(const rk_model *m, const double *q, const double *v, double *s);
    /** optional (NULL: none): r_ddot of a sticking mode with one degree of freedom at y = (y0, y1) under (ag, ag_v),
     *  bit for bit the dy[1] of mode_rhs (dy[0] is y1), taken and returned in registers: the Runge-Kutta stages
     *  of such a mode chain through it without a store and a load of the state per stage (rk_step) */
    double (*mode_acc1)(const rk_model *m, int mode, double y0, double y1, double ag, double ag_v);
} rk_model_ops;

/** An instance: the kernel, its parameters and derived constants. Plain data (copy by assignment); the only
 *  pointer is to the constant ops. */
struct rk_model {
    const rk_model_ops *ops;
    double p[RK_MAX_PARAMS];        /**< declared parameters, in declared order */
    double d[RK_MAX_DERIVED];       /**< derived constants, kernel-private layout (e.g. R, alpha, I_c, p) */
    /* common fields, filled by ops->init */
    double e_N;                     /**< [1] */
    double e_T;                     /**< [1] e_N if impact_law == 1 else 0 (RockingModel.e_T) */
    double mu;                      /**< [1] INFINITY: the sticking law */
    double g;                       /**< [m/s2] */
    int impact_law;                 /**< 0 newton, 1 energy_consistent */
    double length_scale;            /**< [m] */
    double time_scale;              /**< [s] */
    double force_scale;             /**< [N] */
    double step_limit;              /**< [s] largest Moreau-Jean step (INFINITY: none) */
    double dof_scales[RK_MAX_DOF];  /**< RockingModel.dof_scales */
    double rest_abscissae[RK_MAX_CONTACTS];   /**< contact_abscissae(rest_position()) (slip) */
    /* closed_of and stick_of, pure functions of the mode, tabulated by rk_model_init: the drivers ask them at
     * every event function, rhs and output row (read through rk_closed_of / rk_stick_of) */
    rk_set mode_closed[RK_MAX_MODES];
    signed char mode_stick[RK_MAX_MODES];
    signed char mode_sigma[RK_MAX_MODES];
    /** [m] the base's horizontal offset from its rest position in the driver's current sticking mode: read by
     *  the mode kernels of a model whose forces depend on where the base stands (a tendon anchored in the
     *  ground); 0 outside a driver. */
    double offset;
    /* rk_sincos's memo: sin and cos of the last two arguments (trig_ok[i] 0: slot i empty, as a zeroed model
     * starts; trig_next: the slot written next). Not part of the model's meaning: a cache, which the const kernels
     * write through it */
    int trig_ok[2], trig_next;
    uint64_t trig_bits[2];
    double trig_s[2], trig_c[2];
};

/** sin(x) and cos(x) for the generated kernels at an argument the memo cannot hold (a Runge-Kutta stage's: a new
 *  point each time), without the lookup of rk_sincos below; the values are kept in the memo for the evaluations at
 *  the same point that follow (the event functions and outputs at the end of a step, whose last stage is there). */
static inline void rk_sincos_fresh(const rk_model *m, double x, double *s, double *c)
{
    rk_model *w = (rk_model *)m;
    int i;
    /* one call for both (GCC merges sin and cos of one argument itself, but not at every inlined copy; clang has
     * no __builtin_sincos and merges the two calls itself) */
#if defined(__GNUC__) && !defined(__clang__) && defined(__GLIBC__)
    __builtin_sincos(x, s, c);
#else
    *s = sin(x);
    *c = cos(x);
#endif
    i = w->trig_next;
    w->trig_next = 1 - i;
    memcpy(&w->trig_bits[i], &x, sizeof x);
    w->trig_s[i] = *s;
    w->trig_c[i] = *c;
    w->trig_ok[i] = 1;
}

/** sin(x) and cos(x) for the generated kernels, memoised for the last two arguments (compared bit for bit: the
 *  same values as computing them again). One step's end asks them repeatedly for the same coordinate: the rhs's
 *  last stage, the event functions there, the outputs of a sample, and at the next communication step the settle
 *  and the restart under the new input; the second slot keeps the step's end while the dip search looks at its
 *  middle. */
static inline void rk_sincos(const rk_model *m, double x, double *s, double *c)
{
    rk_model *w = (rk_model *)m;
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    if (w->trig_ok[0] && bits == w->trig_bits[0]) {
        *s = w->trig_s[0];
        *c = w->trig_c[0];
        return;
    }
    if (w->trig_ok[1] && bits == w->trig_bits[1]) {
        *s = w->trig_s[1];
        *c = w->trig_c[1];
        return;
    }
    rk_sincos_fresh(m, x, s, c);
}

/** ops->closed_of(m, mode) from the table (an indirect call for a mode beyond it). */
static inline rk_set rk_closed_of(const rk_model *m, int mode)
{
    return (mode >= 0 && mode < RK_MAX_MODES) ? m->mode_closed[mode] : m->ops->closed_of(m, mode);
}

/** ops->stick_of(m, mode, sigma) from the table (sigma may be NULL). */
static inline int rk_stick_of(const rk_model *m, int mode, int *sigma)
{
    if (mode >= 0 && mode < RK_MAX_MODES) {
        if (sigma != NULL)
            *sigma = m->mode_sigma[mode];
        return m->mode_stick[mode];
    }
    return m->ops->stick_of(m, mode, sigma);
}

/** Whether mode is a sliding mode (stick_of's sigma != 0). */
static inline int rk_mode_sliding(const rk_model *m, int mode)
{
    int sigma = 0;
    rk_stick_of(m, mode, &sigma);
    return sigma != 0;
}

/* ------------------------------------------------------------------------------------------ registry */
/** The kernels, NULL-terminated (rk_model.c). */
const rk_model_ops *const *rk_model_kinds(void);
/** The kernel of a kind name ("rigid", "flexible") or Python class name, built in or added; NULL if none. */
const rk_model_ops *rk_model_find(const char *kind);
/** Add the kernel of a model declared after the build (generated and compiled into a library of its own). Not
 *  thread-safe: call it before any engine of that kind exists, from one thread (the binding holds the GIL).
 *  A kind built into the engine cannot be replaced; adding a kind again makes the new kernel the one found. */
rk_status rk_model_add(const rk_model_ops *ops, rk_error *err);
/** The known kinds as "'rigid', 'flexible', ..." (for messages). */
void rk_model_kind_names(char *buf, size_t n);
/** Build an instance: ops->init plus rest_abscissae and the mode tables. */
rk_status rk_model_init(rk_model *m, const rk_model_ops *ops, const double *params, int n_params,
                        rk_error *err);
/** Fill the tables of rk_closed_of / rk_stick_of from m->ops (rk_model_init does; a model assembled by hand, as
 *  the contact tests' ContactTestModel, calls it once its ops are set; a missing stick_of: every mode sticks). */
void rk_model_tabulate_modes(rk_model *m);
/** ContactTolerances.for_model. */
void rk_model_scale_tolerances(const rk_model *m, const rk_tolerances *tol, rk_model_tolerances *out);

/* ------------------------------------------------------------------------------------------ any mode
 * (rk_model.c, dispatching to the kernel for sticking modes and to rk_sliding.c for sliding ones:
 *  RockingModel.dofs_of, embed_any, reduce_any, functions_of, outputs_of, force_totals_of). */

/** M^-1(q): the kernel's closed form, else a generic Gauss-Jordan inverse with partial pivoting. */
void rk_model_inverse_mass(const rk_model *m, const double *q, double *Minv);
/** dofs_of: writes the indices, returns k. */
int rk_dofs_of(const rk_model *m, int mode, int *idx);
/** embed_any (without the shift of a sticking mode: the driver adds it at slide_index). */
void rk_embed_any(const rk_model *m, int mode, const double *y, double *q, double *v);
/** reduce_any: y = [r, r_dot] of a full state that satisfies the mode's constraints; returns k. */
int rk_reduce_any(const rk_model *m, int mode, const double *q, const double *v, double *y);
/** The rhs of any mode (functions_of()[0]). Returns RK_OK (a sliding mode's solve may fail: RK_ERR_SOLVER). */
rk_status rk_mode_rhs(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *dy);
/** The event functions of any mode (functions_of()[1]: with a finite mu a closed sticking mode gets the cone
 *  event (mu lam_N - |lam_T|) / force_scale before the overturning margin; a sliding mode's are
 *  sliding.slide_functions' monitors). Writes them into g and returns their number (n_contacts + 1, or + 2 with
 *  the friction event); totals (may be NULL) receives (sum lambda_N, sum lambda_T) [N] when the mode has
 *  closed contacts (functions_of()[2]) and *has_totals is set to 1 (0 in flight). */
int rk_mode_monitors(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *g, double *totals,
                     int *has_totals);
/** rk_mode_monitors' g[i] alone where the model has it without ag and the contact forces (mode_monitor_one):
 *  returns 1 with *gi set (the same value bit for bit), 0 otherwise (sliding modes, the friction event, the
 *  contact force monitors). */
int rk_mode_monitor_one(const rk_model *m, int mode, const double *y, int i, double *gi);
/** outputs_of(mode, y, shift): out in the order of ops->output_decls; shift [m] added to the SHIFTED outputs.
 *  (rk_outputs_of: the common case, a mode's own kernel without offset, inline, as every output row of a sampled
 *  run asks it; rk_outputs_of_general: all cases.) */
void rk_outputs_of_general(const rk_model *m, int mode, const double *y, double shift, double *out);
static inline void rk_outputs_of(const rk_model *m, int mode, const double *y, double shift, double *out)
{
    if (shift == 0.0 && m->ops->mode_outputs != NULL && !rk_mode_sliding(m, mode))
        m->ops->mode_outputs(m, mode, y, out);
    else
        rk_outputs_of_general(m, mode, y, shift, out);
}
/** RockingModel.slip(q) [m]. */
double rk_model_slip(const rk_model *m, const double *q);
/** sliding.shift_of: horizontal offset of a full state on the closed contacts of a sticking mode [m]. */
double rk_shift_of(const rk_model *m, int mode, const double *q);
/** sliding.force_totals at a full state (sum lambda_N, sum lambda_T) [N] of a sticking mode. */
void rk_force_totals(const rk_model *m, int mode, const double *q, const double *v, double ag, double ag_v,
                     double *totals);

/** Generic fallbacks (used when the kernel leaves the optional pointer NULL; pinned on both models by
 *  comparing with the Python generic code of RockingModel). */
void rk_model_generic_rhs(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *dy);
void rk_model_generic_monitors(const rk_model *m, int mode, const double *y, double ag, double ag_v, double *g,
                               double *totals);

/* ------------------------------------------------------------------------------------------ sliding modes
 * rk_sliding.c, the port of rocking_model/models/sliding.py (generic: any kernel). */
int rk_slide_dofs(const rk_model *m, int mode, int *idx);
void rk_slide_embed(const rk_model *m, int mode, const double *r, const double *r_dot, double *q, double *v);
int rk_slide_reduce(const rk_model *m, int mode, const double *q, const double *v, double *y);
/** slide_motion: the full acceleration a and tau = mu lambda_N of each closed contact (in increasing contact
 *  order). RK_ERR_SOLVER only where numpy's lstsq fallback would also fail. */
rk_status rk_slide_motion(const rk_model *m, int mode, const double *q, const double *v, double ag,
                          double ag_v, double *a, double *tau);
rk_status rk_slide_acceleration(const rk_model *m, int mode, const double *r, const double *r_dot, double ag,
                                double ag_v, double *r_ddot);
void rk_slide_jacobian(const rk_model *m, int mode, const double *r, const double *r_dot, double *J, double *jd);

/* ------------------------------------------------------------------------------------------ helpers
 * (added by part A: shared by the kernels, rk_model.c) */
/** Param.check of one value: RK_OK and the checked value in *out (a choice as its code), or RK_ERR_VALUE with
 *  the Python message ("b = 0 is out of range; allowed range [1e-06, 1000]", "... is not finite ...",
 *  "impact_law = 2.0 is not supported; allowed values: 0, 1, 'newton', 'energy_consistent'"). */
rk_status rk_param_check(const rk_param_decl *decl, double value, double *out, rk_error *err);
/** Python's repr() of a float ("0.1", "1e-06", "2.0", "inf", "nan") into buf (at least 32 bytes). */
void rk_float_repr(double x, char *buf, size_t n);
/** Python's math.hypot(a, b) (CPython's vector_norm, which is not libm's hypot: they differ in the last bit
 *  on about 1 in 700 arguments). */
double rk_py_hypot(double a, double b);
/** The four sticking and six sliding modes of the two-corner models (rocking_model.modes): mode_from_closed,
 *  CLOSED, SLIDING/stick_mode/slide_sign, pivot_sign (-1 left, +1 right). */
int rk_two_corner_mode_of(const rk_model *m, rk_set closed, int sigma);
rk_set rk_two_corner_closed_of(const rk_model *m, int mode);
int rk_two_corner_stick_of(const rk_model *m, int mode, int *sigma);
/* inline: the kernels call it in every rhs, monitor and output row */
static inline int rk_pivot_sign(int mode)
{
    return (mode == RK_MODE_LEFT || mode == RK_MODE_LEFT_SLIDE_POS || mode == RK_MODE_LEFT_SLIDE_NEG) ? -1 : 1;
}
/** RockingModel.mode_of_initial_state. */
int rk_mode_of_initial_state(double phi_0, double phi_dot_0);
/** Small dense solves (n <= RK_MAX_Y; the kernels' and the contact problems'): Gaussian elimination with partial pivoting (np.linalg.solve;
 *  RK_ERR_SOLVER on an exactly zero pivot, where LAPACK reports a singular matrix), and minimum-norm least
 *  squares through an SVD (np.linalg.lstsq; rcond < 0: numpy's default eps * max(rows, cols)). Row-major. */
rk_status rk_la_solve(int n, const double *A, const double *b, double *x);
rk_status rk_la_lstsq(int rows, int cols, const double *A, const double *b, double rcond, double *x);
/** the overturning angle HALF_PI = 0.5 * math.pi [rad] */
#define RK_HALF_PI (0.5 * 3.141592653589793)

/* ------------------------------------------------------------------------------------------ kernels */
/** The kernels of the declared models, NULL-terminated: generated at build time into rk_models_gen.c by
 *  rocking_model/engine/gen_models.py from each model's declaration. */
extern const rk_model_ops *const rk_generated_models[];

#ifdef __cplusplus
}
#endif
#endif /* RK_MODEL_H */
