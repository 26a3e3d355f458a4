/* Minimal non-Python FMI 2.0 co-simulation host for the rocking FMUs (pythonfmu).
 *
 * Usage: host <unzipped FMU dir> <modelIdentifier> <guid> <vr of ag> <vr of phi> <ag [m/s2]> <t_end [s]> <dt [s]>
 *
 * dlopens <dir>/binaries/linux64/<modelIdentifier>.so, instantiates a co-simulation slave with the resource
 * location file://<dir>/resources (pythonfmu's wrapper finds the Python slave class there), sets the input ag,
 * steps from 0 to t_end with step dt and prints "t,phi" after every step (%.17g).
 *
 * pythonfmu's binary embeds Python but is not linked against libpython: load it first, e.g.
 *   LD_PRELOAD=/path/to/libpython3.11.so PYTHONPATH=<site-packages with numpy, scipy> ./host ...
 * Build: cc -std=c99 -I<dir with fmi2Functions.h> host.c -o host -ldl
 */
#define _XOPEN_SOURCE 700
#include <dlfcn.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    va_list args;
    va_start(args, message);
    fprintf(stderr, "[%s] status=%d %s: ", instance ? instance : "?", (int)status, category ? category : "");
    vfprintf(stderr, message, args);
    fprintf(stderr, "\n");
    va_end(args);
}

#define LOAD(name)                                                                   \
    name##TYPE *name = (name##TYPE *)dlsym(lib, #name);                              \
    if (!name) {                                                                     \
        fprintf(stderr, "host: symbol %s not found: %s\n", #name, dlerror());        \
        return 2;                                                                    \
    }

#define CHECK(call)                                                                  \
    do {                                                                             \
        fmi2Status s_ = (call);                                                      \
        if (s_ > fmi2Warning) {                                                      \
            fprintf(stderr, "host: %s failed with status %d\n", #call, (int)s_);     \
            return 3;                                                                \
        }                                                                            \
    } while (0)

int main(int argc, char **argv) {
    if (argc != 9) {
        fprintf(stderr, "usage: %s <fmu dir> <modelIdentifier> <guid> <vr ag> <vr phi> <ag> <t_end> <dt>\n", argv[0]);
        return 1;
    }
    char dir[PATH_MAX];
    if (!realpath(argv[1], dir)) {
        perror("host: realpath");
        return 1;
    }
    const char *model = argv[2], *guid = argv[3];
    fmi2ValueReference vr_ag = (fmi2ValueReference)strtoul(argv[4], NULL, 10);
    fmi2ValueReference vr_phi = (fmi2ValueReference)strtoul(argv[5], NULL, 10);
    fmi2Real ag = strtod(argv[6], NULL), t_end = strtod(argv[7], NULL), dt = strtod(argv[8], NULL);

    char so[PATH_MAX + 256], resources[PATH_MAX + 64];
    snprintf(so, sizeof so, "%s/binaries/linux64/%s.so", dir, model);
    snprintf(resources, sizeof resources, "file://%s/resources", dir);

    void *lib = dlopen(so, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "host: dlopen failed: %s\n", dlerror());
        return 2;
    }
    LOAD(fmi2Instantiate)
    LOAD(fmi2SetupExperiment)
    LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode)
    LOAD(fmi2SetReal)
    LOAD(fmi2GetReal)
    LOAD(fmi2DoStep)
    LOAD(fmi2Terminate)
    LOAD(fmi2FreeInstance)

    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("host", fmi2CoSimulation, guid, resources, &callbacks, fmi2False, fmi2False);
    if (!c) {
        fprintf(stderr, "host: fmi2Instantiate failed (resources %s)\n", resources);
        return 3;
    }
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, t_end));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    CHECK(fmi2SetReal(c, &vr_ag, 1, &ag));
    long n = (long)(t_end / dt + 0.5);
    for (long k = 0; k < n; ++k) {
        fmi2Real t = k * dt, phi;
        CHECK(fmi2DoStep(c, t, dt, fmi2True));
        CHECK(fmi2GetReal(c, &vr_phi, 1, &phi));
        printf("%.17g,%.17g\n", (k + 1) * dt, phi);
        fflush(stdout);
    }
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    fflush(stdout);
    /* pythonfmu 0.7's binary runs Py_FinalizeEx from a static destructor when it is unloaded. With numpy and
     * scipy imported that crashed (SIGSEGV in the garbage collector during finalize_modules, Python 3.11)
     * after every FMI call had returned. Set HOST_UNLOAD=1 to dlclose and return normally anyway; by default
     * the host ends the process without running the destructors. */
    if (getenv("HOST_UNLOAD")) {
        dlclose(lib);
        return 0;
    }
    _exit(0);
}
