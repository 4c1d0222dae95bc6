/* What the FMI 2 and FMI 3 layers share (see guard.h): instances, instantiation, logging, checks. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include "guard.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bridge.h"
#include "fmu_state.h"
#include "platform.h"
#include "pointer_set.h"
#include "python_runtime.h"
#include "text.h"

#define IDENTITY_FILE "identity.cfg" /* in resources/, written by the build: model, token, archive, entry */

/* ------------------------------------------------------------------------------- instances */

static pointer_set instances = POINTER_SET_INIT; /* its lock also guards every instance's references */

int guard_register(guard_instance *g) {
    g->references = 1; /* the host's */
    return pointer_set_add(&instances, g);
}

guard_instance *guard_acquire(void *c, const char *model_identifier, const char *function) {
    if (!c) {
        guard_orphan(model_identifier, function, "the instance is NULL");
        return NULL;
    }
    platform_lock(&instances.lock);
    int live = pointer_set_has_locked(&instances, c);
    if (live) ((guard_instance *)c)->references++;
    platform_unlock(&instances.lock);
    if (!live) {
        guard_orphan(model_identifier, function,
                     "%p is not a live instance of this FMU (freed, or never instantiated here)", c);
        return NULL;
    }
    return (guard_instance *)c;
}

void guard_deliver_interrupt(guard_instance *g) {
    if (!g->interrupted) return;
    g->interrupted = 0;
    g->api->Err_SetInterrupt(); /* async-signal-safe, no GIL needed */
}

void guard_release(guard_instance *g) {
    guard_deliver_interrupt(g);
    platform_lock(&instances.lock);
    int last = --g->references == 0;
    platform_unlock(&instances.lock);
    if (last) g->destroy(g);
}

guard_scope guard_scope_begin(guard_instance *g) {
    if (g->depth++ == 0) g->thread = platform_thread_self();
    return (guard_scope){g, g->function};
}

void guard_scope_end(guard_scope *scope) {
    guard_instance *g = scope->g;
    if (!g) return;
    g->function = scope->function;
    if (--g->depth == 0 && g->host_exception) bridge_deliver_host_exception(g);
}

void guard_release_variable(void *variable) {
    guard_instance *g = *(guard_instance **)variable;
    if (g) guard_release(g);
}

int guard_unregister(void *c) {
    platform_lock(&instances.lock);
    int live = c && pointer_set_remove_locked(&instances, c);
    platform_unlock(&instances.lock);
    if (live) guard_release(c); /* the host's reference */
    return live;
}

int guard_init_instance(guard_instance *g, const guard_version *version, const char *interface,
                        const char *name, int logging_on,
                        void (*log)(guard_instance *, int, const char *, const char *),
                        void (*destroy)(guard_instance *)) {
    g->name = strdup(name && name[0] && text_utf8_error(name) < 0 ? name : "?");
    g->at = (guard_position){version->instantiated_state, 0.0, 0.0, 0};
    g->version = version;
    g->interface = interface;
    g->categories = logging_on ? CATEGORIES_EVERY : CATEGORIES_DEFAULT;
    g->function = NULL;
    g->log = log;
    g->destroy = destroy;
    return g->name != NULL;
}

void guard_free_common(guard_instance *g) {
    while (g->states) guard_free_state(g, (void **)&(void *){g->states}); /* the ones the host did not free */
    if (g->python) bridge_call(g, NO_PAYLOAD, "release", "()"), bridge_release(g, g->python);
    if (g->python) guard_deliver_interrupt(g);
    if (g->host_exception) bridge_release(g, g->host_exception), g->host_exception = NULL; /* never delivered */
    g->python = NULL;
    free(g->name);
    free(g->strings);
    g->name = g->strings = NULL;
}

/* ------------------------------------------------------------------------------------ fork */

/* A host may fork() while another thread is inside an FMU call (docs/fmu.md, "Threads and fork").  Around every
 * fork, this copy of the loader holds its locks and, where it started the process's Python, that Python's GIL
 * (python_runtime_fork_prepare), so that the child finds none of them held by a thread it does not have.  In the
 * child, an instance another thread was inside is in its Error state: its call never ends there, and what the
 * Python side had done of it is unknown; its calls say so (guard_refuse_state), and it can be freed. */
static void mark_forked(void *pointer) {
    guard_instance *g = pointer;
    if (g->depth == 0 || g->thread == platform_thread_self()) return; /* idle, or the forking thread's own */
    g->forked_inside = g->function ? g->function : "an FMI function";
    g->at.state = g->version->error_state;
    g->references -= g->depth; /* the calls that will not return; the host's reference stays */
    g->depth = 0;
}

static void fork_prepare(void) {
    python_runtime_fork_prepare(); /* the GIL first: a call takes it with none of these locks held */
    platform_lock(&instances.lock);
    fmu_state_fork_prepare();
}

static void fork_parent(void) {
    fmu_state_fork_after();
    platform_unlock(&instances.lock);
    python_runtime_fork_parent();
}

static void fork_child(void) {
    fmu_state_fork_after();
    pointer_set_each_locked(&instances, mark_forked);
    platform_unlock(&instances.lock);
    python_runtime_fork_child();
}

/* Registered when the library is loaded (one thread: the dynamic loader's), dropped when it is unloaded. */
__attribute__((constructor)) static void register_fork_handlers(void) {
    platform_at_fork(fork_prepare, fork_parent, fork_child);
}

int guard_refuse_state(guard_instance *g, const char *function, const char *state) {
    if (g->forked_inside)
        return guard_fail(g, "%s: this process was forked while another thread was inside %s of this instance; that "
                          "call cannot end in the child, so the instance is in the Error state: free it and "
                          "instantiate a new one", function, g->forked_inside);
    return guard_fail(g, "%s: illegal call sequence: not allowed in state %s", function, state);
}

/* ---------------------------------------------------------------------------- instantiation */

/* resources/identity.cfg: the model, token, code archive, package and entry module of the FMU whose resources
 * these are. */
typedef struct {
    char model[256], token[256], archive[256], package[256], entry[256];
} identity;

static int read_identity(const char *resources, identity *id) {
    char path[PLATFORM_PATH_MAX], line[512];
    memset(id, 0, sizeof *id);
    if (snprintf(path, sizeof path, "%s/%s", resources, IDENTITY_FILE) >= (int)sizeof path) return 0;
    FILE *file = platform_open_text(path);
    if (!file) return 0;
    while (fgets(line, sizeof line, file)) {
        line[strcspn(line, "\r\n")] = '\0';
        char *value = strchr(line, '=');
        if (!value || line[0] == '#') continue;
        *value++ = '\0';
        char *field = strcmp(line, "model") == 0 ? id->model : strcmp(line, "token") == 0 ? id->token
                      : strcmp(line, "entry") == 0 ? id->entry : strcmp(line, "package") == 0 ? id->package
                      : strcmp(line, "archive") == 0 ? id->archive : NULL;
        if (field) text_format(field, sizeof id->model, "%s", value);
    }
    fclose(file);
    return id->model[0] && id->token[0] && id->archive[0] && id->package[0] && id->entry[0];
}

int guard_check_instantiation(const guard_version *v, const char *name, const char *token, const char *location,
                              char *resources, size_t size, char *why, size_t why_size) {
    long bad;
    identity id;
    if (!name || !name[0]) text_format(why, why_size, "instanceName is %s", name ? "empty" : "NULL");
    else if ((bad = text_utf8_error(name)) >= 0)
        text_format(why, why_size, "instanceName is not UTF-8 (byte %ld is 0x%02x; an %sString is UTF-8 encoded)",
                     bad, (unsigned char)name[bad], v->prefix);
    else if (!token || strcmp(token, v->token) != 0)
        text_format(why, why_size, "%s %s%.100s%s is not this FMU's %s: the binary and its modelDescription.xml "
                     "come from different builds", v->token_name, token ? "\"" : "", token ? token : "NULL",
                     token ? "\"" : "", v->token);
    else if (!location || !location[0])
        text_format(why, why_size, "%s is %s: the FMU needs its resources folder", v->resources_name,
                     location ? "empty" : "NULL");
    else if ((bad = text_utf8_error(location)) >= 0)
        text_format(why, why_size, "%s \"%.1000s\" is not UTF-8 (byte %ld; an %sString is UTF-8 encoded)",
                     v->resources_name, location, bad, v->prefix);
    else if (!guard_uri_to_path(location, resources, size))
        text_format(why, why_size, "%s \"%.1000s\" is not a file URI or path of this machine", v->resources_name,
                     location);
    else if ((bad = text_utf8_error(resources)) >= 0)
        text_format(why, why_size, "%s \"%.1000s\": the folder's path is not UTF-8 (byte %ld), which the FMU's "
                     "Python side cannot take", v->resources_name, location, bad);
    else if (!platform_is_directory(resources))
        text_format(why, why_size, "%s \"%.1000s\": there is no folder %.1000s", v->resources_name, location,
                     resources);
    else if (!read_identity(resources, &id))
        text_format(why, why_size, "%s \"%.1000s\" is not this FMU's resources folder (no %s in %.1000s)",
                     v->resources_name, location, IDENTITY_FILE, resources);
    else if (strcmp(id.model, v->model_identifier) != 0 || strcmp(id.token, v->token) != 0)
        text_format(why, why_size, "%s \"%.1000s\" is the resources folder of another FMU (%.100s, %s %.100s), "
                     "not of %s (%s %s)", v->resources_name, location, id.model, v->token_name, id.token,
                     v->model_identifier, v->token_name, v->token);
    else
        return 1;
    return 0;
}

int guard_start_python(guard_instance *g, const char *resources, int visible) {
    char why[2048] = "";
    identity id;
    const char *chosen = NULL;
    const python_api *py = python_runtime_start(resources, why, sizeof why, &chosen);
    if (!py) return guard_fail(g, "%s: %s", g->function, why), 0;
    if (chosen) { /* with debug logging on: which Python runs the FMU, and why that one */
        char line[sizeof why + 64];
        text_format(line, sizeof line, "%s: the FMU's Python side runs in %s", g->function, chosen);
        guard_emit(g, STATUS_OK, "logAll", line);
    }
    if (!read_identity(resources, &id))
        return guard_fail(g, "%s: %s/%s cannot be read", g->function, resources, IDENTITY_FILE), 0;
    PyObject *python = NULL;
    int status = bridge_instantiate(g, py, resources, id.archive, id.package, id.entry, g->interface, visible, &python);
    if (status > STATUS_WARNING || !python) {
        if (python) bridge_release(g, python);
        guard_fail(g, "%s: the FMU's Python side could not be instantiated (the message before says why)",
                   g->function);
        bridge_deliver_host_exception(g); /* the host's own exception that stopped it, after every line */
        return 0;
    }
    g->python = python;
    return 1;
}

int guard_reset(guard_instance *g) {
    int status = guard_settle(g, bridge_call(g, NO_PAYLOAD, "reset", "()"));
    if (status <= STATUS_WARNING) g->at = (guard_position){g->version->instantiated_state, 0.0, 0.0, 0};
    return status;
}

/* ----------------------------------------------------------------------------- logging */

void guard_orphan(const char *model_identifier, const char *function, const char *format, ...) {
    char message[2048];
    va_list args;
    va_start(args, format);
    text_vformat(message, sizeof message, format, args);
    va_end(args);
    fprintf(stderr, "[%s] %s: %s\n", model_identifier, function, message);
    fflush(stderr);
}

int guard_set_debug_logging(guard_instance *g, int on, size_t n, const char *const categories[]) {
    char why[512];
    int mask = g->categories;
    if (!guard_debug_categories(&mask, on, n, categories, why, sizeof why)) {
        g->categories |= CATEGORY_ERROR; /* so that this error is seen */
        return guard_fail(g, "%s: %s", g->function, why);
    }
    g->categories = mask;
    return STATUS_OK;
}

/* ------------------------------------------------------------------------------ strings */

/* Strings cross as their UTF-8 bytes, each ended by a NUL (fmi_bridge.py: get_strings, set_strings). */
int guard_get_strings(guard_instance *g, const unsigned int vr[], size_t n, const char *values[]) {
    char *strings = NULL;
    size_t size = 0;
    bridge_payload payload = {PAYLOAD_COPY, NULL, 0, &strings, &size, NULL};
    int status = guard_settle(g, bridge_call(g, payload, "get_strings", "(y#)", (const char *)vr,
                                             (ssize_t)(n * sizeof *vr)));
    if (status > STATUS_WARNING) return status;
    size_t found = 0;
    for (size_t at = 0; at < size && found < n; found++) {
        values[found] = strings + at;
        at += strlen(strings + at) + 1;
    }
    if (found != n || (size && strings[size - 1] != '\0')) {
        free(strings);
        return guard_fail(g, "%s: the FMU's Python side gave %zu strings for %zu value references", g->function,
                          found, n);
    }
    free(g->strings); /* the values of the last call: the host may use them until now */
    g->strings = strings;
    return status;
}

int guard_set_strings(guard_instance *g, const unsigned int vr[], size_t n, const char *const values[]) {
    const guard_version *v = g->version;
    size_t size = 0;
    for (size_t k = 0; k < n; k++) {
        if (!values[k])
            return guard_fail(g, "%s: %s[%zu] (%s %u) is NULL", g->function, v->values_word, k, v->reference_word,
                              vr[k]);
        long bad = text_utf8_error(values[k]);
        if (bad >= 0)
            return guard_fail(g, "%s: %s[%zu] (%s %u) is not UTF-8 (byte %ld is 0x%02x; an %sString is UTF-8 "
                              "encoded)", g->function, v->values_word, k, v->reference_word, vr[k], bad,
                              (unsigned char)values[k][bad], v->prefix);
        size += strlen(values[k]) + 1;
    }
    char *joined = malloc(size ? size : 1), *at = joined;
    if (!joined) return guard_fail(g, "%s: out of memory", g->function);
    for (size_t k = 0; k < n; k++) {
        size_t length = strlen(values[k]) + 1;
        memcpy(at, values[k], length);
        at += length;
    }
    int status = guard_settle(g, bridge_call(g, NO_PAYLOAD, "set_strings", "(y#y#)", (const char *)vr,
                                             (ssize_t)(n * sizeof *vr), joined, (ssize_t)size));
    free(joined);
    return status;
}

int guard_check_step(guard_instance *g, double current, double step) {
    double t = g->at.time;
    if (!(isfinite(step) && step > 0))
        return guard_fail(g, "%s: communicationStepSize = %g s must be finite and > 0", g->function, step), 0;
    /* a master's own sum of the steps differs from the FMU's by rounding only: a millionth of the step,
     * and a few units in the last place of t (which grow with |t|; a skipped step never hides in them) */
    double tolerance = 1e-6 * step + 16 * (nextafter(fabs(t), INFINITY) - fabs(t));
    if (!isfinite(current) || fabs(current - t) > tolerance)
        return guard_fail(g, "%s: currentCommunicationPoint = %.17g s is not the FMU's time %.17g s (the end of the "
                          "last step, or of the FMU state set)", g->function, current, t), 0;
    return 1;
}

/* ------------------------------------------------------------------------------- paths */

static int hex_value(char c) {
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
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
    } else {
        size_t scheme = strspn(p, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789+.-");
        if (scheme >= 2 && p[scheme] == ':') return 0; /* another scheme (one letter and a colon: a drive) */
    }
    size_t n = 0;
    for (; *p; p++) {
        if (n + 1 >= size) return 0; /* too long: never a path cut short */
        if (is_uri && p[0] == '%') {
            int high = hex_value(p[1]), low = high < 0 ? -1 : hex_value(p[2]);
            if (low < 0 || (high == 0 && low == 0)) return 0; /* not two hex digits, or a NUL byte */
            path[n++] = (char)(16 * high + low);
            p += 2;
        } else {
            path[n++] = *p;
        }
    }
    path[n] = '\0';
    if (is_uri) platform_uri_path(path), n = strlen(path);
    while (n > 1 && platform_is_separator(path[n - 1])) path[--n] = '\0';
    return n > 0;
}
