/* Sets of live pointers (see guard.h): the instances and FMU states this binary handed out. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include "pointer_set.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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

int pointer_set_add_locked(pointer_set *set, void *pointer) {
    if (2 * (set->used + 1) > set->capacity && !rehash(set)) return 0;
    size_t at = slot_of(pointer, set->capacity);
    while (set->slots[at] && set->slots[at] != TOMBSTONE) at = (at + 1) & (set->capacity - 1);
    if (!set->slots[at]) set->used++;
    set->slots[at] = pointer;
    set->count++;
    return 1;
}

int pointer_set_add(pointer_set *set, void *pointer) {
    platform_lock(&set->lock);
    int ok = pointer_set_add_locked(set, pointer);
    platform_unlock(&set->lock);
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

int pointer_set_remove_locked(pointer_set *set, void *pointer) {
    void **slot = find(set, pointer);
    if (!slot) return 0;
    *slot = TOMBSTONE;
    set->count--;
    if (set->count == 0) { /* empty: start afresh, so tombstones never pile up */
        memset(set->slots, 0, set->capacity * sizeof *set->slots);
        set->used = 0;
    }
    return 1;
}

int pointer_set_has_locked(pointer_set *set, void *pointer) { return find(set, pointer) != NULL; }

int pointer_set_remove(pointer_set *set, void *pointer) {
    platform_lock(&set->lock);
    int removed = pointer_set_remove_locked(set, pointer);
    platform_unlock(&set->lock);
    return removed;
}

int pointer_set_has(pointer_set *set, void *pointer) {
    platform_lock(&set->lock);
    int found = pointer_set_has_locked(set, pointer);
    platform_unlock(&set->lock);
    return found;
}

void pointer_set_each_locked(pointer_set *set, void (*visit)(void *pointer)) {
    for (size_t k = 0; k < set->capacity; k++)
        if (set->slots[k] && set->slots[k] != TOMBSTONE) visit(set->slots[k]);
}
