/* A minimal FMI 3.0 host in C, for the tests (tests/test_fmi3_c_host.py): no Python in it.
 *
 *   fmi3_host DIR IDENTIFIER TOKEN METHOD STEPS STEP_SIZE [ARG ...] [+ ARG ...]
 *
 * DIR is an extracted FMU; the host loads DIR/binaries/x86_64-linux/IDENTIFIER.so (on Windows
 * DIR/binaries/x86_64-windows/IDENTIFIER.dll, host_common.h) and runs it from t = 0 over STEPS steps of
 * STEP_SIZE, then reads the outputs, terminates, frees the instance and unloads the library. METHOD:
 *   euler, rk4  Model Exchange, integrated by the host with explicit Euler or classical RK4, with
 *               event handling as the FMI 3.0 standard describes it (section 3.2): after every step
 *               fmi3CompletedIntegratorStep; Event Mode on its request, on a time event
 *               (nextEventTime), on a sign change of an event indicator (located to the step's end)
 *               or on an input jump (ARG j:); there fmi3UpdateDiscreteStates until it needs no
 *               further update, the states read again if it changed them; every derivative is
 *               evaluated after fmi3SetTime, the inputs and fmi3SetContinuousStates;
 *   cs          Co-Simulation: fmi3DoStep every step.
 * Like a strict host it initialises every out-argument to a value that would make it go wrong if
 * the FMU did not write it: discreteStatesNeedUpdate = true and nextEventTime = +inf in Event
 * Mode (an unwritten flag iterates until the host gives up after MAX_ITERATIONS), earlyReturn =
 * true and lastSuccessfulTime = NaN in fmi3DoStep.
 * ARGs: r:VR=VALUE (Float64 start value), b:VR=0|1 (Boolean), s:VR=TEXT (String), i:VR=VALUE (input,
 * continuous: set before every evaluation), j:VR=VALUE@T (that input jumps to VALUE at the step end
 * nearest T, in Event Mode), f:PATH (an input table, host_common.h: interpolated at each evaluation under
 * Model Exchange, at each communication point under Co-Simulation), o:VR (Float64 read at the end,
 * printed as "VR VALUE" with 17 digits), O:VR (Float64 read at every step's end from the start, printed
 * as "row T VALUE ..." lines), e:N (the O: rows at t = 0 and at every N-th step's end only: a Model
 * Exchange run of N RK4 steps per output interval prints a row per interval).
 * For the whole run: l:1 (instantiate with loggingOn = true, so that the FMU logs every category it
 * has, not only errors) and c:N (cycles: the run above, from fmi3Instantiate... to fmi3FreeInstance, N
 * times over in the one process with the library loaded once, the outputs printed after the last, the
 * counts below summed over all; after the first cycle and after every 100th the line
 * "memory-kib CYCLE KIB", the process's private memory (host_common.h's memory_kib), so that a test can
 * see it stay flat).
 * A lone "+" among the ARGs makes two instances of the FMU, alive at once: the ARGs before it are the
 * first's, those after it the second's (start values, inputs, jumps, input table and outputs of its own;
 * e:N is the run's). Both are instantiated ("host1", "host2"), initialised, and then stepped alternately
 * (each step of the first, then the same of the second; one that the FMU asked to terminate is stepped
 * no further); each prints its lines, the counts below included, as one instance alone would, prefixed
 * with "instance 1 " or "instance 2 ", so that a test can compare them with two single runs.
 * Log messages go to stdout as "log STATUS CATEGORY: MESSAGE"; a failed call (status above fmi3Warning)
 * prints "CALL failed with status N" on stderr and ends the host (exit status 5). At the end it prints
 * "events N", "event-iterations N", "derivative-evaluations N", "pythons-loaded N" (how many CPython
 * libraries the process has loaded, host_common.h) and "host-unchanged 1" if its environment
 * and signal handlers (on Windows: its environment, host_common.h) are as before it loaded the FMU.
 * Exit status: 0 on success, 2 bad usage, 3 library not loaded, 4 instantiation failed, 5 a call failed,
 * 6 an event iteration did not end, 7 the FMU asked to terminate, 9 a crash on Windows (host_common.h;
 * on Linux a crash ends the host by its signal).
 * On Windows the command line is read as UTF-16: DIR, PATH and TEXT may be any Unicode (host_common.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "host_common.h"

#define MAX_STATES 64
#define MAX_ITERATIONS 100
#define MAX_INSTANCES 2

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    printf("log %d %s: %s\n", (int)status, category ? category : "", message ? message : "");
    fflush(stdout);
}

static host_library library;

#define FUNCTION(name) name##TYPE *name = (name##TYPE *)symbol(library, #name)

static long record_every = 1; /* e:N */
static int printing = 1;      /* the O: rows and the o: outputs: in the last of the c:N cycles only */

/* One instance of the FMU: its ARGs, what it prints ("" alone, "instance K " beside another), its counts
 * and, under Model Exchange, the state of its integration. */
typedef struct {
    const char *name, *prefix;
    fmi3Instance c;
    host_argument starts[MAX_ARGS]; /* the r:, b: and s: ARGs, applied after every instantiation */
    /* inputs: continuous values (as given, and as the jumps changed them in this run), and jumps in Event Mode */
    fmi3ValueReference inputs[MAX_ARGS], jumps[MAX_ARGS], recorded[MAX_ARGS], outputs[MAX_ARGS];
    fmi3Float64 given_input_values[MAX_ARGS], input_values[MAX_ARGS], jump_values[MAX_ARGS], jump_times[MAX_ARGS];
    size_t n_starts, n_inputs, n_jumps, n_recorded, n_outputs;
    input_table table;
    fmi3Float64 table_values[MAX_ARGS];
    long events, iterations, evaluations; /* summed over the c:N cycles */
    size_t n, nz;                         /* continuous states, event indicators */
    fmi3Float64 x[MAX_STATES], z[MAX_STATES];
    int next_defined, terminated;
    double next_time;
} instance;

static instance instances[MAX_INSTANCES]; /* input tables of 64 KiB and more: not on the stack */

/* Set the input table's values at time t (nothing without a table). */
static fmi3Status set_table(instance *in, double t) {
    FUNCTION(fmi3SetFloat64);
    if (!in->table.n_columns) return fmi3OK;
    interpolate_inputs(&in->table, t, in->table_values);
    return fmi3SetFloat64(in->c, in->table.vr, in->table.n_columns, in->table_values, in->table.n_columns);
}

/* Print the recorded outputs at time t as a "row" line (nothing without O: arguments). */
static fmi3Status record_row(instance *in, double t) {
    FUNCTION(fmi3GetFloat64);
    fmi3Float64 row[MAX_ARGS];
    if (!in->n_recorded || !printing) return fmi3OK;
    fmi3Status status = fmi3GetFloat64(in->c, in->recorded, in->n_recorded, row, in->n_recorded);
    printf("%srow %.17g", in->prefix, t);
    for (size_t r = 0; r < in->n_recorded; r++) printf(" %.17g", row[r]);
    printf("\n");
    return status;
}

/* der(x) at (t, x): fmi3SetTime, inputs, fmi3SetContinuousStates, fmi3GetContinuousStateDerivatives
 * (dx NULL: only set time, inputs and states). */
static fmi3Status derivatives(instance *in, fmi3Float64 t, const fmi3Float64 x[], fmi3Float64 dx[]) {
    FUNCTION(fmi3SetTime);
    FUNCTION(fmi3SetFloat64);
    FUNCTION(fmi3SetContinuousStates);
    FUNCTION(fmi3GetContinuousStateDerivatives);
    fmi3Status status = fmi3SetTime(in->c, t);
    if (status <= fmi3Warning && in->n_inputs)
        status = fmi3SetFloat64(in->c, in->inputs, in->n_inputs, in->input_values, in->n_inputs);
    if (status <= fmi3Warning) status = set_table(in, t);
    if (status <= fmi3Warning) status = fmi3SetContinuousStates(in->c, x, in->n);
    if (status <= fmi3Warning && dx) {
        status = fmi3GetContinuousStateDerivatives(in->c, dx, in->n);
        in->evaluations++;
    }
    return status;
}

/* Event Mode at the current instant: fmi3UpdateDiscreteStates until no further update is needed (the
 * first `n` states read again if it changed them). */
static int event_iteration(instance *in, size_t n) {
    FUNCTION(fmi3UpdateDiscreteStates);
    FUNCTION(fmi3GetContinuousStates);
    for (int k = 0; k < MAX_ITERATIONS; k++) {
        fmi3Boolean need = fmi3True, terminate = fmi3False, nominals = fmi3False, values = fmi3False;
        fmi3Boolean defined = fmi3False;
        fmi3Float64 next = INFINITY;
        CHECK(fmi3UpdateDiscreteStates(in->c, &need, &terminate, &nominals, &values, &defined, &next));
        in->iterations++;
        if (values && n) CHECK(fmi3GetContinuousStates(in->c, in->x, n));
        in->next_defined = defined;
        in->next_time = next;
        if (terminate) return 7;
        if (!need) return 0;
    }
    fprintf(stderr, "the event iteration did not end after %d fmi3UpdateDiscreteStates\n", MAX_ITERATIONS);
    return 6;
}

/* Model Exchange from the end of initialisation (Event Mode) to continuous-time mode at t = 0. */
static int start_model_exchange(instance *in) {
    FUNCTION(fmi3EnterContinuousTimeMode);
    FUNCTION(fmi3GetContinuousStates);
    FUNCTION(fmi3GetNumberOfContinuousStates);
    FUNCTION(fmi3GetNumberOfEventIndicators);
    FUNCTION(fmi3GetEventIndicators);
    int status;
    in->n = in->nz = 0;
    in->next_defined = in->terminated = 0;
    in->next_time = INFINITY;
    CHECK(fmi3GetNumberOfContinuousStates(in->c, &in->n));
    CHECK(fmi3GetNumberOfEventIndicators(in->c, &in->nz));
    if (in->n > MAX_STATES || in->nz > MAX_STATES) return 5;
    /* after fmi3ExitInitializationMode the instance is in Event Mode */
    if ((status = event_iteration(in, 0))) return status;
    CHECK(fmi3EnterContinuousTimeMode(in->c));
    CHECK(fmi3GetContinuousStates(in->c, in->x, in->n));
    if (in->nz) CHECK(fmi3GetEventIndicators(in->c, in->z, in->nz));
    CHECK(record_row(in, 0.0));
    return 0;
}

/* Model Exchange step `step` (from step h to (step + 1) h), by RK4 or Euler, and the event handling at its end. */
static int step_model_exchange(instance *in, int rk4, long step, double h) {
    FUNCTION(fmi3EnterEventMode);
    FUNCTION(fmi3EnterContinuousTimeMode);
    FUNCTION(fmi3GetEventIndicators);
    FUNCTION(fmi3CompletedIntegratorStep);
    FUNCTION(fmi3SetFloat64);
    size_t n = in->n, nz = in->nz;
    fmi3Float64 *x = in->x, k1[MAX_STATES], k2[MAX_STATES], k3[MAX_STATES], k4[MAX_STATES], y[MAX_STATES];
    fmi3Float64 z_new[MAX_STATES];
    int status;
    double t = step * h, t_end = (step + 1) * h;
    CHECK(derivatives(in, t, x, k1));
    if (rk4) {
        for (size_t i = 0; i < n; i++) y[i] = x[i] + 0.5 * h * k1[i];
        CHECK(derivatives(in, t + 0.5 * h, y, k2));
        for (size_t i = 0; i < n; i++) y[i] = x[i] + 0.5 * h * k2[i];
        CHECK(derivatives(in, t + 0.5 * h, y, k3));
        for (size_t i = 0; i < n; i++) y[i] = x[i] + h * k3[i];
        CHECK(derivatives(in, t_end, y, k4));
        for (size_t i = 0; i < n; i++) x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    } else {
        for (size_t i = 0; i < n; i++) x[i] += h * k1[i];
    }
    /* the step's end: time, inputs (left limit) and states set, then the step completed */
    CHECK(derivatives(in, t_end, x, NULL));
    fmi3Boolean step_event = fmi3True, terminate = fmi3True;
    CHECK(fmi3CompletedIntegratorStep(in->c, fmi3True, &step_event, &terminate));
    if (terminate) {
        in->terminated = 1; /* stepped no further */
        return 0;
    }
    int state_event = 0;
    if (nz) {
        CHECK(fmi3GetEventIndicators(in->c, z_new, nz));
        for (size_t i = 0; i < nz; i++) state_event |= (in->z[i] > 0) != (z_new[i] > 0);
    }
    int input_event = 0;
    for (size_t k = 0; k < in->n_jumps; k++) input_event |= fabs(in->jump_times[k] - t_end) < 0.5 * h;
    int time_event = in->next_defined && in->next_time <= t_end + 1e-12 * (1.0 + fabs(t_end));
    if (step_event || state_event || input_event || time_event) {
        in->events++;
        CHECK(fmi3EnterEventMode(in->c));
        for (size_t k = 0; k < in->n_jumps; k++) /* the right limit of a jump, set in Event Mode */
            if (fabs(in->jump_times[k] - t_end) < 0.5 * h) {
                for (size_t i = 0; i < in->n_inputs; i++)
                    if (in->inputs[i] == in->jumps[k]) in->input_values[i] = in->jump_values[k];
                CHECK(fmi3SetFloat64(in->c, &in->jumps[k], 1, &in->jump_values[k], 1));
            }
        if ((status = event_iteration(in, n))) return status;
        CHECK(fmi3EnterContinuousTimeMode(in->c));
    }
    if (nz) CHECK(fmi3GetEventIndicators(in->c, in->z, nz));
    if ((step + 1) % record_every == 0) CHECK(record_row(in, t_end));
    return 0;
}

/* Co-Simulation step `step`: the inputs, fmi3DoStep from step h to (step + 1) h, which must get there. */
static int step_co_simulation(instance *in, long step, double h) {
    FUNCTION(fmi3DoStep);
    FUNCTION(fmi3SetFloat64);
    if (in->n_inputs) CHECK(fmi3SetFloat64(in->c, in->inputs, in->n_inputs, in->input_values, in->n_inputs));
    CHECK(set_table(in, step * h));
    fmi3Boolean event = fmi3True, terminate = fmi3True, early = fmi3True;
    fmi3Float64 reached = NAN;
    CHECK(fmi3DoStep(in->c, step * h, (step + 1) * h - step * h, fmi3True, &event, &terminate, &early, &reached));
    if (early || terminate || reached != (step + 1) * h) {
        fprintf(stderr, "fmi3DoStep at t = %g: earlyReturn %d, terminateSimulation %d, lastSuccessfulTime %g\n",
                step * h, (int)early, (int)terminate, reached);
        return 5;
    }
    if ((step + 1) % record_every == 0) CHECK(record_row(in, (step + 1) * h));
    return 0;
}

/* Sort the ARGs of one instance into `in`; 0 (after saying why) if one is bad, or one too many of its kind.
 * c: and l: are the run's: `cycles` and `logging`; so is e:. */
static int read_arguments(instance *in, char **args, int n, long *cycles, fmi3Boolean *logging) {
    for (int k = 0; k < n; k++) {
        host_argument a;
        if (!parse_argument(args[k], &a) || (strchr("ec", a.kind) && a.vr == 0) || in->n_starts == MAX_ARGS ||
            in->n_inputs == MAX_ARGS || in->n_jumps == MAX_ARGS || in->n_outputs == MAX_ARGS ||
            in->n_recorded == MAX_ARGS) {
            fprintf(stderr, "bad argument %s\n", args[k]);
            return 0;
        }
        if (a.kind == 'o') in->outputs[in->n_outputs++] = a.vr;
        else if (a.kind == 'O') in->recorded[in->n_recorded++] = a.vr;
        else if (a.kind == 'e') record_every = (long)a.vr;
        else if (a.kind == 'c') *cycles = (long)a.vr;
        else if (a.kind == 'l') *logging = a.vr ? fmi3True : fmi3False;
        else if (a.kind == 'i') in->inputs[in->n_inputs] = a.vr, in->given_input_values[in->n_inputs++] = a.real;
        else if (a.kind == 'j')
            in->jumps[in->n_jumps] = a.vr, in->jump_values[in->n_jumps] = a.real, in->jump_times[in->n_jumps++] = a.at;
        else if (a.kind != 'f') in->starts[in->n_starts++] = a; /* r:, b:, s: */
        else if (!read_input_table(a.text, &in->table)) {
            fprintf(stderr, "cannot read the input table %s\n", a.text);
            return 0;
        }
    }
    return 1;
}

/* One run of the `n` instances together, from instantiation to fmi3FreeInstance, each phase of it instance
 * by instance, by METHOD (`cs`, else Model Exchange by RK4 or Euler). 0, or the host's exit status. */
static int run(size_t n, int cs, int rk4, const char *token, const char *resources, fmi3Boolean logging, long steps,
               double h) {
    FUNCTION(fmi3InstantiateModelExchange);
    FUNCTION(fmi3InstantiateCoSimulation);
    FUNCTION(fmi3FreeInstance);
    FUNCTION(fmi3EnterInitializationMode);
    FUNCTION(fmi3ExitInitializationMode);
    FUNCTION(fmi3SetFloat64);
    FUNCTION(fmi3SetBoolean);
    FUNCTION(fmi3SetString);
    FUNCTION(fmi3GetFloat64);
    FUNCTION(fmi3Terminate);
    int status;
    for (instance *in = instances; in < instances + n; in++) {
        in->c = cs ? fmi3InstantiateCoSimulation(in->name, token, resources, fmi3False, logging, fmi3False, fmi3False,
                                                 NULL, 0, NULL, logger, NULL)
                   : fmi3InstantiateModelExchange(in->name, token, resources, fmi3False, logging, NULL, logger);
        if (!in->c) {
            fprintf(stderr, "fmi3Instantiate%s returned NULL\n", cs ? "CoSimulation" : "ModelExchange");
            return 4;
        }
        for (const host_argument *a = in->starts; a < in->starts + in->n_starts; a++) {
            fmi3ValueReference vr = a->vr;
            fmi3Boolean boolean = atoi(a->text) ? fmi3True : fmi3False;
            if (a->kind == 'r') CHECK(fmi3SetFloat64(in->c, &vr, 1, &a->real, 1));
            else if (a->kind == 'b') CHECK(fmi3SetBoolean(in->c, &vr, 1, &boolean, 1));
            else CHECK(fmi3SetString(in->c, &vr, 1, &a->text, 1));
        }
        memcpy(in->input_values, in->given_input_values, sizeof in->input_values); /* the last run's jumps undone */
    }
    for (instance *in = instances; in < instances + n; in++) {
        CHECK(fmi3EnterInitializationMode(in->c, fmi3False, 0.0, 0.0, fmi3True, steps * h));
        if (in->n_inputs) CHECK(fmi3SetFloat64(in->c, in->inputs, in->n_inputs, in->input_values, in->n_inputs));
        CHECK(set_table(in, 0.0));
        CHECK(fmi3ExitInitializationMode(in->c));
    }
    for (instance *in = instances; in < instances + n; in++) {
        if (cs) CHECK(record_row(in, 0.0));
        else if ((status = start_model_exchange(in))) return status;
    }
    for (long step = 0; step < steps; step++)
        for (instance *in = instances; in < instances + n; in++) {
            if (in->terminated) continue;
            if ((status = cs ? step_co_simulation(in, step, h) : step_model_exchange(in, rk4, step, h))) return status;
        }
    for (instance *in = instances; in < instances + n; in++) {
        fmi3Float64 values[MAX_ARGS];
        if (in->n_outputs) CHECK(fmi3GetFloat64(in->c, in->outputs, in->n_outputs, values, in->n_outputs));
        for (size_t k = 0; k < in->n_outputs && printing; k++)
            printf("%s%u %.17g\n", in->prefix, in->outputs[k], values[k]);
    }
    for (instance *in = instances; in < instances + n; in++) CHECK(fmi3Terminate(in->c));
    for (instance *in = instances; in < instances + n; in++) fmi3FreeInstance(in->c);
    return 0;
}

int main(int argc, char **argv) {
    host_start(&argc, &argv);
    if (argc < 7) {
        fprintf(stderr, "usage: %s DIR IDENTIFIER TOKEN euler|rk4|cs STEPS STEP_SIZE [ARG ...] [+ ARG ...]\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1], *identifier = argv[2], *token = argv[3], *method = argv[4];
    long steps = atol(argv[5]), cycles = 1;
    double h = atof(argv[6]);
    fmi3Boolean logging = fmi3False;
    int cs = strcmp(method, "cs") == 0, rk4 = strcmp(method, "rk4") == 0;
    if (!cs && !rk4 && strcmp(method, "euler") != 0) return 2;
    int second = 7; /* the first ARG of the second instance, if there is one */
    while (second < argc && strcmp(argv[second], "+") != 0) second++;
    size_t n = second < argc ? 2 : 1;
    instances[0] = (instance){.name = n == 1 ? "host" : "host1", .prefix = n == 1 ? "" : "instance 1 "};
    instances[1] = (instance){.name = "host2", .prefix = "instance 2 "};
    if (!read_arguments(&instances[0], argv + 7, second - 7, &cycles, &logging) ||
        (n == 2 && !read_arguments(&instances[1], argv + second + 1, argc - second - 1, &cycles, &logging)))
        return 2;
    char path[4096], resources[4096];
    if (!fmu_locations(dir, identifier, 3, path, sizeof path, resources, sizeof resources)) return 2;

    static host_state before, after;
    snapshot(&before);
    library = load_library(path);
    if (!library) return 3;
    for (long cycle = 1; cycle <= cycles; cycle++) {
        printing = cycle == cycles;
        int status = run(n, cs, rk4, token, resources, logging, steps, h);
        if (status) return status;
        if (cycles > 1 && (cycle == 1 || cycle % 100 == 0)) printf("memory-kib %ld %ld\n", cycle, memory_kib());
    }
    close_library(library);
    snapshot(&after);
    for (instance *in = instances; in < instances + n; in++)
        printf("%sevents %ld\n%sevent-iterations %ld\n%sderivative-evaluations %ld\n", in->prefix, in->events,
               in->prefix, in->iterations, in->prefix, in->evaluations);
    printf("pythons-loaded %d\n", pythons_loaded());
    printf("host-unchanged %d\n", unchanged(&before, &after));
    return 0;
}
