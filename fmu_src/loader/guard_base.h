/* What every layer of the loader above the base knows of an instance (see scripts/check_loader_layers.py):
 * the FMI statuses, the table of what differs between the FMI versions, an instance's common part, and its
 * log (categories; emit, fail, settle). The units that use an instance (bridge.c, guard.c, fmu_state.c, the
 * version layers) meet here rather than in each other. */
#ifndef GUARD_BASE_H
#define GUARD_BASE_H

#include <stddef.h>

#include "python_runtime.h" /* python_api, PyObject: types only */

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
    PyObject *host_exception; /* another exception of the host's stopped a call: its redelivery (fmi_bridge.py), raised
                               * again in the host's thread when the outermost FMI call of the instance returns */
    int depth;             /* FMI calls of the instance in progress (the host's logger may call in: nested) */
    unsigned long thread;  /* the thread of the outermost call in progress (platform_thread_self) */
    const char *forked_inside; /* the FMI function another thread was inside when the process forked (in the
                                * child, where that thread is gone: the instance is then in its Error state) */
    char *strings;         /* the values of the last get of Strings (valid until the next one) */
    /* give one message to the host's logger, or stderr if it has none */
    void (*log)(guard_instance *g, int status, const char *category, const char *message);
    void (*destroy)(guard_instance *g); /* free the version's struct (its Python object is released) */
};

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

/* Give `message` to the host's logger if its category is on (the status's category if NULL). */
void guard_emit(guard_instance *g, int status, const char *category, const char *message);
/* Log an error, put the instance into its Error state, return STATUS_ERROR. */
int guard_fail(guard_instance *g, const char *format, ...) __attribute__((format(printf, 2, 3)));
/* A status of the Python side as the host gets it: an error puts the instance into its Error state. */
int guard_settle(guard_instance *g, int status);

#endif
