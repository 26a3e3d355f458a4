/* The Python C API as a table of function pointers, resolved at run time.
 *
 * The binary is not linked against libpython, so that it loads in any host: inside a Python host (fmpy,
 * libcosimpy) the functions come from the host's interpreter, which the binary never initializes or
 * finalizes; in a host without Python the binary loads libpython itself (the path recorded at build time,
 * or the environment variable FMI_PYTHON_LIBRARY_ENV) and starts an interpreter, which it never finalizes
 * either (numpy cannot be re-initialized, and the host may load the FMU again).
 *
 * Only the types come from Python.h; every call goes through `py` (the macros Py_INCREF/Py_DECREF would
 * reference libpython's symbols directly: use py.IncRef / py.DecRef). The FMU build links with
 * -Wl,--no-undefined, so a direct reference cannot slip in. */
#ifndef FMI_BINARY_PYAPI_H
#define FMI_BINARY_PYAPI_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

/* environment variables that override what was recorded at build time */
#define FMI_PYTHON_LIBRARY_ENV "ROCKING_FMU_LIBPYTHON"
#define FMI_PYTHON_EXECUTABLE_ENV "ROCKING_FMU_PYTHON"

typedef struct {
    /* interpreter */
    int (*IsInitialized)(void);
    const char *(*GetVersion)(void);
    void (*Config_InitPythonConfig)(PyConfig *);
    PyStatus (*Config_SetBytesString)(PyConfig *, wchar_t **, const char *);
    PyStatus (*InitializeFromConfig)(const PyConfig *);
    void (*Config_Clear)(PyConfig *);
    int (*Status_Exception)(PyStatus);
    PyThreadState *(*Eval_SaveThread)(void);
    PyGILState_STATE (*GILState_Ensure)(void);
    void (*GILState_Release)(PyGILState_STATE);
    /* objects */
    void (*IncRef)(PyObject *);
    void (*DecRef)(PyObject *);
    PyObject *(*Dict_New)(void);
    int (*Dict_SetItemString)(PyObject *, const char *, PyObject *);
    PyObject *(*Dict_GetItemString)(PyObject *, const char *);
    PyObject *(*Eval_GetBuiltins)(void);
    PyObject *(*Run_String)(const char *, int, PyObject *, PyObject *);
    PyObject *(*Object_GetAttrString)(PyObject *, const char *);
    int (*Object_HasAttrString)(PyObject *, const char *);
    PyObject *(*Object_CallFunctionObjArgs)(PyObject *, ...);
    PyObject *(*Object_Vectorcall)(PyObject *, PyObject *const *, size_t, PyObject *);
    PyObject *(*Object_GetAttr)(PyObject *, PyObject *);
    PyObject *(*Object_Str)(PyObject *);
    int (*Object_IsTrue)(PyObject *);
    PyObject *(*List_New)(Py_ssize_t);
    int (*List_SetItem)(PyObject *, Py_ssize_t, PyObject *);
    PyObject *(*List_GetItem)(PyObject *, Py_ssize_t);
    Py_ssize_t (*List_Size)(PyObject *);
    int (*List_SetSlice)(PyObject *, Py_ssize_t, Py_ssize_t, PyObject *);
    PyObject *(*Tuple_GetItem)(PyObject *, Py_ssize_t);
    Py_ssize_t (*Tuple_Size)(PyObject *);
    PyObject *(*Long_FromLong)(long);
    PyObject *(*Long_FromUnsignedLong)(unsigned long);
    long (*Long_AsLong)(PyObject *);
    PyObject *(*Float_FromDouble)(double);
    double (*Float_AsDouble)(PyObject *);
    PyObject *(*Bool_FromLong)(long);
    PyObject *(*Unicode_DecodeUTF8)(const char *, Py_ssize_t, const char *);
    const char *(*Unicode_AsUTF8)(PyObject *);
    PyObject *(*Bytes_FromStringAndSize)(const char *, Py_ssize_t);
    int (*Bytes_AsStringAndSize)(PyObject *, char **, Py_ssize_t *);
    /* errors */
    PyObject *(*Err_Occurred)(void);
    void (*Err_Fetch)(PyObject **, PyObject **, PyObject **);
    void (*Err_NormalizeException)(PyObject **, PyObject **, PyObject **);
    void (*Err_Clear)(void);
    PyObject *None;
} PythonApi;

extern PythonApi py;

/* Make the C API usable: find or load libpython, check its version against the headers the binary was
 * built with, start an interpreter if the process has none (then release its GIL). Thread-safe and
 * idempotent. Returns 0, or -1 with the reason in `why`. `started` is set to 1 when this call (or an
 * earlier one of this binary) started the interpreter. */
int python_load(char *why, size_t why_size, int *started);

#endif
