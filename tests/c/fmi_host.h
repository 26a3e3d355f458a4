/* What the C FMI hosts of the tests (host.c, xhost.c) share: loading a library on POSIX and on Windows, the
 * logger that prints the FMU's messages to stderr, and the LOAD / CHECK macros, which return 2 (a missing
 * symbol) or 3 (a call above fmi2Warning) from the calling function with a message prefixed by HOST_NAME.
 * A host defines HOST_NAME and its feature-test macros, then includes this file first. */
#ifndef FMI_HOST_H
#define FMI_HOST_H

#include <stdarg.h>
#include <stdio.h>

#ifdef _WIN32
#include <windows.h>
typedef HMODULE lib_t;
static lib_t lib_open(const char *path) { return LoadLibraryA(path); }
static void *lib_sym(lib_t lib, const char *name) { return (void *)GetProcAddress(lib, name); }
static void lib_close(lib_t lib) { FreeLibrary(lib); }
static const char *lib_error(void) { static char buf[64]; sprintf(buf, "error %lu", (unsigned long)GetLastError()); return buf; }
#else
#include <dlfcn.h>
typedef void *lib_t;
static lib_t lib_open(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *lib_sym(lib_t lib, const char *name) { return dlsym(lib, name); }
static void lib_close(lib_t lib) { dlclose(lib); }
static const char *lib_error(void) { const char *e = dlerror(); return e ? e : "?"; }
#endif

#include "fmi2Functions.h"

static void host_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                        fmi2String message, ...) {
    (void)env;
    va_list args;
    va_start(args, message);
    fprintf(stderr, "[%s] status=%d %s: ", instance ? instance : "?", (int)status, category ? category : "");
    vfprintf(stderr, message, args);
    fprintf(stderr, "\n");
    va_end(args);
}

#define LOAD(name)                                                                         \
    name##TYPE *name = (name##TYPE *)lib_sym(lib, #name);                                  \
    if (!name) {                                                                           \
        fprintf(stderr, HOST_NAME ": symbol %s not found: %s\n", #name, lib_error());      \
        return 2;                                                                          \
    }

#define CHECK(call)                                                                        \
    do {                                                                                   \
        fmi2Status s_ = (call);                                                            \
        if (s_ > fmi2Warning) {                                                            \
            fprintf(stderr, HOST_NAME ": %s failed with status %d\n", #call, (int)s_);     \
            return 3;                                                                      \
        }                                                                                  \
    } while (0)

#endif /* FMI_HOST_H */
