/* FMI 2.0 co-simulation over the compiled engine (rk_engine.h): the self-contained FMUs, with no
 * Python at all. C99 + libm.
 *
 * The FMI calls (the state machine, the argument checks, the statuses, the messages, the FMU states) are
 * ../fmi2_common.c's, written once for this binary and fmi2_cs.c (the binary of the pythonfmu FMUs;
 * per-call state masks after modelica/Reference-FMUs); this file has fmi2Instantiate and their hooks
 * (fmi2c_backend_*): the slave's part (rocking_model/fmi/slave.py: RockingSlave / ModelSlave), written here
 * in C with the same checks and texts. The variables come from rk_fmu_vars.h, GENERATED at build time by
 * rocking_model/fmi/standalone.py from the declarations the pythonfmu FMUs use.
 *
 * Status of a call (FMI 2.0, section 2.1.3):
 *   fmi2OK / fmi2Warning  the call did its work (fmi2Warning when a warning was logged meanwhile: an inexact
 *                         contact solve; the overturning is an event of the motion, not a warning: fmi2OK,
 *                         its message logged with fmi2OK under logEvents);
 *   fmi2Discard           a refused step: the engine is where it was (fmi2Terminated true until a later step
 *                         succeeds, fmi2LastSuccessfulTime the instance's time);
 *   fmi2Error             an invalid argument, value or call sequence: the message goes to the logger, the
 *                         instance enters the error state (only getters, fmi2SetFMUstate, fmi2Reset,
 *                         fmi2Terminate and fmi2FreeInstance allowed).
 * Messages are passed to the logger as data ("%s"), never as a format.
 * Thread safety: no mutable globals; each instance owns its engine. */
#if !defined(_WIN32) && !defined(_POSIX_C_SOURCE)
#define _POSIX_C_SOURCE 200809L /* stat() */
#endif
#include "rk_fp.h" /* before any function: no contraction into multiply-adds (engine/src/rk_fp.h) */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>

#include "fmi2Functions.h"
#include "rk_engine.h"
#include "uri.h"
#include "fmi2_common.h" /* last: its shorthands (log_error, fail, ...) are macros */

enum { RK_REAL, RK_INTEGER, RK_BOOLEAN, RK_STRING };
enum { RK_PARAMETER, RK_INPUT, RK_OUTPUT };
enum { RK_ROLE_PARAM, RK_ROLE_INITIAL, RK_ROLE_SCHEME, RK_ROLE_DT_MAX, RK_ROLE_TOLERANCE, RK_ROLE_MAX_STEPS,
       RK_ROLE_INPUT, RK_ROLE_OUTPUT, RK_ROLE_CONTACT, RK_ROLE_IMPACTS, RK_ROLE_OVERTURNED,
       RK_ROLE_FRICTION_DEMAND, RK_ROLE_PAINLEVE };
typedef struct {
    const char *name;
    int type, causality, fixed, role, index;
    double start;
    int has_min;
    double min;
    int has_max;
    double max;
} rk_fmu_var;

#include "rk_fmu_vars.h"

static const char *const TYPE_NAMES[] = {"Real", "Integer", "Boolean", "String"};

const unsigned FMI2C_INSTANCE_MAGIC = 0x46d12a7cu;
const unsigned FMI2C_STATE_MAGIC = 0x5d7e0c1au;
#define ERROR_LEN 1024

/* the slave's part of the instance (RockingSlave._clear_state): what an FMU state holds */
typedef struct {
    double values[RK_FMU_N_VARS]; /* every variable as a double (Integer / Boolean exactly representable) */
    int initialized, terminated, frozen;
    double t, t0;                 /* [s] communication point, start time */
    /* per Real input (index 0 ag, 1 ag_v; RockingSlave._rates): input = value + rate (t - rate_t) when has_rate */
    int has_rate[RK_FMU_N_INPUTS];
    double rate[RK_FMU_N_INPUTS], rate_t[RK_FMU_N_INPUTS];
    int has_error;
    char error[ERROR_LEN];        /* permanent failure, until reset */
} Slave;

typedef struct {
    fmi2c_instance f;             /* the FMI part (fmi2_common.h): state, logger, time, statuses */
    Slave s;
    rk_engine *engine;            /* NULL until initialized (or after an error without simulator) */
} Instance;

/* the backend's part of an FMU state (fmi2_common.c): the slave's bytes (see encode_slave) */
typedef struct {
    size_t n;
    unsigned char bytes[];
} Payload;

/* serialized FMU state: the header of fmi2_common.h (magic, time, instance state, fmi2Terminated, last
 * DoStep status, CRC-32 of everything else), then the slave's bytes: PAYLOAD_MAGIC, the GUID, the Slave struct's
 * fields and the engine snapshot. */
#define PAYLOAD_MAGIC "rocking engine FMU state v2\n"
#define PAYLOAD_MAGIC_SIZE (sizeof PAYLOAD_MAGIC - 1)
#define GUID_SIZE 36

/* ------------------------------------------------------------------------------------------ texts */
/* Python's repr of a float: the shortest text that reads back as the same double, in the notation Python
 * chooses (fixed for 1e-4 <= |x| < 1e16, else scientific with a signed two-digit exponent). */
static void py_repr(double x, char *out, size_t size) {
    if (isnan(x)) { snprintf(out, size, "nan"); return; }
    if (isinf(x)) { snprintf(out, size, x > 0 ? "inf" : "-inf"); return; }
    if (x == 0.0) { snprintf(out, size, signbit(x) ? "-0.0" : "0.0"); return; }
    char buf[40];
    int p;
    for (p = 1; p <= 17; p++) {
        snprintf(buf, sizeof buf, "%.*e", p - 1, x);
        if (strtod(buf, NULL) == x) break;
    }
    /* buf: [-]d.ddde[+-]XX */
    char digits[24];
    int nd = 0, neg = buf[0] == '-';
    const char *c = buf + neg;
    for (; *c && *c != 'e'; c++) /* the digits only (a host's locale may write the point as a comma) */
        if (*c >= '0' && *c <= '9') digits[nd++] = *c;
    digits[nd] = 0;
    int e = atoi(c + 1);
    while (nd > 1 && digits[nd - 1] == '0') digits[--nd] = 0;
    char body[64];
    if (e >= -5 + 1 && e < 16) { /* Python: repr uses 'r' format: fixed when -4 <= exp < 16 */
        if (e >= 0) {
            if (nd <= e + 1) {
                snprintf(body, sizeof body, "%s%0*d.0", digits, e + 1 - nd, 0);
                if (e + 1 - nd == 0) snprintf(body, sizeof body, "%s.0", digits);
            } else {
                snprintf(body, sizeof body, "%.*s.%s", e + 1, digits, digits + e + 1);
            }
        } else {
            snprintf(body, sizeof body, "0.%0*d%s", -e - 1, 0, digits);
            if (-e - 1 == 0) snprintf(body, sizeof body, "0.%s", digits);
        }
    } else {
        if (nd > 1) snprintf(body, sizeof body, "%c.%se%c%02d", digits[0], digits + 1, e < 0 ? '-' : '+', abs(e));
        else snprintf(body, sizeof body, "%ce%c%02d", digits[0], e < 0 ? '-' : '+', abs(e));
    }
    snprintf(out, size, "%s%s", neg ? "-" : "", body);
}

/* ------------------------------------------------------------------------------------------ messages */
#define log_warning(S, ...) logf_(S, fmi2Warning, "logStatusWarning", __VA_ARGS__)
/* an event of the motion (the overturning): fmi2OK, under the category logEvents (RockingSlave.EVENTS); it
 * reaches the logger with logging on and the category enabled (fmi2c_emit), and leaves the call's status OK */
#define log_event(S, ...) logf_(S, fmi2OK, "logEvents", __VA_ARGS__)

/* ------------------------------------------------------------------------------------------ the slave */
static void slave_clear(Slave *s) {
    memset(s, 0, sizeof *s);
    for (int i = 0; i < RK_FMU_N_VARS; i++) s->values[i] = RK_FMU_VARS[i].start;
}

/* The engine of the parameter values `values` (ModelSlave.create_simulator): NULL with `why` filled. */
static rk_engine *create_engine(const double *values, double t0, char *why, size_t size) {
    double params[RK_FMU_N_PARAMS > 0 ? RK_FMU_N_PARAMS : 1], initial[RK_FMU_N_INITIAL > 0 ? RK_FMU_N_INITIAL : 1];
    rk_options o;
    rk_options_default(&o);
    o.t0 = t0;
    o.impact_log_size = 0; /* the FMU keeps no impact log (memory flat over any run; the count is kept) */
    for (int i = 0; i < RK_FMU_N_PARAMS; i++) params[i] = RK_FMU_PARAM_DEFAULTS[i];
    for (int i = 0; i < RK_FMU_N_INITIAL; i++) initial[i] = RK_FMU_INITIAL_DEFAULTS[i];
    double max_steps = 0.0;
    for (int i = 0; i < RK_FMU_N_VARS; i++) {
        const rk_fmu_var *v = &RK_FMU_VARS[i];
        switch (v->role) {
        case RK_ROLE_PARAM: params[v->index] = values[i]; break;
        case RK_ROLE_INITIAL: initial[v->index] = values[i]; break;
        case RK_ROLE_SCHEME: o.scheme = (rk_scheme)(int)values[i]; break;
        case RK_ROLE_DT_MAX: o.dt_max = values[i]; break;
        case RK_ROLE_TOLERANCE: o.tolerance = values[i]; break;
        case RK_ROLE_MAX_STEPS: max_steps = values[i]; break;
        default: break;
        }
    }
    if (!(max_steps >= 1 && max_steps <= RK_FMU_MAX_STEPS_LIMIT)) {
        snprintf(why, size, "max_steps = %.0f is out of range; allowed range [1, %d]", max_steps,
                 RK_FMU_MAX_STEPS_LIMIT);
        return NULL;
    }
    /* the scheme is checked after the model's parameters, as the Python builds the model before the Simulator */
    int bad_scheme = !(o.scheme == RK_SCHEME_MOREAU_JEAN || o.scheme == RK_SCHEME_EVENT_DRIVEN);
    if (bad_scheme) o.scheme = RK_SCHEME_EVENT_DRIVEN;
    rk_error err;
    rk_error_clear(&err);
    rk_engine *e = rk_engine_create(RK_FMU_MODEL_KIND, params, RK_FMU_N_PARAMS, initial, RK_FMU_N_INITIAL, &o, &err);
    if (!e) {
        snprintf(why, size, "%s", err.message);
        /* an Integer choice named with its integer value, as the Python's message (the engine reads doubles) */
        for (int i = 0; i < RK_FMU_N_VARS; i++) {
            const rk_fmu_var *v = &RK_FMU_VARS[i];
            char head[160], fixed[160];
            if (v->type != RK_INTEGER) continue;
            snprintf(head, sizeof head, "%s = %.1f is not supported", v->name, values[i]);
            snprintf(fixed, sizeof fixed, "%s = %.0f is not supported", v->name, values[i]);
            if (strncmp(err.message, head, strlen(head)) == 0)
                snprintf(why, size, "%s%s", fixed, err.message + strlen(head));
        }
        return NULL;
    }
    if (bad_scheme) {
        rk_engine_free(e);
        for (int i = 0; i < RK_FMU_N_VARS; i++)
            if (RK_FMU_VARS[i].role == RK_ROLE_SCHEME)
                snprintf(why, size, "scheme = %.0f is not supported; allowed values: %s", values[i],
                         RK_FMU_SCHEME_ALLOWED);
        return NULL;
    }
    if (rk_engine_n_outputs(e) < RK_FMU_N_OUTPUTS) {
        snprintf(why, size, "the engine has %d outputs, the FMU declares %d", rk_engine_n_outputs(e),
                 RK_FMU_N_OUTPUTS);
        rk_engine_free(e);
        return NULL;
    }
    for (int i = 0; i < RK_FMU_N_OUTPUTS; i++)
        if (strcmp(rk_engine_output_name(e, i), RK_FMU_OUTPUT_NAMES[i]) != 0) {
            snprintf(why, size, "the engine's output %d is %s, the FMU declares %s", i, rk_engine_output_name(e, i),
                     RK_FMU_OUTPUT_NAMES[i]);
            rk_engine_free(e);
            return NULL;
        }
    return e;
}

static long long max_steps_of(const Slave *s) {
    for (int i = 0; i < RK_FMU_N_VARS; i++)
        if (RK_FMU_VARS[i].role == RK_ROLE_MAX_STEPS) return (long long)s->values[i];
    return -1;
}

/* the variable (value reference) of Real input k: 0 ag, 1 ag_v */
static int input_var(int k) {
    for (int i = 0; i < RK_FMU_N_VARS; i++)
        if (RK_FMU_VARS[i].role == RK_ROLE_INPUT && RK_FMU_VARS[i].index == k) return i;
    return -1;
}

/* the largest fmi2Integer: the engine's counts (impacts, painleve; 64-bit, any value >= 0 in a state) saturate
 * there in their Integer outputs (documented in the variables' descriptions). Saturated rather than refused: a
 * run that counts past it serializes states with such counts, which the FMU must take back. */
#define RK_FMU_COUNT_MAX 2147483647.0
static double count_value(long long n) { return n > 2147483647LL ? RK_FMU_COUNT_MAX : (double)n; }

/* a value held as a double as an fmi2Integer: saturated at the type's range (nan: 0), never an out-of-range
 * conversion (undefined behaviour in C) */
static fmi2Integer to_integer(double x) {
    if (!(x == x)) return 0;
    if (x >= 2147483647.0) return 2147483647;
    if (x <= -2147483648.0) return -2147483647 - 1;
    return (fmi2Integer)x;
}

/* RockingSlave._update_outputs: the outputs from the engine; the freeze once overturned (logged as an event) */
static void update_outputs(Instance *S) {
    Slave *s = &S->s;
    double out[RK_MAX_OUTPUTS];
    rk_engine_outputs(S->engine, out);
    int overturned = rk_engine_overturned(S->engine);
    for (int i = 0; i < RK_FMU_N_VARS; i++) {
        const rk_fmu_var *v = &RK_FMU_VARS[i];
        switch (v->role) {
        case RK_ROLE_OUTPUT: s->values[i] = out[v->index]; break;
        case RK_ROLE_CONTACT: s->values[i] = rk_engine_contact_code(S->engine); break;
        case RK_ROLE_IMPACTS: s->values[i] = count_value(rk_engine_impacts(S->engine)); break;
        case RK_ROLE_OVERTURNED: s->values[i] = overturned ? 1.0 : 0.0; break;
        case RK_ROLE_FRICTION_DEMAND: s->values[i] = rk_engine_friction_demand(S->engine); break;
        case RK_ROLE_PAINLEVE: s->values[i] = count_value(rk_engine_painleve(S->engine)); break;
        default: break;
        }
    }
    if (RK_FMU_FREEZE && overturned && !s->frozen) {
        s->frozen = 1;
        log_event(S, "overturned at t = %g s: the outputs are frozen from now on", rk_engine_time(S->engine));
    }
}

/* check_real(name, x, lo, hi) of rocking_model.validation: 0, or 1 with the message in `out` */
static int check_real(const char *name, double x, const rk_fmu_var *v, char *out, size_t size) {
    if (isfinite(x) && (!v->has_min || x >= v->min) && (!v->has_max || x <= v->max)) return 0;
    char lo[32], hi[32], r[40];
    if (v->has_min) snprintf(lo, sizeof lo, "%g", v->min); else snprintf(lo, sizeof lo, "-inf");
    if (v->has_max) snprintf(hi, sizeof hi, "%g", v->max); else snprintf(hi, sizeof hi, "inf");
    char rng[80];
    snprintf(rng, sizeof rng, "%c%s, %s%c", v->has_min ? '[' : '(', lo, hi, v->has_max ? ']' : ')');
    if (!isfinite(x)) {
        py_repr(x, r, sizeof r);
        snprintf(out, size, "%s = %s is not finite; allowed range %s", name, r, rng);
    } else {
        snprintf(out, size, "%s = %g is out of range; allowed range %s", name, x, rng);
    }
    return 1;
}

static const rk_fmu_var RATE_RANGE = {"rate", RK_REAL, RK_INPUT, 0, 0, 0, 0.0, 1, -RK_FMU_INPUT_RATE_MAX, 1,
                                      RK_FMU_INPUT_RATE_MAX};

/* the resource folder exists (the FMU reads nothing from it; a missing one means a broken extraction) */
static int is_directory(const char *path) {
#ifdef _WIN32
    struct _stat st;
    return _stat(path, &st) == 0 && (st.st_mode & _S_IFDIR);
#else
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
#endif
}

/* ------------------------------------------------------------------------------------------ life cycle */
fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)visible;
    if (fmi2c_check_instantiate(functions, instanceName, fmuType, fmuGUID) != 0) return NULL;
    if (strcmp(fmuGUID, RK_FMU_GUID) != 0) {
        fmi2c_instantiate_error(functions, instanceName, "fmi2Instantiate: fmuGUID \"%.100s\" does not match the "
                                "GUID of this binary, %s (the modelDescription.xml belongs to another FMU or build)",
                                fmuGUID, RK_FMU_GUID);
        return NULL;
    }
    /* the FMU reads no resources, but a location that is not a file URI is refused as the project's other
     * binary refuses it (../uri.c, the same messages) */
    char resources[4096];
    if (fmi2c_resource_folder(functions, instanceName, fmuResourceLocation, resources, sizeof resources,
                              is_directory, NULL, NULL) != 0)
        return NULL;
    /* messages of at most 4095 bytes */
    Instance *S = (Instance *)fmi2c_new_instance(sizeof(Instance), functions, instanceName, loggingOn,
                                                 FMI2C_MESSAGE_MAX);
    if (!S) return NULL;
    slave_clear(&S->s);
    return S;
}

/* ------------------------------------------------------------------------------------------ backend hooks */
/* the backend's part of the FMI calls of fmi2_common.c (fmi2c_backend): the slave, the engine */
void fmi2c_backend_free_instance(fmi2c_instance *F) { rk_engine_free(((Instance *)F)->engine); }

fmi2Status fmi2c_backend_setup_experiment(fmi2c_instance *F, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                   fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    ((Instance *)F)->s.t0 = startTime;
    return fmi2OK;
}

fmi2Status fmi2c_backend_enter_initialization_mode(fmi2c_instance *F) {
    (void)F;
    return fmi2OK;
}

fmi2Status fmi2c_backend_exit_initialization_mode(fmi2c_instance *F) {
    Instance *S = (Instance *)F;
    char why[RK_MSG_LEN + 128];
    rk_engine *e = create_engine(S->s.values, S->s.t0, why, sizeof why);
    if (!e) {
        log_error(S, "fmi2ExitInitializationMode: invalid parameters: %s", why);
        return fmi2Error;
    }
    rk_engine_free(S->engine);
    S->engine = e;
    S->s.initialized = 1;
    S->s.t = S->s.t0;
    /* a rate set before initialization refers to the start of the first communication step */
    for (int k = 0; k < RK_FMU_N_INPUTS; k++)
        if (S->s.has_rate[k]) S->s.rate_t[k] = S->s.t0;
    update_outputs(S);
    return S->f.worst_logged;
}

fmi2Status fmi2c_backend_terminate(fmi2c_instance *F) {
    ((Instance *)F)->s.terminated = 1;
    return fmi2OK;
}

fmi2Status fmi2c_backend_reset(fmi2c_instance *F) {
    Instance *S = (Instance *)F;
    rk_engine_free(S->engine);
    S->engine = NULL;
    slave_clear(&S->s);
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ values */
/* the variable of reference vr if it has type `type`; else NULL with the problem appended to `problems` */
static const rk_fmu_var *lookup(fmi2ValueReference vr, int type, char *problems, size_t size) {
    size_t n = strlen(problems);
    const char *sep = n ? "; " : "";
    if (vr >= RK_FMU_N_VARS) {
        snprintf(problems + n, size - n, "%svalue reference %u is unknown to %s", sep, (unsigned)vr, RK_FMU_NAME);
        return NULL;
    }
    const rk_fmu_var *v = &RK_FMU_VARS[vr];
    if (v->type != type) {
        snprintf(problems + n, size - n, "%svalue reference %u is '%s', a %s variable, not %s", sep, (unsigned)vr,
                 v->name, TYPE_NAMES[v->type], TYPE_NAMES[type]);
        return NULL;
    }
    return v;
}

static void append(char *problems, size_t size, const char *text) {
    size_t n = strlen(problems);
    snprintf(problems + n, size - n, "%s%s", n ? "; " : "", text);
}

#define PROBLEMS_LEN 4096

static fmi2Status get_values(Instance *S, const char *function, int type, const fmi2ValueReference vr[],
                             size_t nvr, double *out) {
    char problems[PROBLEMS_LEN] = "";
    for (size_t i = 0; i < nvr; i++) {
        const rk_fmu_var *v = lookup(vr[i], type, problems, sizeof problems);
        out[i] = v ? S->s.values[vr[i]] : 0.0;
    }
    if (problems[0]) {
        log_error(S, "%s: %s", function, problems);
        return fmi2Error;
    }
    return fmi2OK;
}

/* the backend's part of the value calls of fmi2_common.c (fmi2c_backend hooks; the arguments are checked) */
fmi2Status fmi2c_backend_get_real(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    return get_values((Instance *)c, "fmi2GetReal", RK_REAL, vr, nvr, value);
}

#define INT_GETTER(HOOK, F, TYPE, KIND, CONVERT)                                                            \
    fmi2Status fmi2c_backend_##HOOK(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,        \
                                    TYPE value[]) {                                                         \
        Instance *S = (Instance *)c;                                                                        \
        char problems[PROBLEMS_LEN] = "";                                                                   \
        for (size_t i = 0; i < nvr; i++) {                                                                  \
            const rk_fmu_var *v = lookup(vr[i], KIND, problems, sizeof problems);                           \
            double x = v ? S->s.values[vr[i]] : 0.0;                                                        \
            value[i] = CONVERT;                                                                             \
        }                                                                                                   \
        if (problems[0]) {                                                                                  \
            log_error(S, "fmi2" #F ": %s", problems);                                                       \
            return fmi2Error;                                                                               \
        }                                                                                                   \
        return fmi2OK;                                                                                      \
    }

INT_GETTER(get_integer, GetInteger, fmi2Integer, RK_INTEGER, to_integer(x))
INT_GETTER(get_boolean, GetBoolean, fmi2Boolean, RK_BOOLEAN, x != 0.0 ? fmi2True : fmi2False)

fmi2Status fmi2c_backend_get_string(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,
                                    fmi2String value[]) {
    Instance *S = (Instance *)c;
    char problems[PROBLEMS_LEN] = "";
    for (size_t i = 0; i < nvr; i++) {
        lookup(vr[i], RK_STRING, problems, sizeof problems);
        value[i] = "";
    }
    if (problems[0]) {
        log_error(S, "fmi2GetString: %s", problems);
        return fmi2Error;
    }
    return fmi2OK;
}

/* RockingSlave._set: every value checked, all set or none */
static fmi2Status set_values(Instance *S, const char *function, int type, const fmi2ValueReference vr[],
                             size_t nvr, const double *x) {
    char problems[PROBLEMS_LEN] = "";
    for (size_t i = 0; i < nvr; i++) {
        const rk_fmu_var *v = lookup(vr[i], type, problems, sizeof problems);
        if (!v) continue;
        char text[600];
        if (v->causality == RK_OUTPUT) {
            snprintf(text, sizeof text, "%s is an output and cannot be set", v->name);
            append(problems, sizeof problems, text);
        } else if (v->causality == RK_INPUT && v->type == RK_REAL) {
            char why[512];
            if (check_real(v->name, x[i], v, why, sizeof why)) {
                snprintf(text, sizeof text, "input %s", why);
                append(problems, sizeof problems, text);
            }
        } else if (v->causality == RK_PARAMETER && S->s.initialized && v->fixed) {
            double old = S->s.values[vr[i]];
            if (!(x[i] == old || (isnan(x[i]) && isnan(old)))) {
                char a[40], b[40];
                if (v->type == RK_REAL) {
                    py_repr(x[i], a, sizeof a);
                    py_repr(old, b, sizeof b);
                } else if (v->type == RK_BOOLEAN) {
                    snprintf(a, sizeof a, "%s", x[i] != 0.0 ? "True" : "False");
                    snprintf(b, sizeof b, "%s", old != 0.0 ? "True" : "False");
                } else {
                    snprintf(a, sizeof a, "%.0f", x[i]);
                    snprintf(b, sizeof b, "%.0f", old);
                }
                snprintf(text, sizeof text, "parameter %s is 'fixed' and cannot be changed after initialization "
                         "(requested %s, keeping %s); call fmi2Reset first to change it", v->name, a, b);
                append(problems, sizeof problems, text);
            }
        }
    }
    if (problems[0]) {
        log_error(S, "%s: %s (nothing was set)", function, problems);
        return fmi2Error;
    }
    for (size_t i = 0; i < nvr; i++) {
        S->s.values[vr[i]] = x[i];
        if (RK_FMU_VARS[vr[i]].role == RK_ROLE_INPUT) /* held until a rate is given again */
            S->s.has_rate[RK_FMU_VARS[vr[i]].index] = 0;
    }
    return fmi2OK;
}

fmi2Status fmi2c_backend_set_real(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,
                                  const fmi2Real value[]) {
    return set_values((Instance *)c, "fmi2SetReal", RK_REAL, vr, nvr, value);
}

#define INT_SETTER(HOOK, F, TYPE, KIND, CONVERT)                                                            \
    fmi2Status fmi2c_backend_##HOOK(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,        \
                                    const TYPE value[]) {                                                   \
        Instance *S = (Instance *)c;                                                                        \
        double *x = (double *)malloc(nvr * sizeof(double));                                                 \
        if (!x) {                                                                                           \
            log_error(S, "fmi2" #F ": out of memory");                                                      \
            return fmi2Error;                                                                               \
        }                                                                                                   \
        for (size_t i = 0; i < nvr; i++) x[i] = CONVERT;                                                    \
        fmi2Status status = set_values(S, "fmi2" #F, KIND, vr, nvr, x);                                     \
        free(x);                                                                                            \
        return status;                                                                                      \
    }

INT_SETTER(set_integer, SetInteger, fmi2Integer, RK_INTEGER, (double)value[i])
INT_SETTER(set_boolean, SetBoolean, fmi2Boolean, RK_BOOLEAN, value[i] != fmi2False ? 1.0 : 0.0)

fmi2Status fmi2c_backend_set_string(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,
                                    const fmi2String value[]) {
    (void)value;
    Instance *S = (Instance *)c;
    char problems[PROBLEMS_LEN] = "";
    for (size_t i = 0; i < nvr; i++) lookup(vr[i], RK_STRING, problems, sizeof problems);
    log_error(S, "fmi2SetString: %s (nothing was set)", problems[0] ? problems : "no String variables");
    return fmi2Error;
}

/* the value of the variable called `name` (a model parameter of every rocking model: g, e_N), or `fallback` */
static double value_of(const Slave *s, const char *name, double fallback) {
    for (int i = 0; i < RK_FMU_N_VARS; i++)
        if (strcmp(RK_FMU_VARS[i].name, name) == 0) return s->values[i];
    return fallback;
}

/* Simulator._diverged: the message of an advance whose motion overflowed (the engine restored its state):
 * where, and the likely cause. `peak`, `peak_v`: the bounds of |ag| and |ag_v| over the step
 * (GroundMotion.peak_bound of each component; 0 without a vertical one). */
static void diverged(Instance *S, rk_status st, double t_end, double peak, double peak_v, char *out,
                     size_t size) {
    rk_engine *e = S->engine;
    double q[RK_MAX_DOF], v[RK_MAX_DOF], qmax = 0.0, vmax = 0.0;
    int n = rk_engine_full_state(e, q, v);
    for (int i = 0; i < n; i++) {
        qmax = fmax(qmax, fabs(q[i]));
        vmax = fmax(vmax, fabs(v[i]));
    }
    const double g = value_of(&S->s, "g", 9.81), e_N = value_of(&S->s, "e_N", 0.0), t = rk_engine_time(e);
    char causes[1024] = "";
    size_t m;
    if (peak > 10.0 * g)
        snprintf(causes, sizeof causes, "the ground acceleration (|ag| up to %g m/s2, %.3g g); or ", peak, peak / g);
    if (peak_v > 10.0 * g) {
        m = strlen(causes);
        snprintf(causes + m, sizeof causes - m, "the vertical ground acceleration (|ag_v| up to %g m/s2, %.3g g); "
                 "or ", peak_v, peak_v / g);
    }
    if (e_N > 0.0) {
        m = strlen(causes);
        snprintf(causes + m, sizeof causes - m, "energy created at impacts by e_N = %g with sticking (physics "
                 "notes, section 6); or ", e_N);
    }
    m = strlen(causes);
    snprintf(causes + m, sizeof causes - m, "a state far outside the model's range (|q| up to %.3g, |v| up to %.3g "
             "at t = %.17g s)", qmax, vmax, t);
    snprintf(out, size, "the motion is not finite in the step from t = %.17g s to t_end = %.17g s (at t = %.17g s: "
             "%s: %s); the step was refused and the state kept. Likely cause: %s", t, t_end, rk_engine_fail_time(e),
             st == RK_ERR_SOLVER ? "LinAlgError" : "FloatingPointError", rk_engine_message(e), causes);
}

/* ------------------------------------------------------------------------------------------ stepping */
static void log_reports(Instance *S) {
    const rk_reports *r = rk_engine_reports(S->engine);
    if (!r || r->count <= 0) return;
    /* report_summary: per kind, how many and the first */
    char text[4096] = "";
    static const char *const KIND_TEXT[] = {"inexact contact", "failed step"};
    for (int kind = 0; kind < 2; kind++) {
        int n = 0, first = -1;
        int kept = r->count < RK_MAX_REPORTS ? r->count : RK_MAX_REPORTS;
        for (int i = 0; i < kept; i++)
            if ((int)r->items[i].kind == kind) {
                if (first < 0) first = i;
                n++;
            }
        if (n) {
            size_t m = strlen(text);
            snprintf(text + m, sizeof text - m, "%s%d %s report(s), the first: %s", m ? "; " : "", n, KIND_TEXT[kind],
                     r->items[first].message);
        }
    }
    char t[40];
    snprintf(t, sizeof t, "%.17g", rk_engine_time(S->engine));
    log_warning(S, "t = %s s: %s", t, text);
}

static int has_failed_step(const rk_engine *e, const char **first) {
    const rk_reports *r = rk_engine_reports(e);
    int kept = r ? (r->count < RK_MAX_REPORTS ? r->count : RK_MAX_REPORTS) : 0, n = 0;
    for (int i = 0; i < kept; i++)
        if (r->items[i].kind == RK_REPORT_FAILED_STEP) {
            if (!n) *first = r->items[i].message;
            n++;
        }
    return n;
}

/* the step [t, t + h] (fmi2c_backend.do_step) */
fmi2Status fmi2c_backend_do_step(fmi2c_instance *F, double t, double h) {
    Instance *S = (Instance *)F;
    const double t_end = t + h;
    Slave *s = &S->s;
    if (s->has_error || !S->engine) { /* refused before it began: fmi2DoStepStatus stays */
        log_error(S, "fmi2DoStep: RuntimeError: step refused after an earlier failure (call fmi2Reset): %s",
                  s->has_error ? s->error : "no simulator");
        return fmi2Error;
    }
    char rt[40], rte[40];
    py_repr(t, rt, sizeof rt);
    py_repr(t_end, rte, sizeof rte);
    int refused = 0;
    /* the inputs (each held, or a line after fmi2SetRealInputDerivatives) checked in order as the Python does */
    double value[RK_FMU_N_INPUTS];
    char why[1024], rv[40];
    int bad = 0, any_rate = 0;
    double peak[RK_FMU_N_INPUTS] = {0.0}; /* the bound of |ag|, |ag_v| over the step (GroundMotion.peak_bound) */
    for (int k = 0; k < RK_FMU_N_INPUTS && !bad; k++) {
        const rk_fmu_var *iv = &RK_FMU_VARS[input_var(k)];
        value[k] = s->values[input_var(k)];
        bad = check_real(iv->name, value[k], iv, why, sizeof why);
        peak[k] = fabs(value[k]);
        if (!bad && s->has_rate[k]) {
            char name[128];
            double end = value[k] + s->rate[k] * (t_end - s->rate_t[k]);
            double start = value[k] + s->rate[k] * (t - s->rate_t[k]);
            peak[k] = fmax(fabs(start), fabs(end));
            any_rate = 1;
            snprintf(name, sizeof name, "%s at the end of the step (rate %g per s)", iv->name, s->rate[k]);
            bad = check_real(name, end, iv, why, sizeof why);
            if (!bad) {
                snprintf(name, sizeof name, "%s at the start of the step (rate %g per s)", iv->name, s->rate[k]);
                bad = check_real(name, start, iv, why, sizeof why);
            }
        }
        if (bad) {
            py_repr(value[k], rv, sizeof rv);
            log_error(S, "input %s = %s at t = %s is invalid: %s", iv->name, rv, rt, why);
        }
    }
    /* the vertical input: 0 where the FMU has none (then every call is the horizontal-only one) */
    const double ag_v = RK_FMU_N_INPUTS > 1 ? value[RK_FMU_N_INPUTS - 1] : 0.0;
    const int vertical = RK_FMU_N_INPUTS > 1 && (ag_v != 0.0 || s->has_rate[RK_FMU_N_INPUTS - 1]);
    if (bad) {
        refused = 1;
#ifdef RK_FMU_NULL_STEP
    } else if (0) { /* benchmarks/standalone_fmu.py: the do-nothing FMU (the FMI layer without the engine) */
#else
    } else if (!s->frozen) {
#endif
        rk_engine *e = S->engine;
        double target = t_end > rk_engine_time(e) ? t_end : rk_engine_time(e);
        rk_engine_checkpoint(e);
        rk_status st;
        if (any_rate) {
            /* RockingSlave._do_step: a LinearMotion for an input with a rate, a number held for the others */
            rk_motion m, mv;
            if (s->has_rate[0]) rk_motion_linear(&m, value[0], s->rate[0], s->rate_t[0]);
            else rk_motion_constant(&m, value[0]);
            if (vertical) {
                const int k = RK_FMU_N_INPUTS - 1;
                if (s->has_rate[k]) rk_motion_linear(&mv, ag_v, s->rate[k], s->rate_t[k]);
                else rk_motion_constant(&mv, ag_v);
            }
            st = rk_engine_advance_motion(e, target, &m, vertical ? &mv : NULL, max_steps_of(s));
        } else {
            st = rk_engine_advance(e, target, value[0], 0.0, ag_v, 0.0, max_steps_of(s), 0u);
        }
        const char *first = NULL;
        int failures = st == RK_OK ? has_failed_step(e, &first) : 0;
        if (st == RK_OK && failures) {
            /* on_report = "raise": a failed step refuses the advance (SolverFailure), the state kept */
            log_error(S, "step [%s, %s] refused, the FMU state is unchanged: %d failed step(s) in this advance, "
                      "the first: %s", rt, rte, failures, first);
            rk_engine_rollback(e);
            refused = 1;
        } else if (st == RK_OK) {
            rk_engine_commit(e);
            log_reports(S);
            update_outputs(S);
        } else {
            rk_engine_rollback(e); /* the engine restored itself already; this drops our checkpoint */
            if (st == RK_ERR_VALUE || st == RK_ERR_WORK_LIMIT || st == RK_ERR_NONFINITE || st == RK_ERR_SOLVER) {
                /* RockingSlave._describe: a ValueError by its text, other exceptions with their class name */
                char text[3072];
                if (st == RK_ERR_NONFINITE || st == RK_ERR_SOLVER)
                    diverged(S, st, target, peak[0], vertical ? peak[RK_FMU_N_INPUTS - 1] : 0.0, text,
                             sizeof text);
                else
                    snprintf(text, sizeof text, "%s%s", st == RK_ERR_WORK_LIMIT ? "WorkLimitError: " : "",
                             rk_engine_message(e));
                log_error(S, "step [%s, %s] refused, the FMU state is unchanged: %s", rt, rte, text);
                refused = 1;
            } else {
                snprintf(s->error, sizeof s->error, "simulation failed in the step [%s, %s]: %s: %s", rt, rte,
                         rk_status_name(st), rk_engine_message(e));
                s->has_error = 1;
                log_error(S, "fmi2DoStep: RuntimeError: %s", s->error);
                return fmi2c_step_failed(F);
            }
        }
    }
    if (!refused) s->t = t_end;
    return refused ? fmi2Discard : S->f.worst_logged;
}

fmi2Status fmi2c_backend_set_real_input_derivatives(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[], const fmi2Real value[]) {
    Instance *S = (Instance *)c;
    char problems[PROBLEMS_LEN] = "";
    for (size_t i = 0; i < nvr; i++) {
        char text[600];
        const rk_fmu_var *v = lookup(vr[i], RK_REAL, problems, sizeof problems);
        if (!v) continue;
        if (v->causality != RK_INPUT) {
            snprintf(text, sizeof text, "value reference %u is '%s', not a Real input", (unsigned)vr[i], v->name);
            append(problems, sizeof problems, text);
            continue;
        }
        if (order[i] != 1) {
            snprintf(text, sizeof text, "%s: order = %d is not supported; allowed: 1", v->name, (int)order[i]);
            append(problems, sizeof problems, text);
            continue;
        }
        char name[128];
        snprintf(name, sizeof name, "rate of %s", v->name);
        if (check_real(name, value[i], &RATE_RANGE, text, sizeof text)) {
            append(problems, sizeof problems, text);
            continue;
        }
    }
    if (problems[0]) {
        log_error(S, "fmi2SetRealInputDerivatives: %s (nothing was set)", problems);
        return fmi2Error;
    }
    /* all checked: set them in order (a reference given twice: the last rate, from the line of the first) */
    Slave *s = &S->s;
    double now = s->initialized ? s->t : s->t0;
    for (size_t i = 0; i < nvr; i++) {
        const int k = RK_FMU_VARS[vr[i]].index, in = (int)vr[i];
        if (s->has_rate[k] && s->initialized) /* continue the line: the value at this point */
            s->values[in] = s->values[in] + s->rate[k] * (now - s->rate_t[k]);
        s->has_rate[k] = 1;
        s->rate[k] = value[i];
        s->rate_t[k] = now;
    }
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ FMU state */
/* The slave's bytes, field by field (no struct padding, native byte order, little-endian on every FMI
 * platform this project builds; rocking_model/fmi/standalone.py: decode_state_payload reads them):
 *   PAYLOAD_MAGIC (28 bytes, its last line the format version: 2), GUID (36),
 *   int32 n_vars, double values[n_vars] (value-reference order),
 *   int32 initialized, terminated, frozen, has_error,
 *   double t, t0,
 *   int32 n_inputs, then per Real input (ag, ag_v): int32 has_rate, double rate, rate_t,
 *   int32 error length, the error text (no NUL),
 *   int32 has_engine, then (with an engine) its plain-data state (Simulator.get_state's fields,
 *   rk_plain_state): double t, int32 mode, int32 n_y, double y[RK_MAX_Y], double q[RK_MAX_DOF],
 *   double v[RK_MAX_DOF], uint32 closed, int64 impacts, int32 overturned, int64 n_steps, double h, double
 *   shift, double friction_demand, int64 painleve;
 *   uint32 CRC-32 of all the payload's bytes before it (a corruption inside the payload is refused by itself,
 *   as the pythonfmu slave's SHA-256 does). The engine's state, not its memory: no cache keys, no
 *   stepper internals, so two instances in the same state serialize to the same bytes, and setting a state
 *   goes through rk_engine_set_state, which checks every field as Simulator.set_state does (the pythonfmu
 *   FMU restores its Simulator the same way). The FMU keeps no impact log (impact_log_size 0). */
#define PUT(q, x) (memcpy((q), &(x), sizeof(x)), (q) += sizeof(x))
#define GET(x) (memcpy(&(x), p + off, sizeof(x)), off += sizeof(x))

static size_t fixed_payload_size(void) {
    return PAYLOAD_MAGIC_SIZE + GUID_SIZE + 4 + 8 * (size_t)RK_FMU_N_VARS + 4 * 4 + 2 * 8 + 4 +
           (size_t)RK_FMU_N_INPUTS * (4 + 2 * 8) + 4;
}

#define PLAIN_SIZE (8 + 4 + 4 + 8 * RK_MAX_Y + 16 * RK_MAX_DOF + 4 + 8 + 4 + 8 + 8 * 3 + 8)

static void put_plain(unsigned char *q, const rk_plain_state *ps) {
    int32_t mode = ps->mode, n_y = ps->n_y, overturned = ps->overturned;
    uint32_t closed = ps->closed;
    int64_t impacts = ps->impacts, n_steps = ps->n_steps, painleve = ps->painleve;
    PUT(q, ps->t);
    PUT(q, mode);
    PUT(q, n_y);
    memcpy(q, ps->y, sizeof ps->y), q += sizeof ps->y;
    memcpy(q, ps->q, sizeof ps->q), q += sizeof ps->q;
    memcpy(q, ps->v, sizeof ps->v), q += sizeof ps->v;
    PUT(q, closed);
    PUT(q, impacts);
    PUT(q, overturned);
    PUT(q, n_steps);
    PUT(q, ps->h);
    PUT(q, ps->shift);
    PUT(q, ps->friction_demand);
    PUT(q, painleve);
}

static void get_plain(const unsigned char *p, rk_plain_state *ps) {
    size_t off = 0;
    int32_t mode, n_y, overturned;
    uint32_t closed;
    int64_t impacts, n_steps, painleve;
    memset(ps, 0, sizeof *ps);
    GET(ps->t);
    GET(mode);
    GET(n_y);
    memcpy(ps->y, p + off, sizeof ps->y), off += sizeof ps->y;
    memcpy(ps->q, p + off, sizeof ps->q), off += sizeof ps->q;
    memcpy(ps->v, p + off, sizeof ps->v), off += sizeof ps->v;
    GET(closed);
    GET(impacts);
    GET(overturned);
    GET(n_steps);
    GET(ps->h);
    GET(ps->shift);
    GET(ps->friction_demand);
    GET(painleve);
    ps->mode = mode, ps->n_y = n_y, ps->overturned = overturned, ps->closed = closed;
    ps->impacts = impacts, ps->n_steps = n_steps, ps->painleve = painleve;
}

static Payload *encode_slave(Instance *S) {
    const Slave *sl = &S->s;
    int32_t has_engine = S->engine != NULL;
    int32_t n_vars = RK_FMU_N_VARS, len = sl->has_error ? (int32_t)strlen(sl->error) : 0;
    int32_t flags[4] = {sl->initialized, sl->terminated, sl->frozen, sl->has_error};
    double times[2] = {sl->t, sl->t0};
    int32_t n_inputs = RK_FMU_N_INPUTS;
    const size_t n = fixed_payload_size() + (size_t)len + 4 + (has_engine ? PLAIN_SIZE : 0) + 4; /* + CRC-32 */
    Payload *pl = (Payload *)calloc(1, sizeof(Payload) + n);
    if (!pl) return NULL;
    pl->n = n;
    unsigned char *p = pl->bytes, *q = p;
    memcpy(q, PAYLOAD_MAGIC, PAYLOAD_MAGIC_SIZE);
    q += PAYLOAD_MAGIC_SIZE;
    memcpy(q, RK_FMU_GUID, GUID_SIZE);
    q += GUID_SIZE;
    PUT(q, n_vars);
    memcpy(q, sl->values, sizeof sl->values);
    q += sizeof sl->values;
    PUT(q, flags);
    PUT(q, times);
    PUT(q, n_inputs);
    for (int k = 0; k < RK_FMU_N_INPUTS; k++) {
        int32_t has_rate = sl->has_rate[k];
        PUT(q, has_rate);
        PUT(q, sl->rate[k]);
        PUT(q, sl->rate_t[k]);
    }
    PUT(q, len);
    memcpy(q, sl->error, (size_t)len);
    q += len;
    PUT(q, has_engine);
    if (has_engine) {
        rk_plain_state ps;
        memset(&ps, 0, sizeof ps);
        rk_engine_get_state(S->engine, &ps);
        put_plain(q, &ps);
        q += PLAIN_SIZE;
    }
    uint32_t crc = fmi2c_crc32_update(0, p, n - 4);
    memcpy(q, &crc, 4);
    return pl;
}

/* Check the slave's bytes and set them (RockingSlave._restore): nothing changes unless all is valid. */
static int decode_slave(Instance *S, const unsigned char *p, size_t n, char *why, size_t size) {
    if (n < fixed_payload_size() + 8 || memcmp(p, PAYLOAD_MAGIC, PAYLOAD_MAGIC_SIZE) != 0) {
        snprintf(why, size, "bad header: the %zu bytes are not a state of the C engine FMU (format version 2)", n);
        return -1;
    }
    uint32_t crc;
    memcpy(&crc, p + n - 4, 4);
    if (crc != fmi2c_crc32_update(0, p, n - 4)) {
        snprintf(why, size, "the engine FMU state is corrupted (CRC-32 mismatch of its %zu payload bytes)", n - 4);
        return -1;
    }
    n -= 4;
    if (memcmp(p + PAYLOAD_MAGIC_SIZE, RK_FMU_GUID, GUID_SIZE) != 0) {
        snprintf(why, size, "the state belongs to another FMU (or to another version of its variables), not to '%s'",
                 RK_FMU_NAME);
        return -1;
    }
    size_t off = PAYLOAD_MAGIC_SIZE + GUID_SIZE;
    int32_t n_vars, flags[4], len, has_engine, n_inputs, has_rate[RK_FMU_N_INPUTS];
    double times[2];
    Slave s;
    memset(&s, 0, sizeof s);
    GET(n_vars);
    if (n_vars != RK_FMU_N_VARS) {
        snprintf(why, size, "the state has %d variables, %s has %d", (int)n_vars, RK_FMU_NAME, RK_FMU_N_VARS);
        return -1;
    }
    memcpy(s.values, p + off, sizeof s.values);
    off += sizeof s.values;
    GET(flags);
    GET(times);
    GET(n_inputs);
    if (n_inputs != RK_FMU_N_INPUTS) {
        snprintf(why, size, "the state has %d inputs, %s has %d", (int)n_inputs, RK_FMU_NAME, RK_FMU_N_INPUTS);
        return -1;
    }
    for (int k = 0; k < RK_FMU_N_INPUTS; k++) {
        GET(has_rate[k]);
        GET(s.rate[k]);
        GET(s.rate_t[k]);
        s.has_rate[k] = has_rate[k];
    }
    GET(len);
    if (len < 0 || len >= ERROR_LEN || off + (size_t)len + 4 > n) {
        snprintf(why, size, "state field slave.error has an invalid length");
        return -1;
    }
    memcpy(s.error, p + off, (size_t)len);
    off += (size_t)len;
    s.initialized = flags[0], s.terminated = flags[1], s.frozen = flags[2], s.has_error = flags[3];
    s.t = times[0], s.t0 = times[1];
    GET(has_engine);
    if (!(has_engine == 0 || has_engine == 1) || n - off != (has_engine ? (size_t)PLAIN_SIZE : 0)) {
        snprintf(why, size, "the engine state has %zu bytes, expected %d", n - off, has_engine ? PLAIN_SIZE : 0);
        return -1;
    }
    int flags_ok = (s.initialized == 0 || s.initialized == 1) && (s.terminated == 0 || s.terminated == 1) &&
                   (s.frozen == 0 || s.frozen == 1) && (s.has_error == 0 || s.has_error == 1) &&
                   isfinite(s.t) && isfinite(s.t0);
    for (int k = 0; k < RK_FMU_N_INPUTS; k++)
        flags_ok = flags_ok && (s.has_rate[k] == 0 || s.has_rate[k] == 1) && isfinite(s.rate[k]) &&
                   isfinite(s.rate_t[k]) && fabs(s.rate[k]) <= RK_FMU_INPUT_RATE_MAX;
    if (!flags_ok) {
        snprintf(why, size, "state fields of the slave are invalid");
        return -1;
    }
    for (int i = 0; i < RK_FMU_N_VARS; i++) {
        const rk_fmu_var *v = &RK_FMU_VARS[i];
        double x = s.values[i];
        int okv = v->type == RK_REAL ||
                  (v->type == RK_INTEGER && x == floor(x) && x >= -2147483648.0 && x <= 2147483647.0) ||
                  (v->type == RK_BOOLEAN && (x == 0.0 || x == 1.0));
        if (!okv) {
            snprintf(why, size, "state value of %s = %g is not a %s", v->name, x, TYPE_NAMES[v->type]);
            return -1;
        }
    }
    rk_engine *e = NULL;
    if (has_engine) {
        char reason[RK_MSG_LEN + 128];
        rk_plain_state ps;
        get_plain(p + off, &ps);
        e = create_engine(s.values, s.t0, reason, sizeof reason);
        if (!e) {
            snprintf(why, size, "%s", reason);
            return -1;
        }
        if (rk_engine_set_state(e, &ps, NULL, 0, NULL, 0) != RK_OK) {
            snprintf(why, size, "%s", rk_engine_message(e));
            rk_engine_free(e);
            return -1;
        }
    } else if (s.initialized && !s.has_error) {
        snprintf(why, size, "state field simulator is null in an initialized state without an error");
        return -1;
    }
    rk_engine_free(S->engine);
    S->engine = e;
    S->s = s;
    return 0;
}

/* the backend's part of the FMU state calls of fmi2_common.c: `data` is a Payload */
fmi2Status fmi2c_backend_save_state(fmi2c_instance *F, const char *function, void **data) {
    Instance *S = (Instance *)F;
    Payload *pl = encode_slave(S);
    if (!pl) {
        log_error(S, "%s: out of memory", function);
        return fmi2Error;
    }
    *data = pl;
    return fmi2OK;
}

fmi2Status fmi2c_backend_restore_state(fmi2c_instance *F, const char *function, void *data) {
    Instance *S = (Instance *)F;
    const Payload *pl = (const Payload *)data;
    char why[2048];
    if (decode_slave(S, pl->bytes, pl->n, why, sizeof why) != 0) {
        log_error(S, "%s: state rejected, the instance keeps its current state: %s", function, why);
        return fmi2Error;
    }
    return fmi2OK;
}

void fmi2c_backend_free_state(fmi2c_instance *F, void *data) {
    (void)F;
    free(data);
}

fmi2Status fmi2c_backend_state_bytes(fmi2c_instance *F, const char *function, void *data, const unsigned char **bytes,
                              size_t *n, void **hold) {
    (void)F; (void)function;
    const Payload *pl = (const Payload *)data;
    *bytes = pl->bytes;
    *n = pl->n;
    *hold = NULL;
    return fmi2OK;
}

void fmi2c_backend_release_bytes(fmi2c_instance *F, void *hold) { (void)F; (void)hold; }

fmi2Status fmi2c_backend_state_from_bytes(fmi2c_instance *F, const char *function, const unsigned char *bytes, size_t n,
                                   void **data) {
    Payload *pl = (Payload *)malloc(sizeof(Payload) + n);
    if (!pl) {
        log_error((Instance *)F, "%s: out of memory", function);
        return fmi2Error;
    }
    pl->n = n;
    memcpy(pl->bytes, bytes, n);
    *data = pl;
    return fmi2OK;
}
