/* The few operating-system services the FMU binary needs, behind one small interface each, so that a port
 * to another system touches this file and platform.c only.
 *
 *   dl_open / dl_sym / dl_error     load a shared library, look a symbol up (POSIX dlopen, Windows LoadLibrary)
 *   dl_process_sym                  a symbol already loaded into the process (RTLD_DEFAULT / loaded modules)
 *   once_lock / once_unlock         one process-wide lock around the first loading of Python
 *   is_directory / is_file          checks of the resource folder
 */
#ifndef FMI_BINARY_PLATFORM_H
#define FMI_BINARY_PLATFORM_H

#include <stddef.h>

/* Load a shared library with its symbols visible to later loads (Python's extension modules, numpy's
 * among them, resolve the C API through the global namespace). NULL on failure: see dl_error. */
void *dl_open_global(const char *path);
void *dl_sym(void *library, const char *name);
/* A symbol from whatever the process has loaded already (the host's own Python), or NULL. */
void *dl_process_sym(const char *name);
/* The last loader error as text (never NULL). */
const char *dl_error(void);

void once_lock(void);
void once_unlock(void);

int is_directory(const char *path);
int is_file(const char *path);

/* The environment variable `name`, or NULL when unset or empty. */
const char *env_value(const char *name);

#endif
