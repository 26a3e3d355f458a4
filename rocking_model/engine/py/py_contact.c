/* py_contact.c -- test entry points of part B for the pinning tests (tests/test_engine_*.py): thin wrappers
 * that call the C functions of rk_contact on Python floats/lists and return lists, registered into
 * rocking_model._engine by _engine.c (PyModule_AddFunctions). Names start with "contact_" (e.g.
 * _engine.contact_...) so that the parts never collide. Not used by the engine itself.
 * Owner: part B. The table is empty until part B adds its wrappers. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "../src/rk_internal.h"

PyMethodDef rk_py_contact_methods[] = {
    {NULL, NULL, 0, NULL}
};
