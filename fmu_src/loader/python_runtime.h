/* Find, load and start the CPython that runs the FMU's Python side, in any host process, and give the
 * rest of the loader the few functions of its C API it calls (bridge.c).
 *
 * The loader does not link libpython: the Python is chosen at run time (docs/fmu.md, "Use the FMU in
 * other FMI tools"):
 *
 *  1. a CPython already in the process (every Python host) is used as it is: nothing is loaded,
 *     nothing is changed;
 *  2. otherwise one is found, in this order: the interpreter or libpython named by the environment
 *     variable DOUBLE_PENDULUM_FMU_PYTHON (if set, it is the only candidate); the interpreter the FMU
 *     was built with (resources/python.cfg); python3 on PATH.  A candidate must be CPython >= 3.11
 *     with a shared libpython.  An interpreter is asked about itself by running it (bounded by
 *     QUERY_TIMEOUT_MS, in a process group of its own that is killed whole: nothing is left behind);
 *  3. its libpython is loaded privately, checked, then made global, and initialised with that Python's
 *     own home, in UTF-8 mode (file names decode in any locale), without touching the host: no signal
 *     handlers, no change of its locale (configure_locale = 0), no environment variable read or set,
 *     no site-packages.  It stays loaded until the process ends and is never finalised.
 *
 * A failed search is remembered: later instantiations fail at once with the same message, until
 * DOUBLE_PENDULUM_FMU_PYTHON changes.  No lock of the host (not even stderr's) is held while
 * candidates are asked; stderr's lock, the one lock every copy of the loader in the process shares,
 * is held only for the moment Python is started. */
#ifndef PYTHON_RUNTIME_H
#define PYTHON_RUNTIME_H

#include <stdarg.h>
#include <stddef.h>
#include <sys/types.h>

#define PYTHON_OVERRIDE_VARIABLE "DOUBLE_PENDULUM_FMU_PYTHON"
#define PYTHON_MIN_MINOR 11 /* CPython 3.11 or newer */

typedef struct _object PyObject; /* opaque: the loader never looks inside a Python object */

/* The functions of CPython's C API the loader calls (all in the stable ABI, or present in every
 * CPython >= 3.11), resolved once Python is in the process. */
typedef struct {
    int (*GILState_Ensure)(void);
    void (*GILState_Release)(int);
    void (*IncRef)(PyObject *);
    void (*DecRef)(PyObject *);
    PyObject *(*VaBuildValue)(const char *, va_list);
    PyObject *(*Object_GetAttrString)(PyObject *, const char *);
    PyObject *(*Object_Call)(PyObject *, PyObject *, PyObject *);
    PyObject *(*Object_Str)(PyObject *);
    const char *(*Unicode_AsUTF8AndSize)(PyObject *, ssize_t *);
    PyObject *(*Unicode_FromString)(const char *);
    PyObject *(*Bytes_FromStringAndSize)(const char *, ssize_t);
    int (*Bytes_AsStringAndSize)(PyObject *, char **, ssize_t *);
    long (*Long_AsLong)(PyObject *);
    ssize_t (*Tuple_Size)(PyObject *);
    PyObject *(*Tuple_GetItem)(PyObject *, ssize_t);
    PyObject *(*Dict_New)(void);
    int (*Dict_SetItemString)(PyObject *, const char *, PyObject *);
    PyObject *(*Dict_GetItemString)(PyObject *, const char *);
    void (*Dict_Clear)(PyObject *);
    PyObject *(*CompileString)(const char *, const char *, int);
    PyObject *(*Eval_EvalCode)(PyObject *, PyObject *, PyObject *);
    PyObject *(*Err_Occurred)(void);
    void (*Err_Fetch)(PyObject **, PyObject **, PyObject **);
    void (*Err_Clear)(void);
    void (*Err_SetInterrupt)(void);
} python_api;

/* Make a CPython available (see above) and return its C API; `resources` is the FMU's resources
 * folder (a path).  The first call does the work, later calls return the same table.  On failure
 * returns NULL and writes one line to `error` saying what was looked for, where, and how to point the
 * FMU at a Python. */
const python_api *python_runtime_start(const char *resources, char *error, size_t error_size);

#endif
