/* The FMI 2.0 plumbing shared by fmi2_cs.c and standalone/fmi2_engine.c (fmi2_common.h): messages, state
 * checks, status bookkeeping, the serialized state's header, and every FMI call but fmi2Instantiate, each
 * written once over the backend's hooks (fmi2c_backend_*). */
#include "rk_fp.h" /* first: the engine's floating-point contract, no contraction into multiply-adds */
#define FMI2C_IMPLEMENTATION /* none of the backends' shorthands */
#include "fmi2_common.h"
#include "uri.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* [s] tolerance on currentCommunicationPoint against the instance's time, relative to max(1, |time|): the
 * master's time is a sum of step sizes and may differ from ours by round-off */
#define TIME_TOLERANCE 1e-9

enum {
    INSTANTIATED = 1 << 0,
    INITIALIZATION_MODE = 1 << 1,
    STEP_COMPLETE = 1 << 2,
    STEP_FAILED = 1 << 3, /* the last doStep was discarded */
    TERMINATED = 1 << 4,
    ERROR_STATE = 1 << 5,
    FATAL_STATE = 1 << 6,
};
#define ANY_STATE (INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR_STATE | FATAL_STATE)
#define SIMULATING (STEP_COMPLETE | STEP_FAILED)

/* states in which each call is allowed (after modelica/Reference-FMUs, src/fmi2Functions.c) */
#define MASK_SetupExperiment INSTANTIATED
#define MASK_EnterInitializationMode INSTANTIATED
#define MASK_ExitInitializationMode INITIALIZATION_MODE
#define MASK_Terminate (SIMULATING | ERROR_STATE)
#define MASK_Reset (ANY_STATE & ~FATAL_STATE)
#define MASK_SetDebugLogging (ANY_STATE & ~FATAL_STATE)
#define MASK_Get (INITIALIZATION_MODE | SIMULATING | TERMINATED | ERROR_STATE)
#define MASK_Set (INSTANTIATED | INITIALIZATION_MODE | SIMULATING)
#define MASK_GetFMUstate (INSTANTIATED | INITIALIZATION_MODE | SIMULATING | TERMINATED)
#define MASK_SetFMUstate (MASK_GetFMUstate | ERROR_STATE)
#define MASK_FreeFMUstate ANY_STATE
#define MASK_SetRealInputDerivatives (INSTANTIATED | INITIALIZATION_MODE | SIMULATING)
#define MASK_GetRealOutputDerivatives (SIMULATING | TERMINATED)
#define MASK_DoStep SIMULATING
#define MASK_Status (SIMULATING | TERMINATED | ERROR_STATE)

#define log_error(F, ...) fmi2c_logf(F, fmi2Error, "logStatusError", __VA_ARGS__)

/* Entering call F (allowed in the states MASK_F): S is the instance (the FMI part) */
#define BEGIN(F)                                                                                            \
    fmi2c_instance *S = (fmi2c_instance *)c;                                                                \
    if (!valid(S)) return fmi2Error;                                                                        \
    S->worst_logged = fmi2OK;                                                                               \
    if (!(S->state & MASK_##F)) return illegal(S, "fmi2" #F)

#define NOT_NULL(F, p)                                                                                      \
    if (!(p)) {                                                                                             \
        log_error(S, "fmi2" #F ": argument " #p " is NULL");                                                \
        return fail(S, fmi2Error);                                                                          \
    }

static const char *state_name(int state) {
    switch (state) {
    case INSTANTIATED: return "instantiated";
    case INITIALIZATION_MODE: return "in initialization mode";
    case STEP_COMPLETE: return "simulating (step complete)";
    case STEP_FAILED: return "simulating (last step discarded)";
    case TERMINATED: return "terminated";
    case ERROR_STATE: return "in the error state (call fmi2Reset or fmi2FreeInstance)";
    default: return "in the fatal state (only fmi2FreeInstance is allowed)";
    }
}

static int valid(const void *c) { return c && ((const fmi2c_instance *)c)->magic == FMI2C_INSTANCE_MAGIC; }

/* ------------------------------------------------------------------------------------------ messages */
/* Whether fmi2SetDebugLogging enabled `category`: every category when it named none (or was never called) or
 * named logAll ("Log all messages"), else the ones it named. Only messages of status fmi2OK (the events of
 * logEvents) are filtered: with logging on and their category enabled; warnings and worse always pass. */
static int category_enabled(const fmi2c_instance *F, const char *category) {
    if (F->n_categories == 0) return 1;
    for (size_t i = 0; i < F->n_categories; i++)
        if (strcmp(F->categories[i], "logAll") == 0 || (category && strcmp(F->categories[i], category) == 0))
            return 1;
    return 0;
}

void fmi2c_emit(fmi2c_instance *F, fmi2Status status, const char *category, const char *text) {
    if (status > F->worst_logged && status <= fmi2Warning) F->worst_logged = status;
    if (!F->logger) return;
    if (status == fmi2OK && !(F->logging_on && category_enabled(F, category))) return;
    F->logger(F->env, F->name, status, category ? category : "logAll", "%s", text ? text : "");
}

void fmi2c_logf(fmi2c_instance *F, fmi2Status status, const char *category, const char *format, ...) {
    char text[FMI2C_MESSAGE_MAX];
    size_t size = F->message_size > 0 && F->message_size < sizeof text ? F->message_size : sizeof text;
    va_list args;
    va_start(args, format);
    vsnprintf(text, size, format, args);
    va_end(args);
    fmi2c_emit(F, status, category, text);
}

static fmi2Status illegal(fmi2c_instance *F, const char *function) {
    fmi2c_logf(F, fmi2Error, "logStatusError", "%s: illegal call sequence: the instance is %s", function,
               state_name(F->state));
    if (F->state != FATAL_STATE) F->state = ERROR_STATE;
    return fmi2Error;
}

static fmi2Status fail(fmi2c_instance *F, fmi2Status status) {
    if (status == fmi2Error) F->state = ERROR_STATE;
    if (status == fmi2Fatal) F->state = FATAL_STATE;
    return status;
}

static void free_categories(fmi2c_instance *F) {
    for (size_t i = 0; i < F->n_categories; i++) free(F->categories[i]);
    free(F->categories);
    F->categories = NULL;
    F->n_categories = 0;
}

static fmi2Status check_step(fmi2c_instance *F, double t, double h) {
    if (!(h > 0.0) || !isfinite(h)) {
        log_error(F, "fmi2DoStep: communicationStepSize = %g is invalid; allowed range (0, inf)", h);
        return fail(F, fmi2Error);
    }
    if (!isfinite(t) || fabs(t - F->time) > TIME_TOLERANCE * fmax(1.0, fabs(F->time))) {
        log_error(F, "fmi2DoStep: currentCommunicationPoint = %.17g does not match the time of the instance, "
                  "%.17g; each step starts where the last one ended (to go back, restore a state saved with "
                  "fmi2GetFMUstate)", t, F->time);
        return fail(F, fmi2Error);
    }
    if (!isfinite(t + h)) {
        log_error(F, "fmi2DoStep: currentCommunicationPoint + communicationStepSize = %g is not finite", t + h);
        return fail(F, fmi2Error);
    }
    return fmi2OK;
}

fmi2Status fmi2c_step_failed(fmi2c_instance *F) {
    F->last_step_status = fmi2Error;
    return fmi2Error;
}

static fmi2Status check_setup(fmi2c_instance *F, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                              fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    if (!isfinite(startTime)) {
        log_error(F, "fmi2SetupExperiment: startTime = %g is invalid; allowed range: finite values", startTime);
        return fail(F, fmi2Error);
    }
    if (stopTimeDefined && !(stopTime >= startTime)) {
        log_error(F, "fmi2SetupExperiment: stopTime = %g is invalid; allowed range: [startTime = %g, inf]",
                  stopTime, startTime);
        return fail(F, fmi2Error);
    }
    if (toleranceDefined && !(tolerance > 0.0 && isfinite(tolerance))) {
        log_error(F, "fmi2SetupExperiment: tolerance = %g is invalid; allowed range: (0, inf)", tolerance);
        return fail(F, fmi2Error);
    }
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ life cycle */
void fmi2c_instantiate_error(const fmi2CallbackFunctions *functions, fmi2String name, const char *format, ...) {
    if (!functions || !functions->logger) return;
    char text[2048];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    functions->logger(functions->componentEnvironment, name ? name : "", fmi2Error, "logStatusError", "%s", text);
}

int fmi2c_check_instantiate(const fmi2CallbackFunctions *functions, fmi2String instanceName, fmi2Type fmuType,
                            fmi2String fmuGUID) {
    if (!instanceName || !instanceName[0]) {
        fmi2c_instantiate_error(functions, instanceName, "fmi2Instantiate: instanceName is NULL or empty");
        return -1;
    }
    if (fmuType != fmi2CoSimulation) {
        fmi2c_instantiate_error(functions, instanceName, "fmi2Instantiate: fmuType = %d is not supported; this FMU "
                                "implements co-simulation only (fmi2CoSimulation = %d)", (int)fmuType,
                                (int)fmi2CoSimulation);
        return -1;
    }
    if (!fmuGUID) {
        fmi2c_instantiate_error(functions, instanceName, "fmi2Instantiate: fmuGUID is NULL");
        return -1;
    }
    return 0;
}

int fmi2c_resource_folder(const fmi2CallbackFunctions *functions, fmi2String instanceName, fmi2String location,
                          char *resources, size_t size, int (*is_directory)(const char *),
                          int (*is_file)(const char *), const char *required) {
    char why[2048];
    if (uri_to_path(location, resources, size, why, sizeof why) != 0) {
        fmi2c_instantiate_error(functions, instanceName, "fmi2Instantiate: %s", why);
        return -1;
    }
    int has_required = 1;
    if (required) {
        char path[4200];
        snprintf(path, sizeof path, "%s/%s", resources, required);
        has_required = is_file(path);
    }
    if (!is_directory(resources) || !has_required) {
        char problem[256];
        if (is_directory(resources))
            snprintf(problem, sizeof problem, "has no %s (not an FMU of this binary?)", required);
        else
            snprintf(problem, sizeof problem, "does not exist or is not a folder");
        fmi2c_instantiate_error(functions, instanceName, "fmi2Instantiate: the resource folder %s (from "
                                "fmuResourceLocation \"%.500s\") %s", resources, location, problem);
        return -1;
    }
    return 0;
}

void *fmi2c_new_instance(size_t size, const fmi2CallbackFunctions *functions, fmi2String instanceName,
                         fmi2Boolean loggingOn, size_t message_size) {
    fmi2c_instance *F = (fmi2c_instance *)calloc(1, size);
    if (!F || !(F->name = (char *)malloc(strlen(instanceName) + 1))) {
        free(F);
        fmi2c_instantiate_error(functions, instanceName, "fmi2Instantiate: out of memory");
        return NULL;
    }
    strcpy(F->name, instanceName);
    F->magic = FMI2C_INSTANCE_MAGIC;
    F->message_size = message_size;
    F->state = INSTANTIATED;
    F->logger = functions ? functions->logger : NULL;
    F->env = functions ? functions->componentEnvironment : NULL;
    F->logging_on = loggingOn ? 1 : 0;
    F->last_step_status = fmi2OK;
    return F;
}

void fmi2c_destroy(fmi2c_instance *F) {
    free_categories(F);
    F->magic = 0;
    free(F->name);
    free(F);
}

static fmi2c_fields fields_of(const fmi2c_instance *F) {
    fmi2c_fields fields = {F->state, F->time, F->terminated_flag, F->last_step_status};
    return fields;
}

static void restore_fields(fmi2c_instance *F, const fmi2c_fields *fields) {
    F->state = fields->instance_state;
    F->time = fields->time;
    F->terminated_flag = fields->terminated_flag;
    F->last_step_status = fields->last_step_status;
}

/* ------------------------------------------------------------------------------------------ FMI calls */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

void fmi2FreeInstance(fmi2Component c) {
    fmi2c_instance *F = (fmi2c_instance *)c;
    if (!valid(F)) return;
    fmi2c_backend_free_instance(F);
    fmi2c_destroy(F);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    BEGIN(SetupExperiment);
    if (check_setup(S, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime) != fmi2OK)
        return fmi2Error;
    fmi2Status status = fmi2c_backend_setup_experiment(S, toleranceDefined, tolerance, startTime, stopTimeDefined,
                                                       stopTime);
    if (status == fmi2Error) return fail(S, status);
    S->time = startTime;
    return status;
}

/* The end of a life-cycle call whose hook returned `status`: the error state on fmi2Error, else the state
 * `next`; entering the simulation or going back to the start, no step is done yet (fmi2Terminated false,
 * fmi2DoStepStatus fmi2OK), and a reset instance is at time 0. */
static fmi2Status move_to(fmi2c_instance *S, fmi2Status status, int next) {
    if (status == fmi2Error) return fail(S, status);
    S->state = next;
    if (next == STEP_COMPLETE || next == INSTANTIATED) {
        S->terminated_flag = 0;
        S->last_step_status = fmi2OK;
    }
    if (next == INSTANTIATED) S->time = 0.0;
    return status;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    BEGIN(EnterInitializationMode);
    return move_to(S, fmi2c_backend_enter_initialization_mode(S), INITIALIZATION_MODE);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    BEGIN(ExitInitializationMode);
    return move_to(S, fmi2c_backend_exit_initialization_mode(S), STEP_COMPLETE);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    BEGIN(Terminate);
    if (S->state == ERROR_STATE) return fmi2OK; /* nothing to end; the instance stays in the error state */
    return move_to(S, fmi2c_backend_terminate(S), TERMINATED);
}

fmi2Status fmi2Reset(fmi2Component c) {
    BEGIN(Reset);
    return move_to(S, fmi2c_backend_reset(S), INSTANTIATED);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    BEGIN(DoStep);
    const double t = currentCommunicationPoint, h = communicationStepSize;
    if (check_step(S, t, h) != fmi2OK) return fmi2Error;
    fmi2Status status = fmi2c_backend_do_step(S, t, h);
    if (status == fmi2Error) return fail(S, status);
    if (status == fmi2Discard) { /* refused: fmi2Terminated true until a later step succeeds, the time kept */
        S->state = STEP_FAILED;
        S->terminated_flag = 1;
    } else {
        S->state = STEP_COMPLETE;
        S->terminated_flag = 0;
        S->time = t + h;
    }
    S->last_step_status = status;
    return status;
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    BEGIN(SetDebugLogging);
    if (nCategories > 0) NOT_NULL(SetDebugLogging, categories);
    for (size_t i = 0; i < nCategories; i++) NOT_NULL(SetDebugLogging, categories[i]);
    free_categories(S);
    if (nCategories > 0) {
        S->categories = (char **)calloc(nCategories, sizeof(char *));
        if (!S->categories) return fail(S, fmi2Error);
        for (size_t i = 0; i < nCategories; i++) {
            S->categories[i] = (char *)malloc(strlen(categories[i]) + 1);
            if (!S->categories[i]) {
                S->n_categories = i;
                return fail(S, fmi2Error);
            }
            strcpy(S->categories[i], categories[i]);
        }
    }
    S->n_categories = nCategories;
    S->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    fmi2c_instance *S = (fmi2c_instance *)c;
    if (!valid(S)) return fmi2Error;
    log_error(S, "fmi2CancelStep: no step is in progress (fmi2DoStep never returns fmi2Pending)");
    return fail(S, fmi2Error);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)order; (void)value;
    BEGIN(GetRealOutputDerivatives);
    if (nvr == 0) return fmi2OK;
    log_error(S, "fmi2GetRealOutputDerivatives: output derivatives are not provided (maxOutputDerivativeOrder "
              "= 0)");
    return fail(S, fmi2Error);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    fmi2c_instance *S = (fmi2c_instance *)c;
    if (!valid(S)) return fmi2Error;
    log_error(S, "fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative = false)");
    return fail(S, fmi2Error);
}

/* ------------------------------------------------------------------------------------------ values */
/* fmi2Get<Type> and fmi2Set<Type>, one per type as FMI 2.0 declares them: nothing to do for nvr = 0, else
 * neither array may be NULL; the backend's hook does the rest */
#define VALUE_CALL(F, MASK, HOOK, TYPE)                                                                     \
    fmi2Status fmi2##F(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, TYPE value[]) {        \
        BEGIN(MASK);                                                                  \
        if (nvr == 0) return fmi2OK;                                                                        \
        NOT_NULL(F, vr);                                                                              \
        NOT_NULL(F, value);                                                                           \
        fmi2Status status = fmi2c_backend_##HOOK(S, vr, nvr, value);                                        \
        return status == fmi2Error ? fail(S, status) : status;                                        \
    }

VALUE_CALL(GetReal, Get, get_real, fmi2Real)
VALUE_CALL(GetInteger, Get, get_integer, fmi2Integer)
VALUE_CALL(GetBoolean, Get, get_boolean, fmi2Boolean)
VALUE_CALL(GetString, Get, get_string, fmi2String)
VALUE_CALL(SetReal, Set, set_real, const fmi2Real)
VALUE_CALL(SetInteger, Set, set_integer, const fmi2Integer)
VALUE_CALL(SetBoolean, Set, set_boolean, const fmi2Boolean)
VALUE_CALL(SetString, Set, set_string, const fmi2String)

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    BEGIN(SetRealInputDerivatives);
    if (nvr == 0) return fmi2OK;
    NOT_NULL(SetRealInputDerivatives, vr);
    NOT_NULL(SetRealInputDerivatives, order);
    NOT_NULL(SetRealInputDerivatives, value);
    fmi2Status status = fmi2c_backend_set_real_input_derivatives(S, vr, nvr, order, value);
    return status == fmi2Error ? fail(S, status) : status;
}

/* ------------------------------------------------------------------------------------------ status */
/* fmi2Get<Type>Status, one per type as FMI 2.0 declares them (alike in shape only): each answers the one
 * status kind this FMU has of its type -- fmi2DoStepStatus, fmi2LastSuccessfulTime, fmi2Terminated -- and
 * fmi2Discard for any other kind */
static fmi2Status unavailable(fmi2c_instance *S, const char *function, int kind) {
    fmi2c_logf(S, fmi2Discard, "logStatusDiscard", "%s: status kind %d is not available from this FMU", function,
               kind);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    BEGIN(Status);
    NOT_NULL(GetStatus, value);
    if (s != fmi2DoStepStatus) return unavailable(S, "fmi2GetStatus", (int)s);
    *value = S->last_step_status;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    BEGIN(Status);
    NOT_NULL(GetRealStatus, value);
    if (s != fmi2LastSuccessfulTime) return unavailable(S, "fmi2GetRealStatus", (int)s);
    *value = S->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    BEGIN(Status);
    NOT_NULL(GetIntegerStatus, value);
    return unavailable(S, "fmi2GetIntegerStatus", (int)s);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    BEGIN(Status);
    NOT_NULL(GetBooleanStatus, value);
    if (s != fmi2Terminated) return unavailable(S, "fmi2GetBooleanStatus", (int)s);
    *value = S->terminated_flag ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    BEGIN(Status);
    NOT_NULL(GetStringStatus, value);
    return unavailable(S, "fmi2GetStringStatus", (int)s);
}

/* ------------------------------------------------------------------------------------------ state header */
uint32_t fmi2c_crc32_update(uint32_t crc, const unsigned char *p, size_t n) {
    crc = ~crc;
    while (n--) {
        crc ^= *p++;
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

static uint32_t serial_crc(const unsigned char *header, const unsigned char *payload, size_t n) {
    return fmi2c_crc32_update(fmi2c_crc32_update(0, header, SERIAL_CRC_OFFSET), payload, n);
}

static void write_header(unsigned char *p, const fmi2c_fields *fields, const unsigned char *payload, size_t n) {
    int32_t ints[3] = {fields->instance_state, fields->terminated_flag, (int32_t)fields->last_step_status};
    memcpy(p, SERIAL_MAGIC, SERIAL_MAGIC_SIZE);
    memcpy(p + SERIAL_MAGIC_SIZE, &fields->time, 8);
    memcpy(p + SERIAL_MAGIC_SIZE + 8, ints, sizeof ints);
    uint32_t crc = serial_crc(p, payload, n);
    memcpy(p + SERIAL_CRC_OFFSET, &crc, 4);
}

static fmi2Status read_header(fmi2c_instance *F, const fmi2Byte serialized[], size_t size, fmi2c_fields *fields) {
    int32_t header[3];
    double time;
    if (size < SERIAL_HEADER_SIZE || memcmp(serialized, SERIAL_MAGIC, SERIAL_MAGIC_SIZE) != 0) {
        log_error(F, "fmi2DeSerializeFMUstate: the %zu bytes are not a serialized state of this FMU", size);
        return fail(F, fmi2Error);
    }
    uint32_t crc;
    memcpy(&crc, serialized + SERIAL_CRC_OFFSET, 4);
    if (crc != serial_crc((const unsigned char *)serialized,
                          (const unsigned char *)serialized + SERIAL_HEADER_SIZE, size - SERIAL_HEADER_SIZE)) {
        log_error(F, "fmi2DeSerializeFMUstate: state rejected, the instance keeps its current state: the %zu "
                  "bytes are corrupted (CRC-32 mismatch)", size);
        return fail(F, fmi2Error);
    }
    memcpy(&time, serialized + SERIAL_MAGIC_SIZE, 8);
    memcpy(header, serialized + SERIAL_MAGIC_SIZE + 8, sizeof header);
    const int allowed = INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | STEP_FAILED | TERMINATED;
    int single_state = header[0] > 0 && (header[0] & (header[0] - 1)) == 0;
    if (!isfinite(time) || !single_state || !(header[0] & allowed) || (header[1] != 0 && header[1] != 1) ||
        header[2] < fmi2OK || header[2] > fmi2Discard) {
        log_error(F, "fmi2DeSerializeFMUstate: the header of the serialized state is corrupt");
        return fail(F, fmi2Error);
    }
    fields->instance_state = header[0];
    fields->time = time;
    fields->terminated_flag = header[1];
    fields->last_step_status = (fmi2Status)header[2];
    return fmi2OK;
}


/* ------------------------------------------------------------------------------------------ FMU state */
/* a saved FMU state: the FMI part and the backend's part */
typedef struct {
    unsigned magic; /* FMI2C_STATE_MAGIC while the state lives */
    fmi2c_fields fields;
    void *data;
} saved_state;

static saved_state *saved(fmi2c_instance *F, const char *function, fmi2FMUstate p) {
    saved_state *st = (saved_state *)p;
    if (!st || st->magic != FMI2C_STATE_MAGIC || !st->data) {
        log_error(F, "%s: the FMU state is NULL or not a state of this FMU (freed already?)", function);
        return NULL;
    }
    return st;
}

/* Put the backend's `data` with the FMI fields into `st` (a new state when NULL) and hand it out through
 * `out`; fmi2Error logged (`data` freed) when out of memory. */
static fmi2Status keep_state(fmi2c_instance *F, const char *function, saved_state *st, void *data,
                             const fmi2c_fields *fields, fmi2FMUstate *out) {
    if (!st) st = (saved_state *)calloc(1, sizeof(saved_state));
    if (!st) {
        log_error(F, "%s: out of memory", function);
        fmi2c_backend_free_state(F, data);
        return fmi2Error;
    }
    if (st->data) fmi2c_backend_free_state(F, st->data);
    st->fields = *fields;
    st->magic = FMI2C_STATE_MAGIC;
    st->data = data;
    *out = st;
    return fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    BEGIN(GetFMUstate);
    NOT_NULL(GetFMUstate, FMUstate);
    saved_state *st = NULL;
    if (*FMUstate) { /* FMI 2.0: a non-NULL state is overwritten */
        st = saved(S, "fmi2GetFMUstate", *FMUstate);
        if (!st) return fail(S, fmi2Error);
    }
    void *data = NULL;
    fmi2Status status = fmi2c_backend_save_state(S, "fmi2GetFMUstate", &data);
    const fmi2c_fields fields = fields_of(S);
    if (status != fmi2Error && keep_state(S, "fmi2GetFMUstate", st, data, &fields, FMUstate) != fmi2OK)
        status = fmi2Error;
    return status == fmi2Error ? fail(S, status) : status;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    BEGIN(SetFMUstate);
    saved_state *st = saved(S, "fmi2SetFMUstate", FMUstate);
    if (!st) return fail(S, fmi2Error);
    fmi2Status status = fmi2c_backend_restore_state(S, "fmi2SetFMUstate", st->data);
    if (status == fmi2Error) return fail(S, status); /* rejected: the instance kept its state */
    restore_fields(S, &st->fields);
    return status;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    BEGIN(FreeFMUstate);
    if (!FMUstate || !*FMUstate) return fmi2OK;
    saved_state *st = saved(S, "fmi2FreeFMUstate", *FMUstate);
    if (!st) return fail(S, fmi2Error);
    fmi2c_backend_free_state(S, st->data);
    st->data = NULL;
    st->magic = 0;
    free(st);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    BEGIN(SetFMUstate);
    NOT_NULL(SerializedFMUstateSize, size);
    saved_state *st = saved(S, "fmi2SerializedFMUstateSize", FMUstate);
    if (!st) return fail(S, fmi2Error);
    const unsigned char *bytes = NULL;
    size_t n = 0;
    void *hold = NULL;
    fmi2Status status = fmi2c_backend_state_bytes(S, "fmi2SerializedFMUstateSize", st->data, &bytes, &n, &hold);
    if (status == fmi2Error) return fail(S, status);
    *size = SERIAL_HEADER_SIZE + n;
    fmi2c_backend_release_bytes(S, hold);
    return status;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    BEGIN(SetFMUstate);
    NOT_NULL(SerializeFMUstate, serializedState);
    saved_state *st = saved(S, "fmi2SerializeFMUstate", FMUstate);
    if (!st) return fail(S, fmi2Error);
    const unsigned char *bytes = NULL;
    size_t n = 0;
    void *hold = NULL;
    fmi2Status status = fmi2c_backend_state_bytes(S, "fmi2SerializeFMUstate", st->data, &bytes, &n, &hold);
    if (status == fmi2Error) return fail(S, status);
    if (size != SERIAL_HEADER_SIZE + n) {
        log_error(S, "fmi2SerializeFMUstate: size = %zu does not match the serialized size %zu (from "
                  "fmi2SerializedFMUstateSize)", size, SERIAL_HEADER_SIZE + n);
        status = fmi2Error;
    } else {
        unsigned char *p = (unsigned char *)serializedState;
        memcpy(p + SERIAL_HEADER_SIZE, bytes, n);
        write_header(p, &st->fields, bytes, n);
    }
    fmi2c_backend_release_bytes(S, hold);
    return status == fmi2Error ? fail(S, status) : status;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    BEGIN(SetFMUstate);
    NOT_NULL(DeSerializeFMUstate, serializedState);
    NOT_NULL(DeSerializeFMUstate, FMUstate);
    fmi2c_fields fields;
    if (read_header(S, serializedState, size, &fields) != fmi2OK) return fmi2Error;
    saved_state *st = NULL;
    if (*FMUstate) {
        st = saved(S, "fmi2DeSerializeFMUstate", *FMUstate);
        if (!st) return fail(S, fmi2Error);
    }
    void *data = NULL;
    fmi2Status status = fmi2c_backend_state_from_bytes(S, "fmi2DeSerializeFMUstate",
                                                       (const unsigned char *)serializedState + SERIAL_HEADER_SIZE,
                                                       size - SERIAL_HEADER_SIZE, &data);
    if (status != fmi2Error && keep_state(S, "fmi2DeSerializeFMUstate", st, data, &fields, FMUstate) != fmi2OK)
        status = fmi2Error;
    return status == fmi2Error ? fail(S, status) : status;
}
