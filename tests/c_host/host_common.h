/* What the tests' C hosts (fmi2_host.c, fmi3_host.c) share: a record of the host's environment and
 * signal handlers, to show that the FMU left them as it found them; symbol lookup; the check of an
 * FMI call's status (fmi2Warning and fmi3Warning are both 1). */
#ifndef HOST_COMMON_H
#define HOST_COMMON_H

#include <dlfcn.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_ARGS 128

extern char **environ;
static const int SIGNALS[] = {SIGINT, SIGTERM, SIGPIPE, SIGCHLD, SIGXFSZ, SIGSEGV};
#define N_SIGNALS (sizeof SIGNALS / sizeof SIGNALS[0])

/* The environment and the handlers of SIGNALS, as one comparable record. */
typedef struct {
    char environment[65536];
    struct sigaction actions[N_SIGNALS];
} host_state;

static void snapshot(host_state *state) {
    memset(state, 0, sizeof *state);
    for (char **e = environ; *e; e++) {
        strncat(state->environment, *e, sizeof state->environment - strlen(state->environment) - 2);
        strcat(state->environment, "\n");
    }
    for (size_t k = 0; k < N_SIGNALS; k++) sigaction(SIGNALS[k], NULL, &state->actions[k]);
}

static int unchanged(const host_state *before, const host_state *after) {
    if (strcmp(before->environment, after->environment) != 0) return 0;
    for (size_t k = 0; k < N_SIGNALS; k++)
        if (before->actions[k].sa_handler != after->actions[k].sa_handler) return 0;
    return 1;
}

/* A function of the FMU's library; a missing one ends the host with exit status 3. */
static void *symbol(void *library, const char *name) {
    void *f = dlsym(library, name);
    if (!f) {
        fprintf(stderr, "missing %s\n", name);
        exit(3);
    }
    return f;
}

/* One argument of a host: K:VR=VALUE (K: r Float64/Real start value, b Boolean 0|1, s String, i input),
 * j:VR=VALUE@T (an input's jump at T, FMI 3 host only), o:VR (an output to print at the end), O:VR (an
 * output to print at every communication point), e:N (the O: outputs printed at every N-th step's end
 * only, FMI 3 host only; N in `vr`) or f:PATH (an input table, read_input_table). */
typedef struct {
    char kind;
    unsigned int vr;
    double real; /* VALUE as a number */
    const char *text; /* VALUE as text */
    double at;   /* T of a jump */
} host_argument;

/* Parse `text` into `a`; 0 if it is malformed. */
static int parse_argument(const char *text, host_argument *a) {
    const char *value = strchr(text, '='), *at = value ? strchr(value, '@') : NULL;
    *a = (host_argument){text[0], (unsigned int)strtoul(text + 2, NULL, 10), value ? atof(value + 1) : 0.0,
                         value ? value + 1 : "", at ? atof(at + 1) : 0.0};
    if (text[1] != ':') return 0;
    if (a->kind == 'o' || a->kind == 'O' || a->kind == 'e') return 1;
    if (a->kind == 'f') return a->text = text + 2, 1;
    return value && strchr("rbsij", a->kind) && (a->kind != 'j' || at);
}

/* An input table: a CSV file whose first line is "time,VR,VR,..." (value references) and whose rows are
 * numbers; the inputs at time t are interpolated linearly between rows, held before the first and after
 * the last (as the FMI Compliance Checker and fmpy read an _in.csv). */
#define MAX_ROWS 20000
typedef struct {
    size_t n_columns, n_rows;
    unsigned int vr[MAX_ARGS];
    double *rows; /* n_rows x (1 + n_columns): time, values */
} input_table;

/* Read `path` into `table`; 0 if it cannot be read or is malformed. */
static int read_input_table(const char *path, input_table *table) {
    FILE *file = fopen(path, "r");
    if (!file) return 0;
    char line[65536];
    memset(table, 0, sizeof *table);
    if (!fgets(line, sizeof line, file) || strncmp(line, "time", 4) != 0) return fclose(file), 0;
    for (char *field = strchr(line, ','); field && table->n_columns < MAX_ARGS; field = strchr(field + 1, ','))
        table->vr[table->n_columns++] = (unsigned int)strtoul(field + 1, NULL, 10);
    table->rows = malloc(sizeof(double) * MAX_ROWS * (1 + table->n_columns));
    while (table->rows && table->n_rows < MAX_ROWS && fgets(line, sizeof line, file)) {
        char *at = line;
        double *row = table->rows + table->n_rows * (1 + table->n_columns);
        for (size_t k = 0; k <= table->n_columns; k++) {
            char *end;
            row[k] = strtod(at, &end);
            if (end == at) return fclose(file), 0;
            at = *end == ',' ? end + 1 : end;
        }
        table->n_rows++;
    }
    fclose(file);
    return table->rows && table->n_rows > 0;
}

/* The table's values at time `t` into `values` (one per column), in fmpy's arithmetic (Input.interpolate:
 * w0 = (t1 - t) / (t1 - t0), v = w0 v0 + (1 - w0) v1). */
static void interpolate_inputs(const input_table *table, double t, double *values) {
    size_t width = 1 + table->n_columns, k = 0;
    const double *rows = table->rows;
    while (k < table->n_rows && rows[k * width] < t) k++; /* the first row at or after t */
    if (k == 0 || k == table->n_rows) {                  /* hold the first or the last row */
        const double *held = rows + (k == 0 ? 0 : table->n_rows - 1) * width;
        for (size_t c = 0; c < table->n_columns; c++) values[c] = held[1 + c];
        return;
    }
    const double *a = rows + (k - 1) * width, *b = rows + k * width;
    double w0 = (b[0] - t) / (b[0] - a[0]), w1 = 1 - w0;
    for (size_t c = 0; c < table->n_columns; c++) values[c] = w0 * a[1 + c] + w1 * b[1 + c];
}

/* Return 5 from the calling function if an FMI call fails (a status above Warning). */
#define CHECK(call)                                                                                               \
    do {                                                                                                          \
        int status_ = (int)(call);                                                                                \
        if (status_ > 1) {                                                                                        \
            fprintf(stderr, "%s failed with status %d\n", #call, status_);                                       \
            return 5;                                                                                             \
        }                                                                                                         \
    } while (0)

#endif
