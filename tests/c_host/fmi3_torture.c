/* A torture host for the FMI 3.0 FMU, in C, for the tests (tests/test_guard.py): the calls a master may
 * get wrong, each on a fresh instance, with the status and the log lines it got. No Python in it.
 *
 *   fmi3_torture DIR IDENTIFIER TOKEN NAME=VR... MODE [ARG]
 *
 * DIR is an extracted FMU (binaries/x86_64-linux/IDENTIFIER.so), NAME=VR the value references the
 * probes use (phi1_0 phi1 l1 solver pivot_ax air_drag fixed_step omega2_0). MODE:
 *   probes [NAME]     run every probe but those marked OWN (or the one named); print "probe NAME STATUS" and its
 *                     log lines
 *                     "  log STATUS TEXT", then what it noted, "  info TEXT"
 *   threads N ROUNDS  as fmi2_torture.c, with Co-Simulation instances
 *   matrix            every FMI function with valid arguments in every state a fixed call sequence reaches,
 *                     Model Exchange and Co-Simulation, each on a fresh instance: "matrix ME.STATE FUNCTION
 *                     STATUS" (CS.STATE) and its log lines
 * Exit status 0 if it got to the end. */
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
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
    X(fmi3SetDebugLogging) X(fmi3GetDirectionalDerivative) X(fmi3EvaluateDiscreteStates) X(fmi3GetBoolean)          \
    X(fmi3GetString) X(fmi3SetBoolean) X(fmi3GetContinuousStateDerivatives) X(fmi3GetNominalsOfContinuousStates)  \
    X(fmi3GetEventIndicators) X(fmi3GetNumberOfEventIndicators) X(fmi3EnterEventMode)                            \
    X(fmi3SerializedFMUStateSize) X(fmi3SerializeFMUState) X(fmi3GetOutputDerivatives) X(fmi3GetAdjointDerivative)
#define DECLARE(name) static name##TYPE *name##_;
FMI3_USED(DECLARE)

static const char *token;
static char resources[4200];
static fmi3ValueReference PHI1_0, PHI1, L1, SOLVER, PIVOT_AX, AIR_DRAG, FIXED_STEP, OMEGA2_0;

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
/* Counts beyond the FMU's variables: refused before a byte length is computed from them (2^62 + 1 values of 8 bytes
 * wrap to 8 bytes: without the check the call answered OK having read or written one value). */
#define HUGE_COUNT (((size_t)1 << 62) + 1)
PROBE(get_float64_huge_count, stepping(),
      fmi3GetFloat64_(c, (fmi3ValueReference[2]){PHI1, PHI1}, HUGE_COUNT, (fmi3Float64[2]){0}, HUGE_COUNT))
PROBE(set_float64_huge_count, stepping(),
      fmi3SetFloat64_(c, (fmi3ValueReference[2]){PHI1_0, PHI1_0}, HUGE_COUNT - 1, (fmi3Float64[2]){0}, HUGE_COUNT - 1))
PROBE(get_boolean_huge_count, stepping(),
      fmi3GetBoolean_(c, (fmi3ValueReference[2]){PHI1, PHI1}, HUGE_COUNT, (fmi3Boolean[2]){0}, HUGE_COUNT))
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
PROBE(configuration_mode_round_trip, cs(), fmi3EnterConfigurationMode_(c)) /* no structural parameters: an error */
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

/* ---------------------------------------------------------------- host-facing guarantees of Model Exchange */

static char info[8192]; /* what a probe noted: printed after its "probe" line as "  info TEXT" */
static void note(const char *format, ...) __attribute__((format(printf, 1, 2)));
static void note(const char *format, ...) {
    size_t used = strlen(info);
    if (used + 8 >= sizeof info) return;
    memcpy(info + used, "  info ", 7);
    va_list args;
    va_start(args, format);
    vsnprintf(info + used + 7, sizeof info - used - 7, format, args);
    va_end(args);
    used = strlen(info);
    if (used + 1 < sizeof info) info[used] = '\n', info[used + 1] = '\0';
}

#define NX 13 /* the FMU's continuous states */

static int all_finite(const double *x, int n) {
    for (int k = 0; k < n; k++)
        if (!isfinite(x[k])) return 0;
    return 1;
}
static double largest_difference(const double *a, const double *b, int n) {
    double d = 0;
    for (int k = 0; k < n; k++) d = fmax(d, fabs(a[k] - b[k]));
    return d;
}
/* In Initialization Mode the derivatives and the states are given (OK, finite) and equal, to 1e-12, those
 * given right after fmi3ExitInitializationMode: 0 if so, else -2 (the statuses and differences noted). */
static int me_derivatives_in_initialization(void) {
    fmi3Instance c = me();
    double dx_init[NX], x_init[NX], dx_event[NX], x_event[NX];
    int s1 = fmi3EnterInitializationMode_(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    int s2 = fmi3GetContinuousStateDerivatives_(c, dx_init, NX);
    int s3 = fmi3GetContinuousStates_(c, x_init, NX);
    int s4 = fmi3ExitInitializationMode_(c);
    int s5 = fmi3GetContinuousStateDerivatives_(c, dx_event, NX);
    int s6 = fmi3GetContinuousStates_(c, x_event, NX);
    double ddx = largest_difference(dx_init, dx_event, NX), dxx = largest_difference(x_init, x_event, NX);
    note("statuses %d %d %d %d %d %d; finite %d %d; largest differences derivatives %.3g states %.3g", s1, s2, s3,
         s4, s5, s6, all_finite(dx_init, NX), all_finite(x_init, NX), ddx, dxx);
    int ok = !s1 && !s2 && !s3 && !s4 && !s5 && !s6 && all_finite(dx_init, NX) && all_finite(x_init, NX) &&
             ddx <= 1e-12 && dxx <= 1e-12;
    return done(c, ok ? 0 : -2);
}
/* Twice in Instantiated: both fmi3Error (3 if so, else -2). */
static int me_derivatives_twice_in_instantiated(void) {
    fmi3Instance c = me();
    double dx[NX];
    for (int k = 0; k < NX; k++) dx[k] = NAN;
    int a = fmi3GetContinuousStateDerivatives_(c, dx, NX), b = fmi3GetContinuousStateDerivatives_(c, dx, NX);
    note("statuses %d %d; derivatives after the second call finite %d (dx[0] = %g)", a, b, all_finite(dx, NX), dx[0]);
    /* the first is illegal (fmi3Error); the second runs in the Error state, where the state vectors may be read
     * for debugging (FMI 3.0.2, 2.3.1: as in Terminated): those of the start values, finite */
    return done(c, a == fmi3Error && b == fmi3OK && all_finite(dx, NX) ? 0 : -2);
}
/* A state that is NaN: refused before the Python side. */
static int me_set_continuous_states_nan(void) {
    fmi3Instance c = continuous();
    double x[NX];
    fmi3GetContinuousStates_(c, x, NX);
    x[3] = NAN;
    return done(c, fmi3SetContinuousStates_(c, x, NX));
}
/* States of 1e300 (finite) are taken; the derivatives there are not finite: fmi3Discard (the status of
 * GetContinuousStateDerivatives if SetContinuousStates was OK, else -2). */
static int me_huge_states_derivatives_discard(void) {
    fmi3Instance c = continuous();
    double x[NX], dx[NX];
    fmi3GetContinuousStates_(c, x, NX);
    for (int k = 0; k < NX; k++) x[k] = 1e300;
    int set = fmi3SetContinuousStates_(c, x, NX);
    int s = fmi3GetContinuousStateDerivatives_(c, dx, NX);
    note("fmi3SetContinuousStates %d, fmi3GetContinuousStateDerivatives %d", set, s);
    return done(c, set == fmi3OK ? s : -2);
}

/* A Model Exchange state deserialised into a Co-Simulation instance. */
static int tampered_state_interface(void) {
    fmi3Instance m = continuous();
    fmi3FMUState state = NULL;
    size_t size = 0;
    fmi3GetFMUState_(m, &state);
    fmi3SerializedFMUStateSize_(m, state, &size);
    fmi3Byte *bytes = malloc(size);
    fmi3SerializeFMUState_(m, state, bytes, size);
    fmi3FreeInstance_(m);
    fmi3Instance c = stepping();
    fmi3FMUState copy = NULL;
    n_logs = 0; /* only what the Co-Simulation instance says */
    int s = fmi3DeserializeFMUState_(c, bytes, size, &copy);
    free(bytes);
    return done(c, s);
}

/* ------------------------------------------------------------------------------------ the matrix */

/* Every function with valid arguments in every state that a fixed call sequence reaches, for each interface,
 * each on a fresh instance: "matrix INTERFACE.STATE FUNCTION STATUS" and its log lines. */
enum { M_INSTANTIATED, M_CONFIGURATION, M_INITIALIZATION, M_EVENT, M_CONTINUOUS_TIME, M_STEP, M_STEP_DISCARDED,
       M_TERMINATED, M_ERROR };
static const char *const MATRIX_STATES[] = {"Instantiated", "ConfigurationMode", "InitializationMode", "EventMode",
                                            "ContinuousTimeMode", "StepMode", "StepDiscarded", "Terminated", "Error"};
/* no Configuration Mode row: without structural parameters the FMU refuses to enter it (FMI 3.0, 2.3.2) */
static const int ME_ROWS[] = {M_INSTANTIATED, M_INITIALIZATION, M_EVENT, M_CONTINUOUS_TIME, M_TERMINATED, M_ERROR, -1};
static const int CS_ROWS[] = {M_INSTANTIATED, M_INITIALIZATION, M_STEP, M_STEP_DISCARDED, M_TERMINATED, M_ERROR, -1};

typedef struct {
    fmi3Instance c;
    int model_exchange, state;
    double t;          /* the FMU's time */
    fmi3FMUState fmu;  /* a state of this instance, got in Instantiated */
    size_t fmu_size;   /* its serialized size */
} cell;

static fmi3Byte *matrix_bytes[2]; /* a serialized state (Co-Simulation, Model Exchange) of another instance */
static size_t matrix_bytes_size[2];
static double matrix_states[NX]; /* continuous states of an instance in Continuous-Time Mode at t = 0 */

static int enter_initialization(fmi3Instance c) {
    return fmi3EnterInitializationMode_(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
}

/* A fresh instance in `state` (c NULL if the sequence did not get there). */
static cell reach(int model_exchange, int state) {
    cell x = {model_exchange ? me() : cs(), model_exchange, state, 0.0, NULL, 0};
    if (!x.c) return x;
    int ok = fmi3GetFMUState_(x.c, &x.fmu) == fmi3OK && fmi3SerializedFMUStateSize_(x.c, x.fmu, &x.fmu_size) == fmi3OK;
    fmi3Boolean a, b, d, e, f;
    fmi3Float64 next;
    switch (state) {
    case M_INSTANTIATED: break;
    case M_CONFIGURATION: ok = ok && fmi3EnterConfigurationMode_(x.c) == fmi3OK; break;
    case M_INITIALIZATION: ok = ok && enter_initialization(x.c) == fmi3OK; break;
    case M_EVENT:
    case M_CONTINUOUS_TIME:
    case M_STEP:
    case M_TERMINATED:
    case M_ERROR:
        ok = ok && enter_initialization(x.c) == fmi3OK && fmi3ExitInitializationMode_(x.c) == fmi3OK;
        if (state == M_CONTINUOUS_TIME)
            ok = ok && fmi3UpdateDiscreteStates_(x.c, &a, &b, &d, &e, &f, &next) == fmi3OK &&
                 fmi3EnterContinuousTimeMode_(x.c) == fmi3OK;
        if (state == M_TERMINATED)
            ok = ok && (model_exchange || DO_STEP(x.c, 0.0, 0.01) == fmi3OK) && fmi3Terminate_(x.c) == fmi3OK,
            x.t = model_exchange ? 0.0 : 0.01;
        if (state == M_ERROR) ok = ok && fmi3ExitInitializationMode_(x.c) == fmi3Error; /* not allowed there */
        break;
    case M_STEP_DISCARDED: {
        /* explicit Euler, h = 0.5 s, a fast start: the solver gives up within 100 s (fmi2_torture.c) */
        fmi3String euler = "euler";
        fmi3Float64 big = 0.5, fast = 40.0;
        ok = ok && fmi3SetString_(x.c, &SOLVER, 1, &euler, 1) == fmi3OK &&
             fmi3SetFloat64_(x.c, &FIXED_STEP, 1, &big, 1) == fmi3OK &&
             fmi3SetFloat64_(x.c, &OMEGA2_0, 1, &fast, 1) == fmi3OK && enter_initialization(x.c) == fmi3OK &&
             fmi3ExitInitializationMode_(x.c) == fmi3OK;
        int s = fmi3OK;
        for (x.t = 0.0; ok && x.t < 100.0 && (s = DO_STEP(x.c, x.t, 0.5)) == fmi3OK; x.t += 0.5) {
        }
        ok = ok && s == fmi3Discard;
        break;
    }
    }
    if (!ok) fmi3FreeInstance_(x.c), x.c = NULL;
    return x;
}

static const char *const MATRIX_FUNCTIONS[] = {
    "fmi3SetDebugLogging", "fmi3EnterInitializationMode", "fmi3ExitInitializationMode", "fmi3EnterEventMode",
    "fmi3Terminate", "fmi3Reset", "fmi3EnterConfigurationMode", "fmi3ExitConfigurationMode", "fmi3GetFloat64",
    "fmi3GetBoolean", "fmi3GetString", "fmi3SetFloat64", "fmi3SetBoolean", "fmi3SetString", "fmi3GetFMUState",
    "fmi3SetFMUState", "fmi3FreeFMUState", "fmi3SerializedFMUStateSize", "fmi3SerializeFMUState",
    "fmi3DeserializeFMUState", "fmi3UpdateDiscreteStates", "fmi3EnterContinuousTimeMode",
    "fmi3CompletedIntegratorStep", "fmi3SetTime", "fmi3SetContinuousStates", "fmi3GetContinuousStateDerivatives",
    "fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates", "fmi3GetEventIndicators",
    "fmi3GetNumberOfContinuousStates", "fmi3GetNumberOfEventIndicators", "fmi3EnterStepMode", "fmi3DoStep",
    "fmi3GetOutputDerivatives", "fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative",
    "fmi3EvaluateDiscreteStates", NULL};

/* Function `f` of the matrix on x, with valid arguments for x's state where there are any. */
static int matrix_call(int f, cell *x) {
    fmi3Instance c = x->c;
    /* before initialisation a parameter (initial = exact), after it an input (FMI 3.0, 2.3.2 to 2.3.5, 3.2.1,
     * 4.2.1); Boolean and String variables are parameters only */
    int early = x->state == M_INSTANTIATED || x->state == M_INITIALIZATION || x->state == M_CONFIGURATION;
    fmi3ValueReference real_vr = early ? PHI1_0 : PIVOT_AX;
    fmi3Float64 real = early ? 1.0 : 0.1, r = 0, seed = 1, v[NX];
    fmi3Boolean b = fmi3False, a1, a2, a3, a4, a5;
    fmi3String text = "dop853";
    fmi3String categories[] = {"logStatusError"};
    fmi3Int32 order = 1;
    size_t n = 0;
    fmi3FMUState fresh = NULL;
    switch (f) {
    case 0: return fmi3SetDebugLogging_(c, fmi3True, 1, categories);
    case 1: return enter_initialization(c);
    case 2: return fmi3ExitInitializationMode_(c);
    case 3: return fmi3EnterEventMode_(c);
    case 4: return fmi3Terminate_(c);
    case 5: return fmi3Reset_(c);
    case 6: return fmi3EnterConfigurationMode_(c);
    case 7: return fmi3ExitConfigurationMode_(c);
    case 8: return fmi3GetFloat64_(c, &PHI1_0, 1, &r, 1);
    case 9: return fmi3GetBoolean_(c, &AIR_DRAG, 1, &b, 1);
    case 10: return fmi3GetString_(c, &SOLVER, 1, &text, 1);
    case 11: return fmi3SetFloat64_(c, &real_vr, 1, &real, 1);
    case 12: return fmi3SetBoolean_(c, &AIR_DRAG, 1, &b, 1);
    case 13: return fmi3SetString_(c, &SOLVER, 1, &text, 1);
    case 14: {
        int s = fmi3GetFMUState_(c, &fresh);
        if (fresh) fmi3FreeFMUState_(c, &fresh);
        return s;
    }
    case 15: return fmi3SetFMUState_(c, x->fmu);
    case 16: return fmi3FreeFMUState_(c, &x->fmu);
    case 17: return fmi3SerializedFMUStateSize_(c, x->fmu, &n);
    case 18: {
        fmi3Byte *bytes = malloc(x->fmu_size);
        int s = fmi3SerializeFMUState_(c, x->fmu, bytes, x->fmu_size);
        free(bytes);
        return s;
    }
    case 19: {
        int s = fmi3DeserializeFMUState_(c, matrix_bytes[x->model_exchange], matrix_bytes_size[x->model_exchange],
                                         &fresh);
        if (fresh) fmi3FreeFMUState_(c, &fresh);
        return s;
    }
    case 20: return fmi3UpdateDiscreteStates_(c, &a1, &a2, &a3, &a4, &a5, &r);
    case 21: return fmi3EnterContinuousTimeMode_(c);
    case 22: return fmi3CompletedIntegratorStep_(c, fmi3True, &a1, &a2);
    case 23: return fmi3SetTime_(c, x->t);
    case 24: return fmi3SetContinuousStates_(c, matrix_states, NX);
    case 25: return fmi3GetContinuousStateDerivatives_(c, v, NX);
    case 26: return fmi3GetContinuousStates_(c, v, NX);
    case 27: return fmi3GetNominalsOfContinuousStates_(c, v, NX);
    case 28: return fmi3GetEventIndicators_(c, v, 0); /* it has none */
    case 29: return fmi3GetNumberOfContinuousStates_(c, &n);
    case 30: return fmi3GetNumberOfEventIndicators_(c, &n);
    case 31: return fmi3EnterStepMode_(c);
    case 32: /* after a discarded step a smaller one from where the FMU stayed */
        return DO_STEP(c, x->t, x->state == M_STEP_DISCARDED ? 1e-3 : 0.01);
    case 33: return fmi3GetOutputDerivatives_(c, &PHI1, 1, &order, &r, 1);
    case 34: return fmi3GetDirectionalDerivative_(c, &PHI1, 1, &PIVOT_AX, 1, &seed, 1, &r, 1);
    case 35: return fmi3GetAdjointDerivative_(c, &PHI1, 1, &PIVOT_AX, 1, &seed, 1, &r, 1);
    case 36: return fmi3EvaluateDiscreteStates_(c);
    }
    return -100;
}

static void run_matrix(void) {
    for (int model_exchange = 0; model_exchange < 2; model_exchange++) {
        cell helper = reach(model_exchange, M_INSTANTIATED);
        if (helper.c && helper.fmu) {
            matrix_bytes_size[model_exchange] = helper.fmu_size;
            matrix_bytes[model_exchange] = malloc(helper.fmu_size);
            fmi3SerializeFMUState_(helper.c, helper.fmu, matrix_bytes[model_exchange], helper.fmu_size);
        }
        if (helper.c) fmi3FreeInstance_(helper.c);
    }
    fmi3Instance m = continuous();
    if (m) fmi3GetContinuousStates_(m, matrix_states, NX), fmi3FreeInstance_(m);
    for (int model_exchange = 1; model_exchange >= 0; model_exchange--) {
        for (const int *state = model_exchange ? ME_ROWS : CS_ROWS; *state >= 0; state++) {
            for (int f = 0; MATRIX_FUNCTIONS[f]; f++) {
                cell x = reach(model_exchange, *state);
                n_logs = 0;
                int s = x.c ? matrix_call(f, &x) : -9; /* -9: the state was not reached */
                printf("matrix %s.%s %s %d\n", model_exchange ? "ME" : "CS", MATRIX_STATES[*state],
                       MATRIX_FUNCTIONS[f], s);
                for (int j = 0; j < n_logs; j++) printf("  log %d %s\n", log_status[j], logs[j]);
                fflush(stdout);
                if (x.c) fmi3FreeInstance_(x.c);
            }
        }
    }
    free(matrix_bytes[0]), free(matrix_bytes[1]);
}

/* A probe with `own` set runs only when named (in a process of its own). */
static const struct {
    const char *name;
    int (*run)(void);
    int own;
} PROBES[] = {
#define P(name) {#name, name, 0},
#define OWN(name) {#name, name, 1},
    P(exit_in_instantiated) P(exit_twice) P(do_step_before_initialisation) P(terminate_twice)
    P(do_step_after_terminate) P(set_after_terminate) P(enter_step_mode_without_event_mode)
    P(model_exchange_function_in_co_simulation) P(do_step_in_model_exchange) P(step_size_zero) P(step_size_nan)
    P(communication_point_not_the_fmus_time) P(do_step_null_out_argument)
    P(start_time_is_the_first_communication_point) P(start_value_nan) P(values_count_not_references_count)
    P(get_float64_null_references) P(get_float64_null_values) P(get_float64_huge_count) P(set_float64_huge_count)
    P(get_boolean_huge_count) P(get_float32_not_a_type_of_this_fmu) P(get_clock)
    P(format_directives_in_a_string) P(set_string_not_utf8) P(fixed_parameter_after_initialisation) P(wrong_token) P(null_token)
    P(null_resource_path) P(null_instance_name) P(instance_name_not_utf8) P(event_mode_requested) P(scheduled_execution)
    P(null_logger_still_instantiates) P(update_discrete_states_null_out_argument) P(set_continuous_states_wrong_count)
    P(get_continuous_states_null) P(set_time_nan) P(completed_integrator_step_null) P(number_of_states)
    P(get_fmu_state_null) P(set_fmu_state_foreign) P(deserialize_garbage) P(debug_logging_null_categories)
    P(configuration_mode_round_trip) P(directional_derivative) P(evaluate_discrete_states) P(null_instance)
    P(error_state_then_reset) P(me_derivatives_in_initialization) OWN(me_derivatives_twice_in_instantiated)
    P(me_set_continuous_states_nan) P(me_huge_states_derivatives_discard) P(tampered_state_interface)
#undef P
#undef OWN
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
        NAMED("pivot_ax", PIVOT_AX) NAMED("air_drag", AIR_DRAG) NAMED("fixed_step", FIXED_STEP)
        NAMED("omega2_0", OMEGA2_0)
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
            if (k + 1 < argc ? strcmp(argv[k + 1], PROBES[p].name) != 0 : PROBES[p].own) continue;
            n_logs = 0;
            info[0] = '\0';
            int status = PROBES[p].run();
            printf("probe %s %d\n", PROBES[p].name, status);
            for (int j = 0; j < n_logs; j++) printf("  log %d %s\n", log_status[j], logs[j]);
            fputs(info, stdout);
            fflush(stdout);
        }
    } else if (strcmp(argv[k], "matrix") == 0) {
        run_matrix();
    } else if (strcmp(argv[k], "threads") == 0 && k + 2 < argc) {
        run_threads(atoi(argv[k + 1]), atoi(argv[k + 2]));
    } else {
        return 2;
    }
    dlclose(library);
    printf("end\n");
    return 0;
}
