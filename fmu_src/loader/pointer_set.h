/* Sets of live pointers: the instances and FMU states this binary handed out. A pointer the host passes is
 * looked up here before it is used. */
#ifndef POINTER_SET_H
#define POINTER_SET_H

#include <stddef.h>

#include "platform.h"

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
/* Call `visit` with every pointer in the set. */
void pointer_set_each_locked(pointer_set *set, void (*visit)(void *pointer));

#endif
