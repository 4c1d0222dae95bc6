/* A torture host for the FMI 3.0 FMU, in C, for the tests (tests/test_guard.py): the calls a master may
 * get wrong, each on a fresh instance, with the status and the log lines it got. No Python in it.
 *
 *   fmi3_torture DIR IDENTIFIER TOKEN NAME=VR... MODE [ARG]
 *
 * DIR is an extracted FMU (binaries/x86_64-linux/IDENTIFIER.so), NAME=VR the value references the
 * probes use (phi1_0 phi1 l1 solver pivot_ax). MODE:
 *   probes [NAME]     run every probe (or the one named); print "probe NAME STATUS" and its log lines
 *                     "  log STATUS TEXT"
 *   threads N ROUNDS  as fmi2_torture.c, with Co-Simulation instances
 * Exit status 0 if it got to the end. */
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

#define MAX_LOGS 64
#define LOG_SIZE 512

#define FMI3_USED(X)                                                                                              \
    X(fmi3InstantiateCoSimulation) X(fmi3InstantiateModelExchange) X(fmi3InstantiateScheduledExecution)          \
    X(fmi3FreeInstance) X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode) X(fmi3Terminate)            \
    X(fmi3Reset) X(fmi3GetFloat64) X(fmi3SetFloat64) X(fmi3SetString) X(fmi3GetFloat32) X(fmi3GetClock)          \
    X(fmi3DoStep) X(fmi3UpdateDiscreteStates) X(fmi3EnterContinuousTimeMode) X(fmi3SetTime)                     \
    X(fmi3SetContinuousStates) X(fmi3GetContinuousStates) X(fmi3GetNumberOfContinuousStates)                    \
    X(fmi3CompletedIntegratorStep) X(fmi3EnterStepMode) X(fmi3GetFMUState) X(fmi3SetFMUState)                   \
    X(fmi3FreeFMUState) X(fmi3DeserializeFMUState) X(fmi3EnterConfigurationMode) X(fmi3ExitConfigurationMode)   \
    X(fmi3SetDebugLogging) X(fmi3GetDirectionalDerivative) X(fmi3EvaluateDiscreteStates)
#define DECLARE(name) static name##TYPE *name##_;
FMI3_USED(DECLARE)

static const char *token;
static char resources[4200];
static fmi3ValueReference PHI1_0, PHI1, L1, SOLVER, PIVOT_AX;

static pthread_mutex_t log_lock = PTHREAD_MUTEX_INITIALIZER;
static char logs[MAX_LOGS][LOG_SIZE];
static int log_status[MAX_LOGS], n_logs;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env, (void)category;
    pthread_mutex_lock(&log_lock);
    if (n_logs < MAX_LOGS) {
        snprintf(logs[n_logs], LOG_SIZE, "%s", message ? message : "(NULL)");
        for (char *p = logs[n_logs]; *p; p++)
            if (*p == '\n') *p = ' ';
        log_status[n_logs++] = (int)status;
    }
    pthread_mutex_unlock(&log_lock);
}

static fmi3Instance cs(void) {
    return fmi3InstantiateCoSimulation_("torture", token, resources, fmi3False, fmi3False, fmi3False, fmi3False, NULL,
                                        0, NULL, logger, NULL);
}
static fmi3Instance me(void) {
    return fmi3InstantiateModelExchange_("torture", token, resources, fmi3False, fmi3False, NULL, logger);
}
/* Co-Simulation in Step Mode at t = 0. */
static fmi3Instance stepping(void) {
    fmi3Instance c = cs();
    if (!c) return NULL;
    fmi3EnterInitializationMode_(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    fmi3ExitInitializationMode_(c);
    return c;
}
/* Model Exchange in Continuous-Time Mode at t = 0. */
static fmi3Instance continuous(void) {
    fmi3Instance c = me();
    if (!c) return NULL;
    fmi3Boolean a, b, d, e, f;
    fmi3Float64 next;
    fmi3EnterInitializationMode_(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    fmi3ExitInitializationMode_(c);
    fmi3UpdateDiscreteStates_(c, &a, &b, &d, &e, &f, &next);
    fmi3EnterContinuousTimeMode_(c);
    return c;
}
static int done(fmi3Instance c, int status) {
    fmi3FreeInstance_(c);
    return status;
}
static int instance_or_null(fmi3Instance c) { return c ? done(c, 1) : 0; }

static fmi3Boolean flag;
static fmi3Float64 when;
#define DO_STEP(c, t, h) fmi3DoStep_(c, t, h, fmi3True, &flag, &flag, &flag, &when)

#define PROBE(name, make, call)                                                                                   \
    static int name(void) {                                                                                       \
        fmi3Instance c = make;                                                                                    \
        if (!c) return -1;                                                                                        \
        return done(c, call);                                                                                     \
    }

/* the state machine */
PROBE(exit_in_instantiated, cs(), fmi3ExitInitializationMode_(c))
PROBE(exit_twice, stepping(), fmi3ExitInitializationMode_(c))
PROBE(do_step_before_initialisation, cs(), DO_STEP(c, 0.0, 0.01))
static int terminate_twice(void) {
    fmi3Instance c = stepping();
    fmi3Terminate_(c);
    return done(c, fmi3Terminate_(c));
}
static int do_step_after_terminate(void) {
    fmi3Instance c = stepping();
    fmi3Terminate_(c);
    return done(c, DO_STEP(c, 0.0, 0.01));
}
static int set_after_terminate(void) {
    fmi3Instance c = stepping();
    fmi3Terminate_(c);
    fmi3Float64 v = 0.1;
    return done(c, fmi3SetFloat64_(c, &PIVOT_AX, 1, &v, 1));
}
PROBE(enter_step_mode_without_event_mode, stepping(), fmi3EnterStepMode_(c))
PROBE(model_exchange_function_in_co_simulation, stepping(), fmi3SetTime_(c, 0.5))
PROBE(do_step_in_model_exchange, continuous(), DO_STEP(c, 0.0, 0.01))
/* doStep's arguments */
PROBE(step_size_zero, stepping(), DO_STEP(c, 0.0, 0.0))
PROBE(step_size_nan, stepping(), DO_STEP(c, 0.0, NAN))
PROBE(communication_point_not_the_fmus_time, stepping(), DO_STEP(c, 2.0, 0.01))
PROBE(do_step_null_out_argument, stepping(), fmi3DoStep_(c, 0.0, 0.01, fmi3True, NULL, &flag, &flag, &when))
/* a start time: the first doStep continues from it */
static int start_time_is_the_first_communication_point(void) {
    fmi3Instance c = cs();
    fmi3EnterInitializationMode_(c, fmi3False, 0.0, 3.0, fmi3False, 0.0);
    fmi3ExitInitializationMode_(c);
    int from_start = DO_STEP(c, 3.0, 0.01);
    return done(c, from_start == fmi3OK && when == 3.01 ? 0 : -2);
}
/* values */
static int start_value_nan(void) {
    fmi3Instance c = cs();
    fmi3Float64 v = NAN;
    return done(c, fmi3SetFloat64_(c, &PHI1_0, 1, &v, 1));
}
static int values_count_not_references_count(void) {
    fmi3Instance c = cs();
    fmi3Float64 v[2] = {1, 1};
    return done(c, fmi3SetFloat64_(c, &PHI1_0, 1, v, 2));
}
PROBE(get_float64_null_references, stepping(), fmi3GetFloat64_(c, NULL, 2, (fmi3Float64[2]){0}, 2))
PROBE(get_float64_null_values, stepping(), fmi3GetFloat64_(c, &PHI1, 1, NULL, 1))
PROBE(get_float32_not_a_type_of_this_fmu, stepping(), fmi3GetFloat32_(c, &PHI1, 1, (fmi3Float32[1]){0}, 1))
PROBE(get_clock, stepping(), fmi3GetClock_(c, &PHI1, 1, (fmi3Clock[1]){0}))
static int format_directives_in_a_string(void) {
    fmi3Instance c = cs();
    fmi3String v = "%s%s%n";
    return done(c, fmi3SetString_(c, &SOLVER, 1, &v, 1));
}
static int set_string_not_utf8(void) {
    fmi3Instance c = cs();
    fmi3String v = "dop\xe9";
    return done(c, fmi3SetString_(c, &SOLVER, 1, &v, 1));
}
static int fixed_parameter_after_initialisation(void) {
    fmi3Instance c = stepping();
    fmi3Float64 v = 0.5;
    return done(c, fmi3SetFloat64_(c, &L1, 1, &v, 1));
}
/* instantiation */
static int wrong_token(void) {
    return instance_or_null(fmi3InstantiateCoSimulation_("t", "{wrong}", resources, 0, 0, 0, 0, NULL, 0, NULL,
                                                         logger, NULL));
}
static int null_token(void) {
    return instance_or_null(fmi3InstantiateModelExchange_("t", NULL, resources, 0, 0, NULL, logger));
}
static int null_resource_path(void) {
    return instance_or_null(fmi3InstantiateModelExchange_("t", token, NULL, 0, 0, NULL, logger));
}
static int null_instance_name(void) {
    return instance_or_null(fmi3InstantiateModelExchange_(NULL, token, resources, 0, 0, NULL, logger));
}
static int instance_name_not_utf8(void) {
    return instance_or_null(fmi3InstantiateCoSimulation_("t\xff", token, resources, 0, 0, 0, 0, NULL, 0, NULL, logger,
                                                         NULL));
}
static int event_mode_requested(void) {
    return instance_or_null(fmi3InstantiateCoSimulation_("t", token, resources, 0, 0, fmi3True, 0, NULL, 0, NULL,
                                                         logger, NULL));
}
static int scheduled_execution(void) {
    return instance_or_null(
        fmi3InstantiateScheduledExecution_("t", token, resources, 0, 0, NULL, logger, NULL, NULL, NULL));
}
static int null_logger_still_instantiates(void) {
    return instance_or_null(fmi3InstantiateModelExchange_("t", token, resources, 0, 0, NULL, NULL));
}
/* Model Exchange */
static int update_discrete_states_null_out_argument(void) {
    fmi3Instance c = me();
    fmi3EnterInitializationMode_(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    fmi3ExitInitializationMode_(c);
    fmi3Boolean a;
    fmi3Float64 next;
    return done(c, fmi3UpdateDiscreteStates_(c, &a, NULL, &a, &a, &a, &next));
}
PROBE(set_continuous_states_wrong_count, continuous(), fmi3SetContinuousStates_(c, (fmi3Float64[3]){0}, 3))
PROBE(get_continuous_states_null, continuous(), fmi3GetContinuousStates_(c, NULL, 13))
PROBE(set_time_nan, continuous(), fmi3SetTime_(c, NAN))
PROBE(completed_integrator_step_null, continuous(), fmi3CompletedIntegratorStep_(c, fmi3True, NULL, NULL))
static int number_of_states(void) {
    fmi3Instance c = me();
    size_t n = 0;
    int s = fmi3GetNumberOfContinuousStates_(c, &n);
    return done(c, s == fmi3OK && n == 13 ? 0 : -2);
}
/* states, logging, what the FMU does not have */
PROBE(get_fmu_state_null, stepping(), fmi3GetFMUState_(c, NULL))
PROBE(set_fmu_state_foreign, stepping(), fmi3SetFMUState_(c, (fmi3FMUState)&log_lock))
PROBE(deserialize_garbage, stepping(), fmi3DeserializeFMUState_(c, (fmi3Byte *)"garbage bytes of no state", 25,
                                                               &(fmi3FMUState){NULL}))
PROBE(debug_logging_null_categories, stepping(), fmi3SetDebugLogging_(c, fmi3True, 1, NULL))
PROBE(configuration_mode_round_trip, cs(),
      fmi3EnterConfigurationMode_(c) == fmi3OK && fmi3ExitConfigurationMode_(c) == fmi3OK ? 0 : -2)
PROBE(directional_derivative, stepping(), fmi3GetDirectionalDerivative_(c, &PHI1, 1, &PHI1_0, 1, &when, 1, &when, 1))
PROBE(evaluate_discrete_states, stepping(), fmi3EvaluateDiscreteStates_(c))
static int null_instance(void) { return DO_STEP(NULL, 0.0, 0.01); }
static int error_state_then_reset(void) {
    fmi3Instance c = stepping();
    DO_STEP(c, 0.0, -1.0);
    if (DO_STEP(c, 0.0, 0.01) != fmi3Error || fmi3Reset_(c) != fmi3OK) return done(c, -2);
    fmi3EnterInitializationMode_(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    fmi3ExitInitializationMode_(c);
    return done(c, DO_STEP(c, 0.0, 0.01));
}

static const struct {
    const char *name;
    int (*run)(void);
} PROBES[] = {
#define P(name) {#name, name},
    P(exit_in_instantiated) P(exit_twice) P(do_step_before_initialisation) P(terminate_twice)
    P(do_step_after_terminate) P(set_after_terminate) P(enter_step_mode_without_event_mode)
    P(model_exchange_function_in_co_simulation) P(do_step_in_model_exchange) P(step_size_zero) P(step_size_nan)
    P(communication_point_not_the_fmus_time) P(do_step_null_out_argument)
    P(start_time_is_the_first_communication_point) P(start_value_nan) P(values_count_not_references_count)
    P(get_float64_null_references) P(get_float64_null_values) P(get_float32_not_a_type_of_this_fmu) P(get_clock)
    P(format_directives_in_a_string) P(set_string_not_utf8) P(fixed_parameter_after_initialisation) P(wrong_token) P(null_token)
    P(null_resource_path) P(null_instance_name) P(instance_name_not_utf8) P(event_mode_requested) P(scheduled_execution)
    P(null_logger_still_instantiates) P(update_discrete_states_null_out_argument) P(set_continuous_states_wrong_count)
    P(get_continuous_states_null) P(set_time_nan) P(completed_integrator_step_null) P(number_of_states)
    P(get_fmu_state_null) P(set_fmu_state_foreign) P(deserialize_garbage) P(debug_logging_null_categories)
    P(configuration_mode_round_trip) P(directional_derivative) P(evaluate_discrete_states) P(null_instance)
    P(error_state_then_reset)
#undef P
};

/* ----------------------------------------------------------------------------------- threads */

typedef struct {
    double start, phi1;
    int created;
} thread_case;

static void *run_case(void *data) {
    thread_case *t = data;
    t->phi1 = NAN;
    fmi3Instance c = cs();
    t->created = c != NULL;
    if (!c) return NULL;
    fmi3Boolean a, b, e;
    fmi3Float64 last;
    int ok = fmi3SetFloat64_(c, &PHI1_0, 1, &t->start, 1) == fmi3OK &&
             fmi3EnterInitializationMode_(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK &&
             fmi3ExitInitializationMode_(c) == fmi3OK;
    for (int k = 0; ok && k < 20; k++) ok = fmi3DoStep_(c, k * 0.01, 0.01, fmi3True, &a, &b, &e, &last) == fmi3OK;
    if (ok) fmi3GetFloat64_(c, &PHI1, 1, &t->phi1, 1);
    fmi3Terminate_(c);
    fmi3FreeInstance_(c);
    return NULL;
}

static void run_threads(int n, int rounds) {
    thread_case *cases = calloc((size_t)(n * rounds), sizeof *cases), reference;
    pthread_t *threads = calloc((size_t)n, sizeof *threads);
    int created = 0, identical = 1;
    for (int r = 0; r < rounds; r++) {
        for (int k = 0; k < n; k++) {
            cases[r * n + k].start = 0.5 + 0.1 * k;
            pthread_create(&threads[k], NULL, run_case, &cases[r * n + k]);
        }
        for (int k = 0; k < n; k++) pthread_join(threads[k], NULL);
    }
    for (int k = 0; k < n; k++) {
        reference.start = 0.5 + 0.1 * k;
        run_case(&reference);
        for (int r = 0; r < rounds; r++) {
            created += cases[r * n + k].created;
            if (memcmp(&cases[r * n + k].phi1, &reference.phi1, sizeof(double)) != 0 || isnan(reference.phi1))
                identical = 0;
        }
    }
    printf("threads-created %d of %d\nthreads-identical %d\n", created, n * rounds, identical);
    free(cases);
    free(threads);
}

int main(int argc, char **argv) {
    if (argc < 5) {
        fprintf(stderr, "usage: %s DIR IDENTIFIER TOKEN NAME=VR... MODE [ARG]\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1], *identifier = argv[2];
    token = argv[3];
    char path[4096];
    snprintf(path, sizeof path, "%s/binaries/x86_64-linux/%s.so", dir, identifier);
    snprintf(resources, sizeof resources, "%s/resources/", dir);
    int k = 4;
    for (; k < argc && strchr(argv[k], '='); k++) {
        char name[64];
        unsigned int vr;
        if (sscanf(argv[k], "%63[^=]=%u", name, &vr) != 2) return 2;
#define NAMED(n, variable) if (strcmp(name, n) == 0) variable = vr;
        NAMED("phi1_0", PHI1_0) NAMED("phi1", PHI1) NAMED("l1", L1) NAMED("solver", SOLVER)
        NAMED("pivot_ax", PIVOT_AX)
    }
    if (k >= argc) return 2;
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        fprintf(stderr, "cannot load %s: %s\n", path, dlerror());
        return 3;
    }
#define RESOLVE(name)                                                                                             \
    if (!(name##_ = (name##TYPE *)dlsym(library, #name))) {                                                      \
        fprintf(stderr, "missing %s\n", #name);                                                                  \
        return 3;                                                                                                 \
    }
    FMI3_USED(RESOLVE)
    if (strcmp(argv[k], "probes") == 0) {
        for (size_t p = 0; p < sizeof PROBES / sizeof PROBES[0]; p++) {
            if (k + 1 < argc && strcmp(argv[k + 1], PROBES[p].name) != 0) continue;
            n_logs = 0;
            int status = PROBES[p].run();
            printf("probe %s %d\n", PROBES[p].name, status);
            for (int j = 0; j < n_logs; j++) printf("  log %d %s\n", log_status[j], logs[j]);
            fflush(stdout);
        }
    } else if (strcmp(argv[k], "threads") == 0 && k + 2 < argc) {
        run_threads(atoi(argv[k + 1]), atoi(argv[k + 2]));
    } else {
        return 2;
    }
    dlclose(library);
    printf("end\n");
    return 0;
}
