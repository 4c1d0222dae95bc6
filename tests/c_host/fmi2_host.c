/* A minimal FMI 2.0 co-simulation host in C, for the tests (tests/test_c_host.py): no Python in it.
 *
 *   fmi2_host DIR IDENTIFIER GUID STEPS STEP_SIZE [ARG ...] [+ ARG ...]
 *
 * DIR is an extracted FMU; the host loads DIR/binaries/linux64/IDENTIFIER.so (on Windows
 * DIR/binaries/win64/IDENTIFIER.dll, host_common.h), instantiates it (co-simulation, logging off),
 * applies the ARGs, sets up, initialises (inputs set in initialisation mode), runs STEPS doSteps of
 * STEP_SIZE from t = 0 (inputs set before each), reads the outputs, terminates and frees the instance,
 * and unloads the library.
 * ARGs: r:VR=VALUE (Real start value), b:VR=0|1 (Boolean), s:VR=TEXT (String), i:VR=VALUE (Real
 * input set before every doStep), f:PATH (an input table, host_common.h: its inputs interpolated at each
 * communication point and set in initialisation mode and before every doStep, as the FMI Compliance
 * Checker and fmpy set an _in.csv), o:VR (Real read at the end, printed as "VR VALUE" with 17 digits),
 * O:VR (Real read at every communication point from the start, printed as "row T VALUE ..." lines).
 * For the whole run: l:1 (instantiate with loggingOn = true, so that the FMU logs every category it
 * has, not only errors) and c:N (cycles: the run above, from fmi2Instantiate to fmi2FreeInstance, N
 * times over in the one process with the library loaded once, the outputs printed after the last; after
 * the first cycle and after every 100th the line "memory-kib CYCLE KIB", the process's private memory
 * (host_common.h's memory_kib), so that a test can see it stay flat; with STEPS 1 a cycle is
 * instantiate, setup, initialise, one doStep, terminate, free).
 * A lone "+" among the ARGs makes two instances of the FMU, alive at once: the ARGs before it are the
 * first's, those after it the second's (start values, inputs, input table and outputs of its own). Both
 * are instantiated ("host1", "host2"), initialised and then stepped alternately (each doStep of the first,
 * then the same of the second); each prints its lines as one instance alone would, prefixed with
 * "instance 1 " or "instance 2 ", so that a test can compare them with two single runs.
 * Log messages go to stdout as "log STATUS CATEGORY: MESSAGE"; a failed call (status above fmi2Warning)
 * prints "CALL failed with status N" on stderr and ends the host (exit status 5). At the end the host
 * prints "startup-cpu-seconds T" (the process's CPU time from loading the library to the end of the
 * first doStep) and "host-unchanged 1" if its environment and its signal handlers (on Windows: its
 * environment, host_common.h) are as they were before it loaded the FMU, else "host-unchanged 0"; before
 * that, "pythons-loaded N": how many CPython libraries the process has loaded (host_common.h).
 * Exit status: 0 on success, 2 bad usage, 3 library not loaded, 4 instantiation failed, 5 a call failed,
 * 9 a crash on Windows (host_common.h; on Linux a crash ends the host by its signal).
 * On Windows the command line is read as UTF-16: DIR, PATH and TEXT may be any Unicode (host_common.h). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "host_common.h"

#define MAX_INSTANCES 2

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)instance;
    va_list args;
    va_start(args, message);
    printf("log %d %s: ", (int)status, category ? category : "");
    vprintf(message, args);
    printf("\n");
    va_end(args);
    fflush(stdout);
}

/* The FMU's functions, looked up once. */
static fmi2InstantiateTYPE *instantiate;
static fmi2FreeInstanceTYPE *free_instance;
static fmi2SetupExperimentTYPE *setup;
static fmi2EnterInitializationModeTYPE *enter;
static fmi2ExitInitializationModeTYPE *exit_init;
static fmi2SetRealTYPE *set_real;
static fmi2SetBooleanTYPE *set_boolean;
static fmi2SetStringTYPE *set_string;
static fmi2GetRealTYPE *get_real;
static fmi2DoStepTYPE *do_step;
static fmi2TerminateTYPE *terminate;

/* One instance of the FMU: its ARGs, and what it prints ("" alone, "instance K " beside another). */
typedef struct {
    const char *name, *prefix;
    fmi2Component c;
    host_argument starts[MAX_ARGS]; /* the r:, b: and s: ARGs, applied after every fmi2Instantiate */
    fmi2ValueReference inputs[MAX_ARGS], outputs[MAX_ARGS], recorded[MAX_ARGS];
    fmi2Real input_values[MAX_ARGS], table_values[MAX_ARGS];
    size_t n_starts, n_inputs, n_outputs, n_recorded;
    input_table table;
} instance;

static instance instances[MAX_INSTANCES]; /* input tables of 64 KiB and more: not on the stack */

/* Sort the ARGs of one instance into `in`; 0 (after saying why) if one is bad, or one too many of its
 * kind. c: and l: are the run's: `cycles` and `logging`. */
static int read_arguments(instance *in, char **args, int n, long *cycles, fmi2Boolean *logging) {
    for (int k = 0; k < n; k++) {
        host_argument a;
        if (!parse_argument(args[k], &a) || a.kind == 'j' || a.kind == 'e' || (a.kind == 'c' && a.vr == 0) ||
            in->n_starts == MAX_ARGS || in->n_inputs == MAX_ARGS || in->n_outputs == MAX_ARGS ||
            in->n_recorded == MAX_ARGS) {
            fprintf(stderr, "bad argument %s\n", args[k]);
            return 0;
        }
        if (a.kind == 'o') in->outputs[in->n_outputs++] = a.vr;
        else if (a.kind == 'O') in->recorded[in->n_recorded++] = a.vr;
        else if (a.kind == 'i') in->inputs[in->n_inputs] = a.vr, in->input_values[in->n_inputs++] = a.real;
        else if (a.kind == 'c') *cycles = (long)a.vr;
        else if (a.kind == 'l') *logging = a.vr ? fmi2True : fmi2False;
        else if (a.kind != 'f') in->starts[in->n_starts++] = a; /* r:, b:, s: */
        else if (!read_input_table(a.text, &in->table)) {
            fprintf(stderr, "cannot read the input table %s\n", a.text);
            return 0;
        }
    }
    return 1;
}

/* The input table's values at time t into the instance (nothing without a table). */
static int set_table(instance *in, double t) {
    if (in->table.n_columns) {
        interpolate_inputs(&in->table, t, in->table_values);
        CHECK(set_real(in->c, in->table.vr, in->table.n_columns, in->table_values));
    }
    return 0;
}

/* The recorded outputs at time t as a "row" line (nothing without O: arguments, or if not `printing`). */
static int record_row(instance *in, double t, int printing) {
    fmi2Real row[MAX_ARGS];
    if (!in->n_recorded || !printing) return 0;
    CHECK(get_real(in->c, in->recorded, in->n_recorded, row));
    printf("%srow %.17g", in->prefix, t);
    for (size_t r = 0; r < in->n_recorded; r++) printf(" %.17g", row[r]);
    printf("\n");
    return 0;
}

/* One run of the `n` instances together, from fmi2Instantiate to fmi2FreeInstance, each phase of it
 * instance by instance; the outputs printed if `printing`; the CPU time at the end of the first doStep
 * into `*first_step` if it is not NULL. 0, or the host's exit status. */
static int run(size_t n, const char *guid, const char *resources, fmi2Boolean logging, long steps,
               double step_size, int printing, double *first_step) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    int status;
    for (instance *in = instances; in < instances + n; in++) {
        in->c = instantiate(in->name, fmi2CoSimulation, guid, resources, &callbacks, fmi2False, logging);
        if (!in->c) {
            fprintf(stderr, "fmi2Instantiate returned NULL\n");
            return 4;
        }
        for (const host_argument *a = in->starts; a < in->starts + in->n_starts; a++) {
            fmi2ValueReference vr = a->vr;
            fmi2Boolean boolean = atoi(a->text) ? fmi2True : fmi2False;
            if (a->kind == 'r') CHECK(set_real(in->c, &vr, 1, &a->real));
            else if (a->kind == 'b') CHECK(set_boolean(in->c, &vr, 1, &boolean));
            else CHECK(set_string(in->c, &vr, 1, &a->text));
        }
    }
    for (instance *in = instances; in < instances + n; in++) {
        CHECK(setup(in->c, fmi2False, 0.0, 0.0, fmi2True, steps * step_size));
        CHECK(enter(in->c));
        if (in->n_inputs) CHECK(set_real(in->c, in->inputs, in->n_inputs, in->input_values));
        if ((status = set_table(in, 0.0))) return status;
        CHECK(exit_init(in->c));
        if ((status = record_row(in, 0.0, printing))) return status;
    }
    for (long k = 0; k < steps; k++) /* communication points k h, as fmpy's simulate_fmu steps */
        for (instance *in = instances; in < instances + n; in++) {
            if (in->n_inputs) CHECK(set_real(in->c, in->inputs, in->n_inputs, in->input_values));
            if ((status = set_table(in, k * step_size))) return status;
            CHECK(do_step(in->c, k * step_size, (k + 1) * step_size - k * step_size, fmi2True));
            if (k == 0 && first_step) *first_step = cpu_seconds();
            if ((status = record_row(in, (k + 1) * step_size, printing))) return status;
        }
    for (instance *in = instances; in < instances + n; in++) {
        fmi2Real values[MAX_ARGS];
        if (in->n_outputs) CHECK(get_real(in->c, in->outputs, in->n_outputs, values));
        for (size_t k = 0; k < in->n_outputs && printing; k++)
            printf("%s%u %.17g\n", in->prefix, in->outputs[k], values[k]);
    }
    for (instance *in = instances; in < instances + n; in++) CHECK(terminate(in->c));
    for (instance *in = instances; in < instances + n; in++) free_instance(in->c);
    return 0;
}

int main(int argc, char **argv) {
    host_start(&argc, &argv);
    if (argc < 6) {
        fprintf(stderr, "usage: %s DIR IDENTIFIER GUID STEPS STEP_SIZE [ARG ...] [+ ARG ...]\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1], *identifier = argv[2], *guid = argv[3];
    long steps = atol(argv[4]), cycles = 1;
    double step_size = atof(argv[5]);
    fmi2Boolean logging = fmi2False;
    int second = 6; /* the first ARG of the second instance, if there is one */
    while (second < argc && strcmp(argv[second], "+") != 0) second++;
    size_t n = second < argc ? 2 : 1;
    instances[0] = (instance){.name = n == 1 ? "host" : "host1", .prefix = n == 1 ? "" : "instance 1 "};
    instances[1] = (instance){.name = "host2", .prefix = "instance 2 "};
    if (!read_arguments(&instances[0], argv + 6, second - 6, &cycles, &logging) ||
        (n == 2 && !read_arguments(&instances[1], argv + second + 1, argc - second - 1, &cycles, &logging)))
        return 2;
    char path[4096], resources[4096 * 3];
    if (!fmu_locations(dir, identifier, 2, path, sizeof path, resources, sizeof resources)) return 2;

    static host_state before, after;
    snapshot(&before);
    double start = cpu_seconds(), first_step = start;
    host_library library = load_library(path);
    if (!library) return 3;
    instantiate = (fmi2InstantiateTYPE *)symbol(library, "fmi2Instantiate");
    free_instance = (fmi2FreeInstanceTYPE *)symbol(library, "fmi2FreeInstance");
    setup = (fmi2SetupExperimentTYPE *)symbol(library, "fmi2SetupExperiment");
    enter = (fmi2EnterInitializationModeTYPE *)symbol(library, "fmi2EnterInitializationMode");
    exit_init = (fmi2ExitInitializationModeTYPE *)symbol(library, "fmi2ExitInitializationMode");
    set_real = (fmi2SetRealTYPE *)symbol(library, "fmi2SetReal");
    set_boolean = (fmi2SetBooleanTYPE *)symbol(library, "fmi2SetBoolean");
    set_string = (fmi2SetStringTYPE *)symbol(library, "fmi2SetString");
    get_real = (fmi2GetRealTYPE *)symbol(library, "fmi2GetReal");
    do_step = (fmi2DoStepTYPE *)symbol(library, "fmi2DoStep");
    terminate = (fmi2TerminateTYPE *)symbol(library, "fmi2Terminate");

    for (long cycle = 1; cycle <= cycles; cycle++) {
        int status = run(n, guid, resources, logging, steps, step_size, cycle == cycles, cycle == 1 ? &first_step : NULL);
        if (status) return status;
        if (cycles > 1 && (cycle == 1 || cycle % 100 == 0)) printf("memory-kib %ld %ld\n", cycle, memory_kib());
    }
    close_library(library);
    snapshot(&after);
    printf("startup-cpu-seconds %.6f\n", first_step - start);
    printf("pythons-loaded %d\n", pythons_loaded());
    printf("host-unchanged %d\n", unchanged(&before, &after));
    return 0;
}
