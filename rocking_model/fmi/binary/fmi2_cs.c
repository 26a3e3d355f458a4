/* FMI 2.0 co-simulation binary that hosts a Python slave (a pythonfmu `Fmi2Slave` subclass).
 *
 * This file is the Python backend of the FMI plumbing: fmi2Instantiate and the hooks (fmi2c_backend_*) of the
 * FMI calls that fmi2_common.c defines once for both binaries (the state machine, the argument checks, the
 * status bookkeeping, the messages and the FMU states), shared with the self-contained FMUs' binary
 * (standalone/fmi2_engine.c). It knows nothing of the model. The Python side (`fmi2_pyhost.py`,
 * in the FMU's resources) loads the slave class and creates the slave; every FMI call then goes straight to the
 * slave's pythonfmu methods (get_real, set_real, do_step, ...).
 *
 * Status of a call (FMI 2.0, section 2.1.3):
 *   fmi2OK / fmi2Warning  the call did its work (fmi2Warning when the slave logged a warning meanwhile);
 *   fmi2Discard           do_step returned False: the step was refused, the slave is where it was
 *                         (fmi2Terminated is true until a later step succeeds, fmi2LastSuccessfulTime is the
 *                         slave's time); the master may change inputs, restore a state and retry;
 *   fmi2Error             an invalid argument, value or call sequence, or an exception in the slave: the
 *                         message goes to the logger, the instance enters the error state, where only the
 *                         getters, fmi2SetFMUstate, fmi2Reset, fmi2Terminate and fmi2FreeInstance are allowed;
 *   fmi2Fatal             only when the Python interpreter cannot be used at all.
 * Messages: fmi2Warning and worse always reach the logger; the others only with logging on (and their
 * category enabled by fmi2SetDebugLogging). Every message is passed as data ("%s"), never as a format. */
#include "pyapi.h" /* Python.h first */

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "platform.h"
#include "uri.h"
#include "fmi2_common.h" /* last: its shorthands (log_error, fail, ...) are macros */

#define PYHOST_FILE "fmi2_pyhost.py"

/* the slave's methods, bound once per slave */
enum { M_SETUP, M_ENTER, M_EXIT, M_TERMINATE, M_DO_STEP, M_GET_REAL, M_GET_INTEGER, M_GET_BOOLEAN, M_GET_STRING,
       M_SET_REAL, M_SET_INTEGER, M_SET_BOOLEAN, M_SET_STRING, M_GET_STATE, M_SET_STATE, M_STATE_TO_BYTES,
       M_STATE_FROM_BYTES, M_SET_INPUT_DERIVATIVES, N_METHODS };
static const char *method_names[N_METHODS] = {
    "setup_experiment", "enter_initialization_mode", "exit_initialization_mode", "terminate", "do_step",
    "get_real", "get_integer", "get_boolean", "get_string", "set_real", "set_integer", "set_boolean",
    "set_string", "_get_fmu_state", "_set_fmu_state", "_fmu_state_to_bytes", "_fmu_state_from_bytes",
    "set_real_input_derivatives"};

const unsigned FMI2C_INSTANCE_MAGIC = 0x46d12a7bu;
const unsigned FMI2C_STATE_MAGIC = 0x5d7e0c19u;

typedef struct {
    fmi2c_instance f;  /* the FMI part (fmi2_common.h): state, logger, time of the slave, statuses */
    PyObject *host;    /* the fmi2_pyhost.Host */
    PyObject *slave;
    PyObject *methods[N_METHODS]; /* NULL where the slave lacks the method */
    PyObject *log_name; /* the str "log_queue", made once: drain_log runs after every call */
    PyObject *strings; /* the last fmi2GetString result: keeps the returned UTF-8 buffers alive */
} Instance;

/* an FMU state (fmi2_common.c) keeps the slave's state object; serialized: the header of fmi2_common.h
 * (SERIAL_HEADER_SIZE bytes, with its CRC-32), then the slave's bytes (rocking_model/fmi_state.py: its own
 * header and SHA-256) */

/* ------------------------------------------------------------------------------------------ messages */

/* Forward the slave's queued messages (pythonfmu LogMsg: status, category, msg); return the worst status
 * among them, capped at fmi2Warning (a slave reports failures by raising or by do_step returning False). */
static fmi2Status drain_log(Instance *S) {
    if (!S->slave) return fmi2OK;
    /* looked up on every call (a slave may replace its list), by a name object made once */
    PyObject *queue = S->log_name ? py.Object_GetAttr(S->slave, S->log_name)
                                  : py.Object_GetAttrString(S->slave, "log_queue");
    if (!queue) {
        py.Err_Clear();
        return fmi2OK;
    }
    fmi2Status worst = fmi2OK;
    Py_ssize_t n = py.List_Size(queue);
    if (n <= 0) {                   /* the usual case: nothing logged */
        if (n < 0) py.Err_Clear();
        py.DecRef(queue);
        return fmi2OK;
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *item = py.List_GetItem(queue, i); /* borrowed */
        PyObject *status = item ? py.Object_GetAttrString(item, "status") : NULL;
        PyObject *category = item ? py.Object_GetAttrString(item, "category") : NULL;
        PyObject *msg = item ? py.Object_GetAttrString(item, "msg") : NULL;
        PyObject *text = msg ? py.Object_Str(msg) : NULL;
        long s = status ? py.Long_AsLong(status) : (long)fmi2Error;
        const char *c = category ? py.Unicode_AsUTF8(category) : NULL;
        const char *t = text ? py.Unicode_AsUTF8(text) : NULL;
        if (py.Err_Occurred()) py.Err_Clear();
        if (s < fmi2OK || s > fmi2Fatal) s = fmi2Error;
        emit(S, (fmi2Status)s, c, t ? t : "(a message that is not text)");
        if (s > worst) worst = (fmi2Status)s;
        if (status) py.DecRef(status);
        if (category) py.DecRef(category);
        if (msg) py.DecRef(msg);
        if (text) py.DecRef(text);
    }
    if (n > 0 && py.List_SetSlice(queue, 0, n, NULL) < 0) py.Err_Clear();
    py.DecRef(queue);
    return worst > fmi2Warning ? fmi2Warning : worst;
}

/* Log the pending Python exception as an error of `function` and clear it. */
static void log_exception(Instance *S, const char *function) {
    PyObject *type = NULL, *value = NULL, *traceback = NULL;
    py.Err_Fetch(&type, &value, &traceback);
    py.Err_NormalizeException(&type, &value, &traceback);
    PyObject *text = value ? py.Object_Str(value) : NULL;
    PyObject *tname = type ? py.Object_GetAttrString(type, "__name__") : NULL;
    const char *t = text ? py.Unicode_AsUTF8(text) : NULL;
    const char *n = tname ? py.Unicode_AsUTF8(tname) : NULL;
    if (py.Err_Occurred()) py.Err_Clear();
    if (n && strcmp(n, "ValueError") == 0 && t && strncmp(t, function, strlen(function)) == 0)
        log_error(S, "%s", t); /* the message names the call already */
    else if (n && strcmp(n, "ValueError") == 0 && t && t[0])
        log_error(S, "%s: %s", function, t);
    else
        log_error(S, "%s: %s: %s", function, n ? n : "exception", t ? t : "");
    if (text) py.DecRef(text);
    if (tname) py.DecRef(tname);
    if (type) py.DecRef(type);
    if (value) py.DecRef(value);
    if (traceback) py.DecRef(traceback);
}

/* ------------------------------------------------------------------------------------------ helpers */
static void release_slave(Instance *S) {
    for (int i = 0; i < N_METHODS; i++) {
        if (S->methods[i]) py.DecRef(S->methods[i]);
        S->methods[i] = NULL;
    }
    if (S->strings) py.DecRef(S->strings);
    S->strings = NULL;
    if (S->slave) py.DecRef(S->slave);
    S->slave = NULL;
    if (S->log_name) py.DecRef(S->log_name);
    S->log_name = NULL;
}

/* Take the host's current slave and bind its methods; -1 with the exception pending on failure. */
static int bind_slave(Instance *S) {
    release_slave(S);
    S->slave = py.Object_GetAttrString(S->host, "slave");
    if (!S->slave) return -1;
    S->log_name = py.Unicode_DecodeUTF8("log_queue", 9, "strict");
    if (!S->log_name) return -1;
    for (int i = 0; i < N_METHODS; i++) {
        if (py.Object_HasAttrString(S->slave, method_names[i])) {
            S->methods[i] = py.Object_GetAttrString(S->slave, method_names[i]);
            if (!S->methods[i]) return -1;
        }
    }
    return 0;
}

/* Call slave method `m` with the arguments (NULL-terminated); a new reference, or NULL with the exception
 * logged as an error of `function`. */
#define CALL_SLAVE(S, function, m, ...) call_slave(S, function, m, __VA_ARGS__, NULL)
static PyObject *call_slave(Instance *S, const char *function, int m, ...) {
    if (!S->methods[m]) {
        log_error(S, "%s: the slave %s has no method %s", function, S->f.name, method_names[m]);
        return NULL;
    }
    /* vectorcall: no argument tuple built; slot 0 stays free for the bound method's self
     * (PY_VECTORCALL_ARGUMENTS_OFFSET), so that the call allocates nothing */
    PyObject *args[5] = {NULL, NULL, NULL, NULL, NULL};
    size_t nargs = 0;
    va_list ap;
    va_start(ap, m);
    while (nargs < 4) {
        PyObject *a = va_arg(ap, PyObject *);
        if (!a) break;
        args[1 + nargs++] = a;
    }
    va_end(ap);
    PyObject *result = py.Object_Vectorcall(S->methods[m], args + 1, nargs | PY_VECTORCALL_ARGUMENTS_OFFSET, NULL);
    if (!result) log_exception(S, function);
    return result;
}

static PyObject *vr_list(const fmi2ValueReference vr[], size_t nvr) {
    PyObject *list = py.List_New((Py_ssize_t)nvr);
    if (!list) return NULL;
    for (size_t i = 0; i < nvr; i++) {
        PyObject *v = py.Long_FromUnsignedLong(vr[i]);
        if (!v) {
            py.DecRef(list);
            return NULL;
        }
        py.List_SetItem(list, (Py_ssize_t)i, v);
    }
    return list;
}

/* the slave's answer to a getter: a list of nvr items */
static int check_list(Instance *S, const char *function, PyObject *list, size_t nvr) {
    Py_ssize_t n = py.List_Size(list);
    if (n < 0) py.Err_Clear();
    if (n != (Py_ssize_t)nvr) {
        log_error(S, "%s: the slave returned %zd values for %zu value references", function, n, nvr);
        return -1;
    }
    return 0;
}

#define GIL_BEGIN PyGILState_STATE gil_ = py.GILState_Ensure()
#define GIL_END py.GILState_Release(gil_)

/* ------------------------------------------------------------------------------------------ life cycle */
static const char BOOTSTRAP[] =
    "import hashlib, importlib.util, os, sys\n"
    "def load_host(resources):\n"
    "    path = os.path.join(resources, '" PYHOST_FILE "')\n"
    "    with open(path, 'rb') as f:\n"
    "        name = '_fmi2_pyhost_' + hashlib.sha256(f.read()).hexdigest()[:16]\n"
    "    module = sys.modules.get(name)\n"
    "    if module is None:\n"
    "        spec = importlib.util.spec_from_file_location(name, path)\n"
    "        module = importlib.util.module_from_spec(spec)\n"
    "        sys.modules[name] = module\n"
    "        try:\n"
    "            spec.loader.exec_module(module)\n"
    "        except BaseException:\n"
    "            del sys.modules[name]\n"
    "            raise\n"
    "    return module\n";

static PyObject *bootstrap_globals = NULL; /* lives as long as this binary is loaded (set under the GIL) */

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    if (fmi2c_check_instantiate(functions, instanceName, fmuType, fmuGUID) != 0) return NULL;
    char resources[4096], why[2048];
    if (fmi2c_resource_folder(functions, instanceName, fmuResourceLocation, resources, sizeof resources,
                              is_directory, is_file, PYHOST_FILE) != 0)
        return NULL;
    int started = 0;
    if (python_load(why, sizeof why, &started) != 0) {
        fmi2c_instantiate_error(functions, instanceName, "fmi2Instantiate: %s", why);
        return NULL;
    }
    /* messages of at most 2047 bytes (longer texts are cut) */
    Instance *S = (Instance *)fmi2c_new_instance(sizeof(Instance), functions, instanceName, loggingOn, 2048);
    if (!S) return NULL;

    GIL_BEGIN;
    int ok = 0;
    PyObject *module = NULL, *host_class = NULL, *args[5] = {NULL};
    /* under the GIL only: a second lock here could deadlock with a thread that holds it while Python code
     * releases the GIL. Two threads may both run the bootstrap; the first result is kept (the check and the
     * assignment run without a Python call between them, so under the GIL). */
    if (!bootstrap_globals) {
        PyObject *g = py.Dict_New();
        if (g && py.Dict_SetItemString(g, "__builtins__", py.Eval_GetBuiltins()) == 0) {
            PyObject *r = py.Run_String(BOOTSTRAP, Py_file_input, g, g);
            if (r) {
                py.DecRef(r);
                if (!bootstrap_globals) {
                    bootstrap_globals = g;
                    g = NULL;
                }
            }
        }
        if (g) py.DecRef(g);
    }
    PyObject *load_host = bootstrap_globals ? py.Dict_GetItemString(bootstrap_globals, "load_host") : NULL;
    if (load_host) {
        args[0] = py.Unicode_DecodeUTF8(resources, (Py_ssize_t)strlen(resources), "surrogateescape");
        if (args[0]) module = py.Object_CallFunctionObjArgs(load_host, args[0], NULL);
    }
    if (module) host_class = py.Object_GetAttrString(module, "Host");
    if (host_class) {
        args[1] = py.Unicode_DecodeUTF8(instanceName, (Py_ssize_t)strlen(instanceName), "replace");
        args[2] = py.Unicode_DecodeUTF8(fmuGUID, (Py_ssize_t)strlen(fmuGUID), "replace");
        args[3] = py.Bool_FromLong(visible);
        args[4] = py.Bool_FromLong(started);
        if (args[1] && args[2] && args[3] && args[4])
            S->host = py.Object_CallFunctionObjArgs(host_class, args[0], args[1], args[2], args[3], args[4], NULL);
    }
    if (S->host && bind_slave(S) == 0) ok = 1;
    if (!ok) {
        if (py.Err_Occurred()) log_exception(S, "fmi2Instantiate");
        else log_error(S, "fmi2Instantiate: the Python host could not be set up");
    } else {
        drain_log(S);
    }
    for (int i = 0; i < 5; i++)
        if (args[i]) py.DecRef(args[i]);
    if (host_class) py.DecRef(host_class);
    if (module) py.DecRef(module);
    if (!ok) {
        release_slave(S);
        if (S->host) py.DecRef(S->host);
        S->host = NULL;
    }
    GIL_END;
    if (!ok) {
        fmi2c_destroy(&S->f);
        return NULL;
    }
    return S;
}

/* ------------------------------------------------------------------------------------------ backend hooks */
/* the backend's part of the FMI calls of fmi2_common.c (fmi2c_backend): the slave's methods */
void fmi2c_backend_free_instance(fmi2c_instance *F) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    release_slave(S);
    if (S->host) {
        PyObject *r = py.Object_GetAttrString(S->host, "free");
        PyObject *done = r ? py.Object_CallFunctionObjArgs(r, NULL) : NULL;
        if (!done) py.Err_Clear();
        if (done) py.DecRef(done);
        if (r) py.DecRef(r);
        py.DecRef(S->host);
        S->host = NULL;
    }
    GIL_END;
}

/* a call of one slave method without results: status from the call and the messages it logged */
static fmi2Status simple_call(Instance *S, PyObject *result) {
    fmi2Status logged = drain_log(S);
    if (!result) return fmi2Error;
    py.DecRef(result);
    return logged;
}

fmi2Status fmi2c_backend_setup_experiment(fmi2c_instance *F, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                   fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    PyObject *a = py.Float_FromDouble(startTime);
    PyObject *b = stopTimeDefined ? py.Float_FromDouble(stopTime) : (py.IncRef(py.None), py.None);
    PyObject *t = toleranceDefined ? py.Float_FromDouble(tolerance) : (py.IncRef(py.None), py.None);
    fmi2Status status = simple_call(S, CALL_SLAVE(S, "fmi2SetupExperiment", M_SETUP, a, b, t));
    py.DecRef(a);
    py.DecRef(b);
    py.DecRef(t);
    GIL_END;
    return status;
}

/* a slave method without arguments: its status */
static fmi2Status call_method(fmi2c_instance *F, const char *function, int m) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    fmi2Status status = simple_call(S, CALL_SLAVE(S, function, m, NULL));
    GIL_END;
    return status;
}

fmi2Status fmi2c_backend_enter_initialization_mode(fmi2c_instance *F) {
    return call_method(F, "fmi2EnterInitializationMode", M_ENTER);
}

fmi2Status fmi2c_backend_exit_initialization_mode(fmi2c_instance *F) {
    return call_method(F, "fmi2ExitInitializationMode", M_EXIT);
}

fmi2Status fmi2c_backend_terminate(fmi2c_instance *F) { return call_method(F, "fmi2Terminate", M_TERMINATE); }

fmi2Status fmi2c_backend_reset(fmi2c_instance *F) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    /* a new slave from the class: start values, not initialized (as fmi2Instantiate left it) */
    PyObject *renew = py.Object_GetAttrString(S->host, "new_slave");
    PyObject *r = renew ? py.Object_CallFunctionObjArgs(renew, NULL) : NULL;
    fmi2Status status = fmi2OK;
    if (!r || bind_slave(S) != 0) {
        log_exception(S, "fmi2Reset");
        status = fmi2Error;
    } else {
        status = drain_log(S);
    }
    if (r) py.DecRef(r);
    if (renew) py.DecRef(renew);
    GIL_END;
    return status;
}

fmi2Status fmi2c_backend_do_step(fmi2c_instance *F, double t, double h) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    PyObject *a = py.Float_FromDouble(t), *b = py.Float_FromDouble(h); /* the master's time is the reference */
    PyObject *result = (a && b) ? CALL_SLAVE(S, "fmi2DoStep", M_DO_STEP, a, b) : NULL;
    int accepted = result ? py.Object_IsTrue(result) : -1;
    if (accepted < 0 && result) log_exception(S, "fmi2DoStep");
    fmi2Status logged = drain_log(S);
    if (a) py.DecRef(a);
    if (b) py.DecRef(b);
    if (result) py.DecRef(result);
    GIL_END;
    if (accepted < 0) return fmi2c_step_failed(F);
    return accepted ? logged : fmi2Discard; /* do_step returned False: refused, the slave stayed where it was */
}

/* ------------------------------------------------------------------------------------------ values */
static fmi2Status get_values(Instance *S, const char *function, int m, const fmi2ValueReference vr[], size_t nvr,
                             PyObject **out) {
    *out = NULL;
    PyObject *vrs = vr_list(vr, nvr);
    PyObject *result = vrs ? CALL_SLAVE(S, function, m, vrs) : NULL;
    if (vrs) py.DecRef(vrs);
    fmi2Status logged = drain_log(S);
    if (!result) return fmi2Error;
    if (check_list(S, function, result, nvr) != 0) {
        py.DecRef(result);
        return fmi2Error;
    }
    *out = result;
    return logged;
}

/* the backend's part of fmi2Get<Type> (fmi2_common.c checked the arguments): the slave's get_<type> */
#define GETTER(HOOK, F, M, TYPE, CONVERT)                                                                   \
    fmi2Status fmi2c_backend_##HOOK(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,        \
                                    TYPE value[]) {                                                         \
        Instance *S = (Instance *)c;                                                                        \
        GIL_BEGIN;                                                                                          \
        PyObject *list = NULL;                                                                              \
        fmi2Status status = get_values(S, "fmi2" #F, M, vr, nvr, &list);                                    \
        if (list) {                                                                                         \
            for (size_t i = 0; i < nvr; i++) {                                                              \
                PyObject *item = py.List_GetItem(list, (Py_ssize_t)i);                                      \
                CONVERT;                                                                                    \
            }                                                                                               \
            if (py.Err_Occurred()) {                                                                        \
                log_exception(S, "fmi2" #F);                                                                \
                status = fmi2Error;                                                                         \
            }                                                                                               \
            py.DecRef(list);                                                                                \
        }                                                                                                   \
        GIL_END;                                                                                            \
        return status;                                                                                      \
    }

GETTER(get_real, GetReal, M_GET_REAL, fmi2Real, value[i] = py.Float_AsDouble(item))
GETTER(get_integer, GetInteger, M_GET_INTEGER, fmi2Integer, {
    long v = py.Long_AsLong(item);
    if (v < -2147483647L - 1 || v > 2147483647L) {
        if (!py.Err_Occurred()) log_error(S, "fmi2GetInteger: value %ld of reference %u is not a 32-bit integer", v, vr[i]);
        status = fmi2Error;
    }
    value[i] = (fmi2Integer)v;
})
GETTER(get_boolean, GetBoolean, M_GET_BOOLEAN, fmi2Boolean, {
    int v = py.Object_IsTrue(item);
    value[i] = v > 0 ? fmi2True : fmi2False;
})

fmi2Status fmi2c_backend_get_string(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,
                                    fmi2String value[]) {
    Instance *S = (Instance *)c;
    GIL_BEGIN;
    PyObject *list = NULL;
    fmi2Status status = get_values(S, "fmi2GetString", M_GET_STRING, vr, nvr, &list);
    if (list) {
        for (size_t i = 0; i < nvr && status != fmi2Error; i++) {
            const char *s = py.Unicode_AsUTF8(py.List_GetItem(list, (Py_ssize_t)i));
            if (!s) {
                log_exception(S, "fmi2GetString");
                status = fmi2Error;
            }
            value[i] = s;
        }
        /* the buffers live as long as the list: until the next fmi2GetString */
        if (S->strings) py.DecRef(S->strings);
        S->strings = list;
    }
    GIL_END;
    return status;
}

static fmi2Status set_values(Instance *S, const char *function, int m, const fmi2ValueReference vr[], size_t nvr,
                             PyObject *values) {
    PyObject *vrs = vr_list(vr, nvr);
    PyObject *result = (vrs && values) ? CALL_SLAVE(S, function, m, vrs, values) : NULL;
    if (!vrs || !values) {
        if (py.Err_Occurred()) log_exception(S, function);
        else log_error(S, "%s: invalid value", function);
    }
    if (vrs) py.DecRef(vrs);
    if (values) py.DecRef(values);
    return simple_call(S, result);
}

/* the backend's part of fmi2Set<Type> (fmi2_common.c checked the arguments): the slave's set_<type> */
#define SETTER(HOOK, F, M, TYPE, MAKE)                                                                      \
    fmi2Status fmi2c_backend_##HOOK(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,        \
                                    const TYPE value[]) {                                                   \
        Instance *S = (Instance *)c;                                                                        \
        GIL_BEGIN;                                                                                          \
        PyObject *list = py.List_New((Py_ssize_t)nvr);                                                      \
        for (size_t i = 0; list && i < nvr; i++) {                                                          \
            PyObject *item = MAKE;                                                                          \
            if (!item) {                                                                                    \
                py.DecRef(list);                                                                            \
                list = NULL;                                                                                \
                break;                                                                                      \
            }                                                                                               \
            py.List_SetItem(list, (Py_ssize_t)i, item);                                                     \
        }                                                                                                   \
        fmi2Status status = set_values(S, "fmi2" #F, M, vr, nvr, list);                                     \
        GIL_END;                                                                                            \
        return status;                                                                                      \
    }

SETTER(set_real, SetReal, M_SET_REAL, fmi2Real, py.Float_FromDouble(value[i]))
SETTER(set_integer, SetInteger, M_SET_INTEGER, fmi2Integer, py.Long_FromLong(value[i]))
SETTER(set_boolean, SetBoolean, M_SET_BOOLEAN, fmi2Boolean, py.Bool_FromLong(value[i] != fmi2False))
/* strict UTF-8: a string that is not UTF-8 is an invalid value (fmi2Error), never a crash */
SETTER(set_string, SetString, M_SET_STRING, fmi2String,
       value[i] ? py.Unicode_DecodeUTF8(value[i], (Py_ssize_t)strlen(value[i]), "strict") : NULL)

/* ------------------------------------------------------------------------------------------ stepping */
fmi2Status fmi2c_backend_set_real_input_derivatives(fmi2c_instance *c, const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[], const fmi2Real value[]) {
    Instance *S = (Instance *)c;
    GIL_BEGIN;
    fmi2Status status;
    if (!S->methods[M_SET_INPUT_DERIVATIVES]) {
        log_error(S, "fmi2SetRealInputDerivatives: the slave cannot interpolate inputs (canInterpolateInputs "
                  "= false)");
        status = fmi2Error;
    } else {
        PyObject *vrs = vr_list(vr, nvr), *orders = py.List_New((Py_ssize_t)nvr),
                 *values = py.List_New((Py_ssize_t)nvr);
        int ok = vrs && orders && values;
        for (size_t i = 0; ok && i < nvr; i++) {
            PyObject *o = py.Long_FromLong(order[i]), *v = py.Float_FromDouble(value[i]);
            if (o) py.List_SetItem(orders, (Py_ssize_t)i, o);
            if (v) py.List_SetItem(values, (Py_ssize_t)i, v);
            ok = o && v;
        }
        PyObject *result = ok ? CALL_SLAVE(S, "fmi2SetRealInputDerivatives", M_SET_INPUT_DERIVATIVES, vrs,
                                           orders, values) : NULL;
        if (!ok && py.Err_Occurred()) log_exception(S, "fmi2SetRealInputDerivatives");
        if (vrs) py.DecRef(vrs);
        if (orders) py.DecRef(orders);
        if (values) py.DecRef(values);
        status = simple_call(S, result);
    }
    GIL_END;
    return status;
}

/* ------------------------------------------------------------------------------------------ FMU state */
/* the backend's part of the FMU state calls of fmi2_common.c: `data` is the slave's state object */
fmi2Status fmi2c_backend_save_state(fmi2c_instance *F, const char *function, void **data) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    PyObject *state = CALL_SLAVE(S, function, M_GET_STATE, NULL);
    fmi2Status status = drain_log(S);
    GIL_END;
    *data = state;
    return state ? status : fmi2Error;
}

fmi2Status fmi2c_backend_restore_state(fmi2c_instance *F, const char *function, void *data) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    fmi2Status status = simple_call(S, CALL_SLAVE(S, function, M_SET_STATE, (PyObject *)data));
    GIL_END;
    return status; /* fmi2Error: the slave kept its state */
}

void fmi2c_backend_free_state(fmi2c_instance *F, void *data) {
    (void)F;
    GIL_BEGIN;
    py.DecRef((PyObject *)data);
    GIL_END;
}

/* the slave's bytes of a state: `hold` the bytes object */
fmi2Status fmi2c_backend_state_bytes(fmi2c_instance *F, const char *function, void *data, const unsigned char **bytes,
                              size_t *n, void **hold) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    PyObject *out = CALL_SLAVE(S, function, M_STATE_TO_BYTES, (PyObject *)data);
    char *p = NULL;
    Py_ssize_t m = 0;
    if (out && py.Bytes_AsStringAndSize(out, &p, &m) != 0) {
        log_exception(S, function);
        py.DecRef(out);
        out = NULL;
    }
    fmi2Status status = drain_log(S);
    GIL_END;
    if (!out) return fmi2Error;
    *bytes = (const unsigned char *)p;
    *n = (size_t)m;
    *hold = out;
    return status;
}

void fmi2c_backend_release_bytes(fmi2c_instance *F, void *hold) { fmi2c_backend_free_state(F, hold); }

fmi2Status fmi2c_backend_state_from_bytes(fmi2c_instance *F, const char *function, const unsigned char *bytes, size_t n,
                                   void **data) {
    Instance *S = (Instance *)F;
    GIL_BEGIN;
    PyObject *b = py.Bytes_FromStringAndSize((const char *)bytes, (Py_ssize_t)n);
    PyObject *state = b ? CALL_SLAVE(S, function, M_STATE_FROM_BYTES, b) : NULL;
    if (b) py.DecRef(b);
    fmi2Status status = drain_log(S);
    GIL_END;
    *data = state;
    return state ? status : fmi2Error;
}
