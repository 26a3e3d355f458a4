/* libFuzzer harness: arbitrary bytes as a serialized FMU state of one self-contained FMU (fuzz/README.md).
 *
 * Input: byte 0 chooses how, the rest is the state.
 *   bit 0    sign the bytes first (this build's GUID written into the payload, both CRC-32s recomputed, as
 *            anyone writing a state can): the fuzzer reaches the field checks behind the checksums;
 *   bits 1-2 the instance's phase when the state is read: 0 instantiated, 1 initialized, 2 after a step,
 *            3 terminated.
 * An accepted state is set, every variable read back (fmi2Get<Type> of all of them), a step of 0.01 s taken from
 * its time (when its max_steps is at most FUZZ_MAX_STEPS, to keep an input to milliseconds), the variables read
 * again, and the instance's state serialized and read back, which must succeed (a state the FMU writes, it
 * must take back: fmi2DeSerializeFMUstate and fmi2SetFMUstate). ASan/UBSan catch the rest. */
#include "fuzz_fmu.h"

static void phase(fmi2Component c, int which) {
    if (which == 0) return;
    CALL(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CALL(fmi2EnterInitializationMode(c));
    CALL(fmi2ExitInitializationMode(c));
    if (which >= 2) CALL(fmi2DoStep(c, 0.0, 0.01, fmi2True));
    if (which == 3) CALL(fmi2Terminate(c));
}

static void roundtrip(fmi2Component c) {
    fmi2FMUstate st = NULL, back = NULL;
    size_t n = 0;
    if (CALL(fmi2GetFMUstate(c, &st)) != fmi2OK) return;
    if (CALL(fmi2SerializedFMUstateSize(c, st, &n)) == fmi2OK) {
        fmi2Byte *bytes = (fmi2Byte *)malloc(n ? n : 1);
        if (CALL(fmi2SerializeFMUstate(c, st, bytes, n)) == fmi2OK &&
            (CALL(fmi2DeSerializeFMUstate(c, bytes, n, &back)) != fmi2OK || CALL(fmi2SetFMUstate(c, back)) != fmi2OK)) {
            fuzz_refused_own_state(n);
        }
        free(bytes);
    }
    if (back) CALL(fmi2FreeFMUstate(c, &back));
    CALL(fmi2FreeFMUstate(c, &st));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1 || size > (1u << 20)) return 0;
    const int mode = data[0];
    size_t n = size - 1;
    unsigned char *bytes = (unsigned char *)malloc(n ? n : 1); /* a buffer of exactly n bytes: ASan sees overreads */
    memcpy(bytes, data + 1, n);
    if (mode & 1) fuzz_sign_state(bytes, n);

    fmi2Component c = fuzz_instantiate();
    phase(c, (mode >> 1) & 3);
    fmi2FMUstate st = NULL;
    if (CALL(fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, n, &st)) == fmi2OK) {
        if (CALL(fmi2SetFMUstate(c, st)) == fmi2OK) {
            fuzz_get_all(c);
            const fuzz_var *ms = fuzz_var_named("max_steps");
            fmi2Integer max_steps = 0;
            fmi2Real t = 0.0;
            if (ms && CALL(fmi2GetInteger(c, &ms->vr, 1, &max_steps)) == fmi2OK && max_steps <= FUZZ_MAX_STEPS &&
                CALL(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t)) == fmi2OK) {
                CALL(fmi2DoStep(c, t, 0.01, fmi2True));
                fuzz_get_all(c);
            }
            roundtrip(c);
        }
        CALL(fmi2FreeFMUstate(c, &st));
    }
    fmi2FreeInstance(c);
    free(bytes);
    return 0;
}
