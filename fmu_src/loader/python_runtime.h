/* Find, load and start the CPython that runs a pythonfmu FMU (FMI 2) or pythonfmu3 FMU (FMI 3), in
 * any host process.
 *
 * pythonfmu's shared library (pythonfmu3's alike) calls the CPython C API but does not link
 * libpython (on Linux it expects the host to be a Python process).  The FMU's binary is this loader
 * instead: before it loads that library it makes sure the process has a CPython with global
 * symbols, as described in docs/fmu.md ("Use the FMU in other FMI tools"):
 *
 *  1. a CPython already in the process (every Python host) is used as it is: nothing is loaded,
 *     nothing is changed;
 *  2. otherwise one is found, in this order: the interpreter or libpython named by the environment
 *     variable DOUBLE_PENDULUM_FMU_PYTHON (if set, it is the only candidate); the interpreter the FMU
 *     was built with (resources/python.cfg); python3 on PATH.  A candidate must be CPython >= 3.11
 *     with a shared libpython;
 *  3. its libpython is loaded with global symbols and initialised with that Python's own home and
 *     executable, without signal handlers (the host keeps its own) and without touching the
 *     host's environment; it stays loaded until the process ends and is never finalised.
 */
#ifndef PYTHON_RUNTIME_H
#define PYTHON_RUNTIME_H

#include <stddef.h>

#define PYTHON_OVERRIDE_VARIABLE "DOUBLE_PENDULUM_FMU_PYTHON"
#define PYTHON_MIN_MINOR 11 /* CPython 3.11 or newer */

/* Load the FMI library `backend_file` (pythonfmu's or pythonfmu3's; a file name in the folder of
 * this loader) after making a CPython available (see above).  `resources_uri` is the FMU's resource
 * location as passed to fmi2Instantiate (a file URI) or fmi3Instantiate* (a path), may be NULL.
 * Returns the library's handle; the first call does the work, later calls return the same handle.
 * On failure returns NULL and writes one line to `error` saying what was looked for, where, and
 * how to point the FMU at a Python. */
void *python_runtime_load_backend(const char *resources_uri, const char *backend_file, char *error,
                                  size_t error_size);

#endif
