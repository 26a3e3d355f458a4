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

/* ------------------------------------------------------------------------------------------ model level */

/* A test model with constant matrices (two contacts, the rocking models' mode codes), so that the contact.py
 * functions can be pinned independently of the kernels of part A: d[0..15] Minv, d[16..23] W_N,
 * d[24..31] W_T (n_dof <= 4), p[0..3] forces, p[4..5] gaps, p[6..7] a_N, p[8..9] a_T. */
#define TM_DOF_MAX 4
static int tm_mode_of(const rk_model *m, rk_set closed, int sigma)
{
    int mode;
    (void)m;
    if (closed == 3u)
        mode = RK_MODE_FULL;
    else if (closed == 1u)
        mode = RK_MODE_LEFT;
    else if (closed == 2u)
        mode = RK_MODE_RIGHT;
    else
        return RK_MODE_FLIGHT;
    if (!sigma)
        return mode;
    return 4 + 2 * mode + (sigma > 0 ? 0 : 1);
}
static rk_set tm_closed_of(const rk_model *m, int mode)
{
    static const rk_set closed[10] = {3u, 1u, 2u, 0u, 3u, 3u, 1u, 1u, 2u, 2u};
    (void)m;
    return (mode >= 0 && mode < 10) ? closed[mode] : 0u;
}
static void tm_inverse_mass(const rk_model *m, const double *q, double *Minv)
{
    int n = m->ops->n_dof, i;
    (void)q;
    for (i = 0; i < n * n; i++)
        Minv[i] = m->d[i];
}
static void tm_forces(const rk_model *m, const double *q, const double *v, double ag, double ag_v, double *f)
{
    int i;
    (void)q; (void)v; (void)ag; (void)ag_v;
    for (i = 0; i < m->ops->n_dof; i++)
        f[i] = m->p[i];
}
static void tm_gaps(const rk_model *m, const double *q, double *g)
{
    (void)q;
    g[0] = m->p[4];
    g[1] = m->p[5];
}
static void tm_jacobians(const rk_model *m, const double *q, double *W_N, double *W_T)
{
    int i, n = m->ops->n_dof;
    (void)q;
    for (i = 0; i < 2 * n; i++) {
        W_N[i] = m->d[16 + i];
        W_T[i] = m->d[24 + i];
    }
}
static void tm_drift(const rk_model *m, const double *q, const double *v, double *a_N, double *a_T)
{
    (void)q; (void)v;
    a_N[0] = m->p[6];
    a_N[1] = m->p[7];
    a_T[0] = m->p[8];
    a_T[1] = m->p[9];
}

/** data = (Minv, W_N, W_T, f, g, a_N, a_T, e_N, e_T, mu) -> the test model (ops filled, m->ops = ops). */
static int test_model(PyObject *data, rk_model_ops *ops, rk_model *m)
{
    PyObject *Minv, *W_N, *W_T, *f, *g, *a_N, *a_T;
    double e_N, e_T, mu, buf[64];
    int r, c, r2, c2, r3, c3, i;
    if (!PyArg_ParseTuple(data, "OOOOOOOddd", &Minv, &W_N, &W_T, &f, &g, &a_N, &a_T, &e_N, &e_T, &mu))
        return -1;
    memset(ops, 0, sizeof *ops);
    memset(m, 0, sizeof *m);
    if (get_matrix(Minv, "Minv", buf, TM_DOF_MAX, TM_DOF_MAX, &r, &c) < 0)
        return -1;
    if (r != c || r < 1) {
        PyErr_SetString(PyExc_ValueError, "Minv must be square, 1 to 4 dofs");
        return -1;
    }
    for (i = 0; i < r * r; i++)
        m->d[i] = buf[i];
    if (get_matrix(W_N, "W_N", m->d + 16, TM_DOF_MAX, 2, &r2, &c2) < 0
        || get_matrix(W_T, "W_T", m->d + 24, TM_DOF_MAX, 2, &r3, &c3) < 0)
        return -1;
    if (r2 != r || r3 != r || c2 != 2 || c3 != 2) {
        PyErr_SetString(PyExc_ValueError, "W_N and W_T must be n_dof x 2");
        return -1;
    }
    if (get_vector(f, "f", m->p, TM_DOF_MAX) != r || get_vector(g, "g", m->p + 4, 2) != 2
        || get_vector(a_N, "a_N", m->p + 6, 2) != 2 || get_vector(a_T, "a_T", m->p + 8, 2) != 2) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "f has n_dof values, g, a_N, a_T two");
        return -1;
    }
    ops->kind = "contact-test";
    ops->class_name = "ContactTestModel";
    ops->n_dof = r;
    ops->n_contacts = 2;
    ops->n_modes = 10;
    ops->mode_of = tm_mode_of;
    ops->closed_of = tm_closed_of;
    ops->inverse_mass_matrix = tm_inverse_mass;
    ops->forces = tm_forces;
    ops->gaps = tm_gaps;
    ops->contact_jacobians = tm_jacobians;
    ops->contact_drift = tm_drift;
    m->ops = ops;
    rk_model_tabulate_modes(m);
    m->e_N = e_N;
    m->e_T = e_T;
    m->mu = mu;
    return 0;
}

/** model = a test-model tuple, or (kind, params) of a kernel of part A. */
static int get_model(PyObject *spec, rk_model_ops *ops, rk_model *m)
{
    const char *kind;
    PyObject *params;
    double p[RK_MAX_PARAMS];
    Py_ssize_t n;
    const rk_model_ops *found;
    rk_error err;
    if (PyTuple_Check(spec) && PyTuple_GET_SIZE(spec) == 10)
        return test_model(spec, ops, m);
    if (!PyArg_ParseTuple(spec, "sO", &kind, &params))
        return -1;
    n = get_vector(params, "params", p, RK_MAX_PARAMS);
    if (n < 0)
        return -1;
    found = rk_model_find(kind);
    if (found == NULL) {
        PyErr_Format(PyExc_NotImplementedError, "no C kernel for model kind %s (part A)", kind);
        return -1;
    }
    if (rk_model_init(m, found, p, (int)n, &err) != RK_OK) {
        raise_err(&err);
        return -1;
    }
    return 0;
}

static PyObject *py_model_call(PyObject *self, PyObject *args)
{
    PyObject *spec, *rest, *res = NULL;
    const char *name;
    rk_model_ops ops;
    rk_model m;
    rk_error err;
    rk_lcp_solution sol;
    int nd, n;
    (void)self;
    if (PyTuple_GET_SIZE(args) < 2) {
        PyErr_SetString(PyExc_TypeError, "contact_model_call(name, model, *args)");
        return NULL;
    }
    name = PyUnicode_AsUTF8(PyTuple_GET_ITEM(args, 0));
    if (name == NULL)
        return NULL;
    spec = PyTuple_GET_ITEM(args, 1);
    rest = PyTuple_GetSlice(args, 2, PyTuple_GET_SIZE(args));
    if (rest == NULL)
        return NULL;
    if (get_model(spec, &ops, &m) < 0)
        goto done;
    nd = m.ops->n_dof;
    n = m.ops->n_contacts;
    if (strcmp(name, "impact") == 0) {
        /* (q, v_minus, candidates, forced, prefer, e[, lcp_exact, lcp_hint]) with e None or (e_N, e_T) */
        PyObject *q, *v, *cand, *forced, *e;
        double qa[RK_MAX_DOF], va[RK_MAX_DOF];
        rk_tolerances tol = RK_DEFAULT_TOLERANCES;
        rk_contact_args a;
        int prefer;
        if (!PyArg_ParseTuple(rest, "OOOOiO|dd", &q, &v, &cand, &forced, &prefer, &e, &tol.lcp_exact,
                              &tol.lcp_hint))
            goto done;
        rk_contact_args_default(&a);
        a.tolerances = &tol;
        if (get_vector(q, "q", qa, nd) != nd || get_vector(v, "v", va, nd) != nd
            || get_set(forced, "forced", &a.forced, NULL) < 0)
            goto bad_vec;
        {
            rk_set c;
            if (get_set(cand, "candidates", &c, NULL) < 0)
                goto done;
            a.prefer = prefer;
            if (e != Py_None) {
                if (!PyArg_ParseTuple(e, "dd", &a.e_N, &a.e_T))
                    goto done;
                a.has_e = 1;
            }
            if (rk_impact(&m, qa, va, c, &a, &sol, &err) != RK_OK) {
                raise_err(&err);
                goto done;
            }
        }
        res = narrow_dict(&sol, nd, n);
    } else if (strcmp(name, "uplift") == 0) {
        /* (q, v, ag, candidates, forced, slip_tol or None, count, prefer[, ag_v, lcp_exact, lcp_hint]) */
        PyObject *q, *v, *cand, *forced, *slip;
        double qa[RK_MAX_DOF], va[RK_MAX_DOF], ag, ag_v = 0.0;
        rk_tolerances tol = RK_DEFAULT_TOLERANCES;
        rk_contact_args a;
        rk_set c;
        int count, prefer;
        if (!PyArg_ParseTuple(rest, "OOdOOOpi|ddd", &q, &v, &ag, &cand, &forced, &slip, &count, &prefer,
                              &ag_v, &tol.lcp_exact, &tol.lcp_hint))
            goto done;
        rk_contact_args_default(&a);
        a.tolerances = &tol;
        if (get_vector(q, "q", qa, nd) != nd || get_vector(v, "v", va, nd) != nd)
            goto bad_vec;
        if (get_set(cand, "candidates", &c, NULL) < 0 || get_set(forced, "forced", &a.forced, NULL) < 0)
            goto done;
        if (slip != Py_None) {
            a.has_slip_tol = 1;
            a.slip_tol = PyFloat_AsDouble(slip);
            if (PyErr_Occurred())
                goto done;
        }
        a.count = count;
        a.prefer = prefer;
        if (rk_uplift(&m, qa, va, ag, ag_v, c, &a, &sol, &err) != RK_OK) {
            raise_err(&err);
            goto done;
        }
        res = narrow_dict(&sol, nd, n);
    } else if (strcmp(name, "solve_with_friction") == 0) {
        /* (v_free, b_N, b_T, candidates, forced, sliding, count, hint, prefer, lcp_exact, lcp_hint
         *  [, Minv, W_N, W_T]): the model's matrices at q = 0 unless given (Moreau-Jean's effective ones) */
        PyObject *vf, *bN, *bT, *cand, *forced, *sliding, *hint, *mi = NULL, *wn = NULL, *wt = NULL;
        double va[RK_MAX_DOF], b1[RK_MAX_CONTACTS], b2[RK_MAX_CONTACTS], Minv[RK_MAX_DOF * RK_MAX_DOF];
        double W_N[RK_MAX_DOF * RK_MAX_CONTACTS], W_T[RK_MAX_DOF * RK_MAX_CONTACTS], q0[RK_MAX_DOF] = {0};
        int sl[RK_LCP_MAX_CONTACTS], count, prefer, has;
        rk_tolerances tol = RK_DEFAULT_TOLERANCES;
        rk_contact_args a;
        rk_lcp_problem p;
        if (!PyArg_ParseTuple(rest, "OOOOOOpOidd|OOO", &vf, &bN, &bT, &cand, &forced, &sliding, &count, &hint,
                              &prefer, &tol.lcp_exact, &tol.lcp_hint, &mi, &wn, &wt))
            goto done;
        rk_contact_args_default(&a);
        memset(&p, 0, sizeof p);
        if (get_vector(vf, "v_free", va, nd) != nd || get_vector(bN, "b_N", b1, n) != n
            || get_vector(bT, "b_T", b2, n) != n)
            goto bad_vec;
        if (get_set(cand, "candidates", &p.candidates, NULL) < 0 || get_set(forced, "forced", &p.forced, NULL) < 0
            || get_set(hint, "hint", &a.hint, &a.has_hint) < 0)
            goto done;
        has = get_sliding(sliding, sl, n);
        if (has < 0)
            goto done;
        a.sliding = has ? sl : NULL;
        a.count = count;
        a.prefer = prefer;
        a.tolerances = &tol;
        if (mi != NULL && wn != NULL && wt != NULL) {
            int r1, c1, r2, c2, r3, c3;
            if (get_matrix(mi, "Minv", Minv, nd, nd, &r1, &c1) < 0 || get_matrix(wn, "W_N", W_N, nd, n, &r2, &c2) < 0
                || get_matrix(wt, "W_T", W_T, nd, n, &r3, &c3) < 0)
                goto done;
            if (r1 != nd || c1 != nd || r2 != nd || c2 != n || r3 != nd || c3 != n) {
                PyErr_SetString(PyExc_ValueError, "Minv must be n_dof x n_dof, W_N and W_T n_dof x n_contacts");
                goto done;
            }
        } else {
            rk_model_inverse_mass(&m, q0, Minv);
            m.ops->contact_jacobians(&m, q0, W_N, W_T);
        }
        p.n_dof = nd;
        p.n_contacts = n;
        p.Minv = Minv;
        p.W_N = W_N;
        p.W_T = W_T;
        p.v_free = va;
        p.b_N = b1;
        p.b_T = b2;
        if (rk_solve_with_friction(&m, &p, &a, &sol, &err) != RK_OK) {
            raise_err(&err);
            goto done;
        }
        res = narrow_dict(&sol, nd, n);
    } else if (strcmp(name, "project_to_ground") == 0) {
        PyObject *q, *corners;
        double qa[RK_MAX_DOF], out[RK_MAX_DOF];
        rk_set c;
        if (!PyArg_ParseTuple(rest, "OO", &q, &corners))
            goto done;
        if (get_vector(q, "q", qa, nd) != nd)
            goto bad_vec;
        if (get_set(corners, "corners", &c, NULL) < 0)
            goto done;
        if (rk_project_to_ground(&m, qa, c, out, &err) != RK_OK) {
            raise_err(&err);
            goto done;
        }
        res = list_of(out, nd);
    } else if (strcmp(name, "closed_candidates") == 0) {
        PyObject *q, *v;
        double qa[RK_MAX_DOF], va[RK_MAX_DOF], gap_tol, v_tol;
        if (!PyArg_ParseTuple(rest, "OOdd", &q, &v, &gap_tol, &v_tol))
            goto done;
        if (get_vector(q, "q", qa, nd) != nd || get_vector(v, "v", va, nd) != nd)
            goto bad_vec;
        res = set_tuple_of(rk_closed_candidates(&m, qa, va, gap_tol, v_tol), n);
    } else if (strcmp(name, "sliding_delassus") == 0) {
        PyObject *q;
        double qa[RK_MAX_DOF], sigma;
        int i;
        if (!PyArg_ParseTuple(rest, "Oid", &q, &i, &sigma))
            goto done;
        if (get_vector(q, "q", qa, nd) != nd)
            goto bad_vec;
        if (i < 0 || i >= n) {
            PyErr_SetString(PyExc_ValueError, "i is not a contact");
            goto done;
        }
        res = PyFloat_FromDouble(rk_sliding_delassus(&m, qa, i, sigma));
    } else if (strcmp(name, "painleve_sticks") == 0) {
        PyObject *q, *v1, *v2, *cand;
        double qa[RK_MAX_DOF], va[RK_MAX_DOF], vb[RK_MAX_DOF], v_tol;
        rk_set c;
        if (!PyArg_ParseTuple(rest, "OOOOd", &q, &v1, &v2, &cand, &v_tol))
            goto done;
        if (get_vector(q, "q", qa, nd) != nd || get_vector(v1, "v_minus", va, nd) != nd
            || get_vector(v2, "v_plus", vb, nd) != nd)
            goto bad_vec;
        if (get_set(cand, "candidates", &c, NULL) < 0)
            goto done;
        res = set_tuple_of(rk_painleve_sticks(&m, qa, va, vb, c, v_tol), n);
    } else if (strcmp(name, "next_mode") == 0) {
        PyObject *q, *v, *d;
        double qa[RK_MAX_DOF], va[RK_MAX_DOF], ag, gap_tol, v_tol, ag_v = 0.0;
        int prefer, mode, has;
        rk_tolerances tol = RK_DEFAULT_TOLERANCES;
        /* (q, v, ag, gap_tol, v_tol, prefer[, ag_v, lcp_exact, lcp_hint]) */
        if (!PyArg_ParseTuple(rest, "OOdddi|ddd", &q, &v, &ag, &gap_tol, &v_tol, &prefer, &ag_v, &tol.lcp_exact,
                              &tol.lcp_hint))
            goto done;
        if (get_vector(q, "q", qa, nd) != nd || get_vector(v, "v", va, nd) != nd)
            goto bad_vec;
        if (rk_next_mode(&m, qa, va, ag, ag_v, gap_tol, v_tol, prefer, &tol, &mode, &sol, &has, &err) != RK_OK) {
            raise_err(&err);
            goto done;
        }
        if (has) {
            d = narrow_dict(&sol, nd, n);
            if (d == NULL)
                goto done;
        } else {
            d = Py_None;
            Py_INCREF(d);
        }
        res = Py_BuildValue("(iN)", mode, d);
    } else if (strcmp(name, "solution_sigma") == 0) {
        /* (states) of a frictional solution, or () for a sticking one */
        PyObject *states;
        double st[RK_MAX_CONTACTS];
        Py_ssize_t k = -1;
        int i;
        if (!PyArg_ParseTuple(rest, "O", &states))
            goto done;
        memset(&sol, 0, sizeof sol);
        k = get_vector(states, "states", st, RK_MAX_CONTACTS);
        if (k < 0)
            goto done;
        sol.frictional = k > 0;
        for (i = 0; i < k; i++)
            sol.states[i] = (int)st[i];
        res = PyLong_FromLong(rk_solution_sigma(&sol, (int)k));
    } else if (strcmp(name, "mode_forces") == 0) {
        PyObject *q, *v;
        double qa[RK_MAX_DOF], va[RK_MAX_DOF], ag, lam[RK_MAX_CONTACTS], ag_v = 0.0;
        int mode;
        /* (mode, q, v, ag[, ag_v]) */
        if (!PyArg_ParseTuple(rest, "iOOd|d", &mode, &q, &v, &ag, &ag_v))
            goto done;
        if (get_vector(q, "q", qa, nd) != nd || get_vector(v, "v", va, nd) != nd)
            goto bad_vec;
        if (rk_mode_forces(&m, mode, qa, va, ag, ag_v, lam, &err) != RK_OK) {
            raise_err(&err);
            goto done;
        }
        res = list_of(lam, n);
    } else {
        PyErr_Format(PyExc_ValueError, "unknown contact function %s", name);
    }
    goto done;
bad_vec:
    if (!PyErr_Occurred())
        PyErr_SetString(PyExc_ValueError, "q and v need n_dof values, per-contact arrays n_contacts");
done:
    Py_DECREF(rest);
    return res;
}

static PyObject *py_inexact_message(PyObject *self, PyObject *args)
{
    PyObject *active;
    double violation, t;
    const char *what;
    int n;
    rk_lcp_solution sol;
    char buf[RK_MSG_LEN];
    (void)self;
    if (!PyArg_ParseTuple(args, "Odids", &active, &violation, &n, &t, &what))
        return NULL;
    memset(&sol, 0, sizeof sol);
    if (get_set(active, "active", &sol.active, NULL) < 0)
        return NULL;
    sol.violation = violation;
    rk_inexact_message(&sol, n, t, what, buf, sizeof buf);
    return PyUnicode_FromString(buf);
}

static PyObject *py_lstsq(PyObject *self, PyObject *args)
{
    PyObject *A, *b;
    double a[256], bb[16], x[16];
    int r, c;
    (void)self;
    if (!PyArg_ParseTuple(args, "OO", &A, &b))
        return NULL;
    if (get_matrix(A, "A", a, 16, 16, &r, &c) < 0)
        return NULL;
    if (r != c || get_vector(b, "b", bb, 16) != r) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "A must be square (at most 16 x 16) and b match it");
        return NULL;
    }
    rk_lstsq_square(r, a, bb, x);
    return list_of(x, r);
}

PyMethodDef rk_py_contact_methods[] = {
    {"contact_solve_lcp", (PyCFunction)(void (*)(void))py_solve_lcp, METH_VARARGS | METH_KEYWORDS,
     "contact_solve_lcp(Minv, W_N, W_T, v_free, b_N, b_T, candidates, forced=None, rtol=1e-9, hint=None, "
     "hint_tol=1e-12, narrow=False) -> dict: lcp.solve_contact_lcp in C (narrow: through rk_solve_contact_lcp, "
     "at most RK_MAX_CONTACTS contacts)."},
    {"contact_solve_friction", (PyCFunction)(void (*)(void))py_solve_friction, METH_VARARGS | METH_KEYWORDS,
     "contact_solve_friction(Minv, W_N, W_T, v_free, b_N, b_T, candidates, mu, forced=None, rtol=1e-9, "
     "hint=None, sliding=None, count=False, narrow=False) -> dict: lcp.solve_friction_lcp in C."},
    {"contact_model_call", py_model_call, METH_VARARGS,
     "contact_model_call(name, model, *args): a contact.py function in C on a model: model is a test-model tuple "
     "(Minv, W_N, W_T, f, g, a_N, a_T, e_N, e_T, mu) or (kind, params) of a C kernel. name: impact, uplift, "
     "solve_with_friction, project_to_ground, closed_candidates, sliding_delassus, painleve_sticks, next_mode, "
     "solution_sigma, mode_forces (see tests/test_engine_contact.py for the arguments)."},
    {"contact_lstsq", py_lstsq, METH_VARARGS,
     "contact_lstsq(A, b) -> list: rk_lstsq_square, np.linalg.lstsq(A, b, rcond=1e-12)[0] of a square A."},
    {"contact_inexact_message", py_inexact_message, METH_VARARGS,
     "contact_inexact_message(active, violation, n_contacts, t, what) -> str: rk_inexact_message."},
    {NULL, NULL, 0, NULL}
};
