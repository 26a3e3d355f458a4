/* A batch FMI 2.0 co-simulation host for every platform of the self-contained FMUs: the same
 * source compiled for linux64 (cc), win64 (x86_64-w64-mingw32-gcc, run under wine) and aarch64-linux
 * (aarch64-linux-gnu-gcc, run under qemu-user), so that one start of the emulator runs every scene.
 *
 * Usage: xhost <job file>
 *
 * The job file (written by tests/test_cross_platform.py) holds whitespace-separated tokens; every Real is
 * the 16 hexadecimal digits of its IEEE-754 bits (no decimal conversion by the platform's C library: the
 * numbers in and out are exact):
 *
 *   <number of jobs>
 *   then per job:
 *   <library path> <fmuResourceLocation> <guid> <vr of ag> <number of steps> <dt>
 *   <number of outputs> then per output: <R|I|B> <vr>
 *   <number of start values> then per value: <R|I> <vr> <value (Real: hex bits; Integer: decimal)>
 *   <ag of step 0> ... <ag of step n-1>
 *
 * Each job: load the library, fmi2Instantiate (co-simulation, no logging), fmi2SetupExperiment(start 0, no
 * tolerance, no stop time), the start values in initialization mode, then per step k: set ag,
 * fmi2DoStep(k * dt, dt), read the outputs. Output on stdout, per job: "job <i>", then one line per
 * communication point (before the first step, then after each): the status of fmi2DoStep (0 before the first)
 * and every output (Real: hex bits; Integer, Boolean: decimal). A step with a status above fmi2Discard ends
 * the job ("end error"); a job ends with "end". The FMU's messages go to stderr.
 * Build: cc -std=c99 -I<dir with fmi2Functions.h> xhost.c -o xhost [-ldl] (fmi_host.h beside it) */
#ifndef _WIN32
#define _POSIX_C_SOURCE 200809L
#endif
#define HOST_NAME "xhost"
#include "fmi_host.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static char token[8192];

static const char *next(FILE *f) {
    if (fscanf(f, "%8191s", token) != 1) {
        fprintf(stderr, "xhost: the job file ends early\n");
        exit(1);
    }
    return token;
}

static long next_long(FILE *f) { return strtol(next(f), NULL, 10); }

static double next_real(FILE *f) {
    const char *s = next(f);
    uint64_t bits = 0;
    for (int i = 0; i < 16; ++i) {
        char c = s[i];
        int d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
        if (d < 0) {
            fprintf(stderr, "xhost: '%s' is not 16 hexadecimal digits\n", s);
            exit(1);
        }
        bits = bits << 4 | (uint64_t)d;
    }
    double x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

static void print_real(double x) {
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    printf(" %08x%08x", (unsigned)(bits >> 32), (unsigned)(bits & 0xffffffffu));
}

enum { MAX_OUT = 64, MAX_START = 64 };

static int run_job(FILE *f, int job) {
    char library[4096], uri[4096], guid[256];
    snprintf(library, sizeof library, "%s", next(f));
    snprintf(uri, sizeof uri, "%s", next(f));
    snprintf(guid, sizeof guid, "%s", next(f));
    fmi2ValueReference vr_ag = (fmi2ValueReference)next_long(f);
    long n_steps = next_long(f);
    double dt = next_real(f);
    long n_out = next_long(f);
    if (n_out < 0 || n_out > MAX_OUT) return 1;
    char out_type[MAX_OUT];
    fmi2ValueReference out_vr[MAX_OUT];
    for (long i = 0; i < n_out; ++i) {
        out_type[i] = next(f)[0];
        out_vr[i] = (fmi2ValueReference)next_long(f);
    }
    long n_start = next_long(f);
    if (n_start < 0 || n_start > MAX_START) return 1;
    char start_type[MAX_START];
    fmi2ValueReference start_vr[MAX_START];
    double start_real[MAX_START];
    long start_int[MAX_START];
    for (long i = 0; i < n_start; ++i) {
        start_type[i] = next(f)[0];
        start_vr[i] = (fmi2ValueReference)next_long(f);
        if (start_type[i] == 'R') start_real[i] = next_real(f);
        else start_int[i] = next_long(f);
    }
    double *ag = (double *)malloc((size_t)(n_steps > 0 ? n_steps : 1) * sizeof *ag);
    if (!ag) return 1;
    for (long k = 0; k < n_steps; ++k) ag[k] = next_real(f);

    lib_t lib = lib_open(library);
    if (!lib) {
        fprintf(stderr, "xhost: cannot load %s: %s\n", library, lib_error());
        free(ag);
        return 2;
    }
    LOAD(fmi2Instantiate)
    LOAD(fmi2SetupExperiment)
    LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode)
    LOAD(fmi2SetReal)
    LOAD(fmi2SetInteger)
    LOAD(fmi2GetReal)
    LOAD(fmi2GetInteger)
    LOAD(fmi2GetBoolean)
    LOAD(fmi2DoStep)
    LOAD(fmi2Terminate)
    LOAD(fmi2FreeInstance)

    fmi2CallbackFunctions callbacks = {host_logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("xhost", fmi2CoSimulation, guid, uri, &callbacks, fmi2False, fmi2False);
    if (!c) {
        fprintf(stderr, "xhost: fmi2Instantiate failed (%s, resources %s)\n", library, uri);
        return 3;
    }
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    for (long i = 0; i < n_start; ++i) {
        if (start_type[i] == 'R') {
            CHECK(fmi2SetReal(c, &start_vr[i], 1, &start_real[i]));
        } else {
            fmi2Integer v = (fmi2Integer)start_int[i];
            CHECK(fmi2SetInteger(c, &start_vr[i], 1, &v));
        }
    }
    CHECK(fmi2ExitInitializationMode(c));
    printf("job %d\n", job);
    int status = 0;
    for (long k = 0; k <= n_steps; ++k) {
        if (k > 0) {
            CHECK(fmi2SetReal(c, &vr_ag, 1, &ag[k - 1]));
            status = (int)fmi2DoStep(c, (double)(k - 1) * dt, dt, fmi2True);
            if (status > fmi2Discard) {
                printf("end error %d\n", status);
                break;
            }
        }
        printf("%d", status);
        for (long i = 0; i < n_out; ++i) {
            if (out_type[i] == 'R') {
                fmi2Real v;
                CHECK(fmi2GetReal(c, &out_vr[i], 1, &v));
                print_real(v);
            } else if (out_type[i] == 'I') {
                fmi2Integer v;
                CHECK(fmi2GetInteger(c, &out_vr[i], 1, &v));
                printf(" %d", (int)v);
            } else {
                fmi2Boolean v;
                CHECK(fmi2GetBoolean(c, &out_vr[i], 1, &v));
                printf(" %d", v ? 1 : 0);
            }
        }
        printf("\n");
    }
    printf("end\n");
    fmi2Terminate(c);
    fmi2FreeInstance(c);
    lib_close(lib);
    free(ag);
    return 0;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s <job file>\n", argv[0]);
        return 1;
    }
    FILE *f = fopen(argv[1], "r");
    if (!f) {
        perror("xhost: job file");
        return 1;
    }
    long n_jobs = next_long(f);
    for (long j = 0; j < n_jobs; ++j) {
        int rc = run_job(f, (int)j);
        if (rc) {
            fclose(f);
            return rc;
        }
    }
    fclose(f);
    fflush(stdout);
    return 0;
}
