/* What the FMI 2 and FMI 3 layers (fmi2_guard.c, fmi3_guard.c) share: everything but the functions'
 * signatures and the state machines.
 *
 * Each layer gives the host the standard's behaviour whatever the Python side does (docs/fmu.md, "How
 * the FMU answers a master"): a per-instance state machine from the standard's tables, argument checks,
 * instantiation checks, a logger only ever called with the message as data and with no lock held,
 * statuses that say what is lost.  This file holds what both need, behind a small table per FMI version
 * (guard_version): sets of live pointers (an instance or an FMU state the host passes is looked up
 * before it is used, and an instance is freed only when no call is using it), instantiation (checks,
 * Python, the bridge), FMU states (owned by their instance, validated when deserialised), log
 * categories and messages, the time check of doStep, path and UTF-8 checks. */
#ifndef GUARD_H
#define GUARD_H

#include <stddef.h>

#include "guard_base.h"

/* ------------------------------------------------------------------------------- instances */

/* Register a new instance with the host's reference (0 if out of memory). */
int guard_register(guard_instance *g);
/* The host frees `c`: it is no longer live (1 if it was); it is destroyed when no call uses it. */
int guard_unregister(void *c);
/* The live instance `c` for the FMI function `function`, with a reference for the call, or NULL (one
 * line on stderr: no logger).  The reference is given back by guard_release. */
guard_instance *guard_acquire(void *c, const char *model_identifier, const char *function);
void guard_release(guard_instance *g);
/* For __attribute__((cleanup)): release the instance a variable holds (if any) when it goes out of scope. */
void guard_release_variable(void *variable);
#define GUARD_CALL __attribute__((cleanup(guard_release_variable)))
/* An FMI call of an instance, from its start (guard_scope_begin, after guard_acquire) to its end: the function it
 * is in is given back when it ends, so that a call the host's logger makes from inside another (fmi2FreeFMUstate
 * during fmi2GetFMUstate) leaves the outer call's name for its later lines; and when the outermost call ends,
 * the host's own exception that stopped it is raised again (bridge_deliver_host_exception). */
typedef struct {
    guard_instance *g;
    const char *function;
} guard_scope;
guard_scope guard_scope_begin(guard_instance *g);
void guard_scope_end(guard_scope *scope);
#define GUARD_SCOPE __attribute__((cleanup(guard_scope_end)))

/* If a Ctrl-C stopped a call of g, raise it again for the host (a Python host then sees KeyboardInterrupt):
 * the last thing an FMI function does, after every message has been logged (a Python logger would
 * otherwise take the interrupt, and ctypes drops exceptions in callbacks). */
void guard_deliver_interrupt(guard_instance *g);

/* The failure of `function` in a state that does not allow it (`state`: its name), logged: an illegal call sequence,
 * or, in a forked child, the call another thread was inside when the process forked. */
int guard_refuse_state(guard_instance *g, const char *function, const char *state);

/* Fill in `g` (calloc'ed, first in the version's struct) for a new instance. */
int guard_init_instance(guard_instance *g, const guard_version *version, const char *interface,
                        const char *name, int logging_on,
                        void (*log)(guard_instance *, int, const char *, const char *),
                        void (*destroy)(guard_instance *));
/* The checks every instantiation needs (instance name; the token; the resource location: a file URI or a
 * path, decoded into `resources`, a folder of this machine, UTF-8, and this FMU's: resources/identity.cfg
 * names its model and token).  Returns 0 and writes why to `why` if one fails. */
int guard_check_instantiation(const guard_version *v, const char *name, const char *token, const char *location,
                              char *resources, size_t size, char *why, size_t why_size);
/* Start Python (once per process) and make g's Python object; 0 (logged) if that fails. */
int guard_start_python(guard_instance *g, const char *resources, int visible);
/* Release g's Python object and its FMU states, free its name: what every destroy does first. */
void guard_free_common(guard_instance *g);
/* fmiXReset: the Python object made anew, the FMU states kept. */
int guard_reset(guard_instance *g);

/* fmiXSetDebugLogging as specified; STATUS_OK or a failure. */
int guard_set_debug_logging(guard_instance *g, int on, size_t n, const char *const categories[]);
/* One line on stderr for a call that has no instance to log through. */
void guard_orphan(const char *model_identifier, const char *function, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
/* Get / set `n` String values (the values got stay valid until the next get of this instance). */
int guard_get_strings(guard_instance *g, const unsigned int vr[], size_t n, const char *values[]);
int guard_set_strings(guard_instance *g, const unsigned int vr[], size_t n, const char *const values[]);
/* doStep's currentCommunicationPoint and communicationStepSize: 1 if they are right, else logged. */
int guard_check_step(guard_instance *g, double current, double step);

/* ------------------------------------------------------------------------------- paths */

/* A file URI (file:///p, file://localhost/p, file:/p), %XX decoded, or a plain path, to a path
 * without a trailing slash.  Returns 0 for a URI of another scheme or host, a malformed %-escape, a
 * NUL byte, or a path that does not fit. */
int guard_uri_to_path(const char *uri, char *path, size_t size);

#endif
