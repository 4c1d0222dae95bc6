/* Choose the CPython that runs the FMU's Python side, in any host process, start it if it is not running
 * yet (python_start.c), and give the rest of the loader the few functions of its C API it calls
 * (bridge.c).
 *
 * The loader does not link libpython: the Python is chosen at run time (docs/fmu.md, "What a target
 * machine needs"), one per process:
 *
 *  1. a CPython already in the process is used as it is: a Python host's own interpreter, or the one an
 *     earlier FMU started.  Nothing is loaded, nothing is changed.  One that is older than 3.11, or loaded
 *     but not started by its owner, is refused with one line: a second libpython is never loaded beside
 *     one that is already in the process;
 *  2. otherwise the interpreter or libpython named by the environment variable DOUBLE_PENDULUM_FMU_PYTHON,
 *     if it is set (then it is the only candidate);
 *  3. otherwise, in a self-contained FMU, the CPython it carries beside this binary (binaries/<platform>/:
 *     its shared library, its standard library pruned and zipped, its extension modules);
 *  4. otherwise (a lean FMU, built with `double-pendulum build --lean`; POSIX only) the interpreter the FMU
 *     was built with (resources/python.cfg), then python3 on PATH.  An interpreter is asked about itself
 *     by running it (bounded by QUERY_TIMEOUT_MS, in a process group of its own that is killed whole:
 *     nothing is left behind).  A candidate must be CPython >= 3.11 with a shared libpython.
 *
 * A failed search is remembered: later instantiations fail at once with the same message, until
 * DOUBLE_PENDULUM_FMU_PYTHON changes.  No lock of the host is held while candidates are asked; the
 * process-wide lock every copy of the loader shares (platform_lock_process) is held only for the moment
 * Python is started. */
#ifndef PYTHON_RUNTIME_H
#define PYTHON_RUNTIME_H

#include <stdarg.h>
#include <stddef.h>
#include <sys/types.h>

#include "python_start.h"

#define PYTHON_OVERRIDE_VARIABLE "DOUBLE_PENDULUM_FMU_PYTHON"

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
    void (*Err_NormalizeException)(PyObject **, PyObject **, PyObject **);
    int (*Exception_SetTraceback)(PyObject *, PyObject *);
    void *(*GILState_GetThisThreadState)(void); /* a PyThreadState *, NULL in a thread Python does not know */
    unsigned long (*Thread_get_thread_ident)(void);
    int (*ThreadState_SetAsyncExc)(unsigned long, PyObject *);
    void (*OS_BeforeFork)(void); /* these three: NULL where the CPython has no fork (Windows) */
    void (*OS_AfterFork_Parent)(void);
    void (*OS_AfterFork_Child)(void);
    PyObject *None; /* Py_None (_Py_NoneStruct) */
} python_api;

/* Make a CPython available (see above) and return its C API; `resources` is the FMU's resources folder
 * (a path).  The first call does the work, later calls return the same table.  `chosen` (may be NULL)
 * receives which Python runs and why, for the debug log.  On failure returns NULL and writes one line to
 * `error` saying what was looked for, where, and how to point the FMU at a Python. */
const python_api *python_runtime_start(const char *resources, char *error, size_t error_size, const char **chosen);

/* Take the GIL (PyGILState_Ensure) for a call of the FMU's Python side.  In a C host's thread, PyGILState_Ensure first
 * makes a PyThreadState, under a lock of CPython's that a fork could leave held (CPython 3.11's PyOS_AfterFork_Child
 * then waits for it forever): where this copy started the process's Python, no fork happens meanwhile
 * (python_runtime_fork_prepare waits for it). */
int python_runtime_take_gil(void);

/* Around a fork() of the host (the guard's fork handlers call them, guard.c).  Where this copy of the loader
 * started the process's Python, its fork handling is the loader's to do, as os.fork does it in a Python host:
 * prepare waits for a thread that is taking the GIL (python_runtime_take_gil), takes the GIL (the thread inside an FMU
 * call gives it up at its next switch, within about 5 ms) and
 * readies Python for the fork (PyOS_BeforeFork); after the fork, the parent goes on (PyOS_AfterFork_Parent) and the
 * child's Python forgets the threads the child does not have (PyOS_AfterFork_Child), and the GIL is given back.
 * Without this, a child forked while another thread runs the FMU's Python would wait for that thread's GIL
 * forever.  Where the Python is a host's own (its os.fork does this) or another copy's (whose handlers do it),
 * these only hold and let go of this copy's lock. */
void python_runtime_fork_prepare(void);
void python_runtime_fork_parent(void);
void python_runtime_fork_child(void);

/* The path of the zipped standard library of the CPython this copy of the loader started from what the FMU carries
 * ("" if it started none: the Python is the host's, another FMU's, or one found), for the bootstrap to read it
 * faster than zipimport (bridge.c). */
const char *python_runtime_stdlib(void);

#endif
