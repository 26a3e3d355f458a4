/* libFuzzer harness: parameter/input/step sequences on one self-contained FMU (fuzz/README.md).
 *
 * The bytes are read as a program of at most MAX_OPS calls on one instance (instantiated fresh per input), each
 * an opcode byte and its operands: fmi2SetReal / SetInteger / SetBoolean of one to three variables (a value
 * reference chosen among the FMU's, or any 32-bit number), SetupExperiment + Enter/ExitInitializationMode,
 * DoStep, Reset, Terminate, the getters (every variable), SetRealInputDerivatives, GetRealOutputDerivatives,
 * the status getters, and FMU states (get, set, serialize and read back, free; two slots). Doubles are drawn
 * from nan, +-inf, +-DBL_MAX, +-0, subnormals, huge and tiny values, small decimals and raw 8-byte patterns;
 * integers from their limits and raw 4-byte patterns. The work budget max_steps is kept at most FUZZ_MAX_STEPS
 * so that an input runs in milliseconds. Calls in the wrong state are part of the program (they must be
 * refused cleanly). ASan/UBSan catch memory errors and undefined behaviour; the harness checks every status is
 * an fmi2Status and that a state the FMU serialized is taken back. */
#include <float.h>
#include <math.h>

#include "fuzz_fmu.h"

#define MAX_OPS 48

typedef struct {
    const uint8_t *p;
    size_t n;
} Reader;

static uint8_t u8(Reader *r) {
    if (!r->n) return 0;
    r->n--;
    return *r->p++;
}

static void raw(Reader *r, void *out, size_t k) {
    memset(out, 0, k);
    size_t m = k < r->n ? k : r->n;
    memcpy(out, r->p, m);
    r->p += m, r->n -= m;
}

static double any_double(Reader *r) {
    static const double SPECIAL[] = {0.0, -0.0, 1.0, -1.0, 0.5, 0.01, 1e-3, 10.0, 1e6, 1e300, -1e300, 1e-300,
                                     4.9e-324, DBL_MIN, DBL_MAX, -DBL_MAX};
    uint8_t sel = u8(r);
    switch (sel % 8) {
    case 0: return NAN;
    case 1: return (sel & 8) ? -INFINITY : INFINITY;
    case 2: case 3: return SPECIAL[(sel >> 3) % (sizeof SPECIAL / sizeof SPECIAL[0])];
    case 4: case 5: return (double)(int8_t)u8(r) / 16.0;  /* small decimals: the usual values */
    default: {
        double x;
        raw(r, &x, sizeof x);
        return x;
    }
    }
}

static int32_t any_int(Reader *r) {
    uint8_t sel = u8(r);
    switch (sel % 4) {
    case 0: return (sel & 4) ? INT32_MAX : INT32_MIN;
    case 1: case 2: return (int8_t)u8(r);
    default: {
        int32_t x;
        raw(r, &x, sizeof x);
        return x;
    }
    }
}

/* a value reference: one of the FMU's variables of `type` (mostly), or any number */
static fmi2ValueReference any_ref(Reader *r, char type) {
    fmi2ValueReference vr[FUZZ_N_VARS + 1];
    uint8_t sel = u8(r);
    size_t n = fuzz_refs(type, NULL, vr);
    if (sel < 240 && n) return vr[sel % n];
    if (sel < 248) return (fmi2ValueReference)sel;
    uint32_t x;
    raw(r, &x, sizeof x);
    return x;
}

static int is_max_steps(fmi2ValueReference vr) {
    const fuzz_var *v = fuzz_var_named("max_steps");
    return v && v->vr == vr;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    Reader r = {data, size};
    fmi2Component c = fuzz_instantiate();
    fmi2FMUstate slot[2] = {NULL, NULL};
    fmi2Real t = 0.0;
    const fuzz_var *ms = fuzz_var_named("max_steps");
    if (ms) {
        fmi2Integer k = 2000;
        CALL(fmi2SetInteger(c, &ms->vr, 1, &k));
    }
    for (int op = 0; op < MAX_OPS && r.n; op++) {
        uint8_t code = u8(&r);
        switch (code % 13) {
        case 0: case 1: { /* SetReal, the most frequent call */
            size_t k = 1 + u8(&r) % 3;
            fmi2ValueReference vr[3];
            fmi2Real x[3];
            for (size_t i = 0; i < k; i++) vr[i] = any_ref(&r, 'R'), x[i] = any_double(&r);
            CALL(fmi2SetReal(c, vr, k, x));
            break;
        }
        case 2: {
            size_t k = 1 + u8(&r) % 3;
            fmi2ValueReference vr[3];
            fmi2Integer x[3];
            for (size_t i = 0; i < k; i++) {
                vr[i] = any_ref(&r, 'I'), x[i] = any_int(&r);
                if (is_max_steps(vr[i]) && x[i] > FUZZ_MAX_STEPS && x[i] <= 1000000000) x[i] = FUZZ_MAX_STEPS;
            }
            CALL(fmi2SetInteger(c, vr, k, x));
            break;
        }
        case 3: {
            fmi2ValueReference vr = any_ref(&r, 'B');
            fmi2Boolean b = (fmi2Boolean)(int8_t)u8(&r);
            CALL(fmi2SetBoolean(c, &vr, 1, &b));
            break;
        }
        case 4: {
            uint8_t f = u8(&r);
            t = (f & 1) ? any_double(&r) : 0.0;
            CALL(fmi2SetupExperiment(c, (f & 2) != 0, 1e-6, t, (f & 4) != 0, t + 10.0));
            CALL(fmi2EnterInitializationMode(c));
            CALL(fmi2ExitInitializationMode(c));
            break;
        }
        case 5: case 6: { /* DoStep: mostly from the instance's time, with any step size */
            uint8_t f = u8(&r);
            double h = (f & 1) ? any_double(&r) : 0.01 * (1 + (f >> 4));
            double at = (f & 2) ? any_double(&r) : t;
            fmi2Status s = CALL(fmi2DoStep(c, at, h, (f & 4) != 0));
            if (s == fmi2OK || s == fmi2Warning) t = at + h;
            break;
        }
        case 7:
            CALL(fmi2Reset(c));
            t = 0.0;
            break;
        case 8:
            fuzz_get_all(c);
            break;
        case 9: {
            fmi2ValueReference vr = any_ref(&r, 'R');
            fmi2Integer order = (u8(&r) & 1) ? 1 : any_int(&r);
            fmi2Real x = any_double(&r);
            CALL(fmi2SetRealInputDerivatives(c, &vr, 1, &order, &x));
            break;
        }
        case 10: {
            fmi2ValueReference vr = any_ref(&r, 'R');
            fmi2Integer order = 1 + u8(&r) % 2;
            fmi2Real x;
            CALL(fmi2GetRealOutputDerivatives(c, &vr, 1, &order, &x));
            fmi2Status st;
            fmi2Real lt;
            fmi2Boolean term;
            CALL(fmi2GetStatus(c, fmi2DoStepStatus, &st));
            CALL(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &lt));
            CALL(fmi2GetBooleanStatus(c, fmi2Terminated, &term));
            break;
        }
        case 11: { /* FMU states */
            uint8_t f = u8(&r);
            fmi2FMUstate *s = &slot[f & 1];
            switch ((f >> 1) % 4) {
            case 0: CALL(fmi2GetFMUstate(c, s)); break;
            case 1: if (*s) CALL(fmi2SetFMUstate(c, *s)); break;
            case 2: if (*s) CALL(fmi2FreeFMUstate(c, s)); break;
            default: {
                size_t n = 0;
                fmi2FMUstate back = NULL;
                if (*s && CALL(fmi2SerializedFMUstateSize(c, *s, &n)) == fmi2OK) {
                    fmi2Byte *bytes = (fmi2Byte *)malloc(n ? n : 1);
                    if (CALL(fmi2SerializeFMUstate(c, *s, bytes, n)) == fmi2OK &&
                        (CALL(fmi2DeSerializeFMUstate(c, bytes, n, &back)) != fmi2OK ||
                         CALL(fmi2SetFMUstate(c, back)) != fmi2OK)) {
                        fuzz_refused_own_state(n);
                    }
                    free(bytes);
                }
                if (back) CALL(fmi2FreeFMUstate(c, &back));
            }
            }
            break;
        }
        default:
            CALL(fmi2Terminate(c));
            break;
        }
    }
    for (int k = 0; k < 2; k++)
        if (slot[k]) CALL(fmi2FreeFMUstate(c, &slot[k]));
    fmi2FreeInstance(c);
    return 0;
}
