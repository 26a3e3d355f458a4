/* Shared by the libFuzzer harnesses of the self-contained FMUs (fuzz/README.md): the instance set-up and the
 * serialized state's layout. Each harness is linked with one FMU's C sources (its sources/ folder, the files of
 * its modelDescription's <SourceFiles>) and with fuzz_model.h, which fuzz/build.py generates from that FMU's
 * modelDescription.xml (FUZZ_GUID, FUZZ_VARS: value reference, type, causality of every variable). */
#ifndef FUZZ_FMU_H
#define FUZZ_FMU_H

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef struct {
    fmi2ValueReference vr;
    char type;      /* 'R' Real, 'I' Integer, 'B' Boolean, 'S' String */
    char causality; /* 'p' parameter, 'i' input, 'o' output, 'l' local, 'c' calculatedParameter */
    const char *name;
} fuzz_var;

#include "fuzz_model.h"

#define FUZZ_N_VARS (sizeof FUZZ_VARS / sizeof FUZZ_VARS[0])

/* messages go nowhere unless FUZZ_LOG is set (a reproducer run: fuzzer -runs=1 crash-file) */
static int fuzz_log_on = -1;
static char fuzz_last_error[8192]; /* the last message of status fmi2Error */
static void fuzz_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                        fmi2String message, ...) {
    (void)env;
    if (fuzz_log_on < 0) fuzz_log_on = getenv("FUZZ_LOG") != NULL;
    char text[8192];
    va_list ap;
    va_start(ap, message);
    vsnprintf(text, sizeof text, message, ap); /* the FMU passes its texts as data: message is "%s" */
    va_end(ap);
    if (status == fmi2Error) memcpy(fuzz_last_error, text, sizeof text);
    if (fuzz_log_on) fprintf(stderr, "[%s] %d %s: %s\n", name, (int)status, category, text);
}

static const fmi2CallbackFunctions FUZZ_CALLBACKS = {fuzz_logger, calloc, free, NULL, NULL};

/* every status is one of FMI 2.0's */
static fmi2Status fuzz_checked(fmi2Status s) {
    if ((int)s < (int)fmi2OK || (int)s > (int)fmi2Pending) {
        fprintf(stderr, "fuzz: FMI call returned status %d, not an fmi2Status\n", (int)s);
        abort();
    }
    return s;
}
#define CALL(x) fuzz_checked(x)

/* A state the FMU serialized, refused when read back: a finding (abort). */
static void fuzz_refused_own_state(size_t n) {
    fprintf(stderr, "fuzz: %s refuses the state it serialized (%zu bytes): %s\n", FUZZ_MODEL_NAME, n,
            fuzz_last_error);
    abort();
}

static fmi2Component fuzz_instantiate(void) {
    fmi2Component c = fmi2Instantiate("fuzz", fmi2CoSimulation, FUZZ_GUID, "file:///tmp", &FUZZ_CALLBACKS,
                                      fmi2False, fmi2True);
    if (!c) {
        fprintf(stderr, "fuzz: fmi2Instantiate of %s failed\n", FUZZ_MODEL_NAME);
        abort();
    }
    return c;
}

/* the value references of the variables of `type` and of causality in `causalities` (NULL: any) */
static size_t fuzz_refs(char type, const char *causalities, fmi2ValueReference *out) {
    size_t n = 0;
    for (size_t i = 0; i < FUZZ_N_VARS; i++)
        if (FUZZ_VARS[i].type == type && (!causalities || strchr(causalities, FUZZ_VARS[i].causality)))
            out[n++] = FUZZ_VARS[i].vr;
    return n;
}

/* the work budget of one step, bounded so that a fuzz input runs in milliseconds (any value above it is
 * valid for the FMU; values outside [1, 1e9] pass unchanged, to be refused) */
#define FUZZ_MAX_STEPS 20000
static const fuzz_var *fuzz_var_named(const char *name) {
    for (size_t i = 0; i < FUZZ_N_VARS; i++)
        if (strcmp(FUZZ_VARS[i].name, name) == 0) return &FUZZ_VARS[i];
    return NULL;
}

/* Every variable read back (all of each type, then each on its own): the getters' conversions are where a
 * state's out-of-range value would be undefined behaviour. */
static void fuzz_get_all(fmi2Component c) {
    fmi2ValueReference vr[FUZZ_N_VARS + 1];
    fmi2Real r[FUZZ_N_VARS + 1];
    fmi2Integer k[FUZZ_N_VARS + 1];
    fmi2Boolean b[FUZZ_N_VARS + 1];
    fmi2String s[FUZZ_N_VARS + 1];
    size_t n;
    if ((n = fuzz_refs('R', NULL, vr)) > 0) CALL(fmi2GetReal(c, vr, n, r));
    if ((n = fuzz_refs('I', NULL, vr)) > 0) CALL(fmi2GetInteger(c, vr, n, k));
    if ((n = fuzz_refs('B', NULL, vr)) > 0) CALL(fmi2GetBoolean(c, vr, n, b));
    if ((n = fuzz_refs('S', NULL, vr)) > 0) CALL(fmi2GetString(c, vr, n, s));
}

/* ------------------------------------------------------------------ the serialized state (fmi2_common.h) */
/* header: magic (22 bytes), time, 3 int32, CRC-32 at 42 over everything else; then the engine FMU's
 * payload (standalone/fmi2_engine.c): magic (28 bytes), GUID (36), ..., its own CRC-32 in its last 4 bytes */
#define FUZZ_CRC_OFFSET 42
#define FUZZ_HEADER_SIZE 46
#define FUZZ_GUID_OFFSET (FUZZ_HEADER_SIZE + 28)

static uint32_t fuzz_crc32(uint32_t crc, const unsigned char *p, size_t n) {
    crc = ~crc;
    while (n--) {
        crc ^= *p++;
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

/* Sign a state as its writer would: this build's GUID in the payload, the payload's CRC-32 and the header's
 * recomputed (what anyone who writes a state can do: the CRCs guard against accidents only). */
static void fuzz_sign_state(unsigned char *p, size_t n) {
    if (n >= FUZZ_GUID_OFFSET + 36) memcpy(p + FUZZ_GUID_OFFSET, FUZZ_GUID, 36);
    if (n >= FUZZ_HEADER_SIZE + 4) {
        uint32_t crc = fuzz_crc32(0, p + FUZZ_HEADER_SIZE, n - FUZZ_HEADER_SIZE - 4);
        memcpy(p + n - 4, &crc, 4);
    }
    if (n >= FUZZ_HEADER_SIZE) {
        uint32_t crc = fuzz_crc32(fuzz_crc32(0, p, FUZZ_CRC_OFFSET), p + FUZZ_HEADER_SIZE, n - FUZZ_HEADER_SIZE);
        memcpy(p + FUZZ_CRC_OFFSET, &crc, 4);
    }
}

#endif
