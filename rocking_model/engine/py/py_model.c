/* py_model.c -- test entry points of part A for the pinning tests (tests/test_engine_*.py): thin wrappers
 * that call the C functions of rk_model on Python floats/lists and return lists, registered into
 * rocking_model._engine by _engine.c (PyModule_AddFunctions). Names start with "model_" (e.g.
 * _engine.model_...) so that the parts never collide. Not used by the engine itself.
 * Owner: part A. The table is empty until part A adds its wrappers. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "../src/rk_internal.h"

PyMethodDef rk_py_model_methods[] = {
    {NULL, NULL, 0, NULL}
};
