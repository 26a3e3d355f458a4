/* _engine.c -- the CPython extension module rocking_model._engine (part E).
 *
 * Skeleton by the architect: version(), api_version() and create_and_free(kind, params, initial=None), which
 * creates an engine and frees it, raising the exception that matches the C status (ValueError, NotImplementedError,
 * MemoryError, RuntimeError). Part E adds the Engine type (DESIGN.md, part E). Only the limited, stable part of
 * the C API is used (no per-step Python object is created on the hot paths). */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "src/rk_engine.h"

/* the test entry points of parts A-D (rocking_model/engine/py/py_*.c) */
extern PyMethodDef rk_py_model_methods[];
extern PyMethodDef rk_py_contact_methods[];
extern PyMethodDef rk_py_rk_methods[];
extern PyMethodDef rk_py_ed_methods[];

static PyObject *raise_status(rk_status status, const char *message)
{
    PyObject *type;
    switch (status) {
    case RK_ERR_VALUE: case RK_ERR_NONFINITE: type = PyExc_ValueError; break;
    case RK_ERR_NOT_IMPLEMENTED: type = PyExc_NotImplementedError; break;
    case RK_ERR_MEMORY: type = PyExc_MemoryError; break;
    default: type = PyExc_RuntimeError; break;
    }
    PyErr_SetString(type, message);
    return NULL;
}

static int read_doubles(PyObject *seq, const char *name, double *out, int cap, int *n)
{
    PyObject *fast;
    Py_ssize_t i, len;
    if (seq == NULL || seq == Py_None) {
        *n = 0;
        return 0;
    }
    fast = PySequence_Fast(seq, "");
    if (fast == NULL) {
        PyErr_Format(PyExc_TypeError, "%s must be a sequence of numbers", name);
        return -1;
    }
    len = PySequence_Fast_GET_SIZE(fast);
    if (len > cap) {
        Py_DECREF(fast);
        PyErr_Format(PyExc_ValueError, "%s holds %zd values, more than %d", name, len, cap);
        return -1;
    }
    for (i = 0; i < len; i++) {
        double x = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(fast, i));
        if (x == -1.0 && PyErr_Occurred()) {
            Py_DECREF(fast);
            PyErr_Format(PyExc_TypeError, "%s[%zd] must be a number", name, i);
            return -1;
        }
        out[i] = x;
    }
    Py_DECREF(fast);
    *n = (int)len;
    return 0;
}

static PyObject *py_version(PyObject *self, PyObject *args)
{
    (void)self; (void)args;
    return PyUnicode_FromString(rk_engine_version());
}

static PyObject *py_api_version(PyObject *self, PyObject *args)
{
    (void)self; (void)args;
    return PyLong_FromLong(rk_engine_api_version());
}

static PyObject *py_create_and_free(PyObject *self, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"kind", "params", "initial", NULL};
    const char *kind;
    PyObject *params_obj, *initial_obj = Py_None;
    double params[RK_MAX_PARAMS], initial[RK_MAX_INITIAL];
    int n_params, n_initial;
    rk_error err;
    rk_engine *e;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "sO|O", kwlist, &kind, &params_obj, &initial_obj))
        return NULL;
    if (read_doubles(params_obj, "params", params, RK_MAX_PARAMS, &n_params) < 0
        || read_doubles(initial_obj, "initial", initial, RK_MAX_INITIAL, &n_initial) < 0)
        return NULL;
    e = rk_engine_create(kind, params, n_params, initial, n_initial, NULL, &err);
    if (e == NULL)
        return raise_status(err.status, err.message);
    rk_engine_free(e);
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"version", py_version, METH_NOARGS, "version() -> str: the version the C engine was built with."},
    {"api_version", py_api_version, METH_NOARGS, "api_version() -> int: RK_ENGINE_API_VERSION of rk_engine.h."},
    {"create_and_free", (PyCFunction)(void (*)(void))py_create_and_free, METH_VARARGS | METH_KEYWORDS,
     "create_and_free(kind, params, initial=None): create a C engine for model kind ('rigid', 'flexible') with "
     "the declared parameters in order and free it; raises ValueError on bad input, NotImplementedError for a "
     "part not written yet."},
    {NULL, NULL, 0, NULL}
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_engine",
    "The compiled rocking engine (issue 21): see rocking_model/engine/DESIGN.md.", -1, methods,
    NULL, NULL, NULL, NULL
};

PyMODINIT_FUNC PyInit__engine(void)
{
    PyObject *m = PyModule_Create(&module);
    if (m == NULL)
        return NULL;
    if (PyModule_AddFunctions(m, rk_py_model_methods) < 0 || PyModule_AddFunctions(m, rk_py_contact_methods) < 0
        || PyModule_AddFunctions(m, rk_py_rk_methods) < 0 || PyModule_AddFunctions(m, rk_py_ed_methods) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
