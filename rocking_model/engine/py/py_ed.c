/* py_ed.c -- test entry points of part D for the pinning tests (tests/test_engine_*.py): thin wrappers
 * that call the C functions of rk_ed on Python floats/lists and return lists, registered into
 * rocking_model._engine by _engine.c (PyModule_AddFunctions). Names start with "ed_" (e.g.
 * _engine.ed_...) so that the parts never collide. Not used by the engine itself.
 * Owner: part D. The table is empty until part D adds its wrappers. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "../src/rk_internal.h"

PyMethodDef rk_py_ed_methods[] = {
    {NULL, NULL, 0, NULL}
};
