/* py_contact.c -- test entry points of part B for the pinning tests (tests/test_engine_contact.py): thin
 * wrappers that call the C functions of rk_contact on Python floats/lists and return dicts of lists,
 * registered into rocking_model._engine by _engine.c (PyModule_AddFunctions). Names start with "contact_" so
 * that the parts never collide. Not used by the engine itself.
 * Owner: part B. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <string.h>

#include "../src/rk_internal.h"

/* ------------------------------------------------------------------------------------------ conversions */

/** A flat sequence of floats into out (at most cap); returns its length or -1 with an exception. */
static Py_ssize_t get_vector(PyObject *obj, const char *name, double *out, Py_ssize_t cap)
{
    PyObject *fast = PySequence_Fast(obj, "");
    Py_ssize_t i, n;
    if (fast == NULL) {
        PyErr_Format(PyExc_TypeError, "%s must be a sequence of numbers", name);
        return -1;
    }
    n = PySequence_Fast_GET_SIZE(fast);
    if (n > cap) {
        Py_DECREF(fast);
        PyErr_Format(PyExc_ValueError, "%s holds %zd values, more than %zd", name, n, cap);
        return -1;
    }
    for (i = 0; i < n; i++) {
        out[i] = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(fast, i));
        if (out[i] == -1.0 && PyErr_Occurred()) {
            Py_DECREF(fast);
            return -1;
        }
    }
    Py_DECREF(fast);
    return n;
}

/** A matrix (sequence of rows) into out, row-major; rows and cols returned. */
static int get_matrix(PyObject *obj, const char *name, double *out, int max_rows, int max_cols, int *rows,
                      int *cols)
{
    PyObject *fast = PySequence_Fast(obj, "");
    Py_ssize_t i, n;
    *cols = -1;
    if (fast == NULL) {
        PyErr_Format(PyExc_TypeError, "%s must be a sequence of rows", name);
        return -1;
    }
    n = PySequence_Fast_GET_SIZE(fast);
    if (n > max_rows) {
        Py_DECREF(fast);
        PyErr_Format(PyExc_ValueError, "%s has %zd rows, more than %d", name, n, max_rows);
        return -1;
    }
    for (i = 0; i < n; i++) {
        double row[64];
        Py_ssize_t c = get_vector(PySequence_Fast_GET_ITEM(fast, i), name, row, max_cols), j;
        if (c < 0 || (*cols >= 0 && c != *cols)) {
            Py_DECREF(fast);
            if (c >= 0)
                PyErr_Format(PyExc_ValueError, "%s is not rectangular", name);
            return -1;
        }
        *cols = (int)c;
        for (j = 0; j < c; j++)
            out[i * c + j] = row[j];
    }
    Py_DECREF(fast);
    *rows = (int)n;
    if (*cols < 0)
        *cols = 0;
    return 0;
}

/** A set of contact indices (sequence of ints, or None -> has = 0) into a bit mask. */
static int get_set(PyObject *obj, const char *name, rk_set *out, int *has)
{
    PyObject *fast;
    Py_ssize_t i, n;
    *out = 0u;
    if (has != NULL)
        *has = 0;
    if (obj == NULL || obj == Py_None)
        return 0;
    fast = PySequence_Fast(obj, "");
    if (fast == NULL) {
        PyErr_Format(PyExc_TypeError, "%s must be a sequence of contact indices", name);
        return -1;
    }
    n = PySequence_Fast_GET_SIZE(fast);
    for (i = 0; i < n; i++) {
        long k = PyLong_AsLong(PySequence_Fast_GET_ITEM(fast, i));
        if (k == -1 && PyErr_Occurred()) {
            Py_DECREF(fast);
            return -1;
        }
        if (k < 0 || k >= 31) {
            Py_DECREF(fast);
            PyErr_Format(PyExc_ValueError, "%s holds %ld, not a contact index", name, k);
            return -1;
        }
        *out |= 1u << k;
    }
    Py_DECREF(fast);
    if (has != NULL)
        *has = 1;
    return 0;
}

/** The ``sliding`` dict {contact: sigma} (or None) into per-contact 0/+1/-1; returns 1 if given. */
static int get_sliding(PyObject *obj, int *sliding, int n)
{
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    int i;
    for (i = 0; i < RK_LCP_MAX_CONTACTS; i++)
        sliding[i] = 0;
    if (obj == NULL || obj == Py_None)
        return 0;
    if (!PyDict_Check(obj)) {
        PyErr_SetString(PyExc_TypeError, "sliding must be a dict {contact: sigma} or None");
        return -1;
    }
    while (PyDict_Next(obj, &pos, &key, &value)) {
        long k = PyLong_AsLong(key);
        double s = PyFloat_AsDouble(value);
        if (PyErr_Occurred())
            return -1;
        if (k < 0 || k >= n) {
            PyErr_Format(PyExc_ValueError, "sliding holds contact %ld, not in 0..%d", k, n - 1);
            return -1;
        }
        sliding[k] = s > 0 ? 1 : -1;
    }
    return 1;
}

static PyObject *list_of(const double *x, int n)
{
    PyObject *l = PyList_New(n);
    int i;
    if (l == NULL)
        return NULL;
    for (i = 0; i < n; i++)
        PyList_SET_ITEM(l, i, PyFloat_FromDouble(x[i]));
    return l;
}

static PyObject *int_tuple_of(const int *x, int n)
{
    PyObject *t = PyTuple_New(n);
    int i;
    if (t == NULL)
        return NULL;
    for (i = 0; i < n; i++)
        PyTuple_SET_ITEM(t, i, PyLong_FromLong(x[i]));
    return t;
}

static PyObject *set_tuple_of(rk_set s, int n)
{
    int idx[32], k = 0, i;
    for (i = 0; i < n; i++)
        if (RK_IN(s, i))
            idx[k++] = i;
    return int_tuple_of(idx, k);
}

static int put(PyObject *d, const char *key, PyObject *value)
{
    int rc;
    if (value == NULL)
        return -1;
    rc = PyDict_SetItemString(d, key, value);
    Py_DECREF(value);
    return rc;
}

/** The solution fields as a dict (the attribute names of lcp.ContactSolution / FrictionSolution). */
static PyObject *solution_dict(const double *v, int m, const double *P_N, const double *P_T, const double *w_N,
                               const double *w_T, rk_set active, int exact, double violation, int frictional,
                               const int *states, int n_solutions, int painleve, int n)
{
    PyObject *d = PyDict_New();
    if (d == NULL)
        return NULL;
    if (put(d, "v", list_of(v, m)) < 0 || put(d, "P_N", list_of(P_N, n)) < 0 || put(d, "P_T", list_of(P_T, n)) < 0
        || put(d, "w_N", list_of(w_N, n)) < 0 || put(d, "w_T", list_of(w_T, n)) < 0
        || put(d, "active", set_tuple_of(active, n)) < 0 || put(d, "exact", PyBool_FromLong(exact)) < 0
        || put(d, "violation", PyFloat_FromDouble(violation)) < 0
        || put(d, "states", frictional ? int_tuple_of(states, n) : PyTuple_New(0)) < 0
        || put(d, "n_solutions", PyLong_FromLong(n_solutions)) < 0
        || put(d, "painleve", PyBool_FromLong(painleve)) < 0) {
        Py_DECREF(d);
        return NULL;
    }
    return d;
}

static PyObject *wide_dict(const rk_lcp_wide_solution *s, int m, int n)
{
    int painleve = 0, i;
    if (s->frictional && s->n_solutions != -1 && s->n_solutions != 1) {
        for (i = 0; i < n; i++)
            painleve |= s->states[i] == RK_SLIDE_POS || s->states[i] == RK_SLIDE_NEG;
        painleve |= s->has_sliding;
    }
    return solution_dict(s->v, m, s->P_N, s->P_T, s->w_N, s->w_T, s->active, s->exact, s->violation,
                         s->frictional, s->states, s->n_solutions, painleve, n);
}

static PyObject *narrow_dict(const rk_lcp_solution *s, int m, int n)
{
    return solution_dict(s->v, m, s->P_N, s->P_T, s->w_N, s->w_T, s->active, s->exact, s->violation,
                         s->frictional, s->states, s->n_solutions, rk_lcp_painleve(s), n);
}

static PyObject *raise_err(const rk_error *err)
{
    PyErr_SetString(err->status == RK_ERR_VALUE ? PyExc_ValueError
                    : err->status == RK_ERR_NOT_IMPLEMENTED ? PyExc_NotImplementedError : PyExc_RuntimeError,
                    err->message);
    return NULL;
}

/* ------------------------------------------------------------------------------------------ the LCPs */

typedef struct problem_buf {
    double Minv[RK_MAX_DOF * RK_MAX_DOF];
    double W_N[RK_MAX_DOF * RK_LCP_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_LCP_MAX_CONTACTS];
    double v_free[RK_MAX_DOF], b_N[RK_LCP_MAX_CONTACTS], b_T[RK_LCP_MAX_CONTACTS];
    int sliding[RK_LCP_MAX_CONTACTS];
    int hint_states[RK_LCP_MAX_CONTACTS];
} problem_buf;

/** The arrays of a problem: Minv (m x m), W_N, W_T (m x n), v_free (m), b_N, b_T (n). */
static int read_problem(PyObject *Minv, PyObject *W_N, PyObject *W_T, PyObject *v_free, PyObject *b_N,
                        PyObject *b_T, problem_buf *b, rk_lcp_problem *p)
{
    int r1, c1, r2, c2, r3, c3;
    memset(p, 0, sizeof *p);
    if (get_matrix(Minv, "Minv", b->Minv, RK_MAX_DOF, RK_MAX_DOF, &r1, &c1) < 0
        || get_matrix(W_N, "W_N", b->W_N, RK_MAX_DOF, RK_LCP_MAX_CONTACTS, &r2, &c2) < 0
        || get_matrix(W_T, "W_T", b->W_T, RK_MAX_DOF, RK_LCP_MAX_CONTACTS, &r3, &c3) < 0)
        return -1;
    if (r1 != c1 || r2 != r1 || r3 != r1 || c3 != c2) {
        PyErr_SetString(PyExc_ValueError, "Minv must be m x m and W_N, W_T m x n");
        return -1;
    }
    if (get_vector(v_free, "v_free", b->v_free, r1) != r1 || get_vector(b_N, "b_N", b->b_N, c2) != c2
        || get_vector(b_T, "b_T", b->b_T, c2) != c2) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "v_free must have m values, b_N and b_T n");
        return -1;
    }
    p->n_dof = r1;
    p->n_contacts = c2;
    p->Minv = b->Minv;
    p->W_N = b->W_N;
    p->W_T = b->W_T;
    p->v_free = b->v_free;
    p->b_N = b->b_N;
    p->b_T = b->b_T;
    p->mu = INFINITY;
    return 0;
}

static PyObject *py_solve_lcp(PyObject *self, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"Minv", "W_N", "W_T", "v_free", "b_N", "b_T", "candidates", "forced", "rtol",
                             "hint", "hint_tol", "narrow", NULL};
    PyObject *Minv, *W_N, *W_T, *v_free, *b_N, *b_T, *cand, *forced = Py_None, *hint = Py_None;
    double rtol = 1e-9, hint_tol = 1e-12;
    int use_narrow = 0;
    problem_buf b;
    rk_lcp_problem p;
    rk_error err;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOOOOOO|OdOdp", kwlist, &Minv, &W_N, &W_T, &v_free, &b_N,
                                     &b_T, &cand, &forced, &rtol, &hint, &hint_tol, &use_narrow))
        return NULL;
    if (read_problem(Minv, W_N, W_T, v_free, b_N, b_T, &b, &p) < 0 || get_set(cand, "candidates", &p.candidates, NULL) < 0
        || get_set(forced, "forced", &p.forced, NULL) < 0 || get_set(hint, "hint", &p.hint, &p.has_hint) < 0)
        return NULL;
    p.rtol = rtol;
    p.hint_tol = hint_tol;
    if (use_narrow) {
        rk_lcp_solution s;
        if (rk_solve_contact_lcp(&p, &s, &err) != RK_OK)
            return raise_err(&err);
        return narrow_dict(&s, p.n_dof, p.n_contacts);
    } else {
        rk_lcp_wide_solution s;
        if (rk_solve_contact_lcp_wide(&p, &s, &err) != RK_OK)
            return raise_err(&err);
        return wide_dict(&s, p.n_dof, p.n_contacts);
    }
}

static PyObject *py_solve_friction(PyObject *self, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"Minv", "W_N", "W_T", "v_free", "b_N", "b_T", "candidates", "mu", "forced", "rtol",
                             "hint", "sliding", "count", "narrow", NULL};
    PyObject *Minv, *W_N, *W_T, *v_free, *b_N, *b_T, *cand, *forced = Py_None, *hint = Py_None,
             *sliding = Py_None;
    double rtol = 1e-9, mu;
    int count = 0, use_narrow = 0, has;
    problem_buf b;
    rk_lcp_problem p;
    rk_error err;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOOOOOOd|OdOOpp", kwlist, &Minv, &W_N, &W_T, &v_free, &b_N,
                                     &b_T, &cand, &mu, &forced, &rtol, &hint, &sliding, &count, &use_narrow))
        return NULL;
    if (read_problem(Minv, W_N, W_T, v_free, b_N, b_T, &b, &p) < 0 || get_set(cand, "candidates", &p.candidates, NULL) < 0
        || get_set(forced, "forced", &p.forced, NULL) < 0)
        return NULL;
    has = get_sliding(sliding, b.sliding, p.n_contacts);
    if (has < 0)
        return NULL;
    p.sliding = has ? b.sliding : NULL;
    if (hint != Py_None) {
        int n_cand = 0, i;
        double h[RK_LCP_MAX_CONTACTS];
        Py_ssize_t len = get_vector(hint, "hint", h, RK_LCP_MAX_CONTACTS);
        if (len < 0)
            return NULL;
        for (i = 0; i < p.n_contacts; i++)
            n_cand += RK_IN(p.candidates | p.forced, i);
        if (len == n_cand) {        /* the Python ignores a hint of another length */
            for (i = 0; i < n_cand; i++)
                b.hint_states[i] = (int)h[i];
            p.hint_states = b.hint_states;
        }
    }
    p.rtol = rtol;
    p.mu = mu;
    p.count = count;
    if (use_narrow) {
        rk_lcp_solution s;
        if (rk_solve_friction_lcp(&p, &s, &err) != RK_OK)
            return raise_err(&err);
        return narrow_dict(&s, p.n_dof, p.n_contacts);
    } else {
        rk_lcp_wide_solution s;
        if (rk_solve_friction_lcp_wide(&p, &s, &err) != RK_OK)
            return raise_err(&err);
        return wide_dict(&s, p.n_dof, p.n_contacts);
    }
}

PyMethodDef rk_py_contact_methods[] = {
    {"contact_solve_lcp", (PyCFunction)(void (*)(void))py_solve_lcp, METH_VARARGS | METH_KEYWORDS,
     "contact_solve_lcp(Minv, W_N, W_T, v_free, b_N, b_T, candidates, forced=None, rtol=1e-9, hint=None, "
     "hint_tol=1e-12, narrow=False) -> dict: lcp.solve_contact_lcp in C (narrow: through rk_solve_contact_lcp, "
     "at most RK_MAX_CONTACTS contacts)."},
    {"contact_solve_friction", (PyCFunction)(void (*)(void))py_solve_friction, METH_VARARGS | METH_KEYWORDS,
     "contact_solve_friction(Minv, W_N, W_T, v_free, b_N, b_T, candidates, mu, forced=None, rtol=1e-9, "
     "hint=None, sliding=None, count=False, narrow=False) -> dict: lcp.solve_friction_lcp in C."},
    {NULL, NULL, 0, NULL}
};
