/* py_ed.c -- test entry points of part D for the pinning tests (tests/test_engine_*.py): thin wrappers
 * that call the C functions of rk_ed on Python floats/lists and return lists, registered into
 * rocking_model._engine by _engine.c (PyModule_AddFunctions). Names start with "ed_" (e.g.
 * _engine.ed_...) so that the parts never collide. Not used by the engine itself.
 * Owner: part D. Empty on purpose: the event-driven driver has no function worth pinning on its own (its units
 * are the kernels, contact problems and Runge-Kutta code of parts A-C, pinned there); it is pinned scene by scene
 * through part E's Engine type (tests/test_engine_event_driven.py: Simulator(engine="c") against "python"). */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "../src/rk_internal.h"

PyMethodDef rk_py_ed_methods[] = {
    {NULL, NULL, 0, NULL}
};
