/* rk_engine.h -- the public C API of the engine: what the CPython extension (rocking_model._engine) and the
 * FMI binary link against. Nothing else is public.
 *
 * Contract
 * - One rk_engine per simulation: a fixed-size struct plus (with a bounded impact log) one block for the log,
 *   both allocated by rk_engine_create and freed by rk_engine_free; nothing is allocated per step.
 * - No global mutable state: engines are independent; one engine must not be used by two threads at once.
 * - Every fallible call returns an rk_status; on failure rk_engine_message(e) says what (the Python's
 *   wording) and the engine is left EXACTLY as before the call (advance / sample / set_state restore their
 *   own checkpoint). The engine never aborts or exits.
 * - Units SI. Outputs are in the order of the model's declared outputs (rk_engine_output_name).
 * Owner: part E (rk_engine.c), dispatching to the schemes (rk_ed.c: part D, rk_mj.c: part E). */
#ifndef RK_ENGINE_H
#define RK_ENGINE_H

#include "rk_common.h"
#include "rk_motion.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The engine's version (the package version it was built with, e.g. "0.9.0") and the API version of this
 *  header (bumped on every incompatible change). */
const char *rk_engine_version(void);
/* 2: the vertical ground acceleration ag_v in rk_engine_advance / advance_motion / sample */
#define RK_ENGINE_API_VERSION 2
int rk_engine_api_version(void);
/** The plain-data state format (simulation.STATE_VERSION). */
#define RK_STATE_VERSION 2

typedef struct rk_engine rk_engine;

/** Create an engine for model ``kind`` ("rigid", "flexible", or the class name "RigidBlock", ...), with
 *  params[0..n_params-1] in the model's declared order (n_params must equal it), the initial values
 *  initial[0..n_initial-1] in declared order (NULL / 0: the defaults; fewer: the rest default) and options
 *  (NULL: rk_options_default). Checks everything with the Python's messages. Returns NULL on failure with
 *  err filled (err may not be NULL). */
rk_engine *rk_engine_create(const char *kind, const double *params, int n_params, const double *initial,
                            int n_initial, const rk_options *options, rk_error *err);
/** Create at a given full state (mode, q[n_dof], v[n_dof]) instead of initial values: what
 *  Integrator.from_options receives from the Simulator (model.initial_state computed by the caller). The
 *  state is taken as given (as the Python schemes do); n_dof must be the model's. (Added by part E.) */
rk_engine *rk_engine_create_state(const char *kind, const double *params, int n_params, int mode,
                                  const double *q, const double *v, int n_dof, const rk_options *options,
                                  rk_error *err);
/** The time the scheme had reached when the last call failed [s] (before the restore). (Added by part E.) */
double rk_engine_fail_time(const rk_engine *e);
/** The contact code now: the mode, or RK_OVERTURNED once overturned (Integrator.contact_code). (Added.) */
#define RK_OVERTURNED 10
int rk_engine_contact_code(const rk_engine *e);

/** Free (NULL is a no-op). */
void rk_engine_free(rk_engine *e);

/** The status and message of the last failed call on e. */
const char *rk_engine_message(const rk_engine *e);
rk_status rk_engine_status(const rk_engine *e);

/* ------------------------------------------------------------------------------------------ advance */
/** flags of rk_engine_advance */
#define RK_ADVANCE_CONTINUOUS 1u   /**< ag is continuous at the current time with the previous advance's input
                                        (a kink of a record, not a jump): the mode is not re-decided at the
                                        start (the Python's ``kink`` rule inside one SampledMotion advance) */

#define RK_ADVANCE_LINEAR 2u       /**< the input is a LinearMotion even when slope == 0 (the Python's
                                        ``ag.constant`` is False: the event-driven scheme then samples a
                                        stateless phase in steps of stateless_step, as it does under
                                        fmi2SetRealInputDerivatives with a zero rate) */

#define RK_ADVANCE_LINEAR_V 4u     /**< the same for the vertical input: a LinearMotion even when ag_v_slope == 0 */

/** Integrate to exactly t_end [s] (>= the current time) under the first-order hold
 *  ag(t) = ag0 + slope (t - t0), t0 the current time: slope 0 without RK_ADVANCE_LINEAR is the constant path
 *  (ConstantMotion), otherwise LinearMotion(ag0, slope, t_ref = t0). A LinearMotion whose t_ref is not the
 *  current time (the FMU's rate set at another time) goes through rk_engine_advance_motion with
 *  rk_motion_linear, which evaluates value + rate (t - t_ref) exactly as the Python does.
 *  The vertical ground acceleration [m/s2, positive upward] is held the same way:
 *  ag_v(t) = ag_v0 + ag_v_slope (t - t0) (RK_ADVANCE_LINEAR_V for a LinearMotion with a zero slope); ag_v0 =
 *  ag_v_slope = 0 without RK_ADVANCE_LINEAR_V is no vertical motion (today's path, bit-identical). The pair is
 *  the Python's TwoComponentMotion: constant when both components are.
 *  max_steps: work budget of this call (< 0: none): RK_ERR_WORK_LIMIT beyond it, state restored. */
rk_status rk_engine_advance(rk_engine *e, double t_end, double ag0, double slope, double ag_v0, double ag_v_slope,
                            long long max_steps, unsigned flags);
/** The same under any ground motion (Simulator.advance with a GroundMotion): ag the horizontal component, ag_v
 *  the vertical one (NULL: zero, GroundMotion.vertical is None). */
rk_status rk_engine_advance_motion(rk_engine *e, double t_end, rk_motion *ag, rk_motion *ag_v,
                                   long long max_steps);

/** Integrator.sample: advance through the increasing times[0..n_times-1] (> current time) and write the
 *  outputs at the current time and at each of them (n_times + 1 rows): modes[row], values[row * stride + j]
 *  with stride = n_outputs + 2 (the model's outputs, then friction_demand, painleve), impacts[row],
 *  overturned[row]. The work budget applies between consecutive times. Arrays are caller-owned. ag_v: the
 *  vertical component (NULL: zero). */
rk_status rk_engine_sample(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n_times,
                           long long max_steps, int *modes, double *values, long long *impacts, int *overturned);
/** rk_engine_sample with values in columns: values[j * (n_times + 1) + row] (one contiguous array per output,
 *  what the Python API returns, without a transposed copy); the same numbers. */
rk_status rk_engine_sample_columns(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times,
                                   long long n_times, long long max_steps, int *modes, double *values,
                                   long long *impacts, int *overturned);

/** simulate(hold="zoh"): rk_engine_sample with the input held over each interval [t_k, t_k+1) of the grid (t_0 the
 *  current time, t_k+1 = times[k]) at ag(t_k) and ag_v(t_k) (ag_v NULL or a held 0: no vertical motion): the
 *  results of n_times calls rk_engine_advance(e, times[k], ag(t_k), 0, ag_v(t_k), 0, max_steps, 0) with the
 *  outputs read after each (each interval settles at its start, has its own work budget and output check), in
 *  one call. columns: the layout of rk_engine_sample_columns, else rk_engine_sample's rows. On failure the
 *  engine is left as before the call. */
rk_status rk_engine_sample_held(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n_times,
                                long long max_steps, int columns, int *modes, double *values, long long *impacts,
                                int *overturned);

/* ------------------------------------------------------------------------------------------ read */
int rk_engine_n_outputs(const rk_engine *e);
const char *rk_engine_output_name(const rk_engine *e, int i);
const char *rk_engine_output_unit(const rk_engine *e, int i);
/** The model's outputs now (computed on demand from the state, cached until the state changes). */
void rk_engine_outputs(rk_engine *e, double *out);
/** Integrator attributes now. */
double rk_engine_time(const rk_engine *e);
int rk_engine_mode(const rk_engine *e);
long long rk_engine_impacts(const rk_engine *e);
int rk_engine_overturned(const rk_engine *e);
long long rk_engine_n_steps(const rk_engine *e);
double rk_engine_friction_demand(const rk_engine *e);
long long rk_engine_painleve(const rk_engine *e);
/** Integrator.contacts: rk_contact_state per contact; returns n_contacts. */
int rk_engine_contacts(const rk_engine *e, int *states);
/** Integrator.state(): full (q, v); returns n_dof. */
int rk_engine_full_state(rk_engine *e, double *q, double *v);
/** Model description: class name ("RigidBlock"), n_dof, n_contacts, n_modes, scheme. */
const char *rk_engine_model_class(const rk_engine *e);
int rk_engine_n_dof(const rk_engine *e);
int rk_engine_n_contacts(const rk_engine *e);
int rk_engine_n_modes(const rk_engine *e);
rk_scheme rk_engine_scheme(const rk_engine *e);
/** The reports of the last advance / sample (Simulator.last_reports). */
const rk_reports *rk_engine_reports(const rk_engine *e);

/* ------------------------------------------------------------------------------------------ plain-data state */
/** The fields of Simulator.get_state without the header (version, scheme, model, n_dof: the caller writes
 *  them from rk_engine_model_class / rk_engine_scheme / rk_engine_n_dof) and without the two variable-length
 *  logs (rk_engine_impact_times / rk_engine_impact_log). Event-driven fields: t, mode, y (n_y = 2k), impacts,
 *  overturned, n_steps, h (NAN: None), shift, friction_demand, painleve. Moreau-Jean fields: t, q, v (n_dof),
 *  mode, closed, impacts, overturned, n_steps, friction_demand, painleve. */
typedef struct rk_plain_state {
    double t;
    int mode;
    int n_y;
    double y[RK_MAX_Y];
    double q[RK_MAX_DOF], v[RK_MAX_DOF];
    rk_set closed;
    long long impacts;
    int overturned;
    long long n_steps;
    double h;
    double shift;
    double friction_demand;
    long long painleve;
} rk_plain_state;

/** Fill s with the current state. */
void rk_engine_get_state(const rk_engine *e, rk_plain_state *s);
/** impact_times: the last maxlen times (BoundedLog.tail). With buf NULL returns the count only; else writes
 *  min(count, cap) and returns count. */
long long rk_engine_impact_times(const rk_engine *e, double *buf, long long cap);
/** impact_log (event-driven only), flattened rows (t, v_minus[n_dof], v_plus[n_dof]) as in get_state; returns
 *  the number of ROWS, writes min(rows, cap_rows). */
long long rk_engine_impact_log(const rk_engine *e, double *buf, long long cap_rows);
/** Load a state (set_state): every field checked as the Python does (RK_ERR_VALUE naming the field,
 *  e.g. "state field 'y' ..."); nothing changes on error. n_log_rows: rows of impact_log (event-driven). */
rk_status rk_engine_set_state(rk_engine *e, const rk_plain_state *s, const double *impact_times,
                              long long n_times, const double *impact_log, long long n_log_rows);

/* ------------------------------------------------------------------------------------------ checkpoint */
/** One checkpoint slot inside the engine (Checkpointed): checkpoint before, then rollback (exact restore) or
 *  commit. A struct copy of the scheme's state plus the log cursors (DESIGN.md "Memory"). advance / sample
 *  use their own internal slot; these are for callers that group several calls (the FMU's doStep). */
void rk_engine_checkpoint(rk_engine *e);
rk_status rk_engine_rollback(rk_engine *e);
void rk_engine_commit(rk_engine *e);
/** Whole-engine snapshots for fmi2GetFMUstate / SetFMUstate / serialization: size in bytes, copy out, copy
 *  in (a snapshot of another engine of the same model, options and log size only: RK_ERR_VALUE otherwise). */
size_t rk_engine_snapshot_size(const rk_engine *e);
rk_status rk_engine_snapshot(const rk_engine *e, void *buf, size_t size);
rk_status rk_engine_restore(rk_engine *e, const void *buf, size_t size);

#ifdef __cplusplus
}
#endif
#endif /* RK_ENGINE_H */
