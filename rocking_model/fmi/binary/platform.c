/* POSIX and Windows implementations of platform.h. Only the POSIX branch is built and tested (Linux x86-64);
 * the Windows branch keeps the code portable and is compiled by nobody yet. */
#include "platform.h"

#include <stdlib.h>

#ifdef _WIN32
#include <windows.h>
#include <psapi.h>
#include <sys/stat.h>

static char win_error[256];

void *dl_open_global(const char *path) {
    HMODULE h = LoadLibraryExA(path, NULL, LOAD_WITH_ALTERED_SEARCH_PATH);
    if (!h) snprintf(win_error, sizeof win_error, "LoadLibrary failed with error %lu", GetLastError());
    return (void *)h;
}

void *dl_sym(void *library, const char *name) { return (void *)GetProcAddress((HMODULE)library, name); }

void *dl_process_sym(const char *name) {
    HMODULE modules[1024];
    DWORD needed = 0;
    if (!EnumProcessModules(GetCurrentProcess(), modules, sizeof modules, &needed)) return NULL;
    for (DWORD i = 0; i < needed / sizeof(HMODULE) && i < 1024; i++) {
        void *p = (void *)GetProcAddress(modules[i], name);
        if (p) return p;
    }
    return NULL;
}

const char *dl_error(void) { return win_error[0] ? win_error : "unknown error"; }

static INIT_ONCE init_once = INIT_ONCE_STATIC_INIT;
static CRITICAL_SECTION lock;
static BOOL CALLBACK init_lock(PINIT_ONCE o, PVOID p, PVOID *c) {
    (void)o; (void)p; (void)c;
    InitializeCriticalSection(&lock);
    return TRUE;
}
void once_lock(void) {
    InitOnceExecuteOnce(&init_once, init_lock, NULL, NULL);
    EnterCriticalSection(&lock);
}
void once_unlock(void) { LeaveCriticalSection(&lock); }

int is_directory(const char *path) {
    DWORD a = GetFileAttributesA(path);
    return a != INVALID_FILE_ATTRIBUTES && (a & FILE_ATTRIBUTE_DIRECTORY);
}
int is_file(const char *path) {
    DWORD a = GetFileAttributesA(path);
    return a != INVALID_FILE_ATTRIBUTES && !(a & FILE_ATTRIBUTE_DIRECTORY);
}

#else /* POSIX */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* RTLD_DEFAULT on glibc */
#endif
#include <dlfcn.h>
#include <pthread.h>
#include <sys/stat.h>

void *dl_open_global(const char *path) { return dlopen(path, RTLD_NOW | RTLD_GLOBAL); }

void *dl_sym(void *library, const char *name) { return dlsym(library, name); }

void *dl_process_sym(const char *name) {
#ifdef RTLD_DEFAULT
    return dlsym(RTLD_DEFAULT, name);
#else
    void *self = dlopen(NULL, RTLD_NOW); /* the global namespace on systems without RTLD_DEFAULT */
    return self ? dlsym(self, name) : NULL;
#endif
}

const char *dl_error(void) {
    const char *e = dlerror();
    return e ? e : "unknown error";
}

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
void once_lock(void) { pthread_mutex_lock(&lock); }
void once_unlock(void) { pthread_mutex_unlock(&lock); }

int is_directory(const char *path) {
    struct stat s;
    return stat(path, &s) == 0 && S_ISDIR(s.st_mode);
}
int is_file(const char *path) {
    struct stat s;
    return stat(path, &s) == 0 && S_ISREG(s.st_mode);
}
#endif

const char *env_value(const char *name) {
    const char *v = getenv(name);
    return (v && v[0]) ? v : NULL;
}
