/* FMU states, for both FMI versions (see guard.h): the Python side's state with the instance's FMI state
 * and time, so that setting a state also restores where the next doStep starts.
 *
 * A state belongs to the instance that made it (or deserialised it): another instance may not set,
 * serialise or free it.  Its serialized form is a header (this FMU's token, the interface it was made
 * for, the FMI state and time) and the Python side's bytes (JSON), and deserialising checks all of it:
 * the header here, the bytes on the Python side (fmu_src/fmi_bridge.py), before anything is changed.
 *
 * A call of the Python side may run the host's logger, and the logger may free the state the call uses
 * (fmi2FreeFMUstate from the callback). A state is therefore held for the call (hold) and looked at again only
 * through let_go, which frees a state the host freed meanwhile and says so: no state is read after it was
 * freed. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bridge.h"
#include "fmu_state.h"
#include "platform.h"
#include "pointer_set.h"
#include "text.h"

#define STATE_MAGIC "DPFMUST2"

static pointer_set fmu_states = POINTER_SET_INIT; /* its lock also guards the instances' lists of states */

typedef struct {
    char magic[8];
    char token[64];     /* the FMU's GUID / instantiation token */
    char interface[16]; /* "CoSimulation", "ModelExchange" */
    int32_t state, wants_to_terminate;
    double time, last_successful_time;
    uint64_t payload_size; /* the Python side's bytes that follow */
} state_header;

/* The state `s` if it is a live state of g; else NULL, logged. */
static guard_state *known(guard_instance *g, void *s) {
    if (!s) return guard_fail(g, "%s: the FMU state is NULL", g->function), NULL;
    char owner[256] = "";
    platform_lock(&fmu_states.lock);
    int live = pointer_set_has_locked(&fmu_states, s);
    int foreign = live && ((guard_state *)s)->owner != g;
    if (foreign) text_format(owner, sizeof owner, "%s", ((guard_state *)s)->owner->name);
    platform_unlock(&fmu_states.lock);
    if (!live)
        return guard_fail(g, "%s: FMU state %p is not a live state of this FMU (freed, or from another FMU)",
                          g->function, s), NULL;
    if (foreign)
        return guard_fail(g, "%s: FMU state %p belongs to instance \"%s\", not to this one (\"%s\"): a state is "
                          "used by the instance that made it", g->function, s, owner, g->name), NULL;
    return s;
}

static guard_state *new_state(guard_instance *g, PyObject *python, guard_position at) {
    guard_state *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    *s = (guard_state){g, python, at, NULL, 0, NULL, g->states, 0, 0};
    platform_lock(&fmu_states.lock);
    int added = pointer_set_add_locked(&fmu_states, s);
    if (added) {
        if (g->states) g->states->previous = s;
        g->states = s;
    }
    platform_unlock(&fmu_states.lock);
    if (!added) free(s);
    return added ? s : NULL;
}

/* Give s a new Python state (the old one released, its serialized form dropped). */
static void replace_python(guard_instance *g, guard_state *s, PyObject *python, guard_position at) {
    bridge_release(g, s->python);
    free(s->serialized);
    s->python = python, s->at = at, s->serialized = NULL, s->serialized_size = 0;
}

/* Hold s (NULL: nothing) for a call of the Python side that may run the host's logger. */
static void hold(guard_state *s) {
    if (!s) return;
    platform_lock(&fmu_states.lock);
    s->busy++;
    platform_unlock(&fmu_states.lock);
}

/* End the hold of s after the call: 1 if s is still the host's, 0 (logged) if the host freed it during the
 * call, which frees it now. */
static int let_go(guard_instance *g, guard_state *s) {
    if (!s) return 1;
    platform_lock(&fmu_states.lock);
    int freed = --s->busy == 0 && s->doomed;
    int doomed = s->doomed;
    platform_unlock(&fmu_states.lock);
    if (freed) {
        replace_python(g, s, NULL, s->at);
        free(s);
    }
    if (doomed)
        guard_fail(g, "%s: the FMU state was freed (by the host's logger) during this call, which used it",
                   g->function);
    return !doomed;
}

/* Into `s` (NULL: a new state; else a live one of g, held for the call that made `python`, overwritten) the
 * Python state `python`, through the host's *FMUstate. */
static int deliver(guard_instance *g, void **FMUstate, guard_state *s, PyObject *python, guard_position at) {
    if (!let_go(g, s)) {
        bridge_release(g, python);
        return STATUS_ERROR;
    }
    if (s) {
        replace_python(g, s, python, at);
        return STATUS_OK;
    }
    if (!(s = new_state(g, python, at))) {
        bridge_release(g, python);
        return guard_fail(g, "%s: out of memory", g->function);
    }
    *FMUstate = s;
    return STATUS_OK;
}

int guard_get_state(guard_instance *g, void **FMUstate) {
    if (!FMUstate) return guard_fail(g, "%s: %s is NULL", g->function, g->version->state_word);
    guard_state *s = *FMUstate;
    if (s && !known(g, s)) return STATUS_ERROR;
    PyObject *python = NULL;
    bridge_payload payload = {PAYLOAD_OBJECT, NULL, 0, NULL, NULL, &python};
    hold(s);
    int status = guard_settle(g, bridge_call(g, payload, "get_fmu_state", "()"));
    if (status > STATUS_WARNING) return let_go(g, s), status;
    return deliver(g, FMUstate, s, python, g->at);
}

int guard_set_state(guard_instance *g, void *FMUstate) {
    guard_state *s = known(g, FMUstate);
    if (!s) return STATUS_ERROR;
    guard_position at = s->at; /* read before the call: the host's logger may free s during it */
    int status = guard_settle(g, bridge_call(g, NO_PAYLOAD, "set_fmu_state", "(O)", s->python));
    if (status <= STATUS_WARNING) g->at = at;
    return status;
}

int guard_free_state(guard_instance *g, void **FMUstate) {
    if (!FMUstate) return guard_fail(g, "%s: %s is NULL", g->function, g->version->state_word);
    if (!*FMUstate) return STATUS_OK; /* nothing to free */
    guard_state *s = known(g, *FMUstate);
    if (!s) return STATUS_ERROR;
    platform_lock(&fmu_states.lock);
    pointer_set_remove_locked(&fmu_states, s);
    if (s->previous) s->previous->next = s->next;
    else g->states = s->next;
    if (s->next) s->next->previous = s->previous;
    int busy = s->busy;
    if (busy) s->doomed = 1, s->previous = s->next = NULL; /* a call in progress uses it: let_go frees it */
    platform_unlock(&fmu_states.lock);
    *FMUstate = NULL;
    if (busy) return STATUS_OK;
    replace_python(g, s, NULL, s->at);
    free(s);
    return STATUS_OK;
}

/* The Python side's bytes of s, made once. */
static int serialized(guard_instance *g, guard_state *s) {
    if (s->serialized) return STATUS_OK;
    bridge_payload payload = {PAYLOAD_COPY, NULL, 0, &s->serialized, &s->serialized_size, NULL};
    return guard_settle(g, bridge_call(g, payload, "serialize_fmu_state", "(O)", s->python));
}

/* serialized(g, s) with s held for the call: STATUS_ERROR (logged) if the host freed s during it. */
static int serialized_held(guard_instance *g, guard_state *s) {
    hold(s);
    int status = serialized(g, s);
    return let_go(g, s) ? status : STATUS_ERROR;
}

int guard_serialized_size(guard_instance *g, void *FMUstate, size_t *size) {
    if (!size) return guard_fail(g, "%s: size is NULL", g->function);
    guard_state *s = known(g, FMUstate);
    if (!s) return STATUS_ERROR;
    int status = serialized_held(g, s);
    if (status <= STATUS_WARNING) *size = sizeof(state_header) + s->serialized_size;
    return status;
}

int guard_serialize_state(guard_instance *g, void *FMUstate, unsigned char *bytes, size_t size) {
    if (!bytes) return guard_fail(g, "%s: serializedState is NULL", g->function);
    guard_state *s = known(g, FMUstate);
    if (!s) return STATUS_ERROR;
    int status = serialized_held(g, s);
    if (status > STATUS_WARNING) return status;
    size_t needed = sizeof(state_header) + s->serialized_size;
    if (size != needed)
        return guard_fail(g, "%s: size = %zu, but %sSerialized%sSize gives %zu", g->function, size,
                          g->version->prefix, g->version->state_word, needed);
    state_header header;
    memset(&header, 0, sizeof header);
    memcpy(header.magic, STATE_MAGIC, sizeof header.magic);
    text_format(header.token, sizeof header.token, "%s", g->version->token);
    text_format(header.interface, sizeof header.interface, "%s", g->interface);
    header.state = s->at.state, header.wants_to_terminate = s->at.wants_to_terminate;
    header.time = s->at.time, header.last_successful_time = s->at.last_successful_time;
    header.payload_size = s->serialized_size;
    memcpy(bytes, &header, sizeof header);
    memcpy(bytes + sizeof header, s->serialized, s->serialized_size);
    return STATUS_OK;
}

int guard_deserialize_state(guard_instance *g, const unsigned char *bytes, size_t size, void **FMUstate) {
    const guard_version *v = g->version;
    if (!bytes) return guard_fail(g, "%s: serializedState is NULL", g->function);
    if (!FMUstate) return guard_fail(g, "%s: %s is NULL", g->function, v->state_word);
    guard_state *s = *FMUstate;
    if (s && !known(g, s)) return STATUS_ERROR;
    state_header header;
    if (size < sizeof header || memcmp(bytes, STATE_MAGIC, sizeof header.magic) != 0)
        return guard_fail(g, "%s: the %zu bytes are not a serialized state of this FMU (no header)", g->function, size);
    memcpy(&header, bytes, sizeof header);
    header.token[sizeof header.token - 1] = header.interface[sizeof header.interface - 1] = '\0';
    if (strcmp(header.token, v->token) != 0)
        return guard_fail(g, "%s: the bytes are a state of another FMU or build (token %s, this FMU's is %s)",
                          g->function, header.token, v->token);
    if (strcmp(header.interface, g->interface) != 0)
        return guard_fail(g, "%s: the bytes are a %s state; this instance is %s", g->function, header.interface,
                          g->interface);
    if (!(header.state & v->any_state) || (header.state & (header.state - 1)) || !isfinite(header.time) ||
        !isfinite(header.last_successful_time) || header.last_successful_time > header.time ||
        (header.wants_to_terminate & ~1))
        return guard_fail(g, "%s: the state is malformed: its header holds FMI state %d at t = %.17g s (last "
                          "successful time %.17g s)", g->function, (int)header.state, header.time,
                          header.last_successful_time);
    if (header.payload_size != size - sizeof header)
        return guard_fail(g, "%s: the state is malformed: %zu bytes, but its header counts %llu", g->function, size,
                          (unsigned long long)(sizeof header + header.payload_size));
    if (!v->state_allowed(g->interface, header.state))
        return guard_fail(g, "%s: the state is malformed: %s is not a state of %s", g->function,
                          v->state_name(header.state), g->interface);
    PyObject *python = NULL;
    bridge_payload payload = {PAYLOAD_OBJECT, NULL, 0, NULL, NULL, &python};
    hold(s);
    int status = guard_settle(g, bridge_call(g, payload, "deserialize_fmu_state", "(y#d)",
                                             (const char *)bytes + sizeof header, (ssize_t)header.payload_size,
                                             header.time));
    if (status > STATUS_WARNING) return let_go(g, s), status;
    guard_position at = {header.state, header.time, header.last_successful_time, header.wants_to_terminate};
    return deliver(g, FMUstate, s, python, at);
}

void fmu_state_fork_prepare(void) { platform_lock(&fmu_states.lock); }

void fmu_state_fork_after(void) { platform_unlock(&fmu_states.lock); }
