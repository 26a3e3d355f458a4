/* rk_internal.h -- the engine struct and the scheme interfaces (parts D and E; not public).
 *
 * The engine is one struct of plain data: the model instance, the options, the scheme's state (a union of
 * the event-driven and Moreau-Jean states), the checkpoint slot, the reports and the message buffer. The
 * only pointers: the constant model ops and tableaux, the impact-log storage (one block allocated at create),
 * and during a call the borrowed ground motion. No pointer points into the struct itself, so a checkpoint is
 * a struct copy of ``core`` (DESIGN.md "Memory"). */
#ifndef RK_INTERNAL_H
#define RK_INTERNAL_H

#include "rk_common.h"
#include "rk_model.h"
#include "rk_contact.h"
#include "rk_rk.h"
#include "rk_motion.h"
#include "rk_engine.h"

#ifdef __cplusplus
extern "C" {
#endif

/** An append-only log of fixed-size rows (impact_times: 1 double; impact_log: 1 + 2 n_dof), BoundedLog with
 *  maxlen: kept in a ring of capacity 2 maxlen rows (the Python trims to maxlen when it exceeds 2 maxlen and
 *  returns the last maxlen in tail()); maxlen < 0: unbounded, the storage doubles on an append that needs it
 *  (impacts only, never per step). Rows are addressed by absolute index: rows [first, end) are present. */
typedef struct rk_log {
    double *data;               /**< heap storage, cap * row_len doubles (owned by the engine) */
    int row_len;
    long long cap;              /**< rows of storage */
    long long maxlen;           /**< -1: unbounded */
    long long first, end;       /**< absolute indices of the present rows */
} rk_log;

/** Append a row (no allocation when bounded); RK_ERR_MEMORY if an unbounded log cannot grow. */
rk_status rk_log_append(rk_log *log, const double *row);
/** Rows of tail() (the last maxlen, all if unbounded). */
long long rk_log_tail_count(const rk_log *log);
/** Copy tail() rows out (up to cap_rows); returns the count copied. */
long long rk_log_tail(const rk_log *log, double *buf, long long cap_rows);

/** The event-driven scheme's state (EventDriven's attributes). */
typedef struct rk_ed_state {
    /* what get_state returns */
    double t;
    int mode;
    int k;                              /**< reduced dofs of mode; y has 2k entries */
    double y[RK_MAX_Y];
    double shift;                       /**< [m] base offset of a sticking mode on the ground (e->model.offset) */
    long long impacts;
    int overturned;
    long long n_steps;
    double h;                           /**< [s] last step size (NAN: None) */
    double friction_demand;
    long long painleve;
    /* the live stepper (EventDriven._live): carried between advances, bit-identical restart otherwise */
    int live;                           /**< 1: ``stepper`` may go on (the Python's ``_live`` is not None and
                                             ``st.y is self.y``: the last segment ended without an event at
                                             the current state; cleared by every other state change) */
    rk_stepper stepper;
    /* identity of the stepper's right-hand side (the Python's ``st.fun is rhs``: `_functions` caches the
     * closures by (mode, ag.value) for a constant input and by (mode, id(ag)) otherwise, so a new constant
     * input of the same value keeps the FSAL derivative, and any new non-constant motion restarts) */
    int rhs_mode;
    int rhs_constant;                   /**< 1: built for a constant input of value rhs_value */
    double rhs_value;
    double rhs_value_v;                 /**< the vertical component's value of that constant input (0: none) */
    unsigned long long rhs_motion;      /**< non-constant: the serial of the motion (motion_serial at its call) */
    unsigned long long motion_serial;   /**< incremented by every advance / sample call with a non-constant
                                             motion (a new GroundMotion object in the Python) */
    unsigned long long motion_key;      /**< (part D) the key of the current call's non-constant motion: its
                                             rk_motion.identity (the same GroundMotion object: the Python's
                                             id(ag)) with the top bit set, or a new motion_serial when 0 */
    /* the side of each switch of the model's force laws (+1: its value positive), so that its event
     * function (the value times the side) falls through zero at the next crossing either way; set from the
     * value at each segment's start where clearly away from zero, flipped by each switch event */
    double switch_side[RK_MAX_SWITCHES];
    /* the kinds of the event functions of mode kinds_mode (-1: none yet): ed_kinds' last answer */
    int kinds_mode, kinds_n;
    int kinds[RK_MAX_EVENTS];
    /* settings (from the options and the model; constant after create) */
    double tolerance, dt_max;
    const rk_tableau *tab;
    double gap_tol, v_tol, v_zeno, event_tol, stateless_step, force_floor;
    int max_events;
    /* per-advance work budget (_max_work, _work_end, _span, _impacts0) */
    long long max_work;                 /**< -1: none */
    double work_end;
    double span0, span1;
    long long impacts0;
} rk_ed_state;

/** The Moreau-Jean scheme's state (MoreauJean's attributes). */
typedef struct rk_mj_state {
    double t;
    double q[RK_MAX_DOF], v[RK_MAX_DOF];
    int mode;
    rk_set closed;                      /**< contacts that carried impulse in the last step */
    long long impacts;
    int overturned;
    long long n_steps;
    double friction_demand;
    long long painleve;
    double dt_max, theta;
    double gap_margin, v_rest, force_floor;
} rk_mj_state;

/** What a checkpoint copies. */
typedef struct rk_core {
    union {
        rk_ed_state ed;
        rk_mj_state mj;
    } s;
    long long times_first, times_end;   /**< log cursors */
    long long log_first, log_end;
    unsigned long long token;           /**< changes whenever the state changes (output cache key) */
} rk_core;

struct rk_engine {
    rk_model model;
    rk_options options;
    rk_model_tolerances scaled;         /**< options.tolerances for this model */
    rk_core core;
    rk_core saved;                      /**< the checkpoint slot of rk_engine_checkpoint */
    long long sample_cs;                /**< during rk_engine_sample_columns: the distance between the values of
                                         *   one row (the rows count); 0 otherwise (rows contiguous) */
    int has_saved;
    rk_log impact_times;
    rk_log impact_log;                  /**< event-driven only (maxlen min(1000, impact_log_size)) */
    rk_reports reports;
    unsigned long long out_token;       /**< token of the cached outputs */
    double out_cache[RK_MAX_OUTPUTS];
    rk_error error;                     /**< status and message of the last failed call */
    /* (part E, added) */
    unsigned long long token_serial;    /**< source of core.token values: never rolled back, so that a token
                                             is never reused for another state (the output cache key) */
    double fail_t;                      /**< [s] the time the scheme had reached when the last call failed
                                             (Simulator._diverged's "at t = ..."), before the restore */
    unsigned long long motion_calls;    /**< advance / sample calls with a non-constant motion so far */
    /** (event-driven) the last step end's event functions and force totals: rk_mode_monitors is a pure
     *  function of (mode, y, ag, ag_v) for the model, which never changes, so the next segment, which starts
     *  there, reads them back (outside the checkpointed core: a value for the same inputs is right after any
     *  restore) */
    struct {
        int valid, mode, n_y, has_lam;
        double a, av, y[RK_MAX_Y], g[RK_MAX_EVENTS], lam[2];
    } g_memo;
};

/* ------------------------------------------------------------------------------------------ shared helpers (E)
 * rk_engine.c: the checks of a loaded state (integrators/state.py) and note_demand, used
 * by both schemes' set_state / reports. */
/** state.check_times: times[0..n-1] at most ``impacts`` of them, non-decreasing, not after t (up to
 *  round-off); RK_ERR_VALUE naming field ``key`` otherwise. */
rk_status rk_check_times(const char *key, const double *times, long long n, double t, long long impacts,
                         rk_error *err);
/** The pose of a state: |phi| < pi/2 unless overturned, at rest if overturned, corners not below the ground by
 *  more than gap_tol [m]; RK_ERR_VALUE naming field ``key`` otherwise. */
rk_status rk_check_pose(const rk_model *m, const char *key, const double *q, const double *v, int overturned,
                        double gap_tol, rk_error *err);
/** state.check_configuration: rk_check_pose, and the outputs finite; RK_ERR_VALUE naming field ``key``
 *  otherwise. */
rk_status rk_check_configuration(const rk_model *m, const char *key, const double *q, const double *v,
                                 int overturned, double gap_tol, rk_error *err);
/** Save / load the state (rk_core and the log cursors) to / from a caller's slot (the extension's guard
 *  around a call with a Python callback motion). */
void rk_engine_save(rk_engine *e, rk_core *slot);
void rk_engine_load(rk_engine *e, const rk_core *slot);
/** Integrator.note_demand on a friction_demand field: raise *demand to |lam_T| / lam_N (at most mu) when
 *  lam_N > floor [N]. */
void rk_note_demand(double *demand, double mu, double lam_N, double lam_T, double floor);

/* ------------------------------------------------------------------------------------------ event-driven (D) */
/** EventDriven.from_options + __init__ (options checked with the Python messages). */
rk_status rk_ed_init(rk_engine *e, int mode, const double *q, const double *v, rk_error *err);
/** EventDriven._run: advance (samples NULL) or sample, under the pair (ag, ag_v) (ag_v NULL: no vertical motion,
 *  GroundMotion.vertical is None). Errors leave the state partly advanced: the caller
 *  (rk_engine.c) restores its checkpoint. */
rk_status rk_ed_run(rk_engine *e, double t_end, rk_motion *ag, rk_motion *ag_v, const double *samples,
                    long long n_samples,
                    long long max_steps, int *modes, double *values, long long *impacts, int *overturned,
                    unsigned flags, rk_error *err);
/* (part D) rk_ed_run with samples writes the rows of the samples only, n_samples rows (the Python's ``_run``);
 * the row of the current state that Integrator.sample puts first is rk_ed_row(e, e->core.s.ed.mode,
 * e->core.s.ed.y, e->core.s.ed.overturned, ...), written by the caller before the call. flags:
 * RK_ADVANCE_CONTINUOUS skips the settle at the start (the Python's ``kink``). */
/** One row of Integrator.sample for the reduced state y of mode (shift, friction_demand, painleve, impacts:
 *  the current ones): modes[0] (modes.OVERTURNED = 10 when overturned), values[0 .. n_outputs + 1] (the
 *  outputs, friction_demand, painleve; values[j * e->sample_cs] in the column layout), impacts[0], over[0]. */
void rk_ed_row(rk_engine *e, int mode, const double *y, int overturned, int *modes, double *values,
               long long *impacts, int *over);
void rk_ed_full_state(rk_engine *e, double *q, double *v);
void rk_ed_outputs(rk_engine *e, double *out);
rk_status rk_ed_set_state(rk_engine *e, const rk_plain_state *s, const double *impact_times, long long n_times,
                          const double *impact_log, long long n_log_rows, rk_error *err);

/* ------------------------------------------------------------------------------------------ Moreau-Jean (E) */
rk_status rk_mj_init(rk_engine *e, int mode, const double *q, const double *v, rk_error *err);
rk_status rk_mj_advance(rk_engine *e, double t_end, rk_motion *ag, rk_motion *ag_v, long long max_steps,
                        rk_error *err);
void rk_mj_outputs(rk_engine *e, double *out);
rk_status rk_mj_set_state(rk_engine *e, const rk_plain_state *s, const double *impact_times, long long n_times,
                          rk_error *err);

#ifdef __cplusplus
}
#endif
#endif /* RK_INTERNAL_H */
