/* What the FMI 2 and FMI 3 guards (fmi2_guard.c, fmi3_guard.c) share.
 *
 * Each guard stands in front of the FMI library's binary (pythonfmu's, pythonfmu3's) and gives the
 * host the standard's behaviour whatever the Python side does (docs/fmu.md, "How the FMU answers a
 * master"): a per-instance state machine from the standard's tables, argument checks, instantiation
 * checks, a logger only ever called with the message as data, statuses that say what is lost.  This
 * file holds the pieces both need: sets of live pointers (an instance or an FMU state the host
 * passes is looked up before it is used), the lock that serialises what must be serialised across
 * threads (imports and the host hygiene of instantiation), log categories, the library's error
 * messages in words, and path checks. */
#ifndef GUARD_H
#define GUARD_H

#include <pthread.h>
#include <stddef.h>

/* ------------------------------------------------------------------------- live pointers */

/* A set of pointers (an open-addressing hash set under a mutex), for the instances and FMU states
 * this binary handed out: a pointer the host passes is dereferenced only if it is in the set. */
typedef struct {
    pthread_mutex_t lock;
    void **slots;
    size_t capacity, count, used; /* used: live entries and tombstones */
} pointer_set;

#define POINTER_SET_INIT {PTHREAD_MUTEX_INITIALIZER, NULL, 0, 0, 0}

int pointer_set_add(pointer_set *set, void *pointer);    /* 0 if out of memory */
int pointer_set_remove(pointer_set *set, void *pointer); /* 1 if it was in the set */
int pointer_set_has(pointer_set *set, void *pointer);

/* ------------------------------------------------------------------------------- instances */

/* FMI 2 and FMI 3 number their statuses alike: OK 0, Warning 1, Discard 2, Error 3, Fatal 4. */
enum { STATUS_OK = 0, STATUS_WARNING = 1, STATUS_DISCARD = 2, STATUS_ERROR = 3, STATUS_FATAL = 4 };

typedef struct guard_instance guard_instance;
typedef struct guard_state guard_state;

/* Where an instance is: what an FMU state restores besides the FMI library's own state. */
typedef struct {
    int state;                   /* one bit of the FMI version's states */
    double time;                 /* the FMU's time: where the next doStep starts [s] */
    double last_successful_time; /* the end of the last step that succeeded [s] */
    int wants_to_terminate;      /* a step was discarded: the FMU cannot go on from there */
} guard_position;

/* What every guarded instance has, first in the FMI version's own struct. */
struct guard_instance {
    guard_position at;
    int error_state;      /* the FMI version's Error state (its bit) */
    int categories;       /* the log categories that reach the host's logger */
    const char *function; /* the FMI function being run, for the library's messages */
    char *name;
    guard_state *states;  /* the FMU states it made */
    /* give one message to the host's logger, or stderr if it has none */
    void (*log)(guard_instance *g, int status, const char *category, const char *message);
};

/* Register a new instance (0 if out of memory) / forget it (1 if it was live). */
int guard_register(guard_instance *g);
int guard_unregister(guard_instance *g);
/* The live instance `c` for the FMI function `function`, or NULL (one line on stderr: no logger). */
guard_instance *guard_lookup(void *c, const char *model_identifier, const char *function);

/* Give `message` to the host's logger if its category is on (the status's category if NULL). */
void guard_emit(guard_instance *g, int status, const char *category, const char *message);
/* Log an error, put the instance into its Error state, return STATUS_ERROR. */
int guard_fail(guard_instance *g, const char *format, ...) __attribute__((format(printf, 2, 3)));
/* The FMI library's status as the host gets it: Fatal, for a Python exception, is an error of this
 * instance only, which a reset recovers; an error puts the instance into its Error state. */
int guard_settle(guard_instance *g, int status);
/* A message of the FMI library (its text, never a format), with its Fatal made an Error. */
void guard_library_message_logged(guard_instance *g, int status, const char *category, const char *message);
/* fmiXSetDebugLogging as specified; STATUS_OK or a failure. */
int guard_set_debug_logging(guard_instance *g, int on, size_t n, const char *const categories[],
                            const char *function);
/* One line on stderr for a call that has no instance to log through. */
void guard_orphan(const char *model_identifier, const char *function, const char *format, ...)
    __attribute__((format(printf, 3, 4)));

/* ------------------------------------------------------------------------------ FMU states */

/* An FMU state as the host holds it: the library's state and the instance's position. */
struct guard_state {
    guard_instance *owner; /* the instance that made it, which frees it if the host does not */
    void *backend;
    guard_position at;
    guard_state *previous, *next; /* the owner's states */
};

/* The state `s`, if it is a live state of this FMU; else NULL and an error on g. */
guard_state *guard_state_known(guard_instance *g, void *s, const char *function);
/* A new live state of g; NULL if out of memory. */
guard_state *guard_state_new(guard_instance *g, void *backend, guard_position at);
/* Forget state s (the caller frees its library state, then s). */
void guard_state_forget(guard_state *s);

/* A serialized FMU state: this header, then the library's bytes. */
typedef struct {
    char magic[8];
    char token[64]; /* the FMU's GUID / instantiation token */
    int state, wants_to_terminate;
    double time, last_successful_time;
} guard_state_header;

void guard_header_write(guard_state_header *header, const char *magic, const char *token, guard_position at);
/* 1 if `header` is one this FMU wrote (magic, token, a single valid state bit within `states`). */
int guard_header_read(const guard_state_header *header, const char *magic, const char *token, int states,
                      guard_position *at);

/* --------------------------------------------------------------------------------- threads */

/* Lock `lock`, which guards Python work (instantiation and reset import modules and edit sys.path).
 * A thread that holds the GIL (a host that calls the FMU from Python without releasing it) releases
 * it while it waits, so that the thread holding `lock` can take the GIL and finish. */
void guard_lock_python(pthread_mutex_t *lock);

/* ---------------------------------------------------------------------------- messages */

/* The log categories of the FMUs' modelDescription (pythonfmu's and pythonfmu3's), as bits. */
enum {
    CATEGORY_ALL = 1 << 0,     /* logAll: messages with status OK */
    CATEGORY_WARNING = 1 << 1, /* logStatusWarning */
    CATEGORY_DISCARD = 1 << 2, /* logStatusDiscard */
    CATEGORY_ERROR = 1 << 3,   /* logStatusError */
    CATEGORY_FATAL = 1 << 4,   /* logStatusFatal */
};
#define CATEGORIES_EVERY (CATEGORY_ALL | CATEGORY_WARNING | CATEGORY_DISCARD | CATEGORY_ERROR | CATEGORY_FATAL)
#define CATEGORIES_ERRORS (CATEGORY_ERROR | CATEGORY_FATAL) /* logged from instantiation on */
#define CATEGORY_NAMES "logAll, logStatusWarning, logStatusDiscard, logStatusError, logStatusFatal"

/* The bit of category `name`, 0 if it is not one of this FMU's. */
int guard_category_bit(const char *name);
/* The category of a message with FMI status `status` (0 OK ... 4 Fatal, as in FMI 2 and FMI 3). */
const char *guard_category_of(int status);
int guard_category_bit_of(int status);

/* Parse fmi2/fmi3SetDebugLogging's categories into `mask` (`on` sets, else clears, their bits;
 * none named: all of them).  Returns 0 and writes why to `why` if an argument is wrong. */
int guard_debug_categories(int *mask, int on, size_t n, const char *const categories[], char *why, size_t size);

/* The FMI library's message for a Python exception ("Fatal py exception encountered: [doStep]
 * PyObject_CallMethod\nValueError('...')") in words: "ValueError: ...".  Other messages are copied. */
void guard_library_message(const char *message, char *out, size_t size);

/* Like snprintf, never fails: a message cut at `size` ends in "...". */
void guard_format(char *out, size_t size, const char *format, ...) __attribute__((format(printf, 3, 4)));

/* The offset of the first byte of `text` that is not strict UTF-8 (what CPython's decoder accepts: no
 * overlong forms, no surrogates, nothing above U+10FFFF), or -1 if all of it is.  FMI strings are UTF-8 (fmi2TypesPlatform.h,
 * fmi3PlatformTypes.h); pythonfmu's libraries decode them as such, and a name that does not decode crashed
 * the host (the instance name) or reached Python with its exception pending (a String value). */
long guard_utf8_error(const char *text);

/* ------------------------------------------------------------------------------- paths */

int guard_is_directory(const char *path);
int guard_is_file(const char *path); /* a readable file that is not a folder */
/* A file URI (file:///p, file://localhost/p, file:/p), %XX decoded, or a plain path, to a path
 * without a trailing slash.  Returns 0 for a URI of another scheme or host. */
int guard_uri_to_path(const char *uri, char *path, size_t size);

#endif
