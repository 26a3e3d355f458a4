/* The FMI 2.0 co-simulation plumbing shared by the two binaries: fmi2_cs.c (the pythonfmu FMUs, a Python
 * slave) and standalone/fmi2_engine.c (the self-contained FMUs, the C engine). fmi2_common.c defines every
 * FMI function but fmi2Instantiate: the instance states and the per-call state masks (after
 * modelica/Reference-FMUs, src/fmi2Functions.c), the call-allowed and argument checks, the messages (always
 * passed to the logger as data, "%s"), the status bookkeeping (fmi2Terminated, fmi2LastSuccessfulTime,
 * fmi2DoStepStatus) and the FMU states with the serialized form's header and its CRC-32; what differs, each
 * backend does in its hooks (fmi2c_backend_*, below). Each backend's Instance starts with an `fmi2c_instance`
 * named `f`. C99. */
#ifndef FMI2_COMMON_H
#define FMI2_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "fmi2Functions.h"

/* the FMI part of an instance: the first member (`f`) of each backend's Instance */
typedef struct {
    unsigned magic;            /* FMI2C_INSTANCE_MAGIC while the instance lives */
    int state;                 /* one of the instance states (fmi2_common.c) */
    char *name;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
    int logging_on;
    char **categories;         /* enabled debug categories; none listed, or logAll among them: all */
    size_t n_categories;
    double time;               /* [s] the communication point (fmi2LastSuccessfulTime) */
    int terminated_flag;       /* fmi2Terminated */
    fmi2Status last_step_status; /* fmi2DoStepStatus */
    fmi2Status worst_logged;   /* the worst status logged during the current call (capped at Warning) */
    size_t message_size;       /* the longest message text + 1 (longer texts are cut) */
} fmi2c_instance;

/* the backend's instance tag (each binary its own, so that one binary never takes the other's instance) */
extern const unsigned FMI2C_INSTANCE_MAGIC;
#define FMI2C_MESSAGE_MAX 4096

void fmi2c_emit(fmi2c_instance *F, fmi2Status status, const char *category, const char *text);
void fmi2c_logf(fmi2c_instance *F, fmi2Status status, const char *category, const char *format, ...);
/* a step that failed (fmi2DoStep's hook): fmi2DoStepStatus becomes fmi2Error; fmi2Error returned */
fmi2Status fmi2c_step_failed(fmi2c_instance *F);

/* fmi2Instantiate: an error message to the caller's logger (no instance yet) */
void fmi2c_instantiate_error(const fmi2CallbackFunctions *functions, fmi2String name, const char *format, ...);
/* fmi2Instantiate's checks of instanceName, fmuType and fmuGUID (not NULL): 0, or -1 with the error logged */
int fmi2c_check_instantiate(const fmi2CallbackFunctions *functions, fmi2String instanceName, fmi2Type fmuType,
                            fmi2String fmuGUID);
/* fmi2Instantiate's resource folder: fmuResourceLocation `location` (a file URI, uri.h) as a local path in
 * `resources` (capacity `size`), a folder that exists and, when `required` is not NULL, holds the file
 * `required`; `is_directory` and `is_file` are the backend's checks of the file system (is_file may be NULL
 * when `required` is). 0, or -1 with the error logged. */
int fmi2c_resource_folder(const fmi2CallbackFunctions *functions, fmi2String instanceName, fmi2String location,
                          char *resources, size_t size, int (*is_directory)(const char *),
                          int (*is_file)(const char *), const char *required);
/* a new instance of `size` bytes (the backend's Instance, zeroed), its FMI part instantiated with a copy of
 * the name and messages of at most message_size - 1 bytes; NULL with the error logged */
void *fmi2c_new_instance(size_t size, const fmi2CallbackFunctions *functions, fmi2String instanceName,
                         fmi2Boolean loggingOn, size_t message_size);
/* free the instance (its FMI part; the backend's part released before) */
void fmi2c_destroy(fmi2c_instance *F);

/* ------------------------------------------------------------------------------------------ backend hooks */
/* What the FMI calls defined in fmi2_common.c leave to the backend (the Python slave, or the C engine); each
 * backend defines every hook. A hook gets the instance's FMI part (the first member of the backend's
 * Instance) and returns fmi2OK or fmi2Warning when it did its work, or fmi2Error with the message logged
 * (`function`: the FMI call to name). The common code does the rest: the call-allowed and argument checks,
 * the instance state (the error state after fmi2Error), the time and the statuses. */
void fmi2c_backend_free_instance(fmi2c_instance *F); /* release the backend's part (fmi2FreeInstance) */
fmi2Status fmi2c_backend_setup_experiment(fmi2c_instance *F, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                          fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime);
fmi2Status fmi2c_backend_enter_initialization_mode(fmi2c_instance *F);
fmi2Status fmi2c_backend_exit_initialization_mode(fmi2c_instance *F);
fmi2Status fmi2c_backend_terminate(fmi2c_instance *F);
fmi2Status fmi2c_backend_reset(fmi2c_instance *F); /* back to the start values, not initialized */
/* the step [t, t + h], its arguments checked: done (fmi2OK / fmi2Warning), refused (fmi2Discard: the slave
 * stayed at F->time; the master may retry, or end at the last successful time), or fmi2Error (through
 * fmi2c_step_failed when the step itself failed) */
fmi2Status fmi2c_backend_do_step(fmi2c_instance *F, double t, double h);

/* fmi2Get<Type> / fmi2Set<Type> / fmi2SetRealInputDerivatives with nvr > 0 and no array NULL */
fmi2Status fmi2c_backend_get_real(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]);
fmi2Status fmi2c_backend_get_integer(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr,
                                     fmi2Integer value[]);
fmi2Status fmi2c_backend_get_boolean(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr,
                                     fmi2Boolean value[]);
fmi2Status fmi2c_backend_get_string(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr,
                                    fmi2String value[]);
fmi2Status fmi2c_backend_set_real(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr,
                                  const fmi2Real value[]);
fmi2Status fmi2c_backend_set_integer(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr,
                                     const fmi2Integer value[]);
fmi2Status fmi2c_backend_set_boolean(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr,
                                     const fmi2Boolean value[]);
fmi2Status fmi2c_backend_set_string(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr,
                                    const fmi2String value[]);
fmi2Status fmi2c_backend_set_real_input_derivatives(fmi2c_instance *F, const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[], const fmi2Real value[]);

/* FMU states: the backend's part of a saved state is `data`, opaque to the common code */
/* the backend's part of the instance's current state (fmi2GetFMUstate) */
fmi2Status fmi2c_backend_save_state(fmi2c_instance *F, const char *function, void **data);
/* set it (fmi2SetFMUstate); on fmi2Error the instance kept its state */
fmi2Status fmi2c_backend_restore_state(fmi2c_instance *F, const char *function, void *data);
void fmi2c_backend_free_state(fmi2c_instance *F, void *data);
/* the n bytes of `data` in a serialized state (after the header), valid until
 * fmi2c_backend_release_bytes(F, *hold) */
fmi2Status fmi2c_backend_state_bytes(fmi2c_instance *F, const char *function, void *data,
                                     const unsigned char **bytes, size_t *n, void **hold);
void fmi2c_backend_release_bytes(fmi2c_instance *F, void *hold);
/* `data` from those n bytes (fmi2DeSerializeFMUstate; the header is checked already) */
fmi2Status fmi2c_backend_state_from_bytes(fmi2c_instance *F, const char *function, const unsigned char *bytes,
                                          size_t n, void **data);
/* the tag of the backend's saved states (one binary never takes the other's) */
extern const unsigned FMI2C_STATE_MAGIC;

/* what an FMU state keeps of the FMI part (the header of its serialized form) */
typedef struct {
    int instance_state;
    double time;
    int terminated_flag;
    fmi2Status last_step_status;
} fmi2c_fields;

#ifndef FMI2C_IMPLEMENTATION
/* the backends' shorthands on their `Instance *S`, whose first member is the fmi2c_instance f */
#define emit(S, ...) fmi2c_emit(&(S)->f, __VA_ARGS__)
#define logf_(S, ...) fmi2c_logf(&(S)->f, __VA_ARGS__)
#define log_error(S, ...) fmi2c_logf(&(S)->f, fmi2Error, "logStatusError", __VA_ARGS__)
#endif

/* serialized FMU state: this header, then the backend's bytes.
 *   offset  size  field
 *   0       22    SERIAL_MAGIC
 *   22      8     time [s] (double)
 *   30      12    instance state, fmi2Terminated flag, last fmi2DoStep status (int32 each)
 *   42      4     CRC-32 (IEEE 802.3) of bytes 0..41 and of the backend's bytes that follow
 *   46      n     the backend's bytes
 * The CRC covers every byte of the state but its own four: any corrupted byte (indeed any error burst of up
 * to 32 bits) is detected before anything is set, and the state is refused with fmi2Error. It guards against
 * accidents, not against someone who rewrites the checksum. */
#define SERIAL_MAGIC "rocking FMI2 state v2\n"
#define SERIAL_MAGIC_SIZE (sizeof SERIAL_MAGIC - 1)
#define SERIAL_CRC_OFFSET (SERIAL_MAGIC_SIZE + 8 + 4 + 4 + 4)
#define SERIAL_HEADER_SIZE (SERIAL_CRC_OFFSET + 4)

/* CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), continued from `crc` (0 to start) */
uint32_t fmi2c_crc32_update(uint32_t crc, const unsigned char *p, size_t n);

#endif
