/* What the FMI 2 and FMI 3 guards share (see guard.h). */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include "guard.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ------------------------------------------------------------------------- live pointers */

#define TOMBSTONE ((void *)1)

static size_t slot_of(const void *pointer, size_t capacity) {
    uint64_t x = (uint64_t)(uintptr_t)pointer;
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    return (size_t)x & (capacity - 1);
}

/* Rebuild with room for twice the live entries (at least 16 slots), dropping the tombstones. */
static int rehash(pointer_set *set) {
    size_t capacity = 16;
    while (capacity < 4 * (set->count + 1)) capacity *= 2;
    void **slots = calloc(capacity, sizeof *slots);
    if (!slots) return 0;
    for (size_t k = 0; k < set->capacity; k++) {
        void *p = set->slots[k];
        if (!p || p == TOMBSTONE) continue;
        size_t at = slot_of(p, capacity);
        while (slots[at]) at = (at + 1) & (capacity - 1);
        slots[at] = p;
    }
    free(set->slots);
    set->slots = slots;
    set->capacity = capacity;
    set->used = set->count;
    return 1;
}

int pointer_set_add(pointer_set *set, void *pointer) {
    pthread_mutex_lock(&set->lock);
    int ok = 1;
    if (2 * (set->used + 1) > set->capacity) ok = rehash(set);
    if (ok) {
        size_t at = slot_of(pointer, set->capacity);
        while (set->slots[at] && set->slots[at] != TOMBSTONE) at = (at + 1) & (set->capacity - 1);
        if (!set->slots[at]) set->used++;
        set->slots[at] = pointer;
        set->count++;
    }
    pthread_mutex_unlock(&set->lock);
    return ok;
}

/* The slot holding `pointer`, or NULL (called with the lock held). */
static void **find(pointer_set *set, const void *pointer) {
    if (!set->capacity || !pointer || pointer == TOMBSTONE) return NULL;
    for (size_t at = slot_of(pointer, set->capacity);; at = (at + 1) & (set->capacity - 1)) {
        if (!set->slots[at]) return NULL;
        if (set->slots[at] == pointer) return &set->slots[at];
    }
}

int pointer_set_remove(pointer_set *set, void *pointer) {
    pthread_mutex_lock(&set->lock);
    void **slot = find(set, pointer);
    if (slot) {
        *slot = TOMBSTONE;
        set->count--;
        if (set->count == 0) { /* empty: start afresh, so tombstones never pile up */
            memset(set->slots, 0, set->capacity * sizeof *set->slots);
            set->used = 0;
        }
    }
    pthread_mutex_unlock(&set->lock);
    return slot != NULL;
}

int pointer_set_has(pointer_set *set, void *pointer) {
    pthread_mutex_lock(&set->lock);
    int found = find(set, pointer) != NULL;
    pthread_mutex_unlock(&set->lock);
    return found;
}

/* ------------------------------------------------------------------------------- instances */

static pointer_set instances = POINTER_SET_INIT;
static pointer_set fmu_states = POINTER_SET_INIT;
static pthread_mutex_t states_lock = PTHREAD_MUTEX_INITIALIZER; /* the instances' lists of states */

int guard_register(guard_instance *g) { return pointer_set_add(&instances, g); }
int guard_unregister(guard_instance *g) { return pointer_set_remove(&instances, g); }

void guard_orphan(const char *model_identifier, const char *function, const char *format, ...) {
    char message[2048];
    va_list args;
    va_start(args, format);
    int n = vsnprintf(message, sizeof message, format, args);
    va_end(args);
    if (n < 0) message[0] = '\0';
    fprintf(stderr, "[%s] %s: %s\n", model_identifier, function, message);
    fflush(stderr);
}

guard_instance *guard_lookup(void *c, const char *model_identifier, const char *function) {
    if (!c) {
        guard_orphan(model_identifier, function, "the instance is NULL");
        return NULL;
    }
    if (!pointer_set_has(&instances, c)) {
        guard_orphan(model_identifier, function,
                     "%p is not a live instance of this FMU (freed, or never instantiated here)", c);
        return NULL;
    }
    return (guard_instance *)c;
}

void guard_emit(guard_instance *g, int status, const char *category, const char *message) {
    int bit = guard_category_bit(category);
    if (!bit) {
        bit = guard_category_bit_of(status);
        category = guard_category_of(status);
    }
    if (g->categories & bit) g->log(g, status, category, message);
}

int guard_fail(guard_instance *g, const char *format, ...) {
    char message[2048];
    va_list args;
    va_start(args, format);
    int n = vsnprintf(message, sizeof message, format, args);
    va_end(args);
    if (n < 0) message[0] = '\0';
    guard_emit(g, STATUS_ERROR, "logStatusError", message);
    g->at.state = g->error_state;
    return STATUS_ERROR;
}

int guard_settle(guard_instance *g, int status) {
    if (status >= STATUS_ERROR) {
        g->at.state = g->error_state;
        return STATUS_ERROR;
    }
    return status;
}

void guard_library_message_logged(guard_instance *g, int status, const char *category, const char *message) {
    char text[2048], line[2200];
    guard_library_message(message, text, sizeof text);
    if (status == STATUS_FATAL) status = STATUS_ERROR;
    if (!category || !category[0] || strcmp(category, "logStatusFatal") == 0) category = guard_category_of(status);
    if (status >= STATUS_ERROR) {
        guard_format(line, sizeof line, "%s: %s", g->function ? g->function : "FMU", text);
        guard_emit(g, status, category, line);
    } else {
        guard_emit(g, status, category, text);
    }
}

int guard_set_debug_logging(guard_instance *g, int on, size_t n, const char *const categories[],
                            const char *function) {
    char why[512];
    int mask = g->categories;
    if (!guard_debug_categories(&mask, on, n, categories, why, sizeof why)) {
        g->categories |= CATEGORIES_ERRORS; /* so that this error is seen */
        return guard_fail(g, "%s: %s", function, why);
    }
    g->categories = mask;
    return STATUS_OK;
}

/* ------------------------------------------------------------------------------ FMU states */

guard_state *guard_state_known(guard_instance *g, void *s, const char *function) {
    if (!s) {
        guard_fail(g, "%s: the FMU state is NULL", function);
        return NULL;
    }
    if (!pointer_set_has(&fmu_states, s)) {
        guard_fail(g, "%s: FMU state %p is not a live state of this FMU (freed, or from another FMU)", function, s);
        return NULL;
    }
    return (guard_state *)s;
}

guard_state *guard_state_new(guard_instance *g, void *backend, guard_position at) {
    guard_state *s = calloc(1, sizeof *s);
    if (!s || !pointer_set_add(&fmu_states, s)) {
        free(s);
        return NULL;
    }
    *s = (guard_state){g, backend, at, NULL, NULL};
    pthread_mutex_lock(&states_lock);
    s->next = g->states;
    if (g->states) g->states->previous = s;
    g->states = s;
    pthread_mutex_unlock(&states_lock);
    return s;
}

void guard_state_forget(guard_state *s) {
    pointer_set_remove(&fmu_states, s);
    pthread_mutex_lock(&states_lock);
    if (s->previous) s->previous->next = s->next;
    else s->owner->states = s->next;
    if (s->next) s->next->previous = s->previous;
    s->previous = s->next = NULL;
    pthread_mutex_unlock(&states_lock);
}

void guard_header_write(guard_state_header *header, const char *magic, const char *token, guard_position at) {
    memset(header, 0, sizeof *header);
    memcpy(header->magic, magic, sizeof header->magic);
    snprintf(header->token, sizeof header->token, "%s", token);
    header->state = at.state;
    header->wants_to_terminate = at.wants_to_terminate;
    header->time = at.time;
    header->last_successful_time = at.last_successful_time;
}

int guard_header_read(const guard_state_header *header, const char *magic, const char *token, int states,
                      guard_position *at) {
    if (memcmp(header->magic, magic, sizeof header->magic) != 0) return 0;
    if (strncmp(header->token, token, sizeof header->token) != 0) return 0;
    if (!(header->state & states) || (header->state & (header->state - 1))) return 0;
    if (!isfinite(header->time) || !isfinite(header->last_successful_time)) return 0;
    *at = (guard_position){header->state, header->time, header->last_successful_time, header->wants_to_terminate};
    return 1;
}

/* --------------------------------------------------------------------------------- threads */

typedef int (*gil_check_fn)(void);
typedef void *(*save_thread_fn)(void);
typedef void (*restore_thread_fn)(void *);

static gil_check_fn gil_check;
static save_thread_fn save_thread;
static restore_thread_fn restore_thread;
static pthread_once_t python_functions_once = PTHREAD_ONCE_INIT;

static void resolve_python_functions(void) {
    /* The loader has made the process's CPython global (python_runtime.c) before any instance exists. */
    gil_check = (gil_check_fn)dlsym(RTLD_DEFAULT, "PyGILState_Check");
    save_thread = (save_thread_fn)dlsym(RTLD_DEFAULT, "PyEval_SaveThread");
    restore_thread = (restore_thread_fn)dlsym(RTLD_DEFAULT, "PyEval_RestoreThread");
}

void guard_lock_python(pthread_mutex_t *lock) {
    if (pthread_mutex_trylock(lock) == 0) return;
    pthread_once(&python_functions_once, resolve_python_functions);
    if (gil_check && save_thread && restore_thread && gil_check()) {
        void *thread_state = save_thread();
        pthread_mutex_lock(lock);
        restore_thread(thread_state);
        return;
    }
    pthread_mutex_lock(lock);
}

/* ---------------------------------------------------------------------------- messages */

static const struct {
    const char *name;
    int bit;
} CATEGORIES[] = {{"logAll", CATEGORY_ALL},
                  {"logStatusWarning", CATEGORY_WARNING},
                  {"logStatusDiscard", CATEGORY_DISCARD},
                  {"logStatusError", CATEGORY_ERROR},
                  {"logStatusFatal", CATEGORY_FATAL}};
#define N_CATEGORIES (sizeof CATEGORIES / sizeof CATEGORIES[0])

int guard_category_bit(const char *name) {
    for (size_t k = 0; name && k < N_CATEGORIES; k++)
        if (strcmp(name, CATEGORIES[k].name) == 0) return CATEGORIES[k].bit;
    return 0;
}

const char *guard_category_of(int status) {
    return status >= 0 && status < (int)N_CATEGORIES ? CATEGORIES[status].name : "logStatusError";
}

int guard_category_bit_of(int status) {
    return status >= 0 && status < (int)N_CATEGORIES ? CATEGORIES[status].bit : CATEGORY_ERROR;
}

int guard_debug_categories(int *mask, int on, size_t n, const char *const categories[], char *why, size_t size) {
    if (n == 0) {
        *mask = on ? CATEGORIES_EVERY : 0;
        return 1;
    }
    if (!categories) {
        guard_format(why, size, "categories is NULL with nCategories = %zu", n);
        return 0;
    }
    int bits = 0;
    for (size_t k = 0; k < n; k++) {
        int bit = guard_category_bit(categories[k]);
        if (!categories[k]) {
            guard_format(why, size, "categories[%zu] is NULL", k);
            return 0;
        }
        if (!bit) {
            guard_format(why, size, "unknown log category \"%.200s\" (this FMU's: %s)", categories[k], CATEGORY_NAMES);
            return 0;
        }
        bits |= bit;
    }
    *mask = on ? (*mask | bits) : (*mask & ~bits);
    return 1;
}

void guard_library_message(const char *message, char *out, size_t size) {
    static const char prefix[] = "Fatal py exception encountered: ";
    if (!message) message = "";
    if (strncmp(message, prefix, sizeof prefix - 1) != 0) {
        guard_format(out, size, "%s", message);
        return;
    }
    const char *repr = strchr(message, '\n');
    repr = repr ? repr + 1 : message + sizeof prefix - 1;
    /* the repr of the exception: Name('text') or Name("text") */
    size_t n = strlen(repr);
    const char *open = strchr(repr, '(');
    if (open && n >= 4 && repr[n - 1] == ')' && (open[1] == '\'' || open[1] == '"') && repr[n - 2] == open[1] &&
        open + 2 <= repr + n - 2)
        guard_format(out, size, "%.*s: %.*s", (int)(open - repr), repr, (int)(repr + n - 2 - (open + 2)), open + 2);
    else
        guard_format(out, size, "%s", repr);
}

void guard_format(char *out, size_t size, const char *format, ...) {
    if (!size) return;
    va_list args;
    va_start(args, format);
    int n = vsnprintf(out, size, format, args);
    va_end(args);
    if (n < 0) out[0] = '\0';
    else if ((size_t)n >= size && size > 4) memcpy(out + size - 4, "...", 4);
}

long guard_utf8_error(const char *text) {
    const unsigned char *s = (const unsigned char *)text;
    for (long k = 0; s[k];) {
        unsigned char b = s[k];
        int n = b < 0x80 ? 0 : b >= 0xC2 && b <= 0xDF ? 1 : b >= 0xE0 && b <= 0xEF ? 2 : b >= 0xF0 && b <= 0xF4 ? 3 : -1;
        if (n < 0) return k;
        /* the second byte's range rules out overlong forms, surrogates and code points above U+10FFFF */
        unsigned char low = b == 0xE0 ? 0xA0 : b == 0xF0 ? 0x90 : 0x80;
        unsigned char high = b == 0xED ? 0x9F : b == 0xF4 ? 0x8F : 0xBF;
        for (int j = 1; j <= n; j++) {
            unsigned char next = s[k + j];
            if (next < (j == 1 ? low : 0x80) || next > (j == 1 ? high : 0xBF)) return k;
        }
        k += n + 1;
    }
    return -1;
}

/* ------------------------------------------------------------------------------- paths */

int guard_is_directory(const char *path) {
    int fd = open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return 0;
    close(fd);
    return 1;
}

int guard_is_file(const char *path) {
    if (access(path, R_OK) != 0) return 0;
    int fd = open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC); /* no stat: see glibc_compat.h */
    if (fd >= 0) {
        close(fd);
        return 0;
    }
    return errno == ENOTDIR;
}

int guard_uri_to_path(const char *uri, char *path, size_t size) {
    const char *p = uri;
    int is_uri = strncmp(p, "file:", 5) == 0;
    if (strncmp(p, "file://", 7) == 0) {
        p += 7;
        if (strncmp(p, "localhost/", 10) == 0) p += 9;
        else if (*p != '/') return 0; /* file://host/...: another machine */
    } else if (is_uri) {
        p += 5;
    } else if (strchr(p, ':') && strchr(p, ':') < (strchr(p, '/') ? strchr(p, '/') : p + strlen(p))) {
        return 0; /* another scheme */
    }
    size_t n = 0;
    for (; *p && n + 1 < size; p++) {
        unsigned int code;
        if (is_uri && p[0] == '%' && p[1] && p[2] && sscanf(p + 1, "%2x", &code) == 1) {
            path[n++] = (char)code;
            p += 2;
        } else {
            path[n++] = *p;
        }
    }
    path[n] = '\0';
    while (n > 1 && path[n - 1] == '/') path[--n] = '\0';
    return n > 0;
}
