/* py_model.c -- test entry points of part A for the pinning tests (tests/test_engine_model.py): thin wrappers
 * that call the C functions of rk_model on Python floats/lists and return lists, registered into
 * rocking_model._engine by _engine.c (PyModule_AddFunctions). Not used by the engine itself.
 *
 * _engine.model_call(kind, params, name, mode=0, a=None, b=None, ag=0.0) builds the model (kind "rigid" or
 * "flexible", params in declared order; a bad value raises ValueError with the Python message) and calls the
 * function ``name`` on the float lists a, b (see CALLS below for what each name takes and returns).
 * _engine.model_kinds() lists the registry with each kernel's declarations. Owner: part A. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <string.h>

#include "../src/rk_internal.h"

static int read_list(PyObject *obj, double *out, int cap, int *n)
{
    PyObject *fast;
    Py_ssize_t i, len;
    *n = 0;
    if (obj == NULL || obj == Py_None)
        return 0;
    fast = PySequence_Fast(obj, "a sequence of numbers is expected");
    if (fast == NULL)
        return -1;
    len = PySequence_Fast_GET_SIZE(fast);
    if (len > cap) {
        Py_DECREF(fast);
        PyErr_Format(PyExc_ValueError, "%zd values, more than %d", len, cap);
        return -1;
    }
    for (i = 0; i < len; i++) {
        out[i] = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(fast, i));
        if (out[i] == -1.0 && PyErr_Occurred()) {
            Py_DECREF(fast);
            return -1;
        }
    }
    Py_DECREF(fast);
    *n = (int)len;
    return 0;
}

static PyObject *list_of(const double *x, int n)
{
    PyObject *out = PyList_New(n);
    int i;
    if (out == NULL)
        return NULL;
    for (i = 0; i < n; i++)
        PyList_SET_ITEM(out, i, PyFloat_FromDouble(x[i]));
    return out;
}

static PyObject *int_list_of(const int *x, int n)
{
    PyObject *out = PyList_New(n);
    int i;
    if (out == NULL)
        return NULL;
    for (i = 0; i < n; i++)
        PyList_SET_ITEM(out, i, PyLong_FromLong(x[i]));
    return out;
}

static PyObject *value_error(const rk_error *err)
{
    PyObject *type = err->status == RK_ERR_NOT_IMPLEMENTED ? PyExc_NotImplementedError
                     : err->status == RK_ERR_VALUE ? PyExc_ValueError : PyExc_RuntimeError;
    PyErr_SetString(type, err->message);
    return NULL;
}

static int build_model(const char *kind, PyObject *params_obj, rk_model *m)
{
    double params[RK_MAX_PARAMS];
    int n;
    rk_error err;
    const rk_model_ops *ops = rk_model_find(kind);
    if (ops == NULL) {
        PyErr_Format(PyExc_ValueError, "unknown model kind %s", kind);
        return -1;
    }
    if (read_list(params_obj, params, RK_MAX_PARAMS, &n) < 0)
        return -1;
    rk_error_clear(&err);
    if (rk_model_init(m, ops, params, n, &err) != RK_OK) {
        value_error(&err);
        return -1;
    }
    return 0;
}

static PyObject *decls_of(const rk_param_decl *d, int n)
{
    PyObject *out = PyList_New(n);
    int i;
    if (out == NULL)
        return NULL;
    for (i = 0; i < n; i++)
        PyList_SET_ITEM(out, i, Py_BuildValue("(ssdddiiiii)", d[i].name, d[i].unit, d[i].default_value, d[i].lo,
                                              d[i].hi, d[i].lo_open, d[i].hi_open, d[i].inf_ok, d[i].integer,
                                              d[i].n_items));
    return out;
}

static PyObject *py_model_kinds(PyObject *self, PyObject *args)
{
    const rk_model_ops *const *k;
    PyObject *out = PyList_New(0);
    (void)self; (void)args;
    if (out == NULL)
        return NULL;
    for (k = rk_model_kinds(); *k != NULL; k++) {
        const rk_model_ops *o = *k;
        PyObject *item = Py_BuildValue("{s:s,s:s,s:i,s:i,s:i,s:i,s:i,s:i,s:N,s:N,s:N,s:N}", "kind", o->kind,
                                       "class_name", o->class_name, "n_dof", o->n_dof, "n_contacts", o->n_contacts,
                                       "n_modes", o->n_modes, "phi_index", o->phi_index, "slide_index",
                                       o->slide_index, "lift_index", o->lift_index,
                                       "params", decls_of(o->param_decls, o->n_params),
                                       "initial", decls_of(o->initial_decls, o->n_initial),
                                       "outputs", decls_of(o->output_decls, o->n_outputs),
                                       "shifted", int_list_of(o->shifted, o->n_shifted));
        if (item == NULL || PyList_Append(out, item) < 0) {
            Py_XDECREF(item);
            Py_DECREF(out);
            return NULL;
        }
        Py_DECREF(item);
    }
    return out;
}

#define N_ALL (RK_MAX_DOF * RK_MAX_DOF)

static PyObject *py_model_call(PyObject *self, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"kind", "params", "name", "mode", "a", "b", "ag", "ag_v", NULL};
    const char *kind, *name;
    PyObject *params_obj, *a_obj = Py_None, *b_obj = Py_None;
    int mode = 0, na, nb, n, nc, k, i;
    double ag = 0.0, ag_v = 0.0, a[N_ALL], b[N_ALL], x1[N_ALL], x2[N_ALL];
    int idx[RK_MAX_DOF];
    rk_model m;
    rk_error err;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "sOs|iOOdd", kwlist, &kind, &params_obj, &name, &mode, &a_obj,
                                     &b_obj, &ag, &ag_v))
        return NULL;
    rk_model_ops bare;
    if (build_model(kind, params_obj, &m) < 0)
        return NULL;
    if (strncmp(name, "bare:", 5) == 0 || strncmp(name, "bare_all:", 9) == 0) {
        /* a kernel with only the required functions (plus contact_forces and the model's own rules): the
         * generic fallbacks of rk_model.c, as a third model would get them */
        bare = *m.ops;
        bare.inverse_mass_matrix = NULL;
        bare.mode_rhs = NULL;
        bare.mode_monitors = NULL;
        bare.mode_outputs = NULL;
        if (name[4] == '_') {
            bare.contact_forces = NULL;     /* the generic contact forces too (contact.mode_forces, part B) */
            name += 4;
        }
        m.ops = &bare;
        name += 5;
    }
    if (read_list(a_obj, a, N_ALL, &na) < 0 || read_list(b_obj, b, N_ALL, &nb) < 0)
        return NULL;
    n = m.ops->n_dof;
    nc = m.ops->n_contacts;
    rk_error_clear(&err);
    memset(x1, 0, sizeof x1);
    memset(x2, 0, sizeof x2);
    if (mode < 0 || mode >= m.ops->n_modes) {
        PyErr_Format(PyExc_ValueError, "mode %d out of range", mode);
        return NULL;
    }
    /* ---------------------------------------------------------------- derived constants */
    if (strcmp(name, "derived") == 0) {
        return Py_BuildValue("{s:N,s:d,s:d,s:d,s:d,s:i,s:d,s:d,s:d,s:d,s:N,s:N}", "p", list_of(m.p, m.ops->n_params),
                             "e_N", m.e_N, "e_T", m.e_T, "mu", m.mu, "g", m.g, "impact_law", m.impact_law,
                             "length_scale", m.length_scale, "time_scale", m.time_scale, "force_scale",
                             m.force_scale, "step_limit", m.step_limit, "dof_scales", list_of(m.dof_scales, n),
                             "rest_abscissae", list_of(m.rest_abscissae, nc));
    }
    if (strcmp(name, "d") == 0)
        return list_of(m.d, RK_MAX_DERIVED);
    if (strcmp(name, "scale_tolerances") == 0) {
        rk_tolerances tol = RK_DEFAULT_TOLERANCES;
        rk_model_tolerances mt;
        rk_model_scale_tolerances(&m, &tol, &mt);
        return Py_BuildValue("{s:d,s:d,s:d,s:d,s:d,s:d,s:d}", "gap", mt.gap, "step_gap", mt.step_gap,
                             "rest_velocity", mt.rest_velocity, "step_rest_velocity", mt.step_rest_velocity,
                             "stateless_step", mt.stateless_step, "velocity_scale", mt.velocity_scale,
                             "force_floor", mt.force_floor);
    }
    /* ---------------------------------------------------------------- modes */
    if (strcmp(name, "mode_of") == 0)       /* a: the closed contacts, mode: sigma + 1 */
    {
        rk_set s = 0u;
        for (i = 0; i < na; i++)
            s |= 1u << (int)a[i];
        return PyLong_FromLong(m.ops->mode_of(&m, s, mode - 1));
    }
    if (strcmp(name, "closed_of") == 0) {
        rk_set s = m.ops->closed_of(&m, mode);
        k = 0;
        for (i = 0; i < nc; i++)
            if (RK_IN(s, i))
                idx[k++] = i;
        return int_list_of(idx, k);
    }
    if (strcmp(name, "stick_of") == 0) {
        int sigma = 0, st = m.ops->stick_of(&m, mode, &sigma);
        return Py_BuildValue("(ii)", st, sigma);
    }
    /* ---------------------------------------------------------------- dynamical system (a = q, b = v) */
    if (strcmp(name, "mass_matrix") == 0) {
        m.ops->mass_matrix(&m, a, x1);
        return list_of(x1, n * n);
    }
    if (strcmp(name, "inverse_mass") == 0) {
        rk_model_inverse_mass(&m, a, x1);
        return list_of(x1, n * n);
    }
    if (strcmp(name, "generic_inverse_mass") == 0) {
        rk_model_ops ops = *m.ops;
        ops.inverse_mass_matrix = NULL;
        m.ops = &ops;
        rk_model_inverse_mass(&m, a, x1);
        return list_of(x1, n * n);
    }
    if (strcmp(name, "forces") == 0) {
        m.ops->forces(&m, a, b, ag, ag_v, x1);
        return list_of(x1, n);
    }
    if (strcmp(name, "stiff_jacobians") == 0) {
        if (m.ops->stiff_jacobians == NULL || !m.ops->stiff_jacobians(&m, a, b, x1, x2))
            Py_RETURN_NONE;
        return Py_BuildValue("(NN)", list_of(x1, n * n), list_of(x2, n * n));
    }
    if (strcmp(name, "gaps") == 0) {
        m.ops->gaps(&m, a, x1);
        return list_of(x1, nc);
    }
    if (strcmp(name, "contact_jacobians") == 0) {
        m.ops->contact_jacobians(&m, a, x1, x2);
        return Py_BuildValue("(NN)", list_of(x1, n * nc), list_of(x2, n * nc));
    }
    if (strcmp(name, "contact_drift") == 0) {
        m.ops->contact_drift(&m, a, b, x1, x2);
        return Py_BuildValue("(NN)", list_of(x1, nc), list_of(x2, nc));
    }
    if (strcmp(name, "contact_abscissae") == 0) {
        m.ops->contact_abscissae(&m, a, x1);
        return list_of(x1, nc);
    }
    if (strcmp(name, "slip") == 0)
        return PyFloat_FromDouble(rk_model_slip(&m, a));
    if (strcmp(name, "rest_position") == 0) {
        m.ops->rest_position(&m, x1);
        return list_of(x1, n);
    }
    if (strcmp(name, "energy") == 0)
        return PyFloat_FromDouble(m.ops->energy(&m, a, b));
    if (strcmp(name, "outputs") == 0) {
        m.ops->outputs(&m, a, b, x1);
        return list_of(x1, m.ops->n_outputs);
    }
    if (strcmp(name, "initial_state") == 0) {
        int md;
        if (m.ops->initial_state(&m, a, &md, x1, x2, &err) != RK_OK)
            return value_error(&err);
        return Py_BuildValue("(iNN)", md, list_of(x1, n), list_of(x2, n));
    }
    if (strcmp(name, "classical_impact_velocity") == 0) {
        int rc = m.ops->classical_impact_velocity == NULL ? 0 : m.ops->classical_impact_velocity(&m, a, b, mode, x1);
        if (rc < 0) {
            PyErr_SetString(PyExc_ValueError, "classical_impact_velocity: invalid impact (the Python raises here)");
            return NULL;
        }
        if (rc == 0)
            Py_RETURN_NONE;
        return list_of(x1, n);
    }
    if (strcmp(name, "work_note") == 0) {
        char buf[RK_MSG_LEN] = "";
        if (m.ops->work_note != NULL)
            m.ops->work_note(&m, buf, sizeof buf);
        return PyUnicode_FromString(buf);
    }
    /* ---------------------------------------------------------------- sticking modes (kernel) */
    if (strcmp(name, "mode_dofs") == 0) {
        k = m.ops->mode_dofs(&m, mode, idx);
        return int_list_of(idx, k);
    }
    if (strcmp(name, "embed") == 0) {          /* a = r, b = r_dot */
        m.ops->embed(&m, mode, a, b, x1, x2);
        return Py_BuildValue("(NN)", list_of(x1, n), list_of(x2, n));
    }
    if (strcmp(name, "mode_jacobian") == 0) {
        k = m.ops->mode_dofs(&m, mode, idx);
        m.ops->mode_jacobian(&m, mode, a, b, x1, x2);
        return Py_BuildValue("(NN)", list_of(x1, n * k), list_of(x2, n));
    }
    if (strcmp(name, "kernel_rhs") == 0 || strcmp(name, "generic_rhs") == 0) {  /* a = y */
        k = m.ops->mode_dofs(&m, mode, idx);
        if (name[0] == 'k' && m.ops->mode_rhs != NULL)
            m.ops->mode_rhs(&m, mode, a, ag, ag_v, x1);
        else
            rk_model_generic_rhs(&m, mode, a, ag, ag_v, x1);
        return list_of(x1, 2 * k);
    }
    if (strcmp(name, "kernel_monitors") == 0 || strcmp(name, "generic_monitors") == 0) {
        rk_set s = m.ops->closed_of(&m, mode);
        for (i = 0; i < 2; i++)
            x2[i] = NAN;
        if (name[0] == 'k' && m.ops->mode_monitors != NULL)
            m.ops->mode_monitors(&m, mode, a, ag, ag_v, x1, x2);
        else
            rk_model_generic_monitors(&m, mode, a, ag, ag_v, x1, x2);
        if (!s)
            return Py_BuildValue("(NO)", list_of(x1, nc + 1), Py_None);
        return Py_BuildValue("(NN)", list_of(x1, nc + 1), list_of(x2, 2));
    }
    if (strcmp(name, "mode_outputs") == 0) {
        if (m.ops->mode_outputs == NULL)
            Py_RETURN_NONE;
        m.ops->mode_outputs(&m, mode, a, x1);
        return list_of(x1, m.ops->n_outputs);
    }
    if (strcmp(name, "contact_forces") == 0) {
        if (m.ops->contact_forces == NULL)
            Py_RETURN_NONE;
        m.ops->contact_forces(&m, mode, a, b, ag, ag_v, x1);
        return list_of(x1, nc);
    }
    /* ---------------------------------------------------------------- any mode */
    if (strcmp(name, "dofs_of") == 0) {
        k = rk_dofs_of(&m, mode, idx);
        return int_list_of(idx, k);
    }
    if (strcmp(name, "embed_any") == 0) {      /* a = y */
        rk_embed_any(&m, mode, a, x1, x2);
        return Py_BuildValue("(NN)", list_of(x1, n), list_of(x2, n));
    }
    if (strcmp(name, "reduce_any") == 0) {
        k = rk_reduce_any(&m, mode, a, b, x1);
        return list_of(x1, 2 * k);
    }
    if (strcmp(name, "rhs") == 0) {
        rk_status st;
        k = rk_dofs_of(&m, mode, idx);
        st = rk_mode_rhs(&m, mode, a, ag, ag_v, x1);
        if (st != RK_OK) {
            PyErr_Format(PyExc_RuntimeError, "rk_mode_rhs failed with status %d", (int)st);
            return NULL;
        }
        return list_of(x1, 2 * k);
    }
    if (strcmp(name, "monitors") == 0) {
        int has = 0, ng = rk_mode_monitors(&m, mode, a, ag, ag_v, x1, x2, &has);
        if (!has)
            return Py_BuildValue("(NO)", list_of(x1, ng), Py_None);
        return Py_BuildValue("(NN)", list_of(x1, ng), list_of(x2, 2));
    }
    if (strcmp(name, "monitors_only") == 0) {   /* rk_mode_monitors without totals (the event functions) */
        int ng = rk_mode_monitors(&m, mode, a, ag, ag_v, x1, NULL, NULL);
        return list_of(x1, ng);
    }
    if (strcmp(name, "monitor_one") == 0) {    /* rk_mode_monitor_one for each index: its value or None */
        int ng = rk_mode_monitors(&m, mode, a, ag, ag_v, x1, NULL, NULL);
        PyObject *lst = PyList_New(ng);
        if (lst == NULL)
            return NULL;
        for (i = 0; i < ng; i++) {
            double gi = NAN;
            PyObject *item = rk_mode_monitor_one(&m, mode, a, i, &gi) ? PyFloat_FromDouble(gi)
                                                                       : (Py_INCREF(Py_None), Py_None);
            if (item == NULL) {
                Py_DECREF(lst);
                return NULL;
            }
            PyList_SET_ITEM(lst, i, item);
        }
        return lst;
    }
    if (strcmp(name, "outputs_of") == 0) {     /* a = y, ag = shift */
        rk_outputs_of(&m, mode, a, ag, x1);
        return list_of(x1, m.ops->n_outputs);
    }
    if (strcmp(name, "shift_of") == 0)
        return PyFloat_FromDouble(rk_shift_of(&m, mode, a));
    if (strcmp(name, "force_totals") == 0) {
        rk_force_totals(&m, mode, a, b, ag, ag_v, x1);
        return list_of(x1, 2);
    }
    /* ---------------------------------------------------------------- sliding (a = r or q, b = r_dot or v) */
    if (strcmp(name, "slide_motion") == 0) {
        rk_set s = m.ops->closed_of(&m, mode);
        int kc = 0;
        for (i = 0; i < nc; i++)
            kc += RK_IN(s, i);
        if (rk_slide_motion(&m, mode, a, b, ag, ag_v, x1, x2) != RK_OK) {
            PyErr_SetString(PyExc_RuntimeError, "rk_slide_motion failed");
            return NULL;
        }
        return Py_BuildValue("(NN)", list_of(x1, n), list_of(x2, kc));
    }
    if (strcmp(name, "slide_acceleration") == 0) {
        k = rk_slide_dofs(&m, mode, idx);
        if (rk_slide_acceleration(&m, mode, a, b, ag, ag_v, x1) != RK_OK) {
            PyErr_SetString(PyExc_RuntimeError, "rk_slide_acceleration failed");
            return NULL;
        }
        return list_of(x1, k);
    }
    if (strcmp(name, "slide_jacobian") == 0) {
        k = rk_slide_dofs(&m, mode, idx);
        rk_slide_jacobian(&m, mode, a, b, x1, x2);
        return Py_BuildValue("(NN)", list_of(x1, n * k), list_of(x2, n));
    }
    PyErr_Format(PyExc_ValueError, "model_call: unknown function %s", name);
    return NULL;
}

/* _engine.model_float_repr(x): rk_float_repr (pinned to repr()) */
static PyObject *py_model_float_repr(PyObject *self, PyObject *arg)
{
    char buf[64];
    double x = PyFloat_AsDouble(arg);
    (void)self;
    if (x == -1.0 && PyErr_Occurred())
        return NULL;
    rk_float_repr(x, buf, sizeof buf);
    return PyUnicode_FromString(buf);
}

/* _engine.model_hypot(a, b): rk_py_hypot (pinned to math.hypot) */
static PyObject *py_model_hypot(PyObject *self, PyObject *args)
{
    double x, y;
    (void)self;
    if (!PyArg_ParseTuple(args, "dd", &x, &y))
        return NULL;
    return PyFloat_FromDouble(rk_py_hypot(x, y));
}

/* _engine.model_la(name, rows, cols, A, b, rcond): rk_la_solve / rk_la_lstsq (None: singular) */
static PyObject *py_model_la(PyObject *self, PyObject *args)
{
    const char *name;
    int rows, cols, na, nb;
    double rcond, A[N_ALL * 4], b[RK_MAX_Y], x[RK_MAX_Y];
    PyObject *A_obj, *b_obj;
    rk_status st;
    (void)self;
    if (!PyArg_ParseTuple(args, "siiOOd", &name, &rows, &cols, &A_obj, &b_obj, &rcond))
        return NULL;
    if (rows < 1 || cols < 1 || rows > RK_MAX_Y || cols > RK_MAX_Y || (name[0] == 's' && rows > RK_MAX_DOF)) {
        PyErr_SetString(PyExc_ValueError, "size out of range");
        return NULL;
    }
    if (read_list(A_obj, A, N_ALL * 4, &na) < 0 || read_list(b_obj, b, RK_MAX_Y, &nb) < 0)
        return NULL;
    st = name[0] == 's' ? rk_la_solve(rows, A, b, x) : rk_la_lstsq(rows, cols, A, b, rcond, x);
    if (st != RK_OK)
        Py_RETURN_NONE;
    return list_of(x, cols);
}

PyMethodDef rk_py_model_methods[] = {
    {"model_call", (PyCFunction)(void (*)(void))py_model_call, METH_VARARGS | METH_KEYWORDS,
     "model_call(kind, params, name, mode=0, a=None, b=None, ag=0.0): a C model kernel function (tests)"},
    {"model_kinds", py_model_kinds, METH_NOARGS, "the registered model kernels and their declarations"},
    {"model_float_repr", py_model_float_repr, METH_O, "rk_float_repr(x)"},
    {"model_hypot", py_model_hypot, METH_VARARGS, "rk_py_hypot(a, b)"},
    {"model_la", py_model_la, METH_VARARGS, "rk_la_solve / rk_la_lstsq"},
    {NULL, NULL, 0, NULL}
};
