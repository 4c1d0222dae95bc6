/* A torture host for the FMI 2.0 FMUs, in C, for the tests (tests/test_guard.py): every call a master
 * may get wrong, each on a fresh instance, with the status and the log lines it got. No Python in it.
 *
 *   fmi2_torture DIR IDENTIFIER GUID NAME=VR... MODE [ARG]
 *
 * DIR is an extracted FMU (binaries/linux64/IDENTIFIER.so), NAME=VR the value references the probes
 * use (phi1_0 m1 l1 solver phi1 pivot_ax air_drag fixed_step omega2_0). MODE:
 *   probes [NAME]     run every probe (or the one named); print "probe NAME STATUS" and its log lines
 *                     "  log STATUS TEXT"
 *   threads N ROUNDS  N threads at once instantiate, set a start value, run 20 steps, read phi1 and
 *                     free, ROUNDS times; then the same sequentially; print "threads-created K of M" and
 *                     "threads-identical 1" if every result equals the sequential one bit for bit
 *   soak N            N instantiate/initialise/step/free cycles; print "rss CYCLE KIB" every N/20 cycles
 *   neighbour DIR2 IDENTIFIER2 GUID2
 *                     run a case, then another FMU from DIR2 (a pythonfmu FMU of another author that uses
 *                     the same module names) for 10 steps, then the case again; print "neighbour-ran 1"
 *                     if the other FMU ran and "neighbour-identical 1" if both runs of the case agree
 * The host's logger formats the message with the arguments it is given, as a C host does: a message
 * passed as a format would crash it here. Exit status 0 if it got to the end. */
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fmi2Functions.h"

#define MAX_LOGS 64
#define LOG_SIZE 512

/* ------------------------------------------------------------------------------ the FMU */

#define FMI2_ALL(X)                                                                                               \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment) X(fmi2EnterInitializationMode)                 \
    X(fmi2ExitInitializationMode) X(fmi2Terminate) X(fmi2Reset) X(fmi2GetReal) X(fmi2GetInteger)                \
    X(fmi2GetBoolean) X(fmi2GetString) X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean) X(fmi2SetString)     \
    X(fmi2GetFMUstate) X(fmi2SetFMUstate) X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize)                     \
    X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate) X(fmi2DoStep) X(fmi2SetDebugLogging)                    \
    X(fmi2GetDirectionalDerivative) X(fmi2SetRealInputDerivatives) X(fmi2GetRealOutputDerivatives)              \
    X(fmi2CancelStep) X(fmi2GetStatus) X(fmi2GetRealStatus) X(fmi2GetIntegerStatus) X(fmi2GetBooleanStatus)      \
    X(fmi2GetStringStatus)
#define DECLARE(name) static name##TYPE *name##_;
FMI2_ALL(DECLARE)

static const char *guid;
static char resources[4200];
static fmi2ValueReference PHI1_0, M1, L1, SOLVER, PHI1, PIVOT_AX, AIR_DRAG, FIXED_STEP, OMEGA2_0;

/* --------------------------------------------------------------------------- the logger */

static pthread_mutex_t log_lock = PTHREAD_MUTEX_INITIALIZER;
static char logs[MAX_LOGS][LOG_SIZE];
static int log_status[MAX_LOGS], n_logs;

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env, (void)instance, (void)category;
    char text[LOG_SIZE];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message, args); /* as C hosts do: the message is a format */
    va_end(args);
    for (char *p = text; *p; p++)
        if (*p == '\n') *p = ' ';
    pthread_mutex_lock(&log_lock);
    if (n_logs < MAX_LOGS) {
        snprintf(logs[n_logs], LOG_SIZE, "%s", text);
        log_status[n_logs++] = (int)status;
    }
    pthread_mutex_unlock(&log_lock);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static fmi2Component instantiate(int logging) {
    return fmi2Instantiate_("torture", fmi2CoSimulation, guid, resources, &callbacks, fmi2False, logging);
}

/* An instance in Step Complete at t = 0 (phi1_0 = 1 rad by default). */
static fmi2Component initialised(void) {
    fmi2Component c = instantiate(fmi2False);
    if (!c) return NULL;
    fmi2SetupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode_(c);
    fmi2ExitInitializationMode_(c);
    return c;
}

/* ---------------------------------------------------------------------------- the probes */

typedef int (*probe_fn)(void);

#define FRESH(c)                                                                                                  \
    fmi2Component c = initialised();                                                                              \
    if (!c) return -1

static int exit_without_enter(void) {
    fmi2Component c = instantiate(fmi2False);
    int s = fmi2ExitInitializationMode_(c);
    fmi2FreeInstance_(c);
    return s;
}
static int enter_twice(void) {
    fmi2Component c = instantiate(fmi2False);
    fmi2EnterInitializationMode_(c);
    int s = fmi2EnterInitializationMode_(c);
    fmi2FreeInstance_(c);
    return s;
}
static int exit_twice(void) {
    FRESH(c);
    int s = fmi2ExitInitializationMode_(c);
    fmi2FreeInstance_(c);
    return s;
}
static int terminate_twice(void) {
    FRESH(c);
    fmi2Terminate_(c);
    int s = fmi2Terminate_(c);
    fmi2FreeInstance_(c);
    return s;
}
static int terminate_before_initialisation(void) {
    fmi2Component c = instantiate(fmi2False);
    int s = fmi2Terminate_(c);
    fmi2FreeInstance_(c);
    return s;
}
static int set_real_after_terminate(void) {
    FRESH(c);
    fmi2Terminate_(c);
    fmi2Real v = 0.1;
    int s = fmi2SetReal_(c, &PIVOT_AX, 1, &v);
    fmi2FreeInstance_(c);
    return s;
}
static int do_step_after_terminate(void) {
    FRESH(c);
    fmi2Terminate_(c);
    int s = fmi2DoStep_(c, 0.0, 0.01, fmi2True);
    fmi2FreeInstance_(c);
    return s;
}
static int setup_experiment_in_step_mode(void) {
    FRESH(c);
    int s = fmi2SetupExperiment_(c, fmi2False, 0.0, 5.0, fmi2False, 0.0);
    fmi2FreeInstance_(c);
    return s;
}
static int do_step_before_initialisation(void) {
    fmi2Component c = instantiate(fmi2False);
    int s = fmi2DoStep_(c, 0.0, 0.01, fmi2True);
    fmi2FreeInstance_(c);
    return s;
}
static int get_real_when_instantiated(void) {
    fmi2Component c = instantiate(fmi2False);
    fmi2Real v;
    int s = fmi2GetReal_(c, &PHI1, 1, &v);
    fmi2FreeInstance_(c);
    return s;
}
#define STEP_PROBE(name, t, h)                                                                                    \
    static int name(void) {                                                                                       \
        FRESH(c);                                                                                                 \
        int s = fmi2DoStep_(c, t, h, fmi2True);                                                                   \
        fmi2FreeInstance_(c);                                                                                     \
        return s;                                                                                                 \
    }
STEP_PROBE(step_size_zero, 0.0, 0.0)
STEP_PROBE(step_size_negative, 0.0, -0.01)
STEP_PROBE(step_size_nan, 0.0, NAN)
STEP_PROBE(step_size_infinite, 0.0, INFINITY)
STEP_PROBE(communication_point_nan, NAN, 0.01)
STEP_PROBE(communication_point_not_the_fmus_time, 0.5, 0.01)

/* After an error only what the Error state allows; reset brings the instance back (status: the step after). */
static int error_state_then_reset(void) {
    FRESH(c);
    fmi2DoStep_(c, 0.0, -1.0, fmi2True);
    fmi2Real v;
    if (fmi2DoStep_(c, 0.0, 0.01, fmi2True) != fmi2Error || fmi2GetReal_(c, &PHI1, 1, &v) != fmi2OK ||
        fmi2Reset_(c) != fmi2OK) {
        fmi2FreeInstance_(c);
        return -2;
    }
    fmi2SetupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode_(c);
    fmi2ExitInitializationMode_(c);
    int s = fmi2DoStep_(c, 0.0, 0.01, fmi2True);
    fmi2FreeInstance_(c);
    return s;
}
#define SET_REAL_PROBE(name, vr, value)                                                                           \
    static int name(void) {                                                                                       \
        fmi2Component c = instantiate(fmi2False);                                                                 \
        fmi2Real v = value;                                                                                       \
        int s = fmi2SetReal_(c, &vr, 1, &v);                                                                      \
        fmi2FreeInstance_(c);                                                                                     \
        return s;                                                                                                 \
    }
SET_REAL_PROBE(start_value_nan, PHI1_0, NAN)
SET_REAL_PROBE(negative_mass, M1, -0.3)
static fmi2ValueReference NO_SUCH_VR = 999999;
SET_REAL_PROBE(unknown_value_reference, NO_SUCH_VR, 1.0)
static int unknown_solver(void) {
    fmi2Component c = instantiate(fmi2False);
    fmi2String v = "radau5";
    int s = fmi2SetString_(c, &SOLVER, 1, &v);
    fmi2FreeInstance_(c);
    return s;
}
static int wrong_type(void) {
    FRESH(c);
    fmi2Boolean v;
    int s = fmi2GetBoolean_(c, &PHI1, 1, &v);
    fmi2FreeInstance_(c);
    return s;
}
static int fixed_parameter_after_initialisation(void) {
    FRESH(c);
    fmi2Real v = 0.5;
    int s = fmi2SetReal_(c, &L1, 1, &v);
    fmi2FreeInstance_(c);
    return s;
}
/* The status is the doStep on a sibling instance after another instance's errors. */
static int errors_leave_siblings_working(void) {
    FRESH(a);
    FRESH(b);
    fmi2Real v = NAN;
    fmi2SetReal_(a, &PIVOT_AX, 1, &v);
    fmi2DoStep_(a, 0.0, -1.0, fmi2True);
    int s = fmi2DoStep_(b, 0.0, 0.01, fmi2True);
    fmi2FreeInstance_(a);
    fmi2FreeInstance_(b);
    return s;
}
/* Returns 0 for NULL (as the test expects), 1 for an instance (freed). */
static int instance_or_null(fmi2Component c) {
    if (!c) return 0;
    fmi2FreeInstance_(c);
    return 1;
}
static int wrong_guid(void) {
    return instance_or_null(fmi2Instantiate_("t", fmi2CoSimulation, "{wrong}", resources, &callbacks, 0, 0));
}
static int empty_guid(void) {
    return instance_or_null(fmi2Instantiate_("t", fmi2CoSimulation, "", resources, &callbacks, 0, 0));
}
static int null_guid(void) {
    return instance_or_null(fmi2Instantiate_("t", fmi2CoSimulation, NULL, resources, &callbacks, 0, 0));
}
static int model_exchange(void) {
    return instance_or_null(fmi2Instantiate_("t", fmi2ModelExchange, guid, resources, &callbacks, 0, 0));
}
static int null_instance_name(void) {
    return instance_or_null(fmi2Instantiate_(NULL, fmi2CoSimulation, guid, resources, &callbacks, 0, 0));
}
static int empty_instance_name(void) {
    return instance_or_null(fmi2Instantiate_("", fmi2CoSimulation, guid, resources, &callbacks, 0, 0));
}
/* Not UTF-8 (an fmi2String is): refused, where pythonfmu's library crashed the host. */
static int instance_name_not_utf8(void) {
    return instance_or_null(fmi2Instantiate_("t\xff", fmi2CoSimulation, guid, resources, &callbacks, 0, 0));
}
static int null_resource_location(void) {
    return instance_or_null(fmi2Instantiate_("t", fmi2CoSimulation, guid, NULL, &callbacks, 0, 0));
}
static int missing_resource_folder(void) {
    return instance_or_null(
        fmi2Instantiate_("t", fmi2CoSimulation, guid, "file:///nonexistent/resources", &callbacks, 0, 0));
}
static int foreign_resource_folder(void) {
    return instance_or_null(fmi2Instantiate_("t", fmi2CoSimulation, guid, "file:///tmp", &callbacks, 0, 0));
}
static int null_callbacks(void) {
    return instance_or_null(fmi2Instantiate_("t", fmi2CoSimulation, guid, resources, NULL, 0, 0));
}
static int null_logger(void) {
    const fmi2CallbackFunctions none = {NULL, calloc, free, NULL, NULL};
    return instance_or_null(fmi2Instantiate_("t", fmi2CoSimulation, guid, resources, &none, 0, 0));
}
/* A String with printf directives, logging on: quoted in the error message, never used as a format. */
static int format_directives_in_a_string(void) {
    fmi2Component c = instantiate(fmi2True);
    fmi2String v = "%s%s%s%n%n%p";
    int s = fmi2SetString_(c, &SOLVER, 1, &v);
    fmi2FreeInstance_(c);
    return s;
}
#define NULL_ARRAY_PROBE(name, call)                                                                              \
    static int name(void) {                                                                                       \
        FRESH(c);                                                                                                 \
        fmi2ValueReference vr[2] = {PHI1, PHI1};                                                                  \
        fmi2Real r[2] = {0, 0};                                                                                   \
        (void)vr, (void)r;                                                                                        \
        int s = call;                                                                                             \
        fmi2FreeInstance_(c);                                                                                     \
        return s;                                                                                                 \
    }
NULL_ARRAY_PROBE(get_real_null_references, fmi2GetReal_(c, NULL, 2, r))
NULL_ARRAY_PROBE(get_real_null_values, fmi2GetReal_(c, vr, 2, NULL))
NULL_ARRAY_PROBE(set_real_null_values, fmi2SetReal_(c, vr, 2, NULL))
NULL_ARRAY_PROBE(get_integer_null_values, fmi2GetInteger_(c, vr, 2, NULL))
NULL_ARRAY_PROBE(get_boolean_null_references, fmi2GetBoolean_(c, NULL, 2, NULL))
NULL_ARRAY_PROBE(get_string_null_values, fmi2GetString_(c, vr, 2, NULL))
NULL_ARRAY_PROBE(set_boolean_null_values, fmi2SetBoolean_(c, vr, 2, NULL))
NULL_ARRAY_PROBE(set_integer_null_references, fmi2SetInteger_(c, NULL, 1, NULL))
NULL_ARRAY_PROBE(zero_values_need_no_arrays, fmi2GetReal_(c, NULL, 0, NULL))
static int set_string_null_element(void) {
    fmi2Component c = instantiate(fmi2False);
    fmi2String v = NULL;
    int s = fmi2SetString_(c, &SOLVER, 1, &v);
    fmi2FreeInstance_(c);
    return s;
}
/* A String value that is not UTF-8: fmi2Error naming it, before pythonfmu's library passes on its decoding error. */
static int set_string_not_utf8(void) {
    fmi2Component c = instantiate(fmi2False);
    fmi2String v = "dop\xe9";
    int s = fmi2SetString_(c, &SOLVER, 1, &v);
    fmi2FreeInstance_(c);
    return s;
}
NULL_ARRAY_PROBE(debug_logging_null_categories, fmi2SetDebugLogging_(c, fmi2True, 2, NULL))
static int debug_logging_unknown_category(void) {
    FRESH(c);
    fmi2String categories[] = {"logEverything"};
    int s = fmi2SetDebugLogging_(c, fmi2True, 1, categories);
    fmi2FreeInstance_(c);
    return s;
}
static int debug_logging_null_category(void) {
    FRESH(c);
    fmi2String categories[] = {"logAll", NULL};
    int s = fmi2SetDebugLogging_(c, fmi2True, 2, categories);
    fmi2FreeInstance_(c);
    return s;
}
/* Logging off by the host (setDebugLogging off, no categories): even errors are not logged. */
static int errors_silenced_by_set_debug_logging(void) {
    FRESH(c);
    fmi2SetDebugLogging_(c, fmi2False, 0, NULL);
    int s = fmi2DoStep_(c, 0.0, -1.0, fmi2True);
    fmi2FreeInstance_(c);
    return s;
}
NULL_ARRAY_PROBE(get_fmu_state_null, fmi2GetFMUstate_(c, NULL))
NULL_ARRAY_PROBE(set_fmu_state_null, fmi2SetFMUstate_(c, NULL))
static int set_fmu_state_foreign_pointer(void) {
    FRESH(c);
    int s = fmi2SetFMUstate_(c, (fmi2FMUstate)&callbacks);
    fmi2FreeInstance_(c);
    return s;
}
NULL_ARRAY_PROBE(free_fmu_state_null_pointer, fmi2FreeFMUstate_(c, NULL))
static int free_fmu_state_null_state(void) {
    FRESH(c);
    fmi2FMUstate s0 = NULL;
    int s = fmi2FreeFMUstate_(c, &s0);
    fmi2FreeInstance_(c);
    return s;
}
static int serialized_size_null(void) {
    FRESH(c);
    fmi2FMUstate state = NULL;
    fmi2GetFMUstate_(c, &state);
    int s = fmi2SerializedFMUstateSize_(c, state, NULL);
    fmi2FreeInstance_(c); /* frees the state too */
    return s;
}
static int deserialize_garbage(void) {
    FRESH(c);
    fmi2Byte bytes[256];
    memset(bytes, 'x', sizeof bytes);
    fmi2FMUstate state = NULL;
    int s = fmi2DeSerializeFMUstate_(c, bytes, sizeof bytes, &state);
    fmi2FreeInstance_(c);
    return s;
}
NULL_ARRAY_PROBE(deserialize_null_bytes, fmi2DeSerializeFMUstate_(c, NULL, 100, NULL))
NULL_ARRAY_PROBE(real_status_null_value, fmi2GetRealStatus_(c, fmi2LastSuccessfulTime, NULL))
static int real_status_unknown_kind(void) {
    FRESH(c);
    fmi2Real v;
    int s = fmi2GetRealStatus_(c, (fmi2StatusKind)99, &v);
    fmi2FreeInstance_(c);
    return s;
}
static int status_kind_not_given(void) {
    FRESH(c);
    fmi2Status v;
    int s = fmi2GetStatus_(c, fmi2DoStepStatus, &v);
    fmi2FreeInstance_(c);
    return s;
}
/* Status 0 if lastSuccessfulTime is the end of the last step, else -2. */
static int last_successful_time(void) {
    FRESH(c);
    fmi2DoStep_(c, 0.0, 0.25, fmi2True);
    fmi2Real t = -1;
    int s = fmi2GetRealStatus_(c, fmi2LastSuccessfulTime, &t);
    fmi2FreeInstance_(c);
    return s == 0 && t == 0.25 ? 0 : -2;
}
NULL_ARRAY_PROBE(directional_derivative, fmi2GetDirectionalDerivative_(c, vr, 1, vr, 1, r, r))
NULL_ARRAY_PROBE(input_derivatives, fmi2SetRealInputDerivatives_(c, vr, 1, NULL, r))
NULL_ARRAY_PROBE(output_derivatives, fmi2GetRealOutputDerivatives_(c, vr, 1, NULL, r))
NULL_ARRAY_PROBE(cancel_step, fmi2CancelStep_(c))
static int null_instance_do_step(void) { return fmi2DoStep_(NULL, 0.0, 0.01, fmi2True); }
static int null_instance_set_real(void) {
    fmi2Real v = 1;
    return fmi2SetReal_(NULL, &PHI1_0, 1, &v);
}
static int null_instance_free(void) {
    fmi2FreeInstance_(NULL);
    return 0;
}
static int freed_instance_used(void) {
    FRESH(c);
    fmi2FreeInstance_(c);
    return fmi2DoStep_(c, 0.0, 0.01, fmi2True);
}
static int freed_twice(void) {
    FRESH(c);
    fmi2FreeInstance_(c);
    fmi2FreeInstance_(c);
    return 0;
}
/* A state saved at t = 0.5 restores where the next doStep starts: 0 if the step from 0.5 works and one
 * from 1.0 is refused after the restore, else -2. */
static int fmu_state_restores_the_time(void) {
    FRESH(c);
    fmi2DoStep_(c, 0.0, 0.5, fmi2True);
    fmi2FMUstate state = NULL;
    fmi2GetFMUstate_(c, &state);
    fmi2DoStep_(c, 0.5, 0.5, fmi2True);
    fmi2SetFMUstate_(c, state);
    int from_half = fmi2DoStep_(c, 0.5, 0.5, fmi2True);
    fmi2SetFMUstate_(c, state);
    int from_one = fmi2DoStep_(c, 1.0, 0.5, fmi2True);
    fmi2FreeFMUstate_(c, &state);
    fmi2FreeInstance_(c);
    return from_half == fmi2OK && from_one == fmi2Error && state == NULL ? 0 : -2;
}
/* A serialized state into a new instance: phi1 after one more step equals the original's (0, else -2). */
static int serialized_state_in_a_new_instance(void) {
    FRESH(a);
    fmi2DoStep_(a, 0.0, 0.5, fmi2True);
    fmi2FMUstate state = NULL;
    size_t size = 0;
    fmi2GetFMUstate_(a, &state);
    fmi2SerializedFMUstateSize_(a, state, &size);
    fmi2Byte *bytes = malloc(size);
    fmi2SerializeFMUstate_(a, state, bytes, size);
    fmi2Component b = instantiate(fmi2False);
    fmi2FMUstate copy = NULL;
    int ok = fmi2DeSerializeFMUstate_(b, bytes, size, &copy) == fmi2OK && fmi2SetFMUstate_(b, copy) == fmi2OK;
    fmi2Real pa = 0, pb = 1;
    ok = ok && fmi2DoStep_(a, 0.5, 0.5, fmi2True) == fmi2OK && fmi2DoStep_(b, 0.5, 0.5, fmi2True) == fmi2OK;
    fmi2GetReal_(a, &PHI1, 1, &pa);
    fmi2GetReal_(b, &PHI1, 1, &pb);
    free(bytes);
    fmi2FreeInstance_(a);
    fmi2FreeInstance_(b);
    return ok && pa == pb ? 0 : -2;
}
/* An instance whose solver gives up within 100 s (euler, h = 0.5 s, fast start): the status of the
 * step that failed, and where it failed (t). */
static int step_until_discard(fmi2Component c, double *t) {
    fmi2String euler = "euler";
    fmi2Real big = 0.5, fast = 40.0;
    fmi2SetString_(c, &SOLVER, 1, &euler);
    fmi2SetReal_(c, &FIXED_STEP, 1, &big);
    fmi2SetReal_(c, &OMEGA2_0, 1, &fast);
    fmi2SetupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode_(c);
    fmi2ExitInitializationMode_(c);
    int s = fmi2OK;
    for (*t = 0.0; *t < 100.0 && (s = fmi2DoStep_(c, *t, 0.5, fmi2True)) == fmi2OK; *t += 0.5) {
    }
    return s;
}
/* A step the solver cannot do is fmi2Discard; then Step Failed: the status says so and terminate is
 * allowed (2 if all that holds, else -2). */
static int discarded_step_then_terminate(void) {
    fmi2Component c = instantiate(fmi2False);
    double t;
    int s = step_until_discard(c, &t);
    fmi2Boolean terminated = fmi2False;
    fmi2Real last = -1;
    int status = fmi2GetBooleanStatus_(c, fmi2Terminated, &terminated);
    int time_status = fmi2GetRealStatus_(c, fmi2LastSuccessfulTime, &last);
    int end = fmi2Terminate_(c);
    fmi2FreeInstance_(c);
    return s == fmi2Discard && status == fmi2OK && terminated && time_status == fmi2OK && last == t &&
                   end == fmi2OK
               ? 2
               : -2;
}
/* In Step Failed no further doStep. */
static int do_step_after_discard(void) {
    fmi2Component c = instantiate(fmi2False);
    double t;
    int s = step_until_discard(c, &t) == fmi2Discard ? (int)fmi2DoStep_(c, t, 0.5, fmi2True) : -2;
    fmi2FreeInstance_(c);
    return s;
}

static const struct {
    const char *name;
    probe_fn run;
} PROBES[] = {
#define P(name) {#name, name},
    P(exit_without_enter) P(enter_twice) P(exit_twice) P(terminate_twice) P(terminate_before_initialisation)
    P(set_real_after_terminate) P(do_step_after_terminate) P(setup_experiment_in_step_mode)
    P(do_step_before_initialisation) P(get_real_when_instantiated) P(step_size_zero) P(step_size_negative)
    P(step_size_nan) P(step_size_infinite) P(communication_point_nan) P(communication_point_not_the_fmus_time)
    P(error_state_then_reset) P(start_value_nan) P(negative_mass) P(unknown_value_reference) P(unknown_solver)
    P(wrong_type) P(fixed_parameter_after_initialisation) P(errors_leave_siblings_working) P(wrong_guid)
    P(empty_guid) P(null_guid) P(model_exchange) P(null_instance_name) P(empty_instance_name)
    P(instance_name_not_utf8)    P(null_resource_location) P(missing_resource_folder) P(foreign_resource_folder) P(null_callbacks)
    P(null_logger) P(format_directives_in_a_string) P(get_real_null_references) P(get_real_null_values)
    P(set_real_null_values) P(get_integer_null_values) P(get_boolean_null_references) P(get_string_null_values)
    P(set_boolean_null_values) P(set_integer_null_references) P(zero_values_need_no_arrays)
    P(set_string_null_element) P(set_string_not_utf8) P(debug_logging_null_categories) P(debug_logging_unknown_category)
    P(debug_logging_null_category) P(errors_silenced_by_set_debug_logging) P(get_fmu_state_null)
    P(set_fmu_state_null) P(set_fmu_state_foreign_pointer) P(free_fmu_state_null_pointer)
    P(free_fmu_state_null_state) P(serialized_size_null) P(deserialize_garbage) P(deserialize_null_bytes)
    P(real_status_null_value) P(real_status_unknown_kind) P(status_kind_not_given) P(last_successful_time)
    P(directional_derivative) P(input_derivatives) P(output_derivatives) P(cancel_step) P(null_instance_do_step)
    P(null_instance_set_real) P(null_instance_free) P(freed_instance_used) P(freed_twice)
    P(fmu_state_restores_the_time) P(serialized_state_in_a_new_instance) P(discarded_step_then_terminate) P(do_step_after_discard)
#undef P
};

/* Every probe, or only the one named `only` (not NULL). */
static void run_probes(const char *only) {
    for (size_t k = 0; k < sizeof PROBES / sizeof PROBES[0]; k++) {
        if (only && strcmp(only, PROBES[k].name) != 0) continue;
        n_logs = 0;
        int status = PROBES[k].run();
        printf("probe %s %d\n", PROBES[k].name, status);
        for (int j = 0; j < n_logs; j++) printf("  log %d %s\n", log_status[j], logs[j]);
        fflush(stdout);
    }
}

/* -------------------------------------------------------------------------- threads and soak */

#define THREAD_STEPS 20

typedef struct {
    double start; /* phi1_0 of this instance */
    double phi1;  /* phi1 after THREAD_STEPS steps, NAN if a call failed */
    int created;
} thread_case;

static void *run_case(void *data) {
    thread_case *t = data;
    t->phi1 = NAN;
    fmi2Component c = instantiate(fmi2False);
    t->created = c != NULL;
    if (!c) return NULL;
    int ok = fmi2SetReal_(c, &PHI1_0, 1, &t->start) == fmi2OK &&
             fmi2SetupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK &&
             fmi2EnterInitializationMode_(c) == fmi2OK && fmi2ExitInitializationMode_(c) == fmi2OK;
    for (int k = 0; ok && k < THREAD_STEPS; k++) ok = fmi2DoStep_(c, k * 0.01, 0.01, fmi2True) == fmi2OK;
    if (ok) fmi2GetReal_(c, &PHI1, 1, &t->phi1);
    fmi2Terminate_(c);
    fmi2FreeInstance_(c);
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
    for (int k = 0; k < n; k++) { /* the same cases, one after another */
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

static long rss_kib(void) {
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0, resident = 0;
    if (f) {
        if (fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
        fclose(f);
    }
    return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

static void run_soak(int cycles) {
    int every = cycles >= 20 ? cycles / 20 : 1;
    for (int k = 1; k <= cycles; k++) {
        fmi2Component c = initialised();
        if (!c) {
            printf("soak-failed %d\n", k);
            return;
        }
        fmi2DoStep_(c, 0.0, 0.001, fmi2True);
        fmi2Terminate_(c);
        fmi2FreeInstance_(c);
        if (k % every == 0) printf("rss %d %ld\n", k, rss_kib());
    }
    fflush(stdout);
}

/* A pythonfmu FMU of another author in this process, 10 steps; 1 if it ran. */
static int run_neighbour(const char *dir, const char *identifier, const char *other_guid) {
    char path[4096], location[4200];
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", dir, identifier);
    snprintf(location, sizeof location, "file://%s/resources", dir);
    void *other = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!other) {
        fprintf(stderr, "cannot load %s: %s\n", path, dlerror());
        return 0;
    }
    fmi2InstantiateTYPE *inst = (fmi2InstantiateTYPE *)dlsym(other, "fmi2Instantiate");
    fmi2SetupExperimentTYPE *setup = (fmi2SetupExperimentTYPE *)dlsym(other, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter = (fmi2EnterInitializationModeTYPE *)dlsym(other, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *leave = (fmi2ExitInitializationModeTYPE *)dlsym(other, "fmi2ExitInitializationMode");
    fmi2DoStepTYPE *step = (fmi2DoStepTYPE *)dlsym(other, "fmi2DoStep");
    fmi2FreeInstanceTYPE *release = (fmi2FreeInstanceTYPE *)dlsym(other, "fmi2FreeInstance");
    fmi2Component c = inst("neighbour", fmi2CoSimulation, other_guid, location, &callbacks, fmi2False, fmi2False);
    int ok = c && setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK && enter(c) == fmi2OK && leave(c) == fmi2OK;
    for (int k = 0; ok && k < 10; k++) ok = step(c, k * 0.01, 0.01, fmi2True) == fmi2OK;
    if (c) release(c);
    dlclose(other);
    return ok;
}

/* ------------------------------------------------------------------------------------ main */

int main(int argc, char **argv) {
    if (argc < 5) {
        fprintf(stderr, "usage: %s DIR IDENTIFIER GUID NAME=VR... MODE [ARG]\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1], *identifier = argv[2];
    guid = argv[3];
    char path[4096];
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", dir, identifier);
    snprintf(resources, sizeof resources, "file://%s/resources", dir);
    int k = 4;
    for (; k < argc && strchr(argv[k], '='); k++) {
        char name[64];
        unsigned int vr;
        if (sscanf(argv[k], "%63[^=]=%u", name, &vr) != 2) return 2;
#define NAMED(n, variable) if (strcmp(name, n) == 0) variable = vr;
        NAMED("phi1_0", PHI1_0) NAMED("m1", M1) NAMED("l1", L1) NAMED("solver", SOLVER) NAMED("phi1", PHI1)
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
    FMI2_ALL(RESOLVE)
    const char *mode = argv[k];
    if (strcmp(mode, "probes") == 0) run_probes(k + 1 < argc ? argv[k + 1] : NULL);
    else if (strcmp(mode, "threads") == 0 && k + 2 < argc) run_threads(atoi(argv[k + 1]), atoi(argv[k + 2]));
    else if (strcmp(mode, "soak") == 0 && k + 1 < argc) run_soak(atoi(argv[k + 1]));
    else if (strcmp(mode, "neighbour") == 0 && k + 3 < argc) {
        thread_case before = {.start = 1.3}, after = {.start = 1.3};
        run_case(&before);
        printf("neighbour-ran %d\n", run_neighbour(argv[k + 1], argv[k + 2], argv[k + 3]));
        run_case(&after);
        printf("neighbour-identical %d\n", !isnan(before.phi1) && before.phi1 == after.phi1);
    }
    else return 2;
    dlclose(library);
    printf("end\n");
    return 0;
}
