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

#include "platform.h"
#include "python_runtime.h"

/* ------------------------------------------------------------------------- live pointers */

/* A set of pointers (an open-addressing hash set under a mutex), for the instances and FMU states
 * this binary handed out: a pointer the host passes is dereferenced only if it is in the set. */
typedef struct {
    platform_mutex lock;
    void **slots;
    size_t capacity, count, used; /* used: live entries and tombstones */
} pointer_set;

#define POINTER_SET_INIT {PLATFORM_MUTEX_INIT, NULL, 0, 0, 0}

int pointer_set_add(pointer_set *set, void *pointer);    /* 0 if out of memory */
int pointer_set_remove(pointer_set *set, void *pointer); /* 1 if it was in the set */
int pointer_set_has(pointer_set *set, void *pointer);
/* The same with set->lock held by the caller. */
int pointer_set_add_locked(pointer_set *set, void *pointer);
int pointer_set_remove_locked(pointer_set *set, void *pointer);
int pointer_set_has_locked(pointer_set *set, void *pointer);

/* ------------------------------------------------------------------------------- versions */

/* FMI 2 and FMI 3 number their statuses alike: OK 0, Warning 1, Discard 2, Error 3, Fatal 4. */
enum { STATUS_OK = 0, STATUS_WARNING = 1, STATUS_DISCARD = 2, STATUS_ERROR = 3, STATUS_FATAL = 4 };

/* What differs between the FMI versions in the shared logic. */
typedef struct {
    const char *prefix;           /* "fmi2", "fmi3" */
    const char *model_identifier; /* MODEL_IDENTIFIER */
    const char *token;            /* FMU_GUID: the GUID (FMI 2) or instantiationToken (FMI 3) */
    const char *token_name;       /* "fmuGUID", "instantiationToken" */
    const char *resources_name;   /* "fmuResourceLocation", "resourcePath" */
    int any_state;                /* the bits of every state */
    int error_state;              /* the bit of the Error state */
    int instantiated_state;       /* the bit of Instantiated (after a reset) */
    const char *state_word;       /* "FMUstate", "FMUState": as the version spells it */
    const char *values_word;      /* "value", "values": the name of a get/set function's values */
    const char *reference_word;   /* "vr", "valueReference": what a value reference is called in messages */
    const char *(*state_name)(int state);
    int (*state_allowed)(const char *interface, int state); /* can an instance of `interface` be in it? */
} guard_version;

/* ------------------------------------------------------------------------------- instances */

typedef struct guard_instance guard_instance;
typedef struct guard_state guard_state;

/* Where an instance is: what an FMU state restores besides the Python side's own state. */
typedef struct {
    int state;                   /* one bit of the FMI version's states */
    double time;                 /* the FMU's time: where the next doStep starts [s] */
    double last_successful_time; /* the end of the last step that succeeded [s] */
    int wants_to_terminate;      /* a step was discarded: the FMU cannot go on from there */
} guard_position;

/* What every instance has, first in the FMI version's own struct. */
struct guard_instance {
    guard_position at;
    const guard_version *version;
    const char *interface; /* "CoSimulation" or "ModelExchange": what it was made for */
    int categories;        /* the log categories that reach the host's logger */
    const char *function;  /* the FMI function being run, for messages */
    char *name;
    guard_state *states;   /* the FMU states it made */
    int references;        /* the host's (until it frees the instance) and one per call running */
    const python_api *api; /* the process's Python */
    PyObject *python;      /* the instance's Python object (fmu_src/fmi_bridge.py) */
    int interrupted;       /* a Ctrl-C stopped a call: raised again for the host when the FMI function returns */
    char *strings;         /* the values of the last get of Strings (valid until the next one) */
    /* give one message to the host's logger, or stderr if it has none */
    void (*log)(guard_instance *g, int status, const char *category, const char *message);
    void (*destroy)(guard_instance *g); /* free the version's struct (its Python object is released) */
};

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

/* If a Ctrl-C stopped a call of g, raise it again for the host (a Python host then sees KeyboardInterrupt):
 * the last thing an FMI function does, after every message has been logged (a Python logger would
 * otherwise take the interrupt, and ctypes drops exceptions in callbacks). */
void guard_deliver_interrupt(guard_instance *g);

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

/* Give `message` to the host's logger if its category is on (the status's category if NULL). */
void guard_emit(guard_instance *g, int status, const char *category, const char *message);
/* Log an error, put the instance into its Error state, return STATUS_ERROR. */
int guard_fail(guard_instance *g, const char *format, ...) __attribute__((format(printf, 2, 3)));
/* A status of the Python side as the host gets it: an error puts the instance into its Error state. */
int guard_settle(guard_instance *g, int status);
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

/* ------------------------------------------------------------------------------ FMU states */

/* An FMU state as the host holds it: the Python side's state and the instance's position. */
struct guard_state {
    guard_instance *owner; /* the instance that made it: the only one that may use or free it */
    PyObject *python;
    guard_position at;
    char *serialized; /* the serialized form, once asked for (its size first, then the bytes) */
    size_t serialized_size;
    guard_state *previous, *next; /* the owner's states */
};

/* The FMU-state functions of both versions (FMUstate is the host's fmiXFMUState*). */
int guard_get_state(guard_instance *g, void **FMUstate);
int guard_set_state(guard_instance *g, void *FMUstate);
int guard_free_state(guard_instance *g, void **FMUstate);
int guard_serialized_size(guard_instance *g, void *FMUstate, size_t *size);
int guard_serialize_state(guard_instance *g, void *FMUstate, unsigned char *bytes, size_t size);
int guard_deserialize_state(guard_instance *g, const unsigned char *bytes, size_t size, void **FMUstate);

/* ---------------------------------------------------------------------------- messages */

/* The log categories of the FMUs' modelDescription, as bits. */
enum {
    CATEGORY_ALL = 1 << 0,     /* logAll: messages with status OK */
    CATEGORY_WARNING = 1 << 1, /* logStatusWarning */
    CATEGORY_DISCARD = 1 << 2, /* logStatusDiscard */
    CATEGORY_ERROR = 1 << 3,   /* logStatusError */
    CATEGORY_FATAL = 1 << 4,   /* logStatusFatal */
};
#define CATEGORIES_EVERY (CATEGORY_ALL | CATEGORY_WARNING | CATEGORY_DISCARD | CATEGORY_ERROR | CATEGORY_FATAL)
/* logged from instantiation on: why a step was discarded, and every error */
#define CATEGORIES_DEFAULT (CATEGORY_DISCARD | CATEGORY_ERROR | CATEGORY_FATAL)
#define CATEGORY_NAMES "logAll, logStatusWarning, logStatusDiscard, logStatusError, logStatusFatal"

/* The bit of category `name`, 0 if it is not one of this FMU's. */
int guard_category_bit(const char *name);
/* The category of a message with FMI status `status` (0 OK ... 4 Fatal, as in FMI 2 and FMI 3). */
const char *guard_category_of(int status);
int guard_category_bit_of(int status);

/* Parse fmi2/fmi3SetDebugLogging's categories into `mask` (`on` sets, else clears, their bits;
 * none named: all of them).  Returns 0 and writes why to `why` if an argument is wrong. */
int guard_debug_categories(int *mask, int on, size_t n, const char *const categories[], char *why, size_t size);

/* Like snprintf, never fails: a message cut at `size` ends in "...". */
void guard_format(char *out, size_t size, const char *format, ...) __attribute__((format(printf, 3, 4)));

/* The offset of the first byte of `text` that is not strict UTF-8 (what CPython's decoder accepts: no
 * overlong forms, no surrogates, nothing above U+10FFFF), or -1 if all of it is.  FMI strings are UTF-8
 * (fmi2TypesPlatform.h, fmi3PlatformTypes.h), and the Python side decodes them as such. */
long guard_utf8_error(const char *text);

/* ------------------------------------------------------------------------------- paths */

/* A file URI (file:///p, file://localhost/p, file:/p), %XX decoded, or a plain path, to a path
 * without a trailing slash.  Returns 0 for a URI of another scheme or host, a malformed %-escape, a
 * NUL byte, or a path that does not fit. */
int guard_uri_to_path(const char *uri, char *path, size_t size);

#endif
