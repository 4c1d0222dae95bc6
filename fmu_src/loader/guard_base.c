/* An instance's log, for every layer that has an instance (see guard_base.h): the log categories, emitting a
 * message to the host's logger, failing with one, and a status as the host gets it. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include "guard_base.h"

#include <stdarg.h>
#include <string.h>

#include "text.h"

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
        text_format(why, size, "categories is NULL with nCategories = %zu", n);
        return 0;
    }
    int bits = 0;
    for (size_t k = 0; k < n; k++) {
        int bit = guard_category_bit(categories[k]);
        if (!categories[k]) {
            text_format(why, size, "categories[%zu] is NULL", k);
            return 0;
        }
        if (!bit) {
            text_format(why, size, "unknown log category \"%.200s\" (this FMU's: %s)", categories[k], CATEGORY_NAMES);
            return 0;
        }
        bits |= bit;
    }
    *mask = on ? (*mask | bits) : (*mask & ~bits);
    return 1;
}

/* ----------------------------------------------------------------------------- the log */

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
    text_vformat(message, sizeof message, format, args);
    va_end(args);
    guard_emit(g, STATUS_ERROR, "logStatusError", message);
    g->at.state = g->version->error_state;
    return STATUS_ERROR;
}

int guard_settle(guard_instance *g, int status) {
    if (status >= STATUS_ERROR) {
        g->at.state = g->version->error_state;
        return STATUS_ERROR;
    }
    return status;
}
