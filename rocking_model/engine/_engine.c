/* _engine.c -- the CPython extension module rocking_model._engine: its hot calls, hand-written (the Engine type's
 * creation, advance, advance_motion, sample, outputs, checkpoint and attributes). The rest of the module (state dicts,
 * snapshots, reports, contacts, full_state, version(), api_version(), model_kinds(), kinds(), add_model()) is bound
 * with cffi in rocking_model/_engine_cold.py, which module init installs here; it reaches this module's copy of the
 * engine through the table of rk_py_api.h (_API), as does model() (one kernel function of a model by name, for
 * rocking_model.models.base). No per-step Python object is created on the hot paths.
 *
 * Why hand-written rather than a binding tool: the hot calls (Engine creation, sample, advance, outputs) cost a
 * pulse simulate (the rigid block under a sine pulse, 4 s, ~58 us) 11.7-12.6 % more when bound with cffi in API
 * mode (same engine sources and flags, one C shim per creation and per sample: benchmarks/compiled_bench.py,
 * binding_ab, 300 interleaved rounds in one process, load average 3.7 on 2 shared cores), more than the 10 % a
 * tool may cost; per call, cffi's advance took ~0.86 us against 0.14 us here, output_dict ~2.5 us against 0.3 us. */

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "src/rk_internal.h"
#include "rk_py_api.h"

#include <math.h>
#include <string.h>

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

/* ------------------------------------------------------------------------------------------ errors */

/** NonFiniteError: the motion overflowed (RK_ERR_NONFINITE): a ValueError; the Python layer turns it into the
 *  Simulator's "the motion is not finite ..." message. Created at module init. */
static PyObject *NonFiniteError = NULL;
/** The package this module belongs to ("rocking_model", or the FMU's bundled copy "rocking_model_<digest>"):
 *  its validation.WorkLimitError is the class the package's callers catch. Set at module init. */
static PyObject *PackageName = NULL;

/** Raise the Python exception of a C status (DESIGN.md "Error handling"). */
static PyObject *raise_status(rk_status status, const char *message)
{
    PyObject *type = NULL, *mod = NULL;
    switch (status) {
    case RK_ERR_VALUE: type = PyExc_ValueError; break;
    case RK_ERR_NONFINITE: type = NonFiniteError != NULL ? NonFiniteError : PyExc_ValueError; break;
    case RK_ERR_NOT_IMPLEMENTED: type = PyExc_NotImplementedError; break;
    case RK_ERR_MEMORY: type = PyExc_MemoryError; break;
    case RK_ERR_WORK_LIMIT: {
        PyObject *name = PackageName != NULL ? PyUnicode_FromFormat("%U.validation", PackageName)
                                             : PyUnicode_FromString("rocking_model.validation");
        if (name == NULL)
            return NULL;
        mod = PyImport_Import(name);
        Py_DECREF(name);
        if (mod != NULL)
            type = PyObject_GetAttrString(mod, "WorkLimitError");
        break;
    }
    case RK_ERR_SOLVER:
        mod = PyImport_ImportModule("numpy.linalg");
        if (mod != NULL)
            type = PyObject_GetAttrString(mod, "LinAlgError");
        break;
    default: type = PyExc_RuntimeError; break;
    }
    if (mod != NULL) {
        Py_DECREF(mod);
        if (type == NULL)
            return NULL;
        PyErr_SetString(type, message);
        Py_DECREF(type);
        return NULL;
    }
    if (type == NULL)
        return NULL;      /* the import failed: its exception is set */
    PyErr_SetString(type, message);
    return NULL;
}

/* ------------------------------------------------------------------------------------------ motions
 * A motion spec (built by rocking_model.engine.motion_spec from a GroundMotion) is a tuple:
 *   ("constant", value) | ("linear", value, rate, t_ref) | ("sampled", t, ag) with t, ag float64 buffers |
 *   ("sine", A, omega_p, t0) | ("scaled", factor, inner_spec) | ("callback", motion, constant, value)
 * where a callback motion is any Python GroundMotion (called with the GIL held). */

#define MAX_MOTIONS 8

typedef struct callback_ctx {
    PyObject *motion;                   /* borrowed */
    PyObject *exc_type, *exc_value, *exc_tb;   /* the first exception a call raised (owned) */
} callback_ctx;

typedef struct motion_holder {
    rk_motion m[MAX_MOTIONS];
    int n_m;
    Py_buffer bufs[2 * MAX_MOTIONS];
    int n_bufs;
    callback_ctx cbs[MAX_MOTIONS];
    int n_cbs;
} motion_holder;

static void cb_store(callback_ctx *c, char *msg)
{
    PyObject *type, *value, *tb;
    PyErr_Fetch(&type, &value, &tb);
    if (msg != NULL) {
        PyObject *text = value != NULL ? PyObject_Str(value) : NULL;
        const char *s = text != NULL ? PyUnicode_AsUTF8(text) : NULL;
        snprintf(msg, RK_MSG_LEN, "%s", s != NULL ? s : "ag: the ground motion raised an exception");
        Py_XDECREF(text);
        PyErr_Clear();
    }
    if (c->exc_type == NULL) {
        c->exc_type = type;
        c->exc_value = value;
        c->exc_tb = tb;
    } else {
        Py_XDECREF(type);
        Py_XDECREF(value);
        Py_XDECREF(tb);
    }
}

static double cb_eval(void *ctx, double t, int *failed, char *msg)
{
    callback_ctx *c = (callback_ctx *)ctx;
    PyObject *r = PyObject_CallFunction(c->motion, "d", t);
    double x;
    if (r == NULL) {
        cb_store(c, msg);
        *failed = 1;
        return NAN;
    }
    x = PyFloat_AsDouble(r);
    Py_DECREF(r);
    if (x == -1.0 && PyErr_Occurred()) {
        cb_store(c, msg);
        *failed = 1;
        return NAN;
    }
    if (!isfinite(x)) {   /* checked_value's refusal (a GroundMotion's values are checked before they get here) */
        char text[160];
        snprintf(text, sizeof(text), "ag(%.17g) = %s is not finite; allowed range [-1000, 1000] m/s2 (AG_MAX)", t,
                 x != x ? "nan" : x > 0 ? "inf" : "-inf");
        PyErr_SetString(PyExc_ValueError, text);
        cb_store(c, msg);
        *failed = 1;
        return NAN;
    }
    return x;
}

static double cb_breakpoint(void *ctx, double t, int *failed, char *msg)
{
    callback_ctx *c = (callback_ctx *)ctx;
    PyObject *r = PyObject_CallMethod(c->motion, "next_breakpoint", "d", t);
    double x;
    if (r == NULL) {
        cb_store(c, msg);
        *failed = 1;
        return NAN;
    }
    x = PyFloat_AsDouble(r);
    Py_DECREF(r);
    if (x == -1.0 && PyErr_Occurred()) {
        cb_store(c, msg);
        *failed = 1;
        return NAN;
    }
    return x;
}

static int cb_continuous(void *ctx, double tb)
{
    callback_ctx *c = (callback_ctx *)ctx;
    PyObject *r = PyObject_CallMethod(c->motion, "continuous_at", "d", tb);
    int yes;
    if (r == NULL) {
        cb_store(c, NULL);
        return 0;
    }
    yes = PyObject_IsTrue(r);
    Py_DECREF(r);
    if (yes < 0) {
        cb_store(c, NULL);
        return 0;
    }
    return yes;
}

static void holder_release(motion_holder *h)
{
    int i;
    for (i = 0; i < h->n_bufs; i++)
        PyBuffer_Release(&h->bufs[i]);
    for (i = 0; i < h->n_cbs; i++) {
        Py_XDECREF(h->cbs[i].exc_type);
        Py_XDECREF(h->cbs[i].exc_value);
        Py_XDECREF(h->cbs[i].exc_tb);
    }
    h->n_bufs = h->n_cbs = h->n_m = 0;
}

/** The first exception a callback raised, restored as the current one (1), or 0 if none. */
static int holder_reraise(motion_holder *h)
{
    int i;
    for (i = 0; i < h->n_cbs; i++) {
        callback_ctx *c = &h->cbs[i];
        if (c->exc_type != NULL) {
            PyErr_Restore(c->exc_type, c->exc_value, c->exc_tb);
            c->exc_type = c->exc_value = c->exc_tb = NULL;
            return 1;
        }
    }
    return 0;
}

static int get_double_buffer(motion_holder *h, PyObject *obj, const char *name, const double **data,
                             Py_ssize_t *n)
{
    Py_buffer *b;
    if (h->n_bufs >= 2 * MAX_MOTIONS) {
        PyErr_SetString(PyExc_ValueError, "motion spec: too many arrays");
        return -1;
    }
    b = &h->bufs[h->n_bufs];
    if (PyObject_GetBuffer(obj, b, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyErr_Format(PyExc_TypeError, "%s must be a contiguous float64 array", name);
        return -1;
    }
    h->n_bufs++;
    if (b->itemsize != (Py_ssize_t)sizeof(double) || b->format == NULL || strcmp(b->format, "d") != 0
        || b->ndim != 1) {
        PyErr_Format(PyExc_TypeError, "%s must be a 1-D float64 array", name);
        return -1;
    }
    *data = (const double *)b->buf;
    *n = b->shape != NULL ? b->shape[0] : b->len / (Py_ssize_t)sizeof(double);
    return 0;
}

/** Parse a motion spec into h->m[...]; returns the index of the motion or -1 with an exception. */
static int parse_motion(motion_holder *h, PyObject *spec, int depth)
{
    const char *kind;
    PyObject *k;
    Py_ssize_t n;
    int idx;
    rk_motion *m;
    rk_error err;
    if (depth > 4 || h->n_m >= MAX_MOTIONS) {
        PyErr_SetString(PyExc_ValueError, "motion spec: nested too deep");
        return -1;
    }
    if (!PyTuple_Check(spec) || PyTuple_GET_SIZE(spec) < 2) {
        PyErr_SetString(PyExc_TypeError, "motion spec must be a tuple (kind, ...)");
        return -1;
    }
    n = PyTuple_GET_SIZE(spec);
    k = PyTuple_GET_ITEM(spec, 0);
    kind = PyUnicode_Check(k) ? PyUnicode_AsUTF8(k) : NULL;
    if (kind == NULL) {
        PyErr_SetString(PyExc_TypeError, "motion spec: the kind must be a str");
        return -1;
    }
    idx = h->n_m++;
    m = &h->m[idx];
#define ARG(i) PyFloat_AsDouble(PyTuple_GET_ITEM(spec, (i)))
    if (strcmp(kind, "constant") == 0 && n == 2) {
        double value = ARG(1);
        if (PyErr_Occurred())
            return -1;
        rk_motion_constant(m, value);
    } else if (strcmp(kind, "linear") == 0 && n == 4) {
        double value = ARG(1), rate = ARG(2), t_ref = ARG(3);
        if (PyErr_Occurred())
            return -1;
        rk_motion_linear(m, value, rate, t_ref);
    } else if (strcmp(kind, "sampled") == 0 && n == 3) {
        const double *t, *ag;
        Py_ssize_t nt, na;
        if (get_double_buffer(h, PyTuple_GET_ITEM(spec, 1), "t", &t, &nt) < 0
            || get_double_buffer(h, PyTuple_GET_ITEM(spec, 2), "ag", &ag, &na) < 0)
            return -1;
        if (nt != na) {
            PyErr_SetString(PyExc_ValueError, "ground motion: t and ag must be 1-D arrays of equal length >= 2");
            return -1;
        }
        if (rk_motion_sampled(m, t, ag, (long long)nt, &err) != RK_OK) {
            raise_status(err.status, err.message);
            return -1;
        }
    } else if (strcmp(kind, "sine") == 0 && n == 4) {
        double A = ARG(1), w = ARG(2), t0 = ARG(3);
        if (PyErr_Occurred())
            return -1;
        if (rk_motion_sine(m, A, w, t0, &err) != RK_OK) {
            raise_status(err.status, err.message);
            return -1;
        }
    } else if ((strcmp(kind, "cosine") == 0 || strcmp(kind, "ricker") == 0 || strcmp(kind, "rect") == 0)
               && n == 4) {
        double A = ARG(1), w = ARG(2), t0 = ARG(3);
        rk_status st;
        if (PyErr_Occurred())
            return -1;
        st = kind[0] == 'c' ? rk_motion_cosine(m, A, w, t0, &err)
             : kind[1] == 'i' ? rk_motion_ricker(m, A, w, t0, &err) : rk_motion_rect(m, A, w, t0, &err);
        if (st != RK_OK) {
            raise_status(err.status, err.message);
            return -1;
        }
    } else if (strcmp(kind, "scaled") == 0 && n == 3) {
        double factor = ARG(1);
        int inner;
        if (PyErr_Occurred())
            return -1;
        inner = parse_motion(h, PyTuple_GET_ITEM(spec, 2), depth + 1);
        if (inner < 0)
            return -1;
        memset(m, 0, sizeof(*m));
        m->kind = RK_MOTION_SCALED;
        m->factor = factor;
        m->inner = &h->m[inner];
        m->constant = h->m[inner].constant;
        m->value = factor * h->m[inner].value;
    } else if (strcmp(kind, "callback") == 0 && n == 4) {
        callback_ctx *c;
        int constant = PyObject_IsTrue(PyTuple_GET_ITEM(spec, 2));
        double value = ARG(3);
        if (constant < 0 || PyErr_Occurred())
            return -1;
        if (!PyCallable_Check(PyTuple_GET_ITEM(spec, 1))) {
            PyErr_SetString(PyExc_TypeError, "motion spec: a callback motion must be callable");
            return -1;
        }
        c = &h->cbs[h->n_cbs++];
        c->motion = PyTuple_GET_ITEM(spec, 1);
        c->exc_type = c->exc_value = c->exc_tb = NULL;
        memset(m, 0, sizeof(*m));
        m->kind = RK_MOTION_CALLBACK;
        m->fn = cb_eval;
        /* a plain callable (no GroundMotion methods): no breakpoints, not continuous (GroundMotion's defaults) */
        m->fn_breakpoint = PyObject_HasAttrString(c->motion, "next_breakpoint") ? cb_breakpoint : NULL;
        m->fn_continuous = PyObject_HasAttrString(c->motion, "continuous_at") ? cb_continuous : NULL;
        m->ctx = c;
        m->constant = constant;
        m->value = value;
    } else {
        PyErr_Format(PyExc_ValueError, "motion spec: unknown kind %R or wrong length %zd", k, n);
        return -1;
    }
#undef ARG
    return idx;
}

/* ------------------------------------------------------------------------------------------ Engine */

typedef struct EngineObject {
    PyObject_HEAD
    rk_engine *e;
    PyObject *keys;     /* the keys of output_dict(): the output names, contact, impacts, overturned,
                           friction_demand, painleve (made once) */
    int callback_raised;    /* the last advance_motion / sample raised a motion callback's own exception */
} EngineObject;

static int read_options(PyObject *kw, rk_options *o);

/* the model kinds whose output_dict() keys are kept (rk_model_kinds() lists 2 today) */
#define RK_MAX_KINDS_CACHED 16

static int engine_init(EngineObject *self, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"kind", "params", "initial", "scheme", "t0", "dt_max", "tolerance", "theta",
                             "zeno_tol", "method", "impact_log_size", "max_events", "tolerances", "state", NULL};
    const char *kind;
    PyObject *params_obj, *initial_obj = Py_None, *scheme = NULL, *method = NULL, *log_size = Py_None;
    PyObject *tolerances = Py_None, *state = Py_None;
    double params[RK_MAX_PARAMS], initial[RK_MAX_INITIAL];
    int n_params, n_initial, max_events = 100000;
    rk_options o;
    rk_error err;
    rk_engine *e;
    rk_options_default(&o);
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "sO|OOdddddOOiOO", kwlist, &kind, &params_obj, &initial_obj,
                                     &scheme, &o.t0, &o.dt_max, &o.tolerance, &o.theta, &o.zeno_tol, &method,
                                     &log_size, &max_events, &tolerances, &state))
        return -1;
    o.max_events = max_events;
    if (read_doubles(params_obj, "params", params, RK_MAX_PARAMS, &n_params) < 0
        || read_doubles(initial_obj, "initial", initial, RK_MAX_INITIAL, &n_initial) < 0)
        return -1;
    if (scheme != NULL) {
        if (PyUnicode_Check(scheme)) {
            const char *s = PyUnicode_AsUTF8(scheme);
            if (s != NULL && strcmp(s, "moreau_jean") == 0)
                o.scheme = RK_SCHEME_MOREAU_JEAN;
            else if (s != NULL && strcmp(s, "event_driven") == 0)
                o.scheme = RK_SCHEME_EVENT_DRIVEN;
            else {
                PyErr_Format(PyExc_ValueError, "scheme = %R is not supported; allowed values: 'moreau_jean', "
                             "'event_driven', 0, 1", scheme);
                return -1;
            }
        } else {
            long s = PyLong_AsLong(scheme);
            if (s == -1 && PyErr_Occurred())
                return -1;
            o.scheme = (rk_scheme)s;
        }
    }
    if (method != NULL) {
        if (PyUnicode_Check(method)) {
            const char *s = PyUnicode_AsUTF8(method);
            if (s != NULL && strcmp(s, "DOP853") == 0)
                o.method = RK_METHOD_DOP853;
            else if (s != NULL && strcmp(s, "DOPRI5") == 0)
                o.method = RK_METHOD_DOPRI5;
            else {
                PyErr_Format(PyExc_ValueError, "method = %R is not supported; allowed values: 'DOP853', 'DOPRI5'",
                             method);
                return -1;
            }
        } else {
            long s = PyLong_AsLong(method);
            if (s == -1 && PyErr_Occurred())
                return -1;
            o.method = (rk_method)s;
        }
    }
    if (log_size != Py_None) {
        long long n = PyLong_AsLongLong(log_size);
        if (n == -1 && PyErr_Occurred())
            return -1;
        if (n < 0) {
            PyErr_Format(PyExc_ValueError, "impact_log_size = %lld is out of range; allowed range [0, inf) or None "
                         "(keep all)", n);
            return -1;
        }
        o.impact_log_size = n;
    } else {
        o.impact_log_size = -1;
    }
    if (tolerances != Py_None && read_options(tolerances, &o) < 0)
        return -1;
    if (state != Py_None) {
        PyObject *mode_obj, *q_obj, *v_obj;
        double q[RK_MAX_DOF], v[RK_MAX_DOF];
        int nq, nv;
        long mode;
        if (!PyArg_ParseTuple(state, "OOO", &mode_obj, &q_obj, &v_obj))
            return -1;
        mode = PyLong_AsLong(mode_obj);
        if (mode == -1 && PyErr_Occurred())
            return -1;
        if (read_doubles(q_obj, "q", q, RK_MAX_DOF, &nq) < 0 || read_doubles(v_obj, "v", v, RK_MAX_DOF, &nv) < 0)
            return -1;
        if (nq != nv) {
            PyErr_SetString(PyExc_ValueError, "state: q and v must have the same length");
            return -1;
        }
        e = rk_engine_create_state(kind, params, n_params, (int)mode, q, v, nq, &o, &err);
    } else {
        e = rk_engine_create(kind, params, n_params, initial, n_initial, &o, &err);
    }
    if (e == NULL) {
        raise_status(err.status, err.message);
        return -1;
    }
    rk_engine_free(self->e);
    self->e = e;
    {
        /* the keys of output_dict(), made once per model kind (an engine per run: interning 13 names each time
         * cost about as much as the engine's creation) */
        static const char *const extra[] = {"contact", "impacts", "overturned", "friction_demand", "painleve"};
        static const rk_model_ops *cached_ops[RK_MAX_KINDS_CACHED];
        static PyObject *cached_keys[RK_MAX_KINDS_CACHED];
        const rk_model_ops *ops = e->model.ops;
        PyObject *keys = NULL;
        int n = rk_engine_n_outputs(e), i, slot;
        for (slot = 0; slot < RK_MAX_KINDS_CACHED && cached_ops[slot] != NULL; slot++)
            if (cached_ops[slot] == ops) {
                keys = cached_keys[slot];
                break;
            }
        if (keys == NULL) {
            keys = PyTuple_New(n + 5);
            if (keys == NULL)
                return -1;
            for (i = 0; i < n + 5; i++) {
                PyObject *k = PyUnicode_InternFromString(i < n ? rk_engine_output_name(e, i) : extra[i - n]);
                if (k == NULL) {
                    Py_DECREF(keys);
                    return -1;
                }
                PyTuple_SET_ITEM(keys, i, k);
            }
            if (slot < RK_MAX_KINDS_CACHED) {      /* kept for the life of the process (one per model kind) */
                cached_ops[slot] = ops;
                cached_keys[slot] = keys;
                Py_INCREF(keys);
            }
        } else {
            Py_INCREF(keys);
        }
        Py_XDECREF(self->keys);
        self->keys = keys;
    }
    return 0;
}

/** The last frozen tolerances object read (a strong reference) and its fields: the engine of every run reads the
 *  same DEFAULT_TOLERANCES (13 attribute reads, about 0.7 us per run otherwise). Only an instance of a frozen
 *  dataclass (ContactTolerances) is kept: its fields cannot change. */
static PyObject *tol_cache_obj = NULL;
static rk_tolerances tol_cache;

/** 1 if tol is an instance of a frozen dataclass, 0 if not, -1 on error. */
static int frozen_dataclass(PyObject *tol)
{
    PyObject *params = PyObject_GetAttrString((PyObject *)Py_TYPE(tol), "__dataclass_params__"), *frozen;
    int r;
    if (params == NULL) {
        PyErr_Clear();
        return 0;
    }
    frozen = PyObject_GetAttrString(params, "frozen");
    Py_DECREF(params);
    if (frozen == NULL) {
        PyErr_Clear();
        return 0;
    }
    r = PyObject_IsTrue(frozen);
    Py_DECREF(frozen);
    return r;
}

/** ContactTolerances (any object with its attribute names) into o->tolerances. */
static int read_options(PyObject *tol, rk_options *o)
{
    static const char *const names[] = {"gap", "step_gap", "grazing", "rest_velocity", "step_rest_velocity",
                                        "event", "rise", "clearly_open", "stateless_step", "lcp_exact",
                                        "lcp_hint", "demand_floor"};
    double *fields[12];
    rk_tolerances *t = &o->tolerances;
    int i, frozen;
    PyObject *x;
    if (tol == tol_cache_obj) {
        *t = tol_cache;
        return 0;
    }
    fields[0] = &t->gap; fields[1] = &t->step_gap; fields[2] = &t->grazing; fields[3] = &t->rest_velocity;
    fields[4] = &t->step_rest_velocity; fields[5] = &t->event; fields[6] = &t->rise; fields[7] = &t->clearly_open;
    fields[8] = &t->stateless_step; fields[9] = &t->lcp_exact; fields[10] = &t->lcp_hint;
    fields[11] = &t->demand_floor;
    for (i = 0; i < 12; i++) {
        x = PyObject_GetAttrString(tol, names[i]);
        if (x == NULL)
            return -1;
        *fields[i] = PyFloat_AsDouble(x);
        Py_DECREF(x);
        if (*fields[i] == -1.0 && PyErr_Occurred())
            return -1;
    }
    x = PyObject_GetAttrString(tol, "sub_samples");
    if (x == NULL)
        return -1;
    {
        long n = PyLong_AsLong(x);
        Py_DECREF(x);
        if (n == -1 && PyErr_Occurred())
            return -1;
        t->sub_samples = (int)n;
    }
    frozen = frozen_dataclass(tol);
    if (frozen < 0)
        return -1;
    if (frozen) {
        Py_INCREF(tol);
        Py_XSETREF(tol_cache_obj, tol);
        tol_cache = *t;
    }
    return 0;
}

static void engine_dealloc(EngineObject *self)
{
    PyTypeObject *type = Py_TYPE(self);
    freefunc tp_free = (freefunc)PyType_GetSlot(type, Py_tp_free);
    rk_engine_free(self->e);
    self->e = NULL;
    Py_XDECREF(self->keys);
    self->keys = NULL;
    tp_free(self);
    Py_DECREF(type);      /* a heap type: each instance holds a reference */
}

static int ready(EngineObject *self)
{
    if (self->e == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "Engine is not initialised");
        return 0;
    }
    return 1;
}

static int read_max_steps(PyObject *obj, long long *out)
{
    if (obj == NULL || obj == Py_None) {
        *out = -1;
        return 0;
    }
    *out = PyLong_AsLongLong(obj);
    if (*out == -1 && PyErr_Occurred())
        return -1;
    if (*out < 0) {
        PyErr_Format(PyExc_ValueError, "max_steps = %lld is out of range; allowed range [1, 2^53] or None "
                     "(unlimited)", *out);
        return -1;
    }
    return 0;
}

/* Engine.advance's parameters, in positional order */
enum { ADV_T_END, ADV_AG0, ADV_SLOPE, ADV_MAX_STEPS, ADV_CONTINUOUS, ADV_LINEAR, ADV_AG_V, ADV_AG_V_SLOPE,
       ADV_LINEAR_V, ADV_N };
static const char *const ADVANCE_NAMES[ADV_N] = {"t_end", "ag0", "slope", "max_steps", "continuous", "linear",
                                                 "ag_v", "ag_v_slope", "linear_v"};

/* a float argument as the "d" format reads it (PyFloat_AsDouble: float, int, __float__) */
static int advance_float(PyObject *obj, int i, double *out)
{
    if (obj == NULL)
        return 0;
    *out = PyFloat_CheckExact(obj) ? PyFloat_AS_DOUBLE(obj) : PyFloat_AsDouble(obj);
    if (*out == -1.0 && PyErr_Occurred()) {
        if (PyErr_ExceptionMatches(PyExc_TypeError)) {
            PyErr_Clear();
            PyErr_Format(PyExc_TypeError, "advance() argument '%s' must be a real number, not %.80s",
                         ADVANCE_NAMES[i], Py_TYPE(obj)->tp_name);
        }
        return -1;
    }
    return 0;
}

/* a bool argument as the "p" format reads it */
static int advance_flag(PyObject *obj, unsigned bit, unsigned *flags)
{
    int truth;
    if (obj == NULL)
        return 0;
    truth = PyObject_IsTrue(obj);
    if (truth < 0)
        return -1;
    if (truth)
        *flags |= bit;
    return 0;
}

/** Engine.advance(t_end, ag0=0.0, slope=0.0, max_steps=None, continuous=False, linear=False, ag_v=0.0,
 *  ag_v_slope=0.0, linear_v=False): METH_FASTCALL with a hand-written parser (the FMU-like loop calls it once
 *  per communication step: the generic keyword parser cost more than a short advance itself). */
static PyObject *engine_advance(EngineObject *self, PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames)
{
    PyObject *arg[ADV_N] = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    double t_end = 0.0, ag0 = 0.0, slope = 0.0, ag_v = 0.0, ag_v_slope = 0.0;
    long long max_steps = -1;
    unsigned flags = 0u;
    Py_ssize_t i, nkw = kwnames == NULL ? 0 : PyTuple_GET_SIZE(kwnames);
    rk_status st;
    if (!ready(self))
        return NULL;
    if (nargs > ADV_N) {
        PyErr_Format(PyExc_TypeError, "advance() takes at most %d arguments (%zd given)", ADV_N, nargs);
        return NULL;
    }
    for (i = 0; i < nargs; i++)
        arg[i] = args[i];
    for (i = 0; i < nkw; i++) {
        PyObject *key = PyTuple_GET_ITEM(kwnames, i);
        int j;
        for (j = 0; j < ADV_N; j++)
            if (PyUnicode_CompareWithASCIIString(key, ADVANCE_NAMES[j]) == 0)
                break;
        if (j == ADV_N) {
            PyErr_Format(PyExc_TypeError, "advance() got an unexpected keyword argument '%U'", key);
            return NULL;
        }
        if (arg[j] != NULL) {
            PyErr_Format(PyExc_TypeError, "advance() got multiple values for argument '%s'", ADVANCE_NAMES[j]);
            return NULL;
        }
        arg[j] = args[nargs + i];
    }
    if (arg[ADV_T_END] == NULL) {
        PyErr_SetString(PyExc_TypeError, "advance() missing required argument 't_end' (pos 1)");
        return NULL;
    }
    if (advance_float(arg[ADV_T_END], ADV_T_END, &t_end) < 0 || advance_float(arg[ADV_AG0], ADV_AG0, &ag0) < 0
        || advance_float(arg[ADV_SLOPE], ADV_SLOPE, &slope) < 0
        || advance_float(arg[ADV_AG_V], ADV_AG_V, &ag_v) < 0
        || advance_float(arg[ADV_AG_V_SLOPE], ADV_AG_V_SLOPE, &ag_v_slope) < 0
        || read_max_steps(arg[ADV_MAX_STEPS], &max_steps) < 0
        || advance_flag(arg[ADV_CONTINUOUS], RK_ADVANCE_CONTINUOUS, &flags) < 0
        || advance_flag(arg[ADV_LINEAR], RK_ADVANCE_LINEAR, &flags) < 0
        || advance_flag(arg[ADV_LINEAR_V], RK_ADVANCE_LINEAR_V, &flags) < 0)
        return NULL;
    Py_BEGIN_ALLOW_THREADS
    st = rk_engine_advance(self->e, t_end, ag0, slope, ag_v, ag_v_slope, max_steps, flags);
    Py_END_ALLOW_THREADS
    if (st != RK_OK)
        return raise_status(st, rk_engine_message(self->e));
    Py_RETURN_NONE;
}

/** Run advance_motion or sample under a parsed motion: the GIL released unless a callback is involved, a
 *  callback's exception re-raised with the state restored. */
static PyObject *finish_call(EngineObject *self, motion_holder *h, rk_status st, rk_core *saved)
{
    self->callback_raised = 0;
    if (h->n_cbs > 0 && holder_reraise(h)) {
        self->callback_raised = 1;
        if (st == RK_OK)
            rk_engine_load(self->e, saved);     /* the call went on past the exception: undo it */
        holder_release(h);
        return NULL;
    }
    holder_release(h);
    if (st != RK_OK)
        return raise_status(st, rk_engine_message(self->e));
    Py_RETURN_NONE;
}

static PyObject *engine_advance_motion(EngineObject *self, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"t_end", "motion", "max_steps", "identity", "vspec", NULL};
    double t_end;
    PyObject *spec, *ms = Py_None, *vspec = Py_None;
    long long max_steps;
    unsigned long long identity = 0;
    motion_holder h;
    int idx, vidx = -1;
    rk_status st;
    rk_core *saved = NULL;
    if (!ready(self) || !PyArg_ParseTupleAndKeywords(args, kwargs, "dO|OKO", kwlist, &t_end, &spec, &ms, &identity,
                                                      &vspec))
        return NULL;
    if (read_max_steps(ms, &max_steps) < 0)
        return NULL;
    memset(&h, 0, sizeof(h));
    idx = parse_motion(&h, spec, 0);
    if (idx >= 0 && vspec != Py_None)
        vidx = parse_motion(&h, vspec, 0);
    if (idx < 0 || (vspec != Py_None && vidx < 0)) {
        holder_release(&h);
        return NULL;
    }
    h.m[idx].identity = identity;
    if (h.n_cbs > 0) {
        saved = (rk_core *)PyMem_Malloc(sizeof(rk_core));
        if (saved == NULL) {
            holder_release(&h);
            return PyErr_NoMemory();
        }
        rk_engine_save(self->e, saved);
        st = rk_engine_advance_motion(self->e, t_end, &h.m[idx], vidx < 0 ? NULL : &h.m[vidx], max_steps);
    } else {
        Py_BEGIN_ALLOW_THREADS
        st = rk_engine_advance_motion(self->e, t_end, &h.m[idx], vidx < 0 ? NULL : &h.m[vidx], max_steps);
        Py_END_ALLOW_THREADS
    }
    {
        PyObject *r = finish_call(self, &h, st, saved);
        PyMem_Free(saved);
        return r;
    }
}

/** A writable C-contiguous buffer of n items of itemsize bytes, or of alt bytes when alt > 0 (Engine.sample's
 *  modes: C int or int64, overturned: C int or bool) */
static int writable_buffer(PyObject *obj, Py_buffer *b, const char *name, Py_ssize_t itemsize, Py_ssize_t alt,
                           Py_ssize_t n)
{
    if (PyObject_GetBuffer(obj, b, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE) < 0) {
        PyErr_Format(PyExc_TypeError, "%s must be a writable contiguous array", name);
        return -1;
    }
    if ((b->itemsize != itemsize && (alt <= 0 || b->itemsize != alt)) || b->len != n * b->itemsize) {
        PyBuffer_Release(b);
        if (alt > 0)
            PyErr_Format(PyExc_ValueError, "%s must hold %zd items of %zd or %zd bytes", name, n, itemsize, alt);
        else
            PyErr_Format(PyExc_ValueError, "%s must hold %zd items of %zd bytes", name, n, itemsize);
        return -1;
    }
    return 0;
}

/** rk_engine_sample (rows or columns) or, hold, rk_engine_sample_held */
static rk_status run_sample(rk_engine *e, rk_motion *ag, rk_motion *ag_v, const double *times, long long n,
                            long long max_steps, int columns, int hold, int *modes, double *values, long long *impacts,
                            int *over)
{
    if (hold)
        return rk_engine_sample_held(e, ag, ag_v, times, n, max_steps, columns, modes, values, impacts, over);
    return (columns ? rk_engine_sample_columns : rk_engine_sample)(e, ag, ag_v, times, n, max_steps, modes, values,
                                                                   impacts, over);
}

static PyObject *engine_sample(EngineObject *self, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"times", "motion", "max_steps", "modes", "values", "impacts", "overturned", "identity",
                             "vspec", "columns", "hold", NULL};
    PyObject *times_obj, *spec, *ms, *modes_obj, *values_obj, *impacts_obj, *over_obj, *r, *vspec = Py_None;
    rk_motion *mv = NULL;
    unsigned long long identity = 0;
    long long max_steps;
    motion_holder h;
    Py_buffer bm, bv, bi, bo;
    const double *times;
    Py_ssize_t n;
    int idx, stride, columns = 0, hold = 0;
    rk_status st;
    rk_core *saved = NULL;
    if (!ready(self) || !PyArg_ParseTupleAndKeywords(args, kwargs, "OOOOOOO|KOpp", kwlist, &times_obj, &spec, &ms,
                                                      &modes_obj, &values_obj, &impacts_obj, &over_obj,
                                                      &identity, &vspec, &columns, &hold))
        return NULL;
    if (read_max_steps(ms, &max_steps) < 0)
        return NULL;
    memset(&h, 0, sizeof(h));
    if (get_double_buffer(&h, times_obj, "times", &times, &n) < 0) {
        holder_release(&h);
        return NULL;
    }
    idx = parse_motion(&h, spec, 0);
    if (idx < 0) {
        holder_release(&h);
        return NULL;
    }
    if (vspec != Py_None) {
        int vidx = parse_motion(&h, vspec, 0);
        if (vidx < 0) {
            holder_release(&h);
            return NULL;
        }
        mv = &h.m[vidx];
    }
    h.m[idx].identity = identity;
    stride = rk_engine_n_outputs(self->e) + 2;
    if (writable_buffer(modes_obj, &bm, "modes", (Py_ssize_t)sizeof(int), 8, n + 1) < 0) {
        holder_release(&h);
        return NULL;
    }
    if (writable_buffer(values_obj, &bv, "values", (Py_ssize_t)sizeof(double), 0, (n + 1) * stride) < 0) {
        PyBuffer_Release(&bm);
        holder_release(&h);
        return NULL;
    }
    if (writable_buffer(impacts_obj, &bi, "impacts", (Py_ssize_t)sizeof(long long), 0, n + 1) < 0) {
        PyBuffer_Release(&bm);
        PyBuffer_Release(&bv);
        holder_release(&h);
        return NULL;
    }
    if (writable_buffer(over_obj, &bo, "overturned", (Py_ssize_t)sizeof(int), 1, n + 1) < 0) {
        PyBuffer_Release(&bm);
        PyBuffer_Release(&bv);
        PyBuffer_Release(&bi);
        holder_release(&h);
        return NULL;
    }
    {
        /* int64 modes and bool overturned (the arrays Integrator.sample returns) are written through int scratch
         * rows and widened / narrowed after the run: the caller needs no converted copies */
        int *modes = (int *)bm.buf, *over = (int *)bo.buf, *scratch = NULL;
        if (bm.itemsize != (Py_ssize_t)sizeof(int) || bo.itemsize != (Py_ssize_t)sizeof(int)) {
            scratch = (int *)PyMem_Malloc(2 * (size_t)(n + 1) * sizeof(int));
            if (scratch == NULL) {
                PyBuffer_Release(&bm);
                PyBuffer_Release(&bv);
                PyBuffer_Release(&bi);
                PyBuffer_Release(&bo);
                holder_release(&h);
                return PyErr_NoMemory();
            }
            if (bm.itemsize != (Py_ssize_t)sizeof(int))
                modes = scratch;
            if (bo.itemsize != (Py_ssize_t)sizeof(int))
                over = scratch + n + 1;
        }
        if (h.n_cbs > 0) {
            saved = (rk_core *)PyMem_Malloc(sizeof(rk_core));
            if (saved == NULL) {
                st = RK_ERR_MEMORY;
                rk_fail(&self->e->error, st, "out of memory");
            } else {
                rk_engine_save(self->e, saved);
                st = run_sample(self->e, &h.m[idx], mv, times, (long long)n, max_steps, columns, hold, modes,
                                (double *)bv.buf, (long long *)bi.buf, over);
            }
        } else {
            Py_BEGIN_ALLOW_THREADS
            st = run_sample(self->e, &h.m[idx], mv, times, (long long)n, max_steps, columns, hold, modes,
                            (double *)bv.buf, (long long *)bi.buf, over);
            Py_END_ALLOW_THREADS
        }
        if (modes != (int *)bm.buf) {
            long long *wide = (long long *)bm.buf;
            Py_ssize_t i;
            for (i = 0; i <= n; i++)
                wide[i] = modes[i];
        }
        if (over != (int *)bo.buf) {
            unsigned char *flags = (unsigned char *)bo.buf;
            Py_ssize_t i;
            for (i = 0; i <= n; i++)
                flags[i] = over[i] != 0;
        }
        PyMem_Free(scratch);
    }
    PyBuffer_Release(&bm);
    PyBuffer_Release(&bv);
    PyBuffer_Release(&bi);
    PyBuffer_Release(&bo);
    r = finish_call(self, &h, st, saved);
    PyMem_Free(saved);
    return r;
}

static PyObject *doubles_tuple(const double *x, int n)
{
    PyObject *t = PyTuple_New(n);
    int i;
    if (t == NULL)
        return NULL;
    for (i = 0; i < n; i++) {
        PyObject *f = PyFloat_FromDouble(x[i]);
        if (f == NULL) {
            Py_DECREF(t);
            return NULL;
        }
        PyTuple_SET_ITEM(t, i, f);
    }
    return t;
}

static PyObject *doubles_list(const double *x, long long n)
{
    PyObject *l = PyList_New((Py_ssize_t)n);
    long long i;
    if (l == NULL)
        return NULL;
    for (i = 0; i < n; i++) {
        PyObject *f = PyFloat_FromDouble(x[i]);
        if (f == NULL) {
            Py_DECREF(l);
            return NULL;
        }
        PyList_SET_ITEM(l, (Py_ssize_t)i, f);
    }
    return l;
}

static PyObject *engine_outputs(EngineObject *self, PyObject *unused)
{
    double out[RK_MAX_OUTPUTS];
    (void)unused;
    if (!ready(self))
        return NULL;
    rk_engine_outputs(self->e, out);
    return doubles_tuple(out, rk_engine_n_outputs(self->e));
}

/** output_dict(): Simulator.outputs() in one call: the model's outputs, contact, impacts, overturned,
 *  friction_demand, painleve. */
static PyObject *engine_output_dict(EngineObject *self, PyObject *unused)
{
    double out[RK_MAX_OUTPUTS];
    PyObject *d, *vals[RK_MAX_OUTPUTS + 5];
    int n, i, ok = 1;
    (void)unused;
    if (!ready(self))
        return NULL;
    n = rk_engine_n_outputs(self->e);
    rk_engine_outputs(self->e, out);
    d = PyDict_New();
    if (d == NULL)
        return NULL;
    for (i = 0; i < n; i++)
        vals[i] = PyFloat_FromDouble(out[i]);
    vals[n] = PyLong_FromLong(rk_engine_contact_code(self->e));
    vals[n + 1] = PyLong_FromLongLong(rk_engine_impacts(self->e));
    vals[n + 2] = PyBool_FromLong(rk_engine_overturned(self->e));
    vals[n + 3] = PyFloat_FromDouble(rk_engine_friction_demand(self->e));
    vals[n + 4] = PyLong_FromLongLong(rk_engine_painleve(self->e));
    for (i = 0; i < n + 5; i++) {
        if (vals[i] == NULL || PyDict_SetItem(d, PyTuple_GET_ITEM(self->keys, i), vals[i]) < 0)
            ok = 0;
        Py_XDECREF(vals[i]);
    }
    if (!ok) {
        Py_DECREF(d);
        return NULL;
    }
    return d;
}

/** output_row(): the values of output_dict() as a tuple of floats in the same order (contact, impacts,
 *  overturned and painleve as exact floats): one row of simulate's zero-order-hold loop. */
static PyObject *engine_output_row(EngineObject *self, PyObject *unused)
{
    double out[RK_MAX_OUTPUTS + 5];
    int n;
    (void)unused;
    if (!ready(self))
        return NULL;
    n = rk_engine_n_outputs(self->e);
    rk_engine_outputs(self->e, out);
    out[n] = (double)rk_engine_contact_code(self->e);
    out[n + 1] = (double)rk_engine_impacts(self->e);
    out[n + 2] = (double)rk_engine_overturned(self->e);
    out[n + 3] = rk_engine_friction_demand(self->e);
    out[n + 4] = (double)rk_engine_painleve(self->e);
    return doubles_tuple(out, n + 5);
}

static PyObject *impact_times_list(rk_engine *e)
{
    long long n = rk_engine_impact_times(e, NULL, 0);
    double *buf = (double *)PyMem_Malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    PyObject *l;
    if (buf == NULL)
        return PyErr_NoMemory();
    rk_engine_impact_times(e, buf, n);
    l = doubles_list(buf, n);
    PyMem_Free(buf);
    return l;
}

static PyObject *engine_checkpoint(EngineObject *self, PyObject *unused)
{
    (void)unused;
    if (!ready(self))
        return NULL;
    rk_engine_checkpoint(self->e);
    Py_RETURN_NONE;
}

static PyObject *engine_rollback(EngineObject *self, PyObject *unused)
{
    (void)unused;
    if (!ready(self))
        return NULL;
    if (rk_engine_rollback(self->e) != RK_OK)
        return raise_status(rk_engine_status(self->e), rk_engine_message(self->e));
    Py_RETURN_NONE;
}

static PyObject *engine_commit(EngineObject *self, PyObject *unused)
{
    (void)unused;
    if (!ready(self))
        return NULL;
    rk_engine_commit(self->e);
    Py_RETURN_NONE;
}

static PyMethodDef engine_methods[] = {
    {"advance", (PyCFunction)(void (*)(void))engine_advance, METH_FASTCALL | METH_KEYWORDS,
     "advance(t_end, ag0=0.0, slope=0.0, max_steps=None, continuous=False, linear=False, ag_v=0.0, "
     "ag_v_slope=0.0, linear_v=False): integrate to t_end under ag(t) = ag0 + slope (t - t0) and the vertical "
     "ag_v(t) = ag_v + ag_v_slope (t - t0); the state is unchanged on any error."},
    {"advance_motion", (PyCFunction)(void (*)(void))engine_advance_motion, METH_VARARGS | METH_KEYWORDS,
     "advance_motion(t_end, motion, max_steps=None, identity=0, vspec=None): integrate to t_end under a motion "
     "spec (vspec: the vertical component's, None: none)."},
    {"sample", (PyCFunction)(void (*)(void))engine_sample, METH_VARARGS | METH_KEYWORDS,
     "sample(times, motion, max_steps, modes, values, impacts, overturned, identity=0, vspec=None, columns=False, "
     "hold=False): "
     "Integrator.sample into the given arrays (modes: int32 or int64 n+1, values: float64 (n+1) x (n_outputs+2), "
     "impacts: int64 n+1, overturned: int32 or bool n+1; columns=True: values (n_outputs+2) x (n+1), one row per "
     "output). hold=True: ag (and ag_v) held at each interval's start (simulate's hold=\"zoh\", "
     "rk_engine_sample_held)."},
    {"outputs", (PyCFunction)engine_outputs, METH_NOARGS, "outputs() -> tuple in the declared order."},
    {"output_dict", (PyCFunction)engine_output_dict, METH_NOARGS,
     "output_dict() -> Simulator.outputs(): the outputs by name, contact, impacts, overturned, friction_demand, "
     "painleve."},
    {"output_row", (PyCFunction)engine_output_row, METH_NOARGS,
     "output_row() -> the values of output_dict() as a tuple of floats, in the same order."},
    {"checkpoint", (PyCFunction)engine_checkpoint, METH_NOARGS, "checkpoint(): save the state in the slot."},
    {"rollback", (PyCFunction)engine_rollback, METH_NOARGS, "rollback(): restore the slot exactly."},
    {"commit", (PyCFunction)engine_commit, METH_NOARGS, "commit(): drop the slot."},
    {NULL, NULL, 0, NULL}
};

#define GETTER(name, expr) \
    static PyObject *get_##name(EngineObject *self, void *closure) \
    { \
        (void)closure; \
        if (!ready(self)) \
            return NULL; \
        return expr; \
    }

GETTER(t, PyFloat_FromDouble(rk_engine_time(self->e)))
GETTER(mode, PyLong_FromLong(rk_engine_mode(self->e)))
GETTER(contact_code, PyLong_FromLong(rk_engine_contact_code(self->e)))
GETTER(impacts, PyLong_FromLongLong(rk_engine_impacts(self->e)))
GETTER(overturned, PyBool_FromLong(rk_engine_overturned(self->e)))
GETTER(n_steps, PyLong_FromLongLong(rk_engine_n_steps(self->e)))
GETTER(friction_demand, PyFloat_FromDouble(rk_engine_friction_demand(self->e)))
GETTER(painleve, PyLong_FromLongLong(rk_engine_painleve(self->e)))
GETTER(fail_time, PyFloat_FromDouble(rk_engine_fail_time(self->e)))
GETTER(n_outputs, PyLong_FromLong(rk_engine_n_outputs(self->e)))
GETTER(n_dof, PyLong_FromLong(rk_engine_n_dof(self->e)))
GETTER(n_contacts, PyLong_FromLong(rk_engine_n_contacts(self->e)))
GETTER(n_modes, PyLong_FromLong(rk_engine_n_modes(self->e)))
GETTER(scheme, PyLong_FromLong((long)rk_engine_scheme(self->e)))
GETTER(model_class, PyUnicode_FromString(rk_engine_model_class(self->e)))
GETTER(report_count, PyLong_FromLong(rk_engine_reports(self->e)->count))
GETTER(callback_raised, PyBool_FromLong(self->callback_raised))
GETTER(impact_times, impact_times_list(self->e))
GETTER(_address, PyLong_FromVoidPtr(self->e))

static PyObject *get_output_names(EngineObject *self, void *closure)
{
    (void)closure;
    if (!ready(self))
        return NULL;
    /* the first n keys of output_dict(): the same (interned) strings every time */
    return PyTuple_GetSlice(self->keys, 0, rk_engine_n_outputs(self->e));
}

static PyGetSetDef engine_getset[] = {
    {"t", (getter)get_t, NULL, "time [s]", NULL},
    {"mode", (getter)get_mode, NULL, "contact mode", NULL},
    {"contact_code", (getter)get_contact_code, NULL, "mode, or 10 once overturned", NULL},
    {"impacts", (getter)get_impacts, NULL, "impacts so far", NULL},
    {"overturned", (getter)get_overturned, NULL, "overturned", NULL},
    {"n_steps", (getter)get_n_steps, NULL, "internal steps", NULL},
    {"friction_demand", (getter)get_friction_demand, NULL, "largest |lambda_T| / lambda_N so far", NULL},
    {"painleve", (getter)get_painleve, NULL, "Painleve situations so far", NULL},
    {"fail_time", (getter)get_fail_time, NULL, "time reached when the last call failed [s]", NULL},
    {"n_outputs", (getter)get_n_outputs, NULL, "number of outputs", NULL},
    {"output_names", (getter)get_output_names, NULL, "output names in order", NULL},
    {"n_dof", (getter)get_n_dof, NULL, "full coordinates", NULL},
    {"n_contacts", (getter)get_n_contacts, NULL, "contacts", NULL},
    {"n_modes", (getter)get_n_modes, NULL, "contact modes", NULL},
    {"scheme", (getter)get_scheme, NULL, "0 moreau_jean, 1 event_driven", NULL},
    {"model_class", (getter)get_model_class, NULL, "the Python class name of the model", NULL},
    {"report_count", (getter)get_report_count, NULL, "reports of the last call (all counted)", NULL},
    {"callback_raised", (getter)get_callback_raised, NULL, "the last advance_motion / sample re-raised a motion "
     "callback's own exception", NULL},
    {"impact_times", (getter)get_impact_times, NULL, "the last impact_log_size impact times [s]", NULL},
    {"_address", (getter)get__address, NULL, "the rk_engine * (for the cffi binding's calls)", NULL},
    {NULL, NULL, NULL, NULL, NULL}
};

static PyType_Slot engine_slots[] = {
    {Py_tp_dealloc, (void *)engine_dealloc},
    {Py_tp_doc, (void *)"Engine(kind, params, initial=None, scheme=1, t0=0.0, dt_max=0.0, tolerance=1e-8, "
                        "theta=0.5, zeno_tol=1e-6, method=0, impact_log_size=None, max_events=100000, "
                        "tolerances=None, state=None): one simulation in the C engine (rk_engine.h). state = "
                        "(mode, q, v) starts there instead of at the initial values. Every argument may be "
                        "passed by position, in this order (CompiledIntegrator does: keywords cost a lookup "
                        "each)."},
    {Py_tp_methods, (void *)engine_methods},
    {Py_tp_getset, (void *)engine_getset},
    {Py_tp_init, (void *)engine_init},
    {Py_tp_new, (void *)PyType_GenericNew},
    {0, NULL}
};

static PyType_Spec engine_spec = {
    "rocking_model._engine.Engine", (int)sizeof(EngineObject), 0, Py_TPFLAGS_DEFAULT, engine_slots
};

/* the calls bound with cffi (rocking_model._engine_cold over rocking_model._rk) reach this copy of the engine */
static const rk_py_api API = {
    sizeof(rk_py_api), rk_engine_version, rk_engine_api_version, rk_engine_message, rk_engine_status, rk_engine_n_dof,
    rk_engine_n_contacts, rk_engine_n_modes, rk_engine_scheme, rk_engine_get_state, rk_engine_impact_times,
    rk_engine_impact_log, rk_engine_set_state, rk_engine_snapshot_size, rk_engine_snapshot, rk_engine_restore,
    rk_engine_reports, rk_engine_contacts, rk_engine_full_state, rk_model_kinds, rk_model_add, rk_model_kind_names,
    rk_model_find, rk_model_init, rk_model_inverse_mass, rk_model_slip
};

static PyMethodDef methods[] = {
    {NULL, NULL, 0, NULL}
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_engine",
    "The compiled rocking engine: see rocking_model/engine/DESIGN.md.", -1, methods,
    NULL, NULL, NULL, NULL
};

PyMODINIT_FUNC PyInit__engine(void)
{
    PyObject *m = PyModule_Create(&module);
    if (m == NULL)
        return NULL;
    {
        PyObject *type = PyType_FromSpec(&engine_spec);
        if (type == NULL || PyModule_AddObject(m, "Engine", type) < 0) {
            Py_XDECREF(type);
            Py_DECREF(m);
            return NULL;
        }
    }
    {   /* the package of this module: "rocking_model" or the FMU's bundled copy */
        PyObject *full = PyModule_GetNameObject(m);
        if (full == NULL) {
            Py_DECREF(m);
            return NULL;
        }
        {
            Py_ssize_t dot = PyUnicode_FindChar(full, '.', 0, PyUnicode_GetLength(full), -1);
            PackageName = dot > 0 ? PyUnicode_Substring(full, 0, dot) : PyUnicode_FromString("rocking_model");
        }
        Py_DECREF(full);
        if (PackageName == NULL) {
            Py_DECREF(m);
            return NULL;
        }
    }
    NonFiniteError = PyErr_NewExceptionWithDoc("rocking_model._engine.NonFiniteError",
                                               "The motion overflowed (non-finite state or outputs); the state was "
                                               "restored.", PyExc_ValueError, NULL);
    if (NonFiniteError == NULL || PyModule_AddObject(m, "NonFiniteError", NonFiniteError) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    Py_INCREF(NonFiniteError);
    {   /* the rest of the API, bound with cffi: <package>._engine_cold.install(module) adds its methods to Engine and
         * its functions to this module */
        PyObject *addr = PyLong_FromVoidPtr((void *)&API), *name, *cold, *r;
        if (addr == NULL || PyModule_AddObject(m, "_API", addr) < 0) {
            Py_XDECREF(addr);
            Py_DECREF(m);
            return NULL;
        }
        name = PyUnicode_FromFormat("%U._engine_cold", PackageName);
        cold = name != NULL ? PyImport_Import(name) : NULL;
        Py_XDECREF(name);
        r = cold != NULL ? PyObject_CallMethod(cold, "install", "O", m) : NULL;
        Py_XDECREF(cold);
        if (r == NULL) {
            Py_DECREF(m);
            return NULL;
        }
        Py_DECREF(r);
    }
    {
        PyObject *info = Py_BuildValue("{s:n,s:n,s:n}", "engine", (Py_ssize_t)sizeof(rk_engine), "core",
                                       (Py_ssize_t)sizeof(rk_core), "stepper", (Py_ssize_t)sizeof(rk_stepper));
        if (info == NULL || PyModule_AddObject(m, "SIZES", info) < 0) {
            Py_XDECREF(info);
            Py_DECREF(m);
            return NULL;
        }
    }
    return m;
}
