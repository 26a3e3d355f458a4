/* rk_version.h -- the engine's version, what rk_engine_version() returns.
 *
 * The package's own builds pass it as the macro RK_ENGINE_VERSION_STRING (setup.py: the extension); the
 * self-contained FMUs ship this header in sources/ with the version written in (rocking_model/fmi/build.py,
 * `version_header`), so that an importer compiling sources/ with nothing but the source files builds a library
 * that reports the version it was made from. Here, in the engine's own sources, it is not known. */
#ifndef RK_VERSION_H
#define RK_VERSION_H

#ifndef RK_ENGINE_VERSION_STRING
#define RK_ENGINE_VERSION_STRING "unknown"
#endif

#endif /* RK_VERSION_H */
