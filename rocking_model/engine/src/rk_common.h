/* rk_common.h -- what every part of the C engine shares: limits, status codes, the error buffer, mode and
 * contact-state codes, the contact tolerances and the solver options.
 *
 * Owner: the architect (changes by agreement only; every part includes it).
 * Rules (DESIGN.md, "Rules"): C99 + libm only; no mutable globals; no malloc outside rk_engine_create /
 * rk_engine_free (and the unbounded impact log); never abort() or exit(); every function that can fail
 * returns an rk_status and writes a message into an rk_error.
 * Units: SI throughout (m, s, kg, N, rad); "[1]" is a pure number. */
#ifndef RK_COMMON_H
#define RK_COMMON_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ limits */
/** largest number of full generalized coordinates q of a model (rigid block 3, flexible oscillator 4) */
#define RK_MAX_DOF 8
/** largest number of contacts of a model (both rocking models: 2, the base corners, 0 = left, 1 = right) */
#define RK_MAX_CONTACTS 4
/** largest reduced state y = [r, r_dot] of a mode (a sliding mode adds the base offset to r) */
#define RK_MAX_Y (2 * RK_MAX_DOF)
/** largest number of switches of a model's force laws (Mechanics.switches: a tendon that slackens) */
#define RK_MAX_SWITCHES 2
/** largest number of event functions of a mode: one per contact, the friction event (slip stop or cone),
 *  the switches, the overturning margin */
#define RK_MAX_EVENTS (RK_MAX_CONTACTS + 2 + RK_MAX_SWITCHES)
/** largest number of contact modes (codes 0 .. n_modes-1) */
#define RK_MAX_MODES 32
/** largest number of declared parameters / initial values / outputs of a model */
#define RK_MAX_PARAMS 24
#define RK_MAX_INITIAL 8
#define RK_MAX_OUTPUTS 16
/** largest number of derived parameters a kernel may keep in rk_model.d */
#define RK_MAX_DERIVED 256
/** models added at run time (rk_model_add) */
#define RK_MAX_ADDED_KINDS 64
/** reports kept per advance (more are counted in rk_engine_report_count but their text is dropped) */
#define RK_MAX_REPORTS 16
/** length of every message buffer (error and report texts), NUL included */
#define RK_MSG_LEN 512

/* ------------------------------------------------------------------------------------------ status */
/** Status of every fallible function. The values map one to one onto the Python exceptions the extension
 *  module raises (DESIGN.md, "Error handling"). */
typedef enum rk_status {
    RK_OK = 0,
    RK_ERR_VALUE = 1,           /**< bad input (ValueError): the message names the variable and its range */
    RK_ERR_WORK_LIMIT = 2,      /**< more than max_steps of work in one advance (WorkLimitError) */
    RK_ERR_NONFINITE = 3,       /**< the motion overflowed: non-finite state or outputs (ValueError, "the motion
                                     is not finite ..." in the Python wording) */
    RK_ERR_SOLVER = 4,          /**< a failed numerical solve that the Python raises (np.linalg.LinAlgError) */
    RK_ERR_NOT_IMPLEMENTED = 5, /**< a part of the engine that is not written yet (never reached by default) */
    RK_ERR_MEMORY = 6,          /**< allocation failed (create, or growing an unbounded impact log) */
    RK_ERR_INTERNAL = 7         /**< a broken invariant of the engine itself: a bug, report it */
} rk_status;

/** An error: its status and a message that says what, where and how to get through (the Python wording). */
typedef struct rk_error {
    rk_status status;
    char message[RK_MSG_LEN];
} rk_error;

/** Set err (may be NULL) to status and a printf-formatted message (truncated to RK_MSG_LEN); returns status.
 *  Implemented in rk_common.c. */
rk_status rk_fail(rk_error *err, rk_status status, const char *fmt, ...);
/** Clear err (status RK_OK, empty message). Inline: every kernel entry point clears its error first. */
static inline void rk_error_clear(rk_error *err)
{
    if (err != NULL) {
        err->status = RK_OK;
        err->message[0] = '\0';
    }
}

/** dst[0..n) = src[0..n) (the same array allowed), and whether a[0..n) and b[0..n) hold the same bits: the few
 *  values of a state, event functions or outputs, without a call into the C library per copy or comparison */
static inline void rk_copy(double *dst, const double *src, int n)
{
    int i;
    for (i = 0; i < n; i++)
        dst[i] = src[i];
}

static inline int rk_same_bits(const double *a, const double *b, int n)
{
    int i;
    for (i = 0; i < n; i++) {
        union { double d; unsigned long long u; } x, y;
        x.d = a[i];
        y.d = b[i];
        if (x.u != y.u)
            return 0;
    }
    return 1;
}

/** nextafter(x, INFINITY) - x, the gap above x (the time resolution at t = x), without libm's call: the next
 *  representable double by its bits (finite x; x = 0: the smallest subnormal, as nextafter gives) */
static inline double rk_gap_above(double x)
{
    union { double d; unsigned long long u; } b;
    if (x == 0.0)
        return 4.9406564584124654e-324;
    b.d = x;
    if (x > 0.0)
        b.u++;
    else
        b.u--;
    return b.d - x;
}

/** A function the compiler must not inline into its caller: a rarely taken branch of a hot function (whose
 *  registers it would otherwise make every call save). GCC and Clang only; elsewhere a hint is not needed. */
#if defined(__GNUC__)
#define RK_NOINLINE __attribute__((noinline))
#else
#define RK_NOINLINE
#endif
/** A short name of a status ("ok", "value", "work_limit", ...). */
const char *rk_status_name(rk_status status);

/* ------------------------------------------------------------------------------------------ modes */
/** The contact modes of the two-corner rocking models, the codes of rocking_model.modes.Mode (the FMU output
 *  ``contact``). A model with other contacts defines its own codes through rk_model_ops.mode_of/closed_of;
 *  the engine never assumes these names, only the kernel interface. */
typedef enum rk_mode {
    RK_MODE_FULL = 0,            /**< both corners closed, stuck */
    RK_MODE_LEFT = 1,            /**< rocking on the left corner (phi > 0) */
    RK_MODE_RIGHT = 2,           /**< rocking on the right corner (phi < 0) */
    RK_MODE_FLIGHT = 3,          /**< both corners open */
    RK_MODE_FULL_SLIDE_POS = 4,  /**< full contact sliding towards +x */
    RK_MODE_FULL_SLIDE_NEG = 5,
    RK_MODE_LEFT_SLIDE_POS = 6,
    RK_MODE_LEFT_SLIDE_NEG = 7,
    RK_MODE_RIGHT_SLIDE_POS = 8,
    RK_MODE_RIGHT_SLIDE_NEG = 9
} rk_mode;

/** Per-contact states of the frictional problem, the codes of rocking_model.lcp (OPEN, STICK, SLIDE_POS,
 *  SLIDE_NEG), which equal rocking_model.modes.ContactState (OPEN, CLOSED, SLIDE_POS, SLIDE_NEG). */
typedef enum rk_contact_state {
    RK_OPEN = 0,
    RK_STICK = 1,
    RK_SLIDE_POS = 2,
    RK_SLIDE_NEG = 3
} rk_contact_state;

/** A set of contacts as a bit mask: bit i set <=> contact i in the set (the Python's sorted tuples). */
typedef unsigned int rk_set;
#define RK_IN(set, i) ((((set) >> (i)) & 1u) != 0u)

/* ------------------------------------------------------------------------------------------ tolerances */
/** rocking_model.tolerances.ContactTolerances, field by field, same names, same units, same defaults
 *  (relative values: [L] length scale, [sqrt(gL)] velocity scale, [1/p] time scale). Each in (0, 1), except
 *  sub_samples, an integer in [2, 1024] (rk_tolerances_check). */
typedef struct rk_tolerances {
    double gap;                 /**< [L]  1e-9  */
    double step_gap;            /**< [L]  1e-12 */
    double grazing;             /**< [gap] 1e-3 */
    double rest_velocity;       /**< [sqrt(gL)] 1e-10 */
    double step_rest_velocity;  /**< [sqrt(gL)] 1e-9 */
    double event;               /**< [1] 1e-10 */
    double rise;                /**< [event] 1e-3 */
    double clearly_open;        /**< [1] 1e-9 */
    double stateless_step;      /**< [1/p] 0.1 */
    int sub_samples;            /**< [1] 16 */
    double lcp_exact;           /**< [1] 1e-9 */
    double lcp_hint;            /**< [1] 1e-12 */
    double demand_floor;        /**< [weight] 1e-6 */
} rk_tolerances;

/** The defaults (DEFAULT_TOLERANCES). A constant object: reading it is thread safe. */
extern const rk_tolerances RK_DEFAULT_TOLERANCES;
/** RK_ERR_VALUE naming the field ("tolerances.gap = ... is out of range; allowed range (0, 1)") if any
 *  field is out of its range. */
rk_status rk_tolerances_check(const rk_tolerances *tol, rk_error *err);

/** rocking_model.tolerances.ModelTolerances: the tolerances scaled to one model (rk_model_scale_tolerances). */
typedef struct rk_model_tolerances {
    double gap;                 /**< [m] */
    double step_gap;            /**< [m] */
    double rest_velocity;       /**< [m/s] */
    double step_rest_velocity;  /**< [m/s] */
    double stateless_step;      /**< [s] */
    double velocity_scale;      /**< [m/s] sqrt(g L) */
    double force_floor;         /**< [N] demand_floor * force_scale */
} rk_model_tolerances;

/* ------------------------------------------------------------------------------------------ options */
/** Scheme codes: the Python Integrator.code (the FMU parameter ``scheme``). */
typedef enum rk_scheme {
    RK_SCHEME_MOREAU_JEAN = 0,
    RK_SCHEME_EVENT_DRIVEN = 1
} rk_scheme;

/** Runge-Kutta pair codes (event_driven.METHOD_CHOICES: 0 "DOP853", 1 "DOPRI5"). */
typedef enum rk_method {
    RK_METHOD_DOP853 = 0,
    RK_METHOD_DOPRI5 = 1
} rk_method;

/** The solver options: rocking_model.integrators.base.SolverOptions plus what the Simulator adds.
 *  Checked by rk_engine_create with the Python ranges and messages (each scheme checks those it uses, as
 *  Integrator.from_options does). */
typedef struct rk_options {
    rk_scheme scheme;           /**< scheme */
    double t0;                  /**< [s] initial time */
    double dt_max;              /**< [s] 0: the scheme's default (Moreau-Jean 1e-3, event-driven inf) */
    double tolerance;           /**< [1] event-driven rtol, in [1e-14, 1e-2] (default 1e-8) */
    double theta;               /**< [1] Moreau-Jean theta, in [0.5, 1] (default 0.5) */
    double zeno_tol;            /**< [1] event-driven Zeno threshold, in (0, 1e-2] (default 1e-6) */
    rk_method method;           /**< event-driven Runge-Kutta pair */
    long long impact_log_size;  /**< impacts kept in impact_times (and min(1000, it) in impact_log); -1: all
                                     (Python None; the log then grows on impacts, DESIGN.md "Memory") */
    int max_events;             /**< event-driven: most events in one advance (EventDriven.max_events, 100000) */
    rk_tolerances tolerances;   /**< contact tolerances */
} rk_options;

/** The defaults of Simulator: event_driven, t0 0, dt_max 0, tolerance 1e-8, theta 0.5, zeno_tol 1e-6,
 *  DOP853, impact_log_size 10000, max_events 100000, RK_DEFAULT_TOLERANCES. */
void rk_options_default(rk_options *opt);

/* ------------------------------------------------------------------------------------------ reports */
/** Report kinds (rocking_model.integrators.base.Report.kind). */
typedef enum rk_report_kind {
    RK_REPORT_INEXACT_CONTACT = 0,  /**< "inexact_contact": an LCP without exact solution */
    RK_REPORT_FAILED_STEP = 1       /**< "failed_step": a step accepted at the smallest size (a FAILURE) */
} rk_report_kind;

/** One report of an advance: kind, time [s], message (the Python text). */
typedef struct rk_report {
    rk_report_kind kind;
    double t;
    char message[RK_MSG_LEN];
} rk_report;

/** The reports of the current advance: the first RK_MAX_REPORTS kept, all counted. Cleared by every
 *  rk_engine_advance / rk_engine_sample. */
typedef struct rk_reports {
    int count;                      /**< reports made (may exceed RK_MAX_REPORTS) */
    rk_report items[RK_MAX_REPORTS];
} rk_reports;

/** Append a report (printf-formatted message); never fails. */
void rk_report_add(rk_reports *reports, rk_report_kind kind, double t, const char *fmt, ...);

#ifdef __cplusplus
}
#endif
#endif /* RK_COMMON_H */
