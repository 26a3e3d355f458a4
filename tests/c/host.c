/* Minimal non-Python FMI 2.0 co-simulation host for the rocking FMUs.
 *
 * Usage: host <unzipped FMU dir> <modelIdentifier> <guid> <vr of ag> <vr of phi> <ag [m/s2]> <t_end [s]> <dt [s]>
 *
 * dlopens <dir>/binaries/linux64/<modelIdentifier>.so, instantiates a co-simulation slave with the resource
 * location file://<dir>/resources, sets the input ag, steps from 0 to t_end with step dt, prints "t,phi"
 * after every step (%.17g), frees the instance and unloads the binary. The FMU's binary loads libpython and
 * finds numpy by itself (the paths recorded when it was built): no LD_PRELOAD, no PYTHONPATH.
 * With a 9th argument --maps, the host reports on stderr whether libpython is mapped into the process
 * (/proc/self/maps) after the run: "host: libpython mapped: yes|no" (the self-contained FMUs never map it).
 * Build: cc -std=c99 -I<dir with fmi2Functions.h> host.c -o host -ldl (fmi_host.h beside it)
 */
#define _XOPEN_SOURCE 700
#define HOST_NAME "host"
#include "fmi_host.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv) {
    int check_maps = argc == 10 && strcmp(argv[9], "--maps") == 0;
    if (argc != 9 && !check_maps) {
        fprintf(stderr, "usage: %s <fmu dir> <modelIdentifier> <guid> <vr ag> <vr phi> <ag> <t_end> <dt> [--maps]\n",
                argv[0]);
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

    lib_t lib = lib_open(so);
    if (!lib) {
        fprintf(stderr, "host: dlopen failed: %s\n", lib_error());
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

    fmi2CallbackFunctions callbacks = {host_logger, calloc, free, NULL, NULL};
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
    if (check_maps) {
        FILE *maps = fopen("/proc/self/maps", "r");
        char line[4096];
        int mapped = 0;
        while (maps && fgets(line, sizeof line, maps))
            if (strstr(line, "libpython")) mapped = 1;
        if (maps) fclose(maps);
        fprintf(stderr, "host: libpython mapped: %s\n", maps ? (mapped ? "yes" : "no") : "unknown");
    }
    fmi2FreeInstance(c);
    fflush(stdout);
    /* the binary never finalizes the interpreter it started: unloading it and returning is safe */
    lib_close(lib);
    return 0;
}
