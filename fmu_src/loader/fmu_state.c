/* FMU states, for both FMI versions (see guard.h): the Python side's state with the instance's FMI state
 * and time, so that setting a state also restores where the next doStep starts.
 *
 * A state belongs to the instance that made it (or deserialised it): another instance may not set,
 * serialise or free it.  Its serialized form is a header (this FMU's token, the interface it was made
 * for, the FMI state and time) and the Python side's bytes (JSON), and deserialising checks all of it:
 * the header here, the bytes on the Python side (fmu_src/fmi_bridge.py), before anything is changed. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bridge.h"
#include "guard.h"

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
    if (foreign) guard_format(owner, sizeof owner, "%s", ((guard_state *)s)->owner->name);
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
    *s = (guard_state){g, python, at, NULL, 0, NULL, g->states};
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

/* Into *FMUstate (a new state if NULL, else a live one of g, overwritten) the Python state `python`. */
static int deliver(guard_instance *g, void **FMUstate, PyObject *python, guard_position at) {
    guard_state *s = *FMUstate;
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
    if (*FMUstate && !known(g, *FMUstate)) return STATUS_ERROR;
    PyObject *python = NULL;
    bridge_payload payload = {PAYLOAD_OBJECT, NULL, 0, NULL, NULL, &python};
    int status = guard_settle(g, bridge_call(g, payload, "get_fmu_state", "()"));
    return status > STATUS_WARNING ? status : deliver(g, FMUstate, python, g->at);
}

int guard_set_state(guard_instance *g, void *FMUstate) {
    guard_state *s = known(g, FMUstate);
    if (!s) return STATUS_ERROR;
    int status = guard_settle(g, bridge_call(g, NO_PAYLOAD, "set_fmu_state", "(O)", s->python));
    if (status <= STATUS_WARNING) g->at = s->at;
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
    platform_unlock(&fmu_states.lock);
    replace_python(g, s, NULL, s->at);
    free(s);
    *FMUstate = NULL;
    return STATUS_OK;
}

/* The Python side's bytes of s, made once. */
static int serialized(guard_instance *g, guard_state *s) {
    if (s->serialized) return STATUS_OK;
    bridge_payload payload = {PAYLOAD_COPY, NULL, 0, &s->serialized, &s->serialized_size, NULL};
    return guard_settle(g, bridge_call(g, payload, "serialize_fmu_state", "(O)", s->python));
}

int guard_serialized_size(guard_instance *g, void *FMUstate, size_t *size) {
    if (!size) return guard_fail(g, "%s: size is NULL", g->function);
    guard_state *s = known(g, FMUstate);
    if (!s) return STATUS_ERROR;
    int status = serialized(g, s);
    if (status <= STATUS_WARNING) *size = sizeof(state_header) + s->serialized_size;
    return status;
}

int guard_serialize_state(guard_instance *g, void *FMUstate, unsigned char *bytes, size_t size) {
    if (!bytes) return guard_fail(g, "%s: serializedState is NULL", g->function);
    guard_state *s = known(g, FMUstate);
    if (!s) return STATUS_ERROR;
    int status = serialized(g, s);
    if (status > STATUS_WARNING) return status;
    size_t needed = sizeof(state_header) + s->serialized_size;
    if (size != needed)
        return guard_fail(g, "%s: size = %zu, but %sSerialized%sSize gives %zu", g->function, size,
                          g->version->prefix, g->version->state_word, needed);
    state_header header;
    memset(&header, 0, sizeof header);
    memcpy(header.magic, STATE_MAGIC, sizeof header.magic);
    guard_format(header.token, sizeof header.token, "%s", g->version->token);
    guard_format(header.interface, sizeof header.interface, "%s", g->interface);
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
    if (*FMUstate && !known(g, *FMUstate)) return STATUS_ERROR;
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
        !isfinite(header.last_successful_time) || (header.wants_to_terminate & ~1))
        return guard_fail(g, "%s: the state is malformed: its header holds FMI state %d at t = %g s", g->function,
                          (int)header.state, header.time);
    if (header.payload_size != size - sizeof header)
        return guard_fail(g, "%s: the state is malformed: %zu bytes, but its header counts %llu", g->function, size,
                          (unsigned long long)(sizeof header + header.payload_size));
    if (!v->state_allowed(g->interface, header.state))
        return guard_fail(g, "%s: the state is malformed: %s is not a state of %s", g->function,
                          v->state_name(header.state), g->interface);
    PyObject *python = NULL;
    bridge_payload payload = {PAYLOAD_OBJECT, NULL, 0, NULL, NULL, &python};
    int status = guard_settle(g, bridge_call(g, payload, "deserialize_fmu_state", "(y#)",
                                             (const char *)bytes + sizeof header, (ssize_t)header.payload_size));
    if (status > STATUS_WARNING) return status;
    guard_position at = {header.state, header.time, header.last_successful_time, header.wants_to_terminate};
    return deliver(g, FMUstate, python, at);
}
