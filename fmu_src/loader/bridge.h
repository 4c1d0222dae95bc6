/* The C half of the bridge to the FMU's Python side (its Python half: fmu_src/fmi_bridge.py).
 *
 * The loader calls the FMU's Python objects itself; no FMI library's binary stands between them.
 * Every call has one shape: a method of the instance's Python object, given numbers, bytes or text,
 * answers a tuple (status, payload, messages) and never raises (it catches everything, Ctrl-C too).
 * Arrays cross as bytes of packed values (struct's native formats), strings as UTF-8 bytes.  The
 * loader takes the GIL only for the call itself: the messages are copied out and given to the host's
 * logger after the GIL is released, so no lock is held while the host's callback runs and a logger
 * may call the FMU again. */
#ifndef BRIDGE_H
#define BRIDGE_H

#include <stddef.h>

#include "guard_base.h"
#include "python_runtime.h"

/* What a call gives back besides its status. */
typedef enum {
    PAYLOAD_NONE,   /* nothing (the payload is ignored) */
    PAYLOAD_EXACT,  /* bytes of exactly `size` bytes, copied into `buffer` */
    PAYLOAD_COPY,   /* bytes of any length, copied into a new malloc'ed `*copy` of `*copy_size` bytes */
    PAYLOAD_OBJECT, /* the object itself: a new reference in `*object` (release with bridge_release) */
} payload_kind;

typedef struct {
    payload_kind kind;
    void *buffer;
    size_t size;
    char **copy;
    size_t *copy_size;
    PyObject **object;
} bridge_payload;

#define NO_PAYLOAD ((bridge_payload){PAYLOAD_NONE, NULL, 0, NULL, NULL, NULL})

/* Python's statuses beyond FMI's: the call was interrupted (KeyboardInterrupt): an error, and the host's
 * own interrupt is raised again once the call returns (a Python host then sees KeyboardInterrupt). */
#define BRIDGE_INTERRUPTED 5
/* Another exception of the host's stopped the call (fmi_bridge.py, host_exception): an error; the answer's payload
 * is the exception's redelivery, which bridge_deliver_host_exception raises in the host's thread. */
#define BRIDGE_HOST 6
/* The one log line of an interrupted call, after the FMI function's name (docs/fmu.md quotes it). */
#define BRIDGE_INTERRUPTED_TEXT                                                                                   \
    "interrupted (KeyboardInterrupt, Ctrl-C): the call was not completed; a reset makes the instance usable again"

/* Make the Python instance of g: load the FMU's package `package` and entry module `entry` from the zip
 * `resources`/`archive` (once per process) and call the entry's bridge's instantiate(resources, name, interface,
 * visible).  Returns the status; on success *instance is the new Python object. */
int bridge_instantiate(guard_instance *g, const python_api *api, const char *resources, const char *archive,
                       const char *package, const char *entry, const char *interface, int visible,
                       PyObject **instance);

/* Call method `method` of g's Python object with the arguments `format` (Py_BuildValue's, always a
 * tuple: "()", "(dd)", "(y#)" with Py_ssize_t lengths ...) and take its payload.  Returns the status
 * (FMI's numbers; an interruption is STATUS_ERROR); the messages have reached the host's logger. */
int bridge_call(guard_instance *g, bridge_payload payload, const char *method, const char *format, ...);

/* Release a Python object (an FMU state, an instance) of g's Python. */
void bridge_release(guard_instance *g, PyObject *object);

/* Raise the host's own exception that stopped a call of g (g->host_exception) again in this thread, where a Python
 * host runs (a C host has no Python exception to get back: it is dropped). The last thing the outermost FMI call
 * does, after every message has been logged. */
void bridge_deliver_host_exception(guard_instance *g);

#endif
