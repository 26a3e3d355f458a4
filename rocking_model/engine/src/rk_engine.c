/* rk_engine.c -- the public API of rk_engine.h (part E): create / free, advance and sample with their
 * internal checkpoint (Simulator._guarded), the outputs on demand (cached by a state token), the plain-data
 * state, the checkpoint slot, snapshots, the impact logs (rk_log_*) and the helpers both schemes share
 * (the checks of integrators/state.py, note_demand).
 *
 * Dispatch on options.scheme: rk_ed_* (rk_ed.c, part D) or rk_mj_* (rk_mj.c). */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rk_version.h" /* RK_ENGINE_VERSION_STRING, unless the build defines it */

/** [1] smallest dt_max (other than 0) relative to the model's time scale: simulation.DT_MIN_REL */
#define RK_DT_MIN_REL 1e-6
/** [m/s2] largest |ag|: validation.AG_MAX */
#define RK_AG_MAX 1000.0
/** rows of storage an unbounded log starts with (it doubles on an impact that needs it) */
#define RK_LOG_START_ROWS 64
/** impact_log keeps min(1000, impact_log_size) rows (EventDriven.__init__) */
#define RK_IMPACT_LOG_ROWS 1000

const char *rk_engine_version(void)
{
    return RK_ENGINE_VERSION_STRING;
}

int rk_engine_api_version(void)
{
    return RK_ENGINE_API_VERSION;
}

/* ------------------------------------------------------------------------------------------ logs */

rk_status rk_log_append(rk_log *log, const double *row)
{
    long long slot;
    if (log->maxlen >= 0) {
        if (log->cap == 0) {            /* BoundedLog(0): keeps nothing */
            log->end++;
            log->first = log->end;
            return RK_OK;
        }
        if (log->end - log->first >= log->cap)
            log->first++;               /* the ring is full: the oldest row goes (tail() never shows it) */
        slot = log->end % log->cap;
    } else {
        if (log->end >= log->cap) {     /* unbounded: first stays 0, rows at their absolute index */
            long long cap = log->cap > 0 ? 2 * log->cap : RK_LOG_START_ROWS;
            double *data = (double *)realloc(log->data, (size_t)cap * (size_t)log->row_len * sizeof(double));
            if (data == NULL)
                return RK_ERR_MEMORY;
            log->data = data;
            log->cap = cap;
        }
        slot = log->end;
    }
    memcpy(log->data + slot * log->row_len, row, (size_t)log->row_len * sizeof(double));
    log->end++;
    return RK_OK;
}

long long rk_log_tail_count(const rk_log *log)
{
    long long n = log->end - log->first;
    if (log->maxlen >= 0 && n > log->maxlen)
        n = log->maxlen;
    return n;
}

long long rk_log_tail(const rk_log *log, double *buf, long long cap_rows)
{
    long long n = rk_log_tail_count(log), i, start = log->end - n;
    if (n > cap_rows)
        n = cap_rows;
    for (i = 0; i < n; i++) {
        long long a = start + i;
        long long slot = log->maxlen >= 0 ? a % log->cap : a;
        memcpy(buf + i * log->row_len, log->data + slot * log->row_len, (size_t)log->row_len * sizeof(double));
    }
    return n;
}

/** Empty the log and append rows (bounded_log(maxlen, items)). */
static rk_status log_load(rk_log *log, const double *rows, long long n)
{
    long long i;
    log->first = log->end = 0;
    for (i = 0; i < n; i++) {
        rk_status st = rk_log_append(log, rows + i * log->row_len);
        if (st != RK_OK)
            return st;
    }
    return RK_OK;
}

static rk_status log_alloc(rk_log *log, int row_len, long long maxlen)
{
    log->row_len = row_len;
    log->maxlen = maxlen;
    log->first = log->end = 0;
    log->cap = maxlen >= 0 ? 2 * maxlen : RK_LOG_START_ROWS;
    log->data = NULL;
    if (log->cap > 0) {
        log->data = (double *)malloc((size_t)log->cap * (size_t)row_len * sizeof(double));
        if (log->data == NULL)
            return RK_ERR_MEMORY;
    }
    return RK_OK;
}

/** Restore cursors saved at a checkpoint: rows appended since are dropped; rows a bounded ring overwrote
 *  since stay lost (DESIGN.md "Memory"). */
static void log_restore(rk_log *log, long long first0, long long end0)
{
    long long first = log->first > first0 ? log->first : first0;
    if (first > end0)
        first = end0;
    log->first = first;
    log->end = end0;
}

/* ------------------------------------------------------------------------------------------ helpers */

static int is_mj(const rk_engine *e)
{
    return e->options.scheme == RK_SCHEME_MOREAU_JEAN;
}

/** A new token: the state changed (or may have). Past every value the token ever had (the schemes also
 *  increment it during a call), so that the output cache never meets an old token for a new state. */
static void touch(rk_engine *e)
{
    if (e->core.token > e->token_serial)
        e->token_serial = e->core.token;
    e->core.token = ++e->token_serial;
}

static void save_core(rk_engine *e, rk_core *slot)
{
    e->core.times_first = e->impact_times.first;
    e->core.times_end = e->impact_times.end;
    e->core.log_first = e->impact_log.first;
    e->core.log_end = e->impact_log.end;
    *slot = e->core;
}

static void restore_core(rk_engine *e, const rk_core *slot)
{
    e->core = *slot;
    log_restore(&e->impact_times, slot->times_first, slot->times_end);
    log_restore(&e->impact_log, slot->log_first, slot->log_end);
    touch(e);
}

void rk_engine_save(rk_engine *e, rk_core *slot)
{
    save_core(e, slot);
}

void rk_engine_load(rk_engine *e, const rk_core *slot)
{
    restore_core(e, slot);
}

rk_status rk_check_times(const char *key, const double *times, long long n, double t, long long impacts,
                         rk_error *err)
{
    long long i;
    double t_max;
    if (n > impacts)
        return rk_fail(err, RK_ERR_VALUE, "state field '%s' holds %lld impacts, more than impacts = %lld", key, n,
                       impacts);
    t_max = t + 1e-12 * (fabs(t) > 1.0 ? fabs(t) : 1.0);
    for (i = 0; i < n; i++) {
        if (times[i] > t_max || (i && times[i] < times[i - 1]))
            return rk_fail(err, RK_ERR_VALUE, "state field '%s': impact time %.17g is after t = %.17g or out of "
                           "order", key, times[i], t);
    }
    return RK_OK;
}

rk_status rk_check_pose(const rk_model *m, const char *key, const double *q, const double *v, int overturned,
                        double gap_tol, rk_error *err)
{
    const rk_model_ops *ops = m->ops;
    double phi = q[ops->phi_index], g[RK_MAX_CONTACTS], gmin;
    int i;
    if (!overturned && !(fabs(phi) < RK_HALF_PI))
        return rk_fail(err, RK_ERR_VALUE, "state field '%s': |phi| = %g rad reaches pi/2 but 'overturned' is "
                       "False; allowed range (-pi/2, pi/2)", key, fabs(phi));
    if (overturned) {
        for (i = 0; i < ops->n_dof; i++) {
            if (v[i] != 0.0)
                return rk_fail(err, RK_ERR_VALUE, "state field '%s': the velocities must be 0 once 'overturned' "
                               "is True (the pose reached at overturning is kept at rest); got a moving state",
                               key);
        }
    }
    ops->gaps(m, q, g);
    gmin = g[0];
    for (i = 1; i < ops->n_contacts; i++) {
        if (g[i] < gmin)
            gmin = g[i];
    }
    if (!overturned && gmin < -gap_tol)
        return rk_fail(err, RK_ERR_VALUE, "state field '%s': a base corner is %g m below the ground; allowed at "
                       "most %g m", key, -gmin, gap_tol);
    return RK_OK;
}

rk_status rk_check_configuration(const rk_model *m, const char *key, const double *q, const double *v,
                                 int overturned, double gap_tol, rk_error *err)
{
    const rk_model_ops *ops = m->ops;
    double out[RK_MAX_OUTPUTS];
    int i;
    rk_status st = rk_check_pose(m, key, q, v, overturned, gap_tol, err);
    if (st != RK_OK)
        return st;
    ops->outputs(m, q, v, out);
    {
        char names[RK_MSG_LEN];
        size_t len = 0;
        names[0] = '\0';
        for (i = 0; i < ops->n_outputs; i++) {
            if (!isfinite(out[i])) {
                int k = snprintf(names + len, sizeof(names) - len, "%s%s", len ? ", " : "",
                                 ops->output_decls[i].name);
                if (k > 0 && (size_t)k < sizeof(names) - len)
                    len += (size_t)k;
            }
        }
        if (len)
            return rk_fail(err, RK_ERR_VALUE, "state field '%s' gives non-finite outputs (%s); the values are "
                           "too large for the model", key, names);
    }
    return RK_OK;
}

void rk_note_demand(double *demand, double mu, double lam_N, double lam_T, double floor)
{
    if (lam_N > floor) {
        double d = fabs(lam_T) / lam_N;
        if (d > *demand)
            *demand = mu < d ? mu : d;    /* min(d, mu): d unless mu is smaller */
    }
}

/* ------------------------------------------------------------------------------------------ create */

static rk_status check_options(const rk_options *o, rk_error *err)
{
    if (o->scheme != RK_SCHEME_MOREAU_JEAN && o->scheme != RK_SCHEME_EVENT_DRIVEN)
        return rk_fail(err, RK_ERR_VALUE, "scheme = %d is out of range; allowed values 0 (moreau_jean) or 1 "
                       "(event_driven)", (int)o->scheme);
    if (!isfinite(o->t0))
        return rk_fail(err, RK_ERR_VALUE, "t0 = %.17g is out of range; allowed range (-inf, inf)", o->t0);
    if (!(o->dt_max >= 0.0) || isnan(o->dt_max))
        return rk_fail(err, RK_ERR_VALUE, "dt_max = %.17g is out of range; allowed range [0, inf]", o->dt_max);
    if (o->method != RK_METHOD_DOP853 && o->method != RK_METHOD_DOPRI5)
        return rk_fail(err, RK_ERR_VALUE, "method = %d is out of range; allowed values 0 (DOP853) or 1 (DOPRI5)",
                       (int)o->method);
    if (o->impact_log_size < -1)
        return rk_fail(err, RK_ERR_VALUE, "impact_log_size = %lld is out of range; allowed range [0, inf) or -1 "
                       "(keep all)", o->impact_log_size);
    if (o->max_events < 1)
        return rk_fail(err, RK_ERR_VALUE, "max_events = %d is out of range; allowed range [1, inf)",
                       o->max_events);
    return rk_tolerances_check(&o->tolerances, err);
}

/** Everything of create but the scheme's start: options, kernel, model, logs. NULL with err on failure. */
static rk_engine *engine_new(const char *kind, const double *params, int n_params, const rk_options *options,
                             rk_error *err)
{
    rk_options opt;
    const rk_model_ops *ops;
    rk_engine *e;
    long long maxlen;
    rk_error_clear(err);
    if (options == NULL)
        rk_options_default(&opt);
    else
        opt = *options;
    if (check_options(&opt, err) != RK_OK)
        return NULL;
    ops = rk_model_find(kind);
    if (ops == NULL) {
        char kinds[256];
        rk_model_kind_names(kinds, sizeof kinds);
        if (kind == NULL)
            rk_fail(err, RK_ERR_VALUE, "model kind is missing; allowed values %s", kinds);
        else
            rk_fail(err, RK_ERR_VALUE, "model kind '%s' is unknown; allowed values %s", kind, kinds);
        return NULL;
    }
    if (n_params != ops->n_params) {
        rk_fail(err, RK_ERR_VALUE, "model '%s' takes %d parameters, got %d", ops->kind, ops->n_params, n_params);
        return NULL;
    }
    e = (rk_engine *)calloc(1, sizeof(rk_engine));
    if (e == NULL) {
        rk_fail(err, RK_ERR_MEMORY, "out of memory creating an engine (%lu bytes)", (unsigned long)sizeof(rk_engine));
        return NULL;
    }
    e->options = opt;
    if (rk_model_init(&e->model, ops, params, n_params, err) != RK_OK) {
        rk_engine_free(e);
        return NULL;
    }
    {   /* Simulator: a dt_max other than 0 is at least DT_MIN_REL time scales */
        double dt_min = RK_DT_MIN_REL * e->model.time_scale;
        if (0.0 < opt.dt_max && opt.dt_max < dt_min) {
            rk_fail(err, RK_ERR_VALUE, "dt_max = %g is out of range; allowed values 0 (the scheme's default) or "
                    "[%.3g, inf) s: at least %g times the model's time scale 1/p = %.3g s", opt.dt_max, dt_min,
                    RK_DT_MIN_REL, e->model.time_scale);
            rk_engine_free(e);
            return NULL;
        }
    }
    rk_model_scale_tolerances(&e->model, &opt.tolerances, &e->scaled);
    maxlen = opt.impact_log_size;
    if (log_alloc(&e->impact_times, 1, maxlen) != RK_OK
        || log_alloc(&e->impact_log, 1 + 2 * ops->n_dof,
                     maxlen < 0 ? -1 : (maxlen < RK_IMPACT_LOG_ROWS ? maxlen : RK_IMPACT_LOG_ROWS)) != RK_OK) {
        rk_fail(err, RK_ERR_MEMORY, "out of memory allocating the impact logs (impact_log_size = %lld)", maxlen);
        rk_engine_free(e);
        return NULL;
    }
    return e;
}

static rk_engine *engine_start(rk_engine *e, int mode, const double *q, const double *v, rk_error *err)
{
    rk_status st = is_mj(e) ? rk_mj_init(e, mode, q, v, err) : rk_ed_init(e, mode, q, v, err);
    if (st != RK_OK) {
        rk_engine_free(e);
        return NULL;
    }
    touch(e);
    rk_error_clear(&e->error);
    return e;
}

rk_engine *rk_engine_create(const char *kind, const double *params, int n_params, const double *initial,
                            int n_initial, const rk_options *options, rk_error *err)
{
    rk_engine *e = engine_new(kind, params, n_params, options, err);
    const rk_model_ops *ops;
    double init[RK_MAX_INITIAL], q[RK_MAX_DOF], v[RK_MAX_DOF];
    int i, mode;
    if (e == NULL)
        return NULL;
    ops = e->model.ops;
    if (n_initial < 0 || n_initial > ops->n_initial || (n_initial > 0 && initial == NULL)) {
        rk_fail(err, RK_ERR_VALUE, "model '%s' takes at most %d initial values, got %d", ops->kind,
                ops->n_initial, n_initial);
        rk_engine_free(e);
        return NULL;
    }
    for (i = 0; i < ops->n_initial; i++)
        init[i] = i < n_initial ? initial[i] : ops->initial_decls[i].default_value;
    if (ops->initial_state(&e->model, init, &mode, q, v, err) != RK_OK) {
        rk_engine_free(e);
        return NULL;
    }
    return engine_start(e, mode, q, v, err);
}

rk_engine *rk_engine_create_state(const char *kind, const double *params, int n_params, int mode,
                                  const double *q, const double *v, int n_dof, const rk_options *options,
                                  rk_error *err)
{
    rk_engine *e = engine_new(kind, params, n_params, options, err);
    int i;
    if (e == NULL)
        return NULL;
    if (n_dof != e->model.ops->n_dof || mode < 0 || mode >= e->model.ops->n_modes) {
        rk_fail(err, RK_ERR_VALUE, "model '%s': a start state needs a mode in [0, %d] and %d coordinates, got "
                "mode %d and %d", e->model.ops->kind, e->model.ops->n_modes - 1, e->model.ops->n_dof, mode, n_dof);
        rk_engine_free(e);
        return NULL;
    }
    for (i = 0; i < n_dof; i++) {
        if (!isfinite(q[i]) || !isfinite(v[i])) {
            rk_fail(err, RK_ERR_VALUE, "model '%s': the start state must be finite", e->model.ops->kind);
            rk_engine_free(e);
            return NULL;
        }
    }
    return engine_start(e, mode, q, v, err);
}

void rk_engine_free(rk_engine *e)
{
    if (e == NULL)
        return;
    free(e->impact_times.data);
    free(e->impact_log.data);
    free(e);
}

const char *rk_engine_message(const rk_engine *e)
{
    return e->error.message;
}

rk_status rk_engine_status(const rk_engine *e)
{
    return e->error.status;
}

double rk_engine_fail_time(const rk_engine *e)
{
    return e->fail_t;
}

/* ------------------------------------------------------------------------------------------ read */

int rk_engine_n_outputs(const rk_engine *e)
{
    return e->model.ops->n_outputs;
}

const char *rk_engine_output_name(const rk_engine *e, int i)
{
    return (i >= 0 && i < e->model.ops->n_outputs) ? e->model.ops->output_decls[i].name : NULL;
}

const char *rk_engine_output_unit(const rk_engine *e, int i)
{
    return (i >= 0 && i < e->model.ops->n_outputs) ? e->model.ops->output_decls[i].unit : NULL;
}

void rk_engine_outputs(rk_engine *e, double *out)
{
    int n = e->model.ops->n_outputs;
    if (e->out_token != e->core.token || e->core.token == 0) {
        if (is_mj(e))
            rk_mj_outputs(e, e->out_cache);
        else
            rk_ed_outputs(e, e->out_cache);
        e->out_token = e->core.token;
    }
    rk_copy(out, e->out_cache, n);
}

double rk_engine_time(const rk_engine *e)
{
    return is_mj(e) ? e->core.s.mj.t : e->core.s.ed.t;
}

int rk_engine_mode(const rk_engine *e)
{
    return is_mj(e) ? e->core.s.mj.mode : e->core.s.ed.mode;
}

long long rk_engine_impacts(const rk_engine *e)
{
    return is_mj(e) ? e->core.s.mj.impacts : e->core.s.ed.impacts;
}

int rk_engine_overturned(const rk_engine *e)
{
    return is_mj(e) ? e->core.s.mj.overturned : e->core.s.ed.overturned;
}

int rk_engine_contact_code(const rk_engine *e)
{
    return rk_engine_overturned(e) ? RK_OVERTURNED : rk_engine_mode(e);
}

long long rk_engine_n_steps(const rk_engine *e)
{
    return is_mj(e) ? e->core.s.mj.n_steps : e->core.s.ed.n_steps;
}

double rk_engine_friction_demand(const rk_engine *e)
{
    return is_mj(e) ? e->core.s.mj.friction_demand : e->core.s.ed.friction_demand;
}

long long rk_engine_painleve(const rk_engine *e)
{
    return is_mj(e) ? e->core.s.mj.painleve : e->core.s.ed.painleve;
}

int rk_engine_contacts(const rk_engine *e, int *states)
{
    const rk_model *m = &e->model;
    int mode = rk_engine_mode(e), sigma = 0, i, on;
    rk_set closed = rk_closed_of(m, mode);
    rk_stick_of(m, mode, &sigma);
    on = sigma == 0 ? RK_STICK : sigma > 0 ? RK_SLIDE_POS : RK_SLIDE_NEG;
    for (i = 0; i < m->ops->n_contacts; i++)
        states[i] = RK_IN(closed, i) ? on : RK_OPEN;
    return m->ops->n_contacts;
}

int rk_engine_full_state(rk_engine *e, double *q, double *v)
{
    int n = e->model.ops->n_dof;
    if (is_mj(e)) {
        memcpy(q, e->core.s.mj.q, (size_t)n * sizeof(double));
        memcpy(v, e->core.s.mj.v, (size_t)n * sizeof(double));
    } else {
        rk_ed_full_state(e, q, v);
    }
    return n;
}

const char *rk_engine_model_class(const rk_engine *e)
{
    return e->model.ops->class_name;
}

int rk_engine_n_dof(const rk_engine *e)
{
    return e->model.ops->n_dof;
}

int rk_engine_n_contacts(const rk_engine *e)
{
    return e->model.ops->n_contacts;
}

int rk_engine_n_modes(const rk_engine *e)
{
    return e->model.ops->n_modes;
}

rk_scheme rk_engine_scheme(const rk_engine *e)
{
    return e->options.scheme;
}

const rk_reports *rk_engine_reports(const rk_engine *e)
{
    return &e->reports;
}

/* ------------------------------------------------------------------------------------------ advance */

/** check_real("ag", value, lo=-AG_MAX, hi=AG_MAX) and LinearMotion's checks with checked_motion's peak. */
/* name: "ag" (horizontal) or "ag_v" (vertical), the variable the messages name */
static rk_status check_input(rk_engine *e, double t_end, double ag0, double slope, int linear, const char *name)
{
    double t = rk_engine_time(e);
    if (!isfinite(ag0))
        return rk_fail(&e->error, RK_ERR_VALUE, "%s = %s is not finite; allowed range [-1000, 1000]", name,
                       isnan(ag0) ? "nan" : ag0 > 0 ? "inf" : "-inf");
    if (!linear) {
        if (fabs(ag0) > RK_AG_MAX)
            return rk_fail(&e->error, RK_ERR_VALUE, "%s = %g is out of range; allowed range [-1000, 1000]", name,
                           ag0);
        return RK_OK;
    }
    if (!isfinite(slope))
        return rk_fail(&e->error, RK_ERR_VALUE, "%s rate = %s is not finite; allowed range (-inf, inf)", name,
                       isnan(slope) ? "nan" : slope > 0 ? "inf" : "-inf");
    {
        double a0 = fabs(ag0 + slope * (t - t)), a1 = fabs(ag0 + slope * (t_end - t));
        double peak = a0 > a1 ? a0 : a1;
        if (!(peak <= RK_AG_MAX))
            return rk_fail(&e->error, RK_ERR_VALUE, "%s: the ground motion's peak |%s| = %g m/s2 is out of "
                           "range; allowed range [-1000, 1000] m/s2 (AG_MAX, about 100 g; check the units of "
                           "the record and its scale factor)", name, name, peak);
    }
    return RK_OK;
}

static rk_status check_t_end(rk_engine *e, double t_end)
{
    double t = rk_engine_time(e);
    if (!isfinite(t_end))
        return rk_fail(&e->error, RK_ERR_VALUE, "t_end = %s is not finite; allowed range (-inf, inf)",
                       isnan(t_end) ? "nan" : t_end > 0 ? "inf" : "-inf");
    if (t_end < t)
        return rk_fail(&e->error, RK_ERR_VALUE, "t_end = %.17g is before the current time; allowed range "
                       "[%.17g, inf)", t_end, t);
    return RK_OK;
}

static void float_text(char *buf, size_t n, double x)
{
    if (isnan(x))
        snprintf(buf, n, "nan");
    else if (isinf(x))
        snprintf(buf, n, x > 0 ? "inf" : "-inf");
    else
        snprintf(buf, n, "%.17g", x);
}

/** RK_ERR_NONFINITE naming the outputs out[] (the model's n_outputs values) that are not finite; RK_OK if none */
static rk_status check_output_values(rk_engine *e, const double *out)
{
    const rk_model_ops *ops = e->model.ops;
    char text[RK_MSG_LEN];
    size_t len = 0;
    int i;
    for (i = 0; i < ops->n_outputs; i++)
        if (!isfinite(out[i]))
            break;
    if (i == ops->n_outputs)
        return RK_OK;
    text[0] = '\0';
    for (; i < ops->n_outputs; i++) {
        if (!isfinite(out[i])) {
            char num[32];
            int k;
            float_text(num, sizeof(num), out[i]);
            k = snprintf(text + len, sizeof(text) - len, "%s%s = %s", len ? ", " : "", ops->output_decls[i].name,
                         num);
            if (k > 0 && (size_t)k < sizeof(text) - len)
                len += (size_t)k;
        }
    }
    return rk_fail(&e->error, RK_ERR_NONFINITE, "non-finite outputs %s", text);
}

/** Simulator._guarded's check of the outputs after an advance: FloatingPointError "non-finite outputs ...". */
static rk_status check_outputs(rk_engine *e)
{
    double out[RK_MAX_OUTPUTS];
    rk_engine_outputs(e, out);
    return check_output_values(e, out);
}

/** The pose the engine ends a call in, held to the bounds its set_state holds a state to (rk_check_pose), so
 *  that every state the engine reports it also takes back (an FMU serializes it and reads it back). An
 *  integration never ends outside them; a run from an absurd state that set_state accepted may (a velocity of
 *  1e12 rad/s): that is a diverged motion, refused with the state before the call kept. (The outputs were found
 *  finite before.) */
static rk_status check_end_pose(rk_engine *e)
{
    double q[RK_MAX_DOF], v[RK_MAX_DOF];
    rk_error why;
    rk_engine_full_state(e, q, v);
    if (rk_check_pose(&e->model, is_mj(e) ? "q" : "y", q, v, rk_engine_overturned(e), e->model.length_scale,
                      &why) == RK_OK)
        return RK_OK;
    return rk_fail(&e->error, RK_ERR_NONFINITE, "the motion diverged: the state it ends in at t = %.17g s is "
                   "outside the states the engine takes (%s); the state before the call is kept", rk_engine_time(e),
                   why.message);
}

/** Run ``action`` with the internal checkpoint: on failure the engine is restored and e->fail_t says where
 *  the scheme was. */
static rk_status guarded_end(rk_engine *e, rk_status st, const rk_core *saved)
{
    if (st == RK_OK) {
        touch(e);
        st = check_outputs(e);
        if (st == RK_OK)
            st = check_end_pose(e);
    } else if (e->error.status == RK_OK) {
        rk_fail(&e->error, st, "the engine failed without a message (status %s)", rk_status_name(st));
    }
    if (st != RK_OK) {
        e->fail_t = rk_engine_time(e);
        restore_core(e, saved);
    }
    return st;
}

static rk_status advance_impl(rk_engine *e, double t_end, rk_motion *ag, rk_motion *ag_v, long long max_steps,
                              unsigned flags)
{
    rk_core saved;
    rk_status st;
    e->reports.count = 0;
    save_core(e, &saved);
    if (!rk_motion_pair_constant(ag, ag_v))
        e->motion_calls++;
    if (is_mj(e))
        st = rk_mj_advance(e, t_end, ag, ag_v, max_steps, &e->error);
    else
        st = rk_ed_run(e, t_end, ag, ag_v, NULL, 0, max_steps, NULL, NULL, NULL, NULL, flags, &e->error);
    return guarded_end(e, st, &saved);
}

rk_status rk_engine_advance(rk_engine *e, double t_end, double ag0, double slope, double ag_v0, double ag_v_slope,
                            long long max_steps, unsigned flags)
{
    rk_motion m, mv;
    int linear = slope != 0.0 || (flags & RK_ADVANCE_LINEAR) != 0u;
    int linear_v = ag_v_slope != 0.0 || (flags & RK_ADVANCE_LINEAR_V) != 0u;
    /* no vertical motion at all: today's path (GroundMotion.vertical is None) */
    int vertical = linear_v || ag_v0 != 0.0;
    rk_error_clear(&e->error);
    e->fail_t = rk_engine_time(e);
    if (check_t_end(e, t_end) != RK_OK || check_input(e, t_end, ag0, slope, linear, "ag") != RK_OK
        || check_input(e, t_end, ag_v0, ag_v_slope, linear_v, "ag_v") != RK_OK)
        return e->error.status;
    if (linear)
        rk_motion_linear(&m, ag0, slope, rk_engine_time(e));
    else
        rk_motion_constant(&m, ag0);
    if (!vertical)
        return advance_impl(e, t_end, &m, NULL, max_steps, flags);
    if (linear_v)
        rk_motion_linear(&mv, ag_v0, ag_v_slope, rk_engine_time(e));
    else
        rk_motion_constant(&mv, ag_v0);
    return advance_impl(e, t_end, &m, &mv, max_steps, flags);
}

/** The numbers a motion is made of are finite (the constructors check theirs; a hand-filled CONSTANT, LINEAR
 *  or SCALED is checked here): a NaN input would make every event test false. */
static int motion_finite(const rk_motion *m)
{
    int depth;
    for (depth = 0; m != NULL && depth < 16; depth++) {
        switch (m->kind) {
        case RK_MOTION_CONSTANT:
            return isfinite(m->value);
        case RK_MOTION_LINEAR:
            return isfinite(m->value) && isfinite(m->rate) && isfinite(m->t_ref);
        case RK_MOTION_SCALED:
            if (!isfinite(m->factor))
                return 0;
            m = m->inner;
            break;
        default:
            return 1;
        }
    }
    return m != NULL;
}

/** The motions of a call: ag given, both finite (ag_v NULL: none). */
static rk_status check_motions(rk_engine *e, const rk_motion *ag, const rk_motion *ag_v)
{
    if (ag == NULL)
        return rk_fail(&e->error, RK_ERR_VALUE, "ag: the ground motion is missing");
    if (!motion_finite(ag))
        return rk_fail(&e->error, RK_ERR_VALUE, "ag: the ground motion's value, rate and factor must be finite; "
                       "allowed range (-inf, inf)");
    if (ag_v != NULL && !motion_finite(ag_v))
        return rk_fail(&e->error, RK_ERR_VALUE, "ag_v: the ground motion's value, rate and factor must be finite; "
                       "allowed range (-inf, inf)");
    return RK_OK;
}

rk_status rk_engine_advance_motion(rk_engine *e, double t_end, rk_motion *ag, rk_motion *ag_v,
                                   long long max_steps)
{
    rk_error_clear(&e->error);
    e->fail_t = rk_engine_time(e);
    if (check_motions(e, ag, ag_v) != RK_OK || check_t_end(e, t_end) != RK_OK)
        return e->error.status;
    return advance_impl(e, t_end, ag, ag_v, max_steps, 0u);
}

/** Integrator._row into row ``r`` of the sample arrays. */
/** Row r of a sample's arrays from the current state; with check, RK_ERR_NONFINITE (nothing written) where an
 *  output is not finite */
static rk_status put_row(rk_engine *e, long long r, int *modes, double *values, long long *impacts, int *overturned,
                         int check)
{
    int n = e->model.ops->n_outputs, j;
    /* entry (r, j) at values[r * rs + j * js]: rows of n + 2 values, or the column layout of
     * rk_engine_sample_columns (columns of sample_cs values) */
    long long cs = e->sample_cs, rs = cs > 1 ? 1 : n + 2, js = cs > 1 ? cs : 1;
    double row[RK_MAX_OUTPUTS + 2], *dst = values + r * rs;
    rk_engine_outputs(e, row);
    if (check && check_output_values(e, row) != RK_OK)
        return e->error.status;
    row[n] = rk_engine_friction_demand(e);
    row[n + 1] = (double)rk_engine_painleve(e);
    if (js == 1) {
        for (j = 0; j < n + 2; j++)
            dst[j] = row[j];
    } else {
        for (j = 0; j < n + 2; j++)
            dst[j * js] = row[j];
    }
    modes[r] = rk_engine_contact_code(e);
    impacts[r] = rk_engine_impacts(e);
    overturned[r] = rk_engine_overturned(e);
    return RK_OK;
}

static void write_row(rk_engine *e, long long r, int *modes, double *values, long long *impacts, int *overturned)
{
    (void)put_row(e, r, modes, values, impacts, overturned, 0);
}

static rk_status sample_impl(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n_times,
                             long long max_steps, int hold, int *modes, double *values, long long *impacts,
                             int *overturned);

rk_status rk_engine_sample(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n_times,
                           long long max_steps, int *modes, double *values, long long *impacts, int *overturned)
{
    e->sample_cs = 0;
    return sample_impl(e, ag, ag_v, times, n_times, max_steps, 0, modes, values, impacts, overturned);
}

rk_status rk_engine_sample_columns(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times,
                                   long long n_times, long long max_steps, int *modes, double *values,
                                   long long *impacts, int *overturned)
{
    rk_status st;
    e->sample_cs = n_times >= 1 ? n_times + 1 : 0;
    st = sample_impl(e, ag, ag_v, times, n_times, max_steps, 0, modes, values, impacts, overturned);
    e->sample_cs = 0;
    return st;
}

rk_status rk_engine_sample_held(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n_times,
                                long long max_steps, int columns, int *modes, double *values, long long *impacts,
                                int *overturned)
{
    rk_status st;
    e->sample_cs = columns && n_times >= 1 ? n_times + 1 : 0;
    st = sample_impl(e, ag, ag_v, times, n_times, max_steps, 1, modes, values, impacts, overturned);
    e->sample_cs = 0;
    return st;
}

/** One interval of the zero-order hold: the advance rk_engine_advance(e, t_end, a, 0, av, 0, max_steps, 0) makes
 *  (its checks, a constant input, no vertical motion where av == 0, the settle at the start), without its own
 *  checkpoint and output check (the caller's). */
static rk_status held_advance(rk_engine *e, double t_end, double a, double av, long long max_steps)
{
    rk_motion m, mv;
    if (check_input(e, t_end, a, 0.0, 0, "ag") != RK_OK || check_input(e, t_end, av, 0.0, 0, "ag_v") != RK_OK)
        return e->error.status;
    rk_motion_constant(&m, a);
    if (av != 0.0)
        rk_motion_constant(&mv, av);
    if (is_mj(e))
        return rk_mj_advance(e, t_end, &m, av != 0.0 ? &mv : NULL, max_steps, &e->error);
    return rk_ed_run(e, t_end, &m, av != 0.0 ? &mv : NULL, NULL, 0, max_steps, NULL, NULL, NULL, NULL, 0u,
                     &e->error);
}

/** The held values ag(t), ag_v(t) (0 without a vertical motion); a callback's failure as RK_ERR_VALUE with its
 *  message (the extension re-raises the callback's own exception). */
static rk_status held_values(rk_engine *e, rk_motion *ag, rk_motion *ag_v, double t, double *a, double *av)
{
    int failed = 0;
    char msg[RK_MSG_LEN];
    msg[0] = '\0';
    *a = rk_motion_eval(ag, t, &failed, msg);
    *av = ag_v != NULL && !failed ? rk_motion_eval(ag_v, t, &failed, msg) : 0.0;
    if (failed)
        return rk_fail(&e->error, RK_ERR_VALUE, "%s", msg);
    return RK_OK;
}

static rk_status sample_impl(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n_times,
                             long long max_steps, int hold, int *modes, double *values, long long *impacts,
                             int *overturned)
{
    rk_core saved;
    rk_status st = RK_OK;
    long long i;
    double t = rk_engine_time(e);
    rk_error_clear(&e->error);
    e->fail_t = t;
    if (check_motions(e, ag, ag_v) != RK_OK)
        return e->error.status;
    if (n_times < 1)
        return rk_fail(&e->error, RK_ERR_VALUE, "times must hold at least one time after the current one");
    for (i = 0; i < n_times; i++) {
        if (!isfinite(times[i]) || times[i] < t)
            return rk_fail(&e->error, RK_ERR_VALUE, "times = %.17g is out of range; allowed range [%.17g, inf)",
                           times[i], t);
        if (i && times[i] < times[i - 1])
            return rk_fail(&e->error, RK_ERR_VALUE, "times must be increasing");
    }
    e->reports.count = 0;
    save_core(e, &saved);
    if (!rk_motion_pair_constant(ag, ag_v))
        e->motion_calls++;
    if (hold) {
        /* the zero-order hold: one constant-input advance per interval [t_k, t_k+1), t_0 the current time, each
         * with its own settle, work budget and output check, as a loop of rk_engine_advance calls makes them */
        write_row(e, 0, modes, values, impacts, overturned);
        for (i = 0; i < n_times && st == RK_OK; i++) {
            double a, av;
            st = held_values(e, ag, ag_v, i ? times[i - 1] : t, &a, &av);
            if (st == RK_OK)
                st = held_advance(e, times[i], a, av, max_steps);
            if (st == RK_OK) {
                touch(e);
                st = put_row(e, i + 1, modes, values, impacts, overturned, 1);
            }
        }
    } else if (is_mj(e)) {
        write_row(e, 0, modes, values, impacts, overturned);
        for (i = 0; i < n_times && st == RK_OK; i++) {
            st = rk_mj_advance(e, times[i], ag, ag_v, max_steps, &e->error);
            if (st == RK_OK) {
                touch(e);
                write_row(e, i + 1, modes, values, impacts, overturned);
            }
        }
    } else {
        /* row 0: the state now (EventDriven.sample's first _sample_row), then the rows of _run */
        long long rs = e->sample_cs > 1 ? 1 : e->model.ops->n_outputs + 2;     /* from one row to the next */
        rk_ed_row(e, e->core.s.ed.mode, e->core.s.ed.y, e->core.s.ed.overturned, modes, values, impacts,
                  overturned);
        st = rk_ed_run(e, times[n_times - 1], ag, ag_v, times, n_times, max_steps, modes + 1, values + rs,
                       impacts + 1, overturned + 1, 0u, &e->error);
    }
    return guarded_end(e, st, &saved);
}

/* ------------------------------------------------------------------------------------------ plain state */

void rk_engine_get_state(const rk_engine *e, rk_plain_state *s)
{
    memset(s, 0, sizeof(*s));
    if (is_mj(e)) {
        const rk_mj_state *m = &e->core.s.mj;
        int n = e->model.ops->n_dof;
        s->t = m->t;
        memcpy(s->q, m->q, (size_t)n * sizeof(double));
        memcpy(s->v, m->v, (size_t)n * sizeof(double));
        s->mode = m->mode;
        s->closed = m->closed;
        s->impacts = m->impacts;
        s->overturned = m->overturned;
        s->n_steps = m->n_steps;
        s->friction_demand = m->friction_demand;
        s->painleve = m->painleve;
        s->h = NAN;
    } else {
        const rk_ed_state *d = &e->core.s.ed;
        s->t = d->t;
        s->mode = d->mode;
        s->n_y = 2 * d->k;
        memcpy(s->y, d->y, (size_t)s->n_y * sizeof(double));
        s->impacts = d->impacts;
        s->overturned = d->overturned;
        s->n_steps = d->n_steps;
        s->h = d->h;
        s->shift = d->shift;
        s->friction_demand = d->friction_demand;
        s->painleve = d->painleve;
    }
}

long long rk_engine_impact_times(const rk_engine *e, double *buf, long long cap)
{
    long long n = rk_log_tail_count(&e->impact_times);
    if (buf != NULL)
        rk_log_tail(&e->impact_times, buf, cap);
    return n;
}

long long rk_engine_impact_log(const rk_engine *e, double *buf, long long cap_rows)
{
    long long n;
    if (is_mj(e))
        return 0;
    n = rk_log_tail_count(&e->impact_log);
    if (buf != NULL)
        rk_log_tail(&e->impact_log, buf, cap_rows);
    return n;
}

rk_status rk_engine_set_state(rk_engine *e, const rk_plain_state *s, const double *impact_times,
                              long long n_times, const double *impact_log, long long n_log_rows)
{
    rk_core saved;
    rk_status st;
    rk_error_clear(&e->error);
    if (n_times < 0 || (n_times > 0 && impact_times == NULL) || n_log_rows < 0
        || (n_log_rows > 0 && impact_log == NULL))
        return rk_fail(&e->error, RK_ERR_VALUE, "state: the impact logs are missing");
    if (e->impact_times.maxlen >= 0 && n_times > e->impact_times.maxlen)
        return rk_fail(&e->error, RK_ERR_VALUE, "state field 'impact_times' has %lld values; allowed at most %lld",
                       n_times, e->impact_times.maxlen);
    if (e->impact_log.maxlen >= 0 && n_log_rows > e->impact_log.maxlen)
        return rk_fail(&e->error, RK_ERR_VALUE, "state field 'impact_log' has %lld values; allowed at most %lld",
                       n_log_rows * e->impact_log.row_len, e->impact_log.maxlen * e->impact_log.row_len);
    save_core(e, &saved);
    if (is_mj(e)) {
        st = rk_mj_set_state(e, s, impact_times, n_times, &e->error);
        if (st == RK_OK && n_log_rows > 0)
            st = rk_fail(&e->error, RK_ERR_VALUE, "state field 'impact_log' is not a field of the moreau_jean "
                         "scheme");
        if (st == RK_OK) {     /* the fields checked: the log (bounded_log(maxlen, items)) */
            st = log_load(&e->impact_times, impact_times, n_times);
            if (st != RK_OK)
                rk_fail(&e->error, st, "out of memory loading the impact log");
        }
    } else {
        st = rk_ed_set_state(e, s, impact_times, n_times, impact_log, n_log_rows, &e->error);   /* loads its logs */
    }
    if (st != RK_OK) {
        restore_core(e, &saved);
        return st;
    }
    e->has_saved = 0;
    touch(e);
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ checkpoint */

void rk_engine_checkpoint(rk_engine *e)
{
    save_core(e, &e->saved);
    e->has_saved = 1;
}

rk_status rk_engine_rollback(rk_engine *e)
{
    if (!e->has_saved)
        return rk_fail(&e->error, RK_ERR_VALUE, "rollback: there is no checkpoint (call checkpoint first)");
    restore_core(e, &e->saved);
    e->has_saved = 0;
    return RK_OK;
}

void rk_engine_commit(rk_engine *e)
{
    e->has_saved = 0;
}

/* ------------------------------------------------------------------------------------------ snapshots
 * Layout: a header (what must match the restoring engine), the rk_core, then the tail rows of both logs.
 * Pointers inside rk_core (the tableau of the event-driven stepper) are re-bound at restore, so a snapshot
 * also survives serialization to another process running the same build. */

#define RK_SNAP_MAGIC 0x524b534eu   /* "RKSN" */

typedef struct snap_header {
    uint32_t magic;
    uint32_t api_version;
    uint64_t core_size;
    char class_name[32];
    double params[RK_MAX_PARAMS];
    int scheme, method, max_events, sub_samples;
    double dt_max, tolerance, theta, zeno_tol;
    double tol[12];
    long long impact_log_size;
    long long n_times, n_log;       /* rows that follow */
    int times_row, log_row;
} snap_header;

static void snap_fill_header(const rk_engine *e, snap_header *h)
{
    const rk_tolerances *t = &e->options.tolerances;
    memset(h, 0, sizeof(*h));
    h->magic = RK_SNAP_MAGIC;
    h->api_version = RK_ENGINE_API_VERSION;
    h->core_size = sizeof(rk_core);
    strncpy(h->class_name, e->model.ops->class_name, sizeof(h->class_name) - 1);
    memcpy(h->params, e->model.p, sizeof(h->params));
    h->scheme = (int)e->options.scheme;
    h->method = (int)e->options.method;
    h->max_events = e->options.max_events;
    h->sub_samples = t->sub_samples;
    h->dt_max = e->options.dt_max;
    h->tolerance = e->options.tolerance;
    h->theta = e->options.theta;
    h->zeno_tol = e->options.zeno_tol;
    h->tol[0] = t->gap; h->tol[1] = t->step_gap; h->tol[2] = t->grazing; h->tol[3] = t->rest_velocity;
    h->tol[4] = t->step_rest_velocity; h->tol[5] = t->event; h->tol[6] = t->rise; h->tol[7] = t->clearly_open;
    h->tol[8] = t->stateless_step; h->tol[9] = t->lcp_exact; h->tol[10] = t->lcp_hint; h->tol[11] = t->demand_floor;
    h->impact_log_size = e->options.impact_log_size;
    h->n_times = rk_log_tail_count(&e->impact_times);
    h->n_log = rk_log_tail_count(&e->impact_log);
    h->times_row = e->impact_times.row_len;
    h->log_row = e->impact_log.row_len;
}

size_t rk_engine_snapshot_size(const rk_engine *e)
{
    return sizeof(snap_header) + sizeof(rk_core)
           + (size_t)rk_log_tail_count(&e->impact_times) * (size_t)e->impact_times.row_len * sizeof(double)
           + (size_t)rk_log_tail_count(&e->impact_log) * (size_t)e->impact_log.row_len * sizeof(double);
}

rk_status rk_engine_snapshot(const rk_engine *e, void *buf, size_t size)
{
    snap_header h;
    rk_core core;
    unsigned char *p = (unsigned char *)buf;
    if (buf == NULL || size < rk_engine_snapshot_size(e))
        return RK_ERR_VALUE;
    snap_fill_header(e, &h);
    memcpy(p, &h, sizeof(h));
    p += sizeof(h);
    core = e->core;
    core.times_first = core.times_end = core.log_first = core.log_end = 0;
    memcpy(p, &core, sizeof(core));
    p += sizeof(core);
    rk_log_tail(&e->impact_times, (double *)(void *)p, h.n_times);
    p += (size_t)h.n_times * (size_t)h.times_row * sizeof(double);
    rk_log_tail(&e->impact_log, (double *)(void *)p, h.n_log);
    return RK_OK;
}

rk_status rk_engine_restore(rk_engine *e, const void *buf, size_t size)
{
    snap_header h, mine;
    rk_core core;
    const unsigned char *p = (const unsigned char *)buf;
    double *rows;
    size_t need;
    rk_error_clear(&e->error);
    if (buf == NULL || size < sizeof(snap_header) + sizeof(rk_core))
        return rk_fail(&e->error, RK_ERR_VALUE, "snapshot: %lu bytes is too short for a snapshot of this engine",
                       (unsigned long)size);
    memcpy(&h, p, sizeof(h));
    snap_fill_header(e, &mine);
    if (h.magic != RK_SNAP_MAGIC || h.api_version != mine.api_version || h.core_size != mine.core_size)
        return rk_fail(&e->error, RK_ERR_VALUE, "snapshot: not a snapshot of this engine build (format or API "
                       "version differs)");
    if (memcmp(h.class_name, mine.class_name, sizeof(h.class_name)) != 0
        || memcmp(h.params, mine.params, sizeof(h.params)) != 0 || h.scheme != mine.scheme
        || h.method != mine.method || h.max_events != mine.max_events || h.sub_samples != mine.sub_samples
        || memcmp(&h.dt_max, &mine.dt_max, 4 * sizeof(double)) != 0
        || memcmp(h.tol, mine.tol, sizeof(h.tol)) != 0 || h.impact_log_size != mine.impact_log_size
        || h.times_row != mine.times_row || h.log_row != mine.log_row)
        return rk_fail(&e->error, RK_ERR_VALUE, "snapshot: taken from an engine with another model, parameters "
                       "or options; restore it into an engine built the same way");
    need = sizeof(h) + sizeof(rk_core) + (size_t)h.n_times * (size_t)h.times_row * sizeof(double)
           + (size_t)h.n_log * (size_t)h.log_row * sizeof(double);
    if (h.n_times < 0 || h.n_log < 0 || size != need
        || (e->impact_times.maxlen >= 0 && h.n_times > e->impact_times.maxlen)
        || (e->impact_log.maxlen >= 0 && h.n_log > e->impact_log.maxlen))
        return rk_fail(&e->error, RK_ERR_VALUE, "snapshot: %lu bytes, expected %lu (a truncated or altered "
                       "snapshot)", (unsigned long)size, (unsigned long)need);
    memcpy(&core, p + sizeof(h), sizeof(core));
    rows = (double *)malloc(need - sizeof(h) - sizeof(core) + sizeof(double));
    if (rows == NULL)
        return rk_fail(&e->error, RK_ERR_MEMORY, "snapshot: out of memory");
    memcpy(rows, p + sizeof(h) + sizeof(core), need - sizeof(h) - sizeof(core));
    if (log_load(&e->impact_times, rows, h.n_times) != RK_OK
        || log_load(&e->impact_log, rows + h.n_times * h.times_row, h.n_log) != RK_OK) {
        free(rows);
        return rk_fail(&e->error, RK_ERR_MEMORY, "snapshot: out of memory loading the impact logs");
    }
    free(rows);
    e->core = core;
    if (!is_mj(e)) {     /* pointers to static data: re-bound for this process */
        const rk_tableau *tab = rk_tableau_of(e->options.method);
        e->core.s.ed.tab = tab;
        e->core.s.ed.stepper.tab = tab;
        e->core.s.ed.stepper.fun = NULL;
        e->core.s.ed.stepper.ctx = NULL;
        e->core.s.ed.stepper.fun1 = NULL;
        e->core.s.ed.stepper.acc1 = NULL;
        e->core.s.ed.stepper.acc1_m = NULL;
    }
    e->has_saved = 0;
    touch(e);
    return RK_OK;
}
