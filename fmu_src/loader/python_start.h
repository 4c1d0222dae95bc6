/* Start a CPython from its shared library, in a host that has none, without ever ending the host: the
 * configuration API whose every step returns a status (PEP 587's PyConfig for CPython 3.11 to 3.13,
 * PEP 741's PyInitConfig for 3.14 and newer), never Py_Initialize, which ends the process when the
 * Python cannot start (a damaged standard library, a wrong home).
 *
 * The Python is started isolated and without touching the host: UTF-8 mode (file names decode in any
 * locale), the host's locale, signal handlers, C stdio and environment left as they are (no signal
 * handler installed, no environment variable read), no site-packages, no bytecode written.  It stays
 * loaded until the process ends and is never finalised.  Which Python to start is python_runtime.c's
 * choice. */
#ifndef PYTHON_START_H
#define PYTHON_START_H

#include <stddef.h>

#include "platform.h"

#define PYTHON_MIN_MINOR 11 /* CPython 3.11 or newer */

/* A CPython to start. */
typedef struct {
    int major, minor;
    char library[PLATFORM_PATH_MAX];    /* its shared library: libpython3.X.so, python3X.dll */
    char home[PLATFORM_PATH_MAX];       /* sys.base_prefix: where its standard library lives */
    char executable[PLATFORM_PATH_MAX]; /* its base interpreter (may be empty) */
    /* the module search path, if the Python's own layout does not give it (a bundled Python: the zipped
     * standard library and the folder of its extension modules); empty: found from `home` */
    char search_path[2][PLATFORM_PATH_MAX];
    /* libraries in `home` its extension modules need beyond the system's, loaded before it starts, so that the
     * dynamic loader finds them by name (a bundled Linux Python's libffi.so.8): names separated by ':' */
    char preload[PLATFORM_PATH_MAX];
} python_install;

/* Load `python`'s library, start it and release the GIL (every call takes it with PyGILState_Ensure).
 * Returns the library's handle, or NULL and why (nothing of a Python that did not start stays global).
 * The caller holds platform_lock_process() and has checked that no Python is in the process. */
void *python_start(const python_install *python, char *why, size_t size);

#endif
