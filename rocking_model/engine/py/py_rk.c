/* py_rk.c -- test entry points of part C for the pinning tests (tests/test_engine_rk.py): thin wrappers
 * that call the C functions of rk_rk on Python floats/lists and return lists, registered into
 * rocking_model._engine by _engine.c (PyModule_AddFunctions). Names start with "rk_" (e.g.
 * _engine.rk_...) so that the parts never collide. Not used by the engine itself.
 * Owner: part C.
 *
 * The right-hand sides and event functions here are small built-in test problems; the tests write the same
 * functions in Python (same operation order) and run rk.py / events.py on them:
 *   "harmonic" [w]:        y0' = y1, y1' = -w * w * y0
 *   "vdp" [mu]:            y0' = y1, y1' = mu * (1.0 - y0 * y0) * y1 - y0
 *   "rocking" [p2, alpha, a]: y0' = y1, y1' = -p2 * (sin(alpha - y0) + a * cos(alpha - y0))
 *   "chain" []:            yj' = sin(y[(j+1) % n]) - 0.5 * (j + 1) * yj       (any size n)
 *   "forced" [lam]:        yj' = lam * (cos(t + j) - yj)                        (time-dependent, stiff for large lam)
 *   "jump" [K]:            yj' = K if yj < 1.0 else -K                          (a discontinuous rhs: failed steps)
 *   "blowup" []:           yj' = yj * yj                                        (overflows: the non-finite error)
 *   "failing" [T]:         yj' = -yj, status RK_ERR_VALUE when t > T            (a failing callback)
 * Event functions: G_i(t, y) = c_i + d_i * t, then + W[i][j] * y_j for j = 0 .. n-1 in order. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <string.h>

#include "../src/rk_internal.h"
#include "../src/rk_tableaux.h"

enum { P_HARMONIC, P_VDP, P_ROCKING, P_CHAIN, P_FORCED, P_JUMP, P_BLOWUP, P_FAILING };

typedef struct test_problem {
    int kind;
    double p[4];
} test_problem;

static rk_status test_rhs(void *ctx, double t, const double *y, double *dy)
{
    const test_problem *pb = (const test_problem *)ctx;
    int n = (int)pb->p[3], j;           /* the state size, carried in p[3] by parse_problem */
    switch (pb->kind) {
    case P_HARMONIC:
        dy[0] = y[1];
        dy[1] = -pb->p[0] * pb->p[0] * y[0];
        break;
    case P_VDP:
        dy[0] = y[1];
        dy[1] = pb->p[0] * (1.0 - y[0] * y[0]) * y[1] - y[0];
        break;
    case P_ROCKING:
        dy[0] = y[1];
        dy[1] = -pb->p[0] * (sin(pb->p[1] - y[0]) + pb->p[2] * cos(pb->p[1] - y[0]));
        break;
    case P_CHAIN:
        for (j = 0; j < n; j++)
            dy[j] = sin(y[(j + 1) % n]) - 0.5 * (j + 1) * y[j];
        break;
    case P_FORCED:
        for (j = 0; j < n; j++)
            dy[j] = pb->p[0] * (cos(t + j) - y[j]);
        break;
    case P_JUMP:
        for (j = 0; j < n; j++)
            dy[j] = y[j] < 1.0 ? pb->p[0] : -pb->p[0];
        break;
    case P_BLOWUP:
        for (j = 0; j < n; j++)
            dy[j] = y[j] * y[j];
        break;
    case P_FAILING:
        if (t > pb->p[0])
            return RK_ERR_VALUE;
        for (j = 0; j < n; j++)
            dy[j] = -y[j];
        break;
    default:
        return RK_ERR_INTERNAL;
    }
    return RK_OK;
}

typedef struct test_events {
    int n_events, n;
    double W[RK_MAX_EVENTS][RK_MAX_Y], c[RK_MAX_EVENTS], d[RK_MAX_EVENTS];
} test_events;

static rk_status test_G(void *ctx, double t, const double *y, double *g)
{
    const test_events *ev = (const test_events *)ctx;
    int i, j;
    for (i = 0; i < ev->n_events; i++) {
        double v = ev->c[i] + ev->d[i] * t;
        for (j = 0; j < ev->n; j++)
            v = v + ev->W[i][j] * y[j];
        g[i] = v;
    }
    return RK_OK;
}

/* ------------------------------------------------------------------------------------------ conversions */
static int get_doubles(PyObject *seq, const char *name, double *out, int cap, int *n)
{
    PyObject *fast;
    Py_ssize_t i, len;
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
            return -1;
        }
        out[i] = x;
    }
    Py_DECREF(fast);
    *n = (int)len;
    return 0;
}

static int get_ints(PyObject *seq, const char *name, int *out, int cap, int *n)
{
    PyObject *fast;
    Py_ssize_t i, len;
    fast = PySequence_Fast(seq, "");
    if (fast == NULL) {
        PyErr_Format(PyExc_TypeError, "%s must be a sequence of ints", name);
        return -1;
    }
    len = PySequence_Fast_GET_SIZE(fast);
    if (len > cap) {
        Py_DECREF(fast);
        PyErr_Format(PyExc_ValueError, "%s holds %zd values, more than %d", name, len, cap);
        return -1;
    }
    for (i = 0; i < len; i++) {
        long x = PyLong_AsLong(PySequence_Fast_GET_ITEM(fast, i));
        if (x == -1 && PyErr_Occurred()) {
            Py_DECREF(fast);
            return -1;
        }
        out[i] = (int)x;
    }
    Py_DECREF(fast);
    *n = (int)len;
    return 0;
}

static PyObject *list_of(const double *x, int n)
{
    PyObject *l = PyList_New(n);
    int i;
    if (l == NULL)
        return NULL;
    for (i = 0; i < n; i++) {
        PyObject *v = PyFloat_FromDouble(x[i]);
        if (v == NULL) {
            Py_DECREF(l);
            return NULL;
        }
        PyList_SET_ITEM(l, i, v);
    }
    return l;
}

static PyObject *int_list_of(const int *x, int n)
{
    PyObject *l = PyList_New(n);
    int i;
    if (l == NULL)
        return NULL;
    for (i = 0; i < n; i++) {
        PyObject *v = PyLong_FromLong(x[i]);
        if (v == NULL) {
            Py_DECREF(l);
            return NULL;
        }
        PyList_SET_ITEM(l, i, v);
    }
    return l;
}

static PyObject *raise_rk(const rk_error *err)
{
    PyObject *type;
    switch (err->status) {
    case RK_ERR_VALUE: case RK_ERR_NONFINITE: type = PyExc_ValueError; break;
    case RK_ERR_NOT_IMPLEMENTED: type = PyExc_NotImplementedError; break;
    case RK_ERR_MEMORY: type = PyExc_MemoryError; break;
    default: type = PyExc_RuntimeError; break;
    }
    PyErr_Format(type, "[%s] %s", rk_status_name(err->status), err->message);
    return NULL;
}

static int parse_problem(const char *name, PyObject *params, int n, test_problem *pb)
{
    static const char *const names[] = {"harmonic", "vdp", "rocking", "chain", "forced", "jump", "blowup", "failing"};
    int k, np = 0;
    memset(pb, 0, sizeof *pb);
    pb->kind = -1;
    for (k = 0; k < 8; k++)
        if (strcmp(name, names[k]) == 0)
            pb->kind = k;
    if (pb->kind < 0) {
        PyErr_Format(PyExc_ValueError, "unknown test problem %s", name);
        return -1;
    }
    if (get_doubles(params, "params", pb->p, 3, &np) < 0)
        return -1;
    if ((pb->kind == P_HARMONIC || pb->kind == P_VDP || pb->kind == P_ROCKING) && n != 2) {
        PyErr_Format(PyExc_ValueError, "test problem %s has 2 states, not %d", name, n);
        return -1;
    }
    pb->p[3] = (double)n;
    return 0;
}

/* a stepper on a test problem: method, problem, params, t0, y0, rtol, atol, max_step, first_step (None) */
typedef struct test_setup {
    test_problem pb;
    rk_stepper st;
    test_events ev;
} test_setup;

static int make_stepper(test_setup *ts, int method, const char *problem, PyObject *params, double t0, PyObject *y0_obj,
                        double rtol, PyObject *atol_obj, double max_step, PyObject *first_obj)
{
    double y0[RK_MAX_Y], atol[RK_MAX_Y], first = NAN;
    int n = 0, na = 0;
    rk_error err;
    const rk_tableau *tab = rk_tableau_of((rk_method)method);
    if (tab == NULL) {
        PyErr_Format(PyExc_ValueError, "unknown method %d", method);
        return -1;
    }
    if (get_doubles(y0_obj, "y0", y0, RK_MAX_Y, &n) < 0 || get_doubles(atol_obj, "atol", atol, RK_MAX_Y, &na) < 0)
        return -1;
    if (na != n) {
        PyErr_SetString(PyExc_ValueError, "atol and y0 differ in size");
        return -1;
    }
    if (first_obj != Py_None) {
        first = PyFloat_AsDouble(first_obj);
        if (first == -1.0 && PyErr_Occurred())
            return -1;
    }
    if (parse_problem(problem, params, n, &ts->pb) < 0)
        return -1;
    if (rk_stepper_init(&ts->st, tab, test_rhs, &ts->pb, t0, y0, n, rtol, atol, max_step, first, NULL, &err) != RK_OK) {
        raise_rk(&err);
        return -1;
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------ tableaux */
static PyObject *lincomb_obj(const rk_lincomb *lc)
{
    PyObject *idx = int_list_of(lc->idx, lc->n), *val = list_of(lc->c, lc->n);
    if (idx == NULL || val == NULL) {
        Py_XDECREF(idx);
        Py_XDECREF(val);
        return NULL;
    }
    return Py_BuildValue("(NN)", idx, val);
}

static PyObject *py_rk_tableau(PyObject *self, PyObject *args)
{
    int method, s;
    const rk_tableau *tab;
    PyObject *A, *E, *D;
    (void)self;
    if (!PyArg_ParseTuple(args, "i", &method))
        return NULL;
    tab = rk_tableau_of((rk_method)method);
    if (tab == NULL)
        return PyErr_Format(PyExc_ValueError, "unknown method %d", method);
    A = PyList_New(tab->n_all);
    E = PyList_New(tab->n_errors);
    D = PyList_New(tab->n_dense);
    if (A == NULL || E == NULL || D == NULL)
        goto fail;
    for (s = 0; s < tab->n_all; s++) {
        PyObject *o = lincomb_obj(&tab->A[s]);
        if (o == NULL)
            goto fail;
        PyList_SET_ITEM(A, s, o);
    }
    for (s = 0; s < tab->n_errors; s++) {
        PyObject *o = lincomb_obj(&tab->E[s]);
        if (o == NULL)
            goto fail;
        PyList_SET_ITEM(E, s, o);
    }
    for (s = 0; s < tab->n_dense; s++) {
        PyObject *o = lincomb_obj(&tab->D[s]);
        if (o == NULL)
            goto fail;
        PyList_SET_ITEM(D, s, o);
    }
    return Py_BuildValue("{s:s,s:i,s:i,s:i,s:i,s:N,s:N,s:N,s:N,s:N}", "name", rk_tableau_name(tab),
                         "order", tab->order, "error_order", tab->error_order, "n_stages", tab->n_stages,
                         "n_all", tab->n_all, "C", list_of(tab->C, tab->n_all), "A", A, "B", lincomb_obj(&tab->B),
                         "E", E, "D", D);
fail:
    Py_XDECREF(A);
    Py_XDECREF(E);
    Py_XDECREF(D);
    return NULL;
}

/* ------------------------------------------------------------------------------------------ integrate */
static PyObject *step_record(rk_stepper *st, const double *fractions, int n_fr)
{
    double y[RK_MAX_Y], mid[RK_MAX_Y];
    PyObject *dense = PyList_New(n_fr), *failure;
    rk_error err;
    int k;
    if (dense == NULL)
        return NULL;
    for (k = 0; k < n_fr; k++) {
        double t = st->t_old + fractions[k] * (st->t - st->t_old);
        PyObject *o;
        if (rk_dense_eval(st, t, y, &err) != RK_OK) {
            Py_DECREF(dense);
            return raise_rk(&err);
        }
        o = list_of(y, st->n);
        if (o == NULL) {
            Py_DECREF(dense);
            return NULL;
        }
        PyList_SET_ITEM(dense, k, o);
    }
    rk_hermite_mid(st, mid);
    failure = st->failed ? PyUnicode_FromString(st->failure) : (Py_INCREF(Py_None), Py_None);
    st->failed = 0;
    return Py_BuildValue("{s:d,s:d,s:N,s:N,s:d,s:L,s:L,s:N,s:N,s:N}", "t_old", st->t_old, "t", st->t,
                         "y", list_of(st->y, st->n), "f", list_of(st->f, st->n), "h_abs", st->h_abs,
                         "n_steps", st->n_steps, "n_rejected", st->n_rejected, "failure", failure,
                         "dense", dense, "mid", list_of(mid, st->n));
}

static PyObject *py_rk_integrate(PyObject *self, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"method", "problem", "params", "t0", "y0", "rtol", "atol", "max_step", "first_step",
                             "t_bounds", "max_steps", "fractions", NULL};
    int method, max_steps = 1000, n_b = 0, n_fr = 0, k, count = 0;
    const char *problem;
    PyObject *params, *y0, *atol, *first = Py_None, *bounds_obj, *fr_obj = NULL, *steps = NULL, *res;
    double t0, rtol, max_step = INFINITY, bounds[64], fractions[32];
    test_setup *ts;
    rk_error err;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "isOdOdO|dOOiO", kwlist, &method, &problem, &params, &t0, &y0,
                                     &rtol, &atol, &max_step, &first, &bounds_obj, &max_steps, &fr_obj))
        return NULL;
    if (get_doubles(bounds_obj, "t_bounds", bounds, 64, &n_b) < 0)
        return NULL;
    if (fr_obj != NULL && get_doubles(fr_obj, "fractions", fractions, 32, &n_fr) < 0)
        return NULL;
    ts = (test_setup *)PyMem_Calloc(1, sizeof *ts);
    if (ts == NULL)
        return PyErr_NoMemory();
    if (make_stepper(ts, method, problem, params, t0, y0, rtol, atol, max_step, first) < 0)
        goto fail;
    steps = PyList_New(0);
    if (steps == NULL)
        goto fail;
    res = Py_BuildValue("{s:d,s:O}", "h0", ts->st.h_abs, "steps", steps);
    if (res == NULL)
        goto fail;
    for (k = 0; k < n_b && count < max_steps; k++) {
        while (ts->st.t < bounds[k] && count < max_steps) {
            PyObject *rec;
            if (rk_step(&ts->st, bounds[k], &err) != RK_OK) {
                PyObject *e = Py_BuildValue("(ss)", rk_status_name(err.status), err.message);
                if (e == NULL || PyDict_SetItemString(res, "error", e) < 0) {
                    Py_XDECREF(e);
                    Py_DECREF(res);
                    goto fail;
                }
                Py_DECREF(e);
                goto done;
            }
            count++;
            rec = step_record(&ts->st, fractions, n_fr);
            if (rec == NULL || PyList_Append(steps, rec) < 0) {
                Py_XDECREF(rec);
                Py_DECREF(res);
                goto fail;
            }
            Py_DECREF(rec);
        }
    }
done:
    Py_DECREF(steps);
    PyMem_Free(ts);
    return res;
fail:
    Py_XDECREF(steps);
    PyMem_Free(ts);
    return NULL;
}

/* restart after k steps: rk_restart(method, problem, params, t0, y0, rtol, atol, max_step, n_before, t_r, y_r,
 * first_step) -> (h_abs after the restart, the record of the next step) */
static PyObject *py_rk_restart(PyObject *self, PyObject *args)
{
    int method, n_before, k, n = 0;
    const char *problem;
    PyObject *params, *y0, *atol, *yr_obj, *first, *res;
    double t0, rtol, max_step, t_r, y_r[RK_MAX_Y], first_step = NAN, h_after;
    test_setup *ts;
    rk_error err;
    (void)self;
    if (!PyArg_ParseTuple(args, "isOdOdOdidOO", &method, &problem, &params, &t0, &y0, &rtol, &atol, &max_step,
                          &n_before, &t_r, &yr_obj, &first))
        return NULL;
    if (yr_obj != Py_None && get_doubles(yr_obj, "y_r", y_r, RK_MAX_Y, &n) < 0)
        return NULL;
    if (first != Py_None) {
        first_step = PyFloat_AsDouble(first);
        if (first_step == -1.0 && PyErr_Occurred())
            return NULL;
    }
    ts = (test_setup *)PyMem_Calloc(1, sizeof *ts);
    if (ts == NULL)
        return PyErr_NoMemory();
    if (make_stepper(ts, method, problem, params, t0, y0, rtol, atol, max_step, Py_None) < 0)
        goto fail;
    if (yr_obj != Py_None && n != ts->st.n) {
        PyErr_SetString(PyExc_ValueError, "y_r and y0 differ in size");
        goto fail;
    }
    for (k = 0; k < n_before; k++)
        if (rk_step(&ts->st, INFINITY, &err) != RK_OK) {
            raise_rk(&err);
            goto fail;
        }
    /* y_r None: restart from the stepper's own point (t, y), passing its own arrays (aliasing) */
    if (yr_obj == Py_None)
        t_r = ts->st.t;
    if (rk_stepper_restart(&ts->st, test_rhs, &ts->pb, t_r, yr_obj == Py_None ? ts->st.y : y_r, first_step, &err) != RK_OK
        || (h_after = ts->st.h_abs, rk_step(&ts->st, INFINITY, &err)) != RK_OK) {
        raise_rk(&err);
        goto fail;
    }
    res = Py_BuildValue("(dN)", h_after, step_record(&ts->st, NULL, 0));
    PyMem_Free(ts);
    return res;
fail:
    PyMem_Free(ts);
    return NULL;
}

/* ------------------------------------------------------------------------------------------ events */
/* setup = (method, problem, params, t0, y0, rtol, atol, first_step, n_steps, W, c, d): a stepper that took
 * n_steps steps (t_bound inf), and the linear test event functions */
static int make_event_setup(test_setup *ts, PyObject *setup)
{
    int method, n_steps, k, n_c = 0, n_d = 0;
    const char *problem;
    PyObject *params, *y0, *atol, *first, *W, *c, *d, *fast;
    double t0, rtol;
    rk_error err;
    if (!PyArg_ParseTuple(setup, "isOdOdOOiOOO", &method, &problem, &params, &t0, &y0, &rtol, &atol, &first,
                          &n_steps, &W, &c, &d))
        return -1;
    if (make_stepper(ts, method, problem, params, t0, y0, rtol, atol, INFINITY, first) < 0)
        return -1;
    for (k = 0; k < n_steps; k++)
        if (rk_step(&ts->st, INFINITY, &err) != RK_OK) {
            raise_rk(&err);
            return -1;
        }
    if (get_doubles(c, "c", ts->ev.c, RK_MAX_EVENTS, &n_c) < 0 || get_doubles(d, "d", ts->ev.d, RK_MAX_EVENTS, &n_d) < 0)
        return -1;
    fast = PySequence_Fast(W, "W must be a sequence of rows");
    if (fast == NULL)
        return -1;
    if (PySequence_Fast_GET_SIZE(fast) != n_c || n_d != n_c) {
        Py_DECREF(fast);
        PyErr_SetString(PyExc_ValueError, "W, c and d differ in length");
        return -1;
    }
    for (k = 0; k < n_c; k++) {
        int m = 0;
        if (get_doubles(PySequence_Fast_GET_ITEM(fast, k), "W[i]", ts->ev.W[k], RK_MAX_Y, &m) < 0) {
            Py_DECREF(fast);
            return -1;
        }
        if (m != ts->st.n) {
            Py_DECREF(fast);
            PyErr_SetString(PyExc_ValueError, "a row of W differs from the state size");
            return -1;
        }
    }
    Py_DECREF(fast);
    ts->ev.n_events = n_c;
    ts->ev.n = ts->st.n;
    return 0;
}

static test_setup *event_setup(PyObject *setup, rk_event_ctx *c)
{
    test_setup *ts = (test_setup *)PyMem_Calloc(1, sizeof *ts);
    if (ts == NULL) {
        PyErr_NoMemory();
        return NULL;
    }
    if (make_event_setup(ts, setup) < 0) {
        PyMem_Free(ts);
        return NULL;
    }
    c->stepper = &ts->st;
    c->G = test_G;
    c->G_ctx = &ts->ev;
    c->n_events = ts->ev.n_events;
    c->G_one = NULL;
    c->G_one_mask = NULL;
    c->one_known = 0;
    return ts;
}

static PyObject *py_rk_events_eval(PyObject *self, PyObject *args)
{
    PyObject *setup;
    double t, g[RK_MAX_EVENTS];
    rk_event_ctx c;
    rk_error err;
    test_setup *ts;
    (void)self;
    if (!PyArg_ParseTuple(args, "Od", &setup, &t) || (ts = event_setup(setup, &c)) == NULL)
        return NULL;
    if (rk_event_eval(&c, t, g, &err) != RK_OK) {
        PyMem_Free(ts);
        return raise_rk(&err);
    }
    PyMem_Free(ts);
    return list_of(g, c.n_events);
}

static PyObject *py_rk_events_locate(PyObject *self, PyObject *args)
{
    PyObject *setup;
    int i;
    double shift, a, ga, b, gb, xtol, t;
    rk_event_ctx c;
    rk_error err;
    test_setup *ts;
    (void)self;
    if (!PyArg_ParseTuple(args, "Oidddddd", &setup, &i, &shift, &a, &ga, &b, &gb, &xtol)
        || (ts = event_setup(setup, &c)) == NULL)
        return NULL;
    if (rk_locate(&c, i, shift, a, ga, b, gb, xtol, &t, &err) != RK_OK) {
        PyMem_Free(ts);
        return raise_rk(&err);
    }
    PyMem_Free(ts);
    return PyFloat_FromDouble(t);
}

/* rk_events_earliest_root(setup, ids, shifts, starts, ta, ga, tb, gb, xtol) -> (t, i); starts: dict i -> (t, g) */
static PyObject *py_rk_events_earliest_root(PyObject *self, PyObject *args)
{
    PyObject *setup, *ids_obj, *shifts_obj, *starts, *ga_obj, *gb_obj;
    int ids[RK_MAX_EVENTS], n_ids = 0, n_sh = 0, n_ga = 0, n_gb = 0, has_start[RK_MAX_EVENTS], i_out;
    double shifts[RK_MAX_EVENTS], start_t[RK_MAX_EVENTS], start_g[RK_MAX_EVENTS * RK_MAX_EVENTS];
    double ta, tb, ga[RK_MAX_EVENTS], gb[RK_MAX_EVENTS], xtol, t_out;
    rk_event_ctx c;
    rk_error err;
    test_setup *ts;
    Py_ssize_t pos = 0;
    PyObject *key, *value;
    (void)self;
    if (!PyArg_ParseTuple(args, "OOOO!dOdOd", &setup, &ids_obj, &shifts_obj, &PyDict_Type, &starts, &ta, &ga_obj,
                          &tb, &gb_obj, &xtol))
        return NULL;
    if (get_ints(ids_obj, "ids", ids, RK_MAX_EVENTS, &n_ids) < 0
        || get_doubles(shifts_obj, "shifts", shifts, RK_MAX_EVENTS, &n_sh) < 0
        || get_doubles(ga_obj, "ga", ga, RK_MAX_EVENTS, &n_ga) < 0
        || get_doubles(gb_obj, "gb", gb, RK_MAX_EVENTS, &n_gb) < 0)
        return NULL;
    memset(has_start, 0, sizeof has_start);
    while (PyDict_Next(starts, &pos, &key, &value)) {
        long i = PyLong_AsLong(key);
        int m = 0;
        PyObject *g_obj;
        if (i == -1 && PyErr_Occurred())
            return NULL;
        if (i < 0 || i >= RK_MAX_EVENTS)
            return PyErr_Format(PyExc_ValueError, "starts: index %ld out of range", i);
        if (!PyArg_ParseTuple(value, "dO", &start_t[i], &g_obj)
            || get_doubles(g_obj, "starts[i][1]", start_g + i * RK_MAX_EVENTS, RK_MAX_EVENTS, &m) < 0)
            return NULL;
        has_start[i] = 1;
    }
    if ((ts = event_setup(setup, &c)) == NULL)
        return NULL;
    if (n_sh != c.n_events || n_ga != c.n_events || n_gb != c.n_events) {
        PyMem_Free(ts);
        return PyErr_Format(PyExc_ValueError, "shifts, ga and gb must hold %d values", c.n_events);
    }
    {
        /* the C takes the start rows packed n_events apart */
        double packed[RK_MAX_EVENTS * RK_MAX_EVENTS];
        int i, k;
        for (i = 0; i < RK_MAX_EVENTS; i++)
            for (k = 0; k < c.n_events; k++)
                packed[i * c.n_events + k] = start_g[i * RK_MAX_EVENTS + k];
        if (rk_earliest_root(&c, ids, n_ids, shifts, has_start, start_t, packed, ta, ga, tb, gb, xtol, &t_out, &i_out,
                             &err) != RK_OK) {
            PyMem_Free(ts);
            return raise_rk(&err);
        }
    }
    PyMem_Free(ts);
    return Py_BuildValue("(di)", t_out, i_out);
}

/* rk_events_first_negative(setup, t0, g0, t1, ids, n) -> None or (neg, ta, ga, tb, gb) */
static PyObject *py_rk_events_first_negative(PyObject *self, PyObject *args)
{
    PyObject *setup, *g0_obj, *ids_obj;
    int ids[RK_MAX_EVENTS], n_ids = 0, n_g0 = 0, n, found, neg[RK_MAX_EVENTS], n_neg;
    double t0, t1, g0[RK_MAX_EVENTS], ta, tb, ga[RK_MAX_EVENTS], gb[RK_MAX_EVENTS];
    rk_event_ctx c;
    rk_error err;
    test_setup *ts;
    (void)self;
    if (!PyArg_ParseTuple(args, "OdOdOi", &setup, &t0, &g0_obj, &t1, &ids_obj, &n))
        return NULL;
    if (get_doubles(g0_obj, "g0", g0, RK_MAX_EVENTS, &n_g0) < 0 || get_ints(ids_obj, "ids", ids, RK_MAX_EVENTS, &n_ids) < 0)
        return NULL;
    if ((ts = event_setup(setup, &c)) == NULL)
        return NULL;
    if (rk_first_negative(&c, t0, g0, t1, ids, n_ids, n, &found, neg, &n_neg, &ta, ga, &tb, gb, &err) != RK_OK) {
        PyMem_Free(ts);
        return raise_rk(&err);
    }
    PyMem_Free(ts);
    if (!found)
        Py_RETURN_NONE;
    return Py_BuildValue("(NdNdN)", int_list_of(neg, n_neg), ta, list_of(ga, c.n_events), tb, list_of(gb, c.n_events));
}

static PyObject *py_rk_events_may_dip(PyObject *self, PyObject *args)
{
    double g0, gm, g1;
    (void)self;
    if (!PyArg_ParseTuple(args, "ddd", &g0, &gm, &g1))
        return NULL;
    return PyBool_FromLong(rk_may_dip(g0, gm, g1));
}

/* rk_events_dip_search(setup, armed, g_prev, g_new, n) -> (hits, ta, tb, ga, gb, used_dense) */
static PyObject *py_rk_events_dip_search(PyObject *self, PyObject *args)
{
    PyObject *setup, *armed_obj, *gp_obj, *gn_obj;
    int armed[RK_MAX_EVENTS], n_armed = 0, n_gp = 0, n_gn = 0, n, hits[RK_MAX_EVENTS], n_hits, used;
    double gp[RK_MAX_EVENTS], gn[RK_MAX_EVENTS], ta, tb, ga[RK_MAX_EVENTS], gb[RK_MAX_EVENTS];
    rk_event_ctx c;
    rk_error err;
    test_setup *ts;
    (void)self;
    if (!PyArg_ParseTuple(args, "OOOOi", &setup, &armed_obj, &gp_obj, &gn_obj, &n))
        return NULL;
    if (get_ints(armed_obj, "armed", armed, RK_MAX_EVENTS, &n_armed) < 0
        || get_doubles(gp_obj, "g_prev", gp, RK_MAX_EVENTS, &n_gp) < 0
        || get_doubles(gn_obj, "g_new", gn, RK_MAX_EVENTS, &n_gn) < 0)
        return NULL;
    if ((ts = event_setup(setup, &c)) == NULL)
        return NULL;
    if (n_gp != c.n_events || n_gn != c.n_events || n_armed < c.n_events - 1) {
        PyMem_Free(ts);
        return PyErr_Format(PyExc_ValueError, "g_prev and g_new must hold %d values", c.n_events);
    }
    if (rk_dip_search(&c, armed, gp, gn, n, hits, &n_hits, &ta, &tb, ga, gb, &used, &err) != RK_OK) {
        PyMem_Free(ts);
        return raise_rk(&err);
    }
    PyMem_Free(ts);
    return Py_BuildValue("(NddNNN)", int_list_of(hits, n_hits), ta, tb, list_of(ga, c.n_events),
                         list_of(gb, c.n_events), PyBool_FromLong(used));
}

/* rk_events_bounce_search(setup, i, t0, t1, level) -> None or (t, g) */
static PyObject *py_rk_events_bounce_search(PyObject *self, PyObject *args)
{
    PyObject *setup;
    int i, found;
    double t0, t1, level, t, g[RK_MAX_EVENTS];
    rk_event_ctx c;
    rk_error err;
    test_setup *ts;
    (void)self;
    if (!PyArg_ParseTuple(args, "Oiddd", &setup, &i, &t0, &t1, &level))
        return NULL;
    if ((ts = event_setup(setup, &c)) == NULL)
        return NULL;
    if (rk_bounce_search(&c, i, t0, t1, level, &found, &t, g, &err) != RK_OK) {
        PyMem_Free(ts);
        return raise_rk(&err);
    }
    PyMem_Free(ts);
    if (!found)
        Py_RETURN_NONE;
    return Py_BuildValue("(dN)", t, list_of(g, c.n_events));
}

static PyObject *py_rk_events_parabola_peak(PyObject *self, PyObject *args)
{
    double f0, fm, f1, x, value;
    (void)self;
    if (!PyArg_ParseTuple(args, "ddd", &f0, &fm, &f1))
        return NULL;
    if (!rk_parabola_peak(f0, fm, f1, &x, &value))
        Py_RETURN_NONE;
    return Py_BuildValue("(dd)", x, value);
}

/* brent_max's test function: G_i(t, dense(t)), None below none_below */
typedef struct brent_ctx {
    rk_event_ctx *c;
    int i;
    double none_below;
    rk_error *err;
} brent_ctx;

static rk_status brent_f(void *ctx, double t, double *value, int *has)
{
    brent_ctx *b = (brent_ctx *)ctx;
    double g[RK_MAX_EVENTS];
    rk_status st = rk_event_eval(b->c, t, g, b->err);
    if (st != RK_OK)
        return st;
    *has = !(g[b->i] < b->none_below);
    *value = g[b->i];
    return RK_OK;
}

/* rk_events_brent_max(setup, i, a, b, x, fx or None, xtol, max_iter, none_below) -> (t, f or None) */
static PyObject *py_rk_events_brent_max(PyObject *self, PyObject *args)
{
    PyObject *setup, *fx_obj;
    int i, max_iter, has_out;
    double a, b, x, fx = 0.0, xtol, none_below, t_out, f_out;
    rk_event_ctx c;
    rk_error err;
    brent_ctx bc;
    test_setup *ts;
    (void)self;
    if (!PyArg_ParseTuple(args, "OidddOdid", &setup, &i, &a, &b, &x, &fx_obj, &xtol, &max_iter, &none_below))
        return NULL;
    if (fx_obj != Py_None) {
        fx = PyFloat_AsDouble(fx_obj);
        if (fx == -1.0 && PyErr_Occurred())
            return NULL;
    }
    if ((ts = event_setup(setup, &c)) == NULL)
        return NULL;
    bc.c = &c;
    bc.i = i;
    bc.none_below = none_below;
    bc.err = &err;
    if (rk_brent_max(brent_f, &bc, a, b, x, fx, fx_obj != Py_None, xtol, max_iter, &t_out, &f_out, &has_out,
                     &err) != RK_OK) {
        PyMem_Free(ts);
        return raise_rk(&err);
    }
    PyMem_Free(ts);
    if (!has_out)
        return Py_BuildValue("(dO)", t_out, Py_None);
    return Py_BuildValue("(dd)", t_out, f_out);
}

PyMethodDef rk_py_rk_methods[] = {
    {"rk_tableau", py_rk_tableau, METH_VARARGS,
     "rk_tableau(method) -> dict: the generated tableau (nonzero terms of A, B, E, D as (indices, values), C)."},
    {"rk_integrate", (PyCFunction)(void (*)(void))py_rk_integrate, METH_VARARGS | METH_KEYWORDS,
     "rk_integrate(method, problem, params, t0, y0, rtol, atol, max_step=inf, first_step=None, t_bounds, "
     "max_steps=1000, fractions=()) -> {'h0', 'steps': [{t_old, t, y, f, h_abs, n_steps, n_rejected, failure, "
     "dense, mid}], 'error'?}: steps to each bound in turn on a built-in test problem."},
    {"rk_restart", py_rk_restart, METH_VARARGS,
     "rk_restart(method, problem, params, t0, y0, rtol, atol, max_step, n_before, t_r, y_r, first_step) -> "
     "(h_abs after the restart, record of the next step); y_r None: from the stepper's own (t, y) (t_r ignored)."},
    {"rk_events_eval", py_rk_events_eval, METH_VARARGS, "rk_events_eval(setup, t) -> G(t, dense(t))."},
    {"rk_events_locate", py_rk_events_locate, METH_VARARGS,
     "rk_events_locate(setup, i, shift, a, ga, b, gb, xtol) -> t (events.locate on G_i + shift)."},
    {"rk_events_earliest_root", py_rk_events_earliest_root, METH_VARARGS,
     "rk_events_earliest_root(setup, ids, shifts, starts, ta, ga, tb, gb, xtol) -> (t, i)."},
    {"rk_events_first_negative", py_rk_events_first_negative, METH_VARARGS,
     "rk_events_first_negative(setup, t0, g0, t1, ids, n) -> None or (neg, ta, ga, tb, gb)."},
    {"rk_events_may_dip", py_rk_events_may_dip, METH_VARARGS, "rk_events_may_dip(g0, gm, g1) -> bool."},
    {"rk_events_dip_search", py_rk_events_dip_search, METH_VARARGS,
     "rk_events_dip_search(setup, armed, g_prev, g_new, n) -> (hits, ta, tb, ga, gb, used_dense)."},
    {"rk_events_bounce_search", py_rk_events_bounce_search, METH_VARARGS,
     "rk_events_bounce_search(setup, i, t0, t1, level) -> None or (t, g)."},
    {"rk_events_parabola_peak", py_rk_events_parabola_peak, METH_VARARGS,
     "rk_events_parabola_peak(f0, fm, f1) -> None or (x, value)."},
    {"rk_events_brent_max", py_rk_events_brent_max, METH_VARARGS,
     "rk_events_brent_max(setup, i, a, b, x, fx, xtol, max_iter, none_below) -> (t, value or None): brent_max "
     "of G_i(t, dense(t)), None where it is below none_below."},
    {NULL, NULL, 0, NULL}
};
