#include "pyapi.h"

#include <stdio.h>
#include <string.h>

#include "platform.h"

/* recorded by the FMU build (rocking_model/fmi/build.py): the libpython and the python executable of the build environment */
#ifndef FMI_PYTHON_LIBRARY
#error "define FMI_PYTHON_LIBRARY (the path of the shared libpython the FMU was built against)"
#endif
#ifndef FMI_PYTHON_EXECUTABLE
#error "define FMI_PYTHON_EXECUTABLE (the python executable of the build environment)"
#endif

PythonApi py;

static int loaded = 0;       /* py is filled */
static int we_started = 0;   /* this binary initialized the interpreter */

typedef void *(*Lookup)(void *library, const char *name);

static void *from_process(void *library, const char *name) {
    (void)library;
    return dl_process_sym(name);
}

#define RESOLVE(field, symbol)                                                                       \
    do {                                                                                             \
        *(void **)(&py.field) = lookup(library, symbol);                                             \
        if (!py.field) {                                                                             \
            snprintf(why, why_size, "the Python library %s has no symbol %s", where, symbol);        \
            return -1;                                                                               \
        }                                                                                            \
    } while (0)

static int resolve(Lookup lookup, void *library, const char *where, char *why, size_t why_size) {
    RESOLVE(IsInitialized, "Py_IsInitialized");
    RESOLVE(GetVersion, "Py_GetVersion");
    RESOLVE(Config_InitPythonConfig, "PyConfig_InitPythonConfig");
    RESOLVE(Config_SetBytesString, "PyConfig_SetBytesString");
    RESOLVE(InitializeFromConfig, "Py_InitializeFromConfig");
    RESOLVE(Config_Clear, "PyConfig_Clear");
    RESOLVE(Status_Exception, "PyStatus_Exception");
    RESOLVE(Eval_SaveThread, "PyEval_SaveThread");
    RESOLVE(GILState_Ensure, "PyGILState_Ensure");
    RESOLVE(GILState_Release, "PyGILState_Release");
    RESOLVE(IncRef, "Py_IncRef");
    RESOLVE(DecRef, "Py_DecRef");
    RESOLVE(Dict_New, "PyDict_New");
    RESOLVE(Dict_SetItemString, "PyDict_SetItemString");
    RESOLVE(Dict_GetItemString, "PyDict_GetItemString");
    RESOLVE(Eval_GetBuiltins, "PyEval_GetBuiltins");
    RESOLVE(Run_String, "PyRun_String");
    RESOLVE(Object_GetAttrString, "PyObject_GetAttrString");
    RESOLVE(Object_HasAttrString, "PyObject_HasAttrString");
    RESOLVE(Object_CallFunctionObjArgs, "PyObject_CallFunctionObjArgs");
    RESOLVE(Object_Vectorcall, "PyObject_Vectorcall");   /* a function since Python 3.9 */
    RESOLVE(Object_GetAttr, "PyObject_GetAttr");
    RESOLVE(Object_Str, "PyObject_Str");
    RESOLVE(Object_IsTrue, "PyObject_IsTrue");
    RESOLVE(List_New, "PyList_New");
    RESOLVE(List_SetItem, "PyList_SetItem");
    RESOLVE(List_GetItem, "PyList_GetItem");
    RESOLVE(List_Size, "PyList_Size");
    RESOLVE(List_SetSlice, "PyList_SetSlice");
    RESOLVE(Tuple_GetItem, "PyTuple_GetItem");
    RESOLVE(Tuple_Size, "PyTuple_Size");
    RESOLVE(Long_FromLong, "PyLong_FromLong");
    RESOLVE(Long_FromUnsignedLong, "PyLong_FromUnsignedLong");
    RESOLVE(Long_AsLong, "PyLong_AsLong");
    RESOLVE(Float_FromDouble, "PyFloat_FromDouble");
    RESOLVE(Float_AsDouble, "PyFloat_AsDouble");
    RESOLVE(Bool_FromLong, "PyBool_FromLong");
    RESOLVE(Unicode_DecodeUTF8, "PyUnicode_DecodeUTF8");
    RESOLVE(Unicode_AsUTF8, "PyUnicode_AsUTF8");
    RESOLVE(Bytes_FromStringAndSize, "PyBytes_FromStringAndSize");
    RESOLVE(Bytes_AsStringAndSize, "PyBytes_AsStringAndSize");
    RESOLVE(Err_Occurred, "PyErr_Occurred");
    RESOLVE(Err_Fetch, "PyErr_Fetch");
    RESOLVE(Err_NormalizeException, "PyErr_NormalizeException");
    RESOLVE(Err_Clear, "PyErr_Clear");
    RESOLVE(None, "_Py_NoneStruct");
    return 0;
}

/* "3.11.7 (main, ...)" must start with the major.minor of the headers: the ABI (PyConfig's layout, the
 * object layout) is only stable within one minor version. */
static int version_matches(const char *version) {
    char expected[16];
    snprintf(expected, sizeof expected, "%d.%d.", PY_MAJOR_VERSION, PY_MINOR_VERSION);
    return version && strncmp(version, expected, strlen(expected)) == 0;
}

static int start_interpreter(char *why, size_t why_size) {
    const char *exe = env_value(FMI_PYTHON_EXECUTABLE_ENV);
    if (!exe) exe = FMI_PYTHON_EXECUTABLE;
    PyConfig config;
    py.Config_InitPythonConfig(&config);
    /* a guest in the host's process: no signal handlers (the host owns SIGINT), no argv parsing */
    config.install_signal_handlers = 0;
    config.parse_argv = 0;
    /* the build environment's python as program name: its prefix (and a virtual environment's
     * pyvenv.cfg) gives the standard library and the site-packages holding numpy */
    PyStatus status = py.Config_SetBytesString(&config, &config.program_name, exe);
    if (!py.Status_Exception(status)) status = py.InitializeFromConfig(&config);
    py.Config_Clear(&config);
    if (py.Status_Exception(status)) {
        snprintf(why, why_size, "starting the Python interpreter failed (%s%s%s); the program name was %s "
                 "(override with the environment variable %s)", status.func ? status.func : "",
                 status.func ? ": " : "", status.err_msg ? status.err_msg : "unknown error", exe,
                 FMI_PYTHON_EXECUTABLE_ENV);
        return -1;
    }
    /* release the GIL: every FMI call takes it with PyGILState_Ensure, from whatever thread */
    py.Eval_SaveThread();
    we_started = 1;
    return 0;
}

int python_load(char *why, size_t why_size, int *started) {
    int rc = 0;
    once_lock();
    if (!loaded) {
        if (dl_process_sym("Py_IsInitialized") && dl_process_sym("PyGILState_Ensure")) {
            /* the host has a Python already (fmpy, libcosimpy, or a host linked with libpython) */
            rc = resolve(from_process, NULL, "of the host process", why, why_size);
        } else {
            const char *path = env_value(FMI_PYTHON_LIBRARY_ENV);
            if (!path) path = FMI_PYTHON_LIBRARY;
            void *library = dl_open_global(path);
            if (!library) {
                snprintf(why, why_size, "cannot load the Python library %s (%s); this FMU needs Python %d.%d "
                         "with numpy: install it, or point the environment variable %s at its shared library "
                         "(libpython%d.%d.so)", path, dl_error(), PY_MAJOR_VERSION, PY_MINOR_VERSION,
                         FMI_PYTHON_LIBRARY_ENV, PY_MAJOR_VERSION, PY_MINOR_VERSION);
                rc = -1;
            } else {
                rc = resolve(dl_sym, library, path, why, why_size);
            }
        }
        if (rc == 0 && !version_matches(py.GetVersion())) {
            snprintf(why, why_size, "the process runs Python %.20s, but this FMU was built for Python %d.%d",
                     py.GetVersion(), PY_MAJOR_VERSION, PY_MINOR_VERSION);
            rc = -1;
        }
        if (rc == 0 && !py.IsInitialized()) rc = start_interpreter(why, why_size);
        if (rc == 0) loaded = 1;
    }
    once_unlock();
    if (started) *started = we_started;
    return rc;
}
