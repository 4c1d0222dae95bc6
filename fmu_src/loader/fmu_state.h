/* FMU states for both FMI versions (fmu_state.c): owned by the instance that made them, serialized with a header
 * this FMU checks when it reads one back. */
#ifndef FMU_STATE_H
#define FMU_STATE_H

#include <stddef.h>

#include "guard_base.h"

/* An FMU state as the host holds it: the Python side's state and the instance's position. */
struct guard_state {
    guard_instance *owner; /* the instance that made it: the only one that may use or free it */
    PyObject *python;
    guard_position at;
    char *serialized; /* the serialized form, once asked for (its size first, then the bytes) */
    size_t serialized_size;
    guard_state *previous, *next; /* the owner's states */
    int busy;   /* calls of the Python side in progress that use it (fmu_state.c: hold, let_go) */
    int doomed; /* freed by the host (its logger) during such a call: freed when the last one ends */
};

/* The FMU-state functions of both versions (FMUstate is the host's fmiXFMUState*). */
int guard_get_state(guard_instance *g, void **FMUstate);
int guard_set_state(guard_instance *g, void *FMUstate);
int guard_free_state(guard_instance *g, void **FMUstate);
int guard_serialized_size(guard_instance *g, void *FMUstate, size_t *size);
int guard_serialize_state(guard_instance *g, void *FMUstate, unsigned char *bytes, size_t size);
int guard_deserialize_state(guard_instance *g, const unsigned char *bytes, size_t size, void **FMUstate);
/* Around a fork (guard.c): hold the states' lock in the forking thread, let go of it after, in either process. */
void fmu_state_fork_prepare(void);
void fmu_state_fork_after(void);

#endif
