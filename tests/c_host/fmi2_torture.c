/* A torture host for the FMI 2.0 FMUs, in C, for the tests (tests/test_guard.py): every call a master
 * may get wrong, each on a fresh instance, with the status and the log lines it got. No Python in it.
 *
 *   fmi2_torture DIR IDENTIFIER GUID NAME=VR... MODE [ARG]
 *
 * DIR is an extracted FMU (binaries/linux64/IDENTIFIER.so), NAME=VR the value references the probes
 * use (phi1_0 m1 l1 solver phi1 pivot_ax air_drag fixed_step omega2_0); other_dir=DIR2 other_id=ID2
 * other_guid=GUID2 name another FMU for the probes foreign_resources*. MODE:
 *   probes [NAME]     run every probe (or the one named); print "probe NAME STATUS" and its log lines
 *                     "  log STATUS TEXT", then what it noted, "  info TEXT"; the probes marked OWN run
 *                     only when named (each in a process of its own)
 *   threads N ROUNDS  N threads at once instantiate, set a start value, run 20 steps, read phi1 and
 *                     free, ROUNDS times; then the same sequentially; print "threads-created K of M" and
 *                     "threads-identical 1" if every result equals the sequential one bit for bit
 *   soak N [EVERY]    N instantiate/initialise/step/free cycles; print "rss CYCLE KIB" every EVERY cycles
 *                     (default N/20)
 *   reload N [EVERY]  N cycles of dlopen, instantiate, free, dlclose; "rss CYCLE KIB" as soak (and at 50)
 *   fork N            a thread steps one instance while the main thread forks N times; each child steps that
 *                     instance (refused: it was inside a call in a thread the child lacks) and runs a new case;
 *                     print "fork-hung H", "fork-identical I" and the other counts of run_fork
 *   matrix            every FMI function with valid arguments in every state a fixed call sequence reaches,
 *                     each on a fresh instance: "matrix STATE FUNCTION STATUS" and its log lines
 *   neighbour DIR2 IDENTIFIER2 GUID2
 *                     run a case, then another FMU from DIR2 (a pythonfmu FMU of another author that uses
 *                     the same module names) for 10 steps, then the case again; print "neighbour-ran 1"
 *                     if the other FMU ran and "neighbour-identical 1" if both runs of the case agree
 * The host's logger formats the message with the arguments it is given, as a C host does: a message
 * passed as a format would crash it here. Exit status 0 if it got to the end. */
#include <dlfcn.h>
#include <sched.h>
#include <sys/wait.h>
#include <locale.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "fmi2Functions.h"
#include "host_common.h"

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
/* Counts beyond the FMU's variables: refused before a byte length is computed from them. 2^62 + 1 values of 8 bytes
 * wrap to 8 bytes, 2^62 to none: without the check the call answered OK having read or written one value or none. */
#define HUGE_COUNT (((size_t)1 << 62) + 1)
NULL_ARRAY_PROBE(get_real_huge_count, fmi2GetReal_(c, vr, HUGE_COUNT, r))
NULL_ARRAY_PROBE(set_real_huge_count, fmi2SetReal_(c, vr, HUGE_COUNT - 1, r))
NULL_ARRAY_PROBE(get_integer_huge_count, fmi2GetInteger_(c, vr, HUGE_COUNT, (fmi2Integer[2]){0}))
NULL_ARRAY_PROBE(get_string_huge_count, fmi2GetString_(c, vr, HUGE_COUNT, (fmi2String[2]){0}))
static int get_real_more_references_than_variables(void) { /* 1,000 names of one variable: more than it has */
    FRESH(c);
    fmi2ValueReference vr[1000];
    fmi2Real r[1000];
    for (size_t k = 0; k < 1000; k++) vr[k] = PHI1;
    int s = fmi2GetReal_(c, vr, 1000, r);
    fmi2FreeInstance_(c);
    return s;
}
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
/* The serialized state of `a` where it is now (malloc'ed, *size bytes). */
static fmi2Byte *serialized_now(fmi2Component a, size_t *size) {
    fmi2FMUstate state = NULL;
    *size = 0;
    fmi2GetFMUstate_(a, &state);
    fmi2SerializedFMUstateSize_(a, state, size);
    fmi2Byte *bytes = malloc(*size);
    fmi2SerializeFMUstate_(a, state, bytes, *size);
    return bytes;
}
/* A serialized state into a new instance: phi1 after one more step equals the original's (0, else -2). */
static int serialized_state_in_a_new_instance(void) {
    FRESH(a);
    fmi2DoStep_(a, 0.0, 0.5, fmi2True);
    size_t size;
    fmi2Byte *bytes = serialized_now(a, &size);
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
/* A state serialized after a step of 0.125 s, changed by `tamper`, deserialized in a fresh instance: the status.
 * The header (fmu_state.c) holds the time at byte 96 and the last successful time at byte 104; the payload is
 * the Python side's JSON, with "time": 0.125. */
static int deserialize_tampered(void (*tamper)(fmi2Byte *bytes, size_t size)) {
    FRESH(a);
    fmi2DoStep_(a, 0.0, 0.125, fmi2True);
    size_t size;
    fmi2Byte *bytes = serialized_now(a, &size);
    fmi2FreeInstance_(a);
    tamper(bytes, size);
    fmi2Component b = instantiate(fmi2False);
    fmi2FMUstate copy = NULL;
    int s = fmi2DeSerializeFMUstate_(b, bytes, size, &copy);
    free(bytes);
    fmi2FreeInstance_(b);
    return s;
}
static void header_time_huge(fmi2Byte *bytes, size_t size) {
    double huge = 1e308;
    (void)size;
    memcpy(bytes + 96, &huge, sizeof huge);
}
static void last_successful_time_after_time(fmi2Byte *bytes, size_t size) {
    double later = 1.0;
    (void)size;
    memcpy(bytes + 104, &later, sizeof later);
}
static void payload_time_huge(fmi2Byte *bytes, size_t size) {
    static const char key[] = "\"time\": 0.125";
    for (size_t k = 120; k + sizeof key - 1 <= size; k++)
        if (memcmp(bytes + k, key, sizeof key - 1) == 0) {
            memcpy(bytes + k + 8, "1e308", 5); /* as long as 0.125: the sizes still agree */
            return;
        }
}
static int tampered_state_header_time(void) { return deserialize_tampered(header_time_huge); }
static int tampered_state_last_successful_time(void) { return deserialize_tampered(last_successful_time_after_time); }
static int tampered_state_payload_time(void) { return deserialize_tampered(payload_time_huge); }
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

/* ------------------------------------------------- what the FMU leaves to the host (host-facing guarantees) */

/* What a probe noted besides its status: printed after its "probe" line as "  info TEXT". */
static char info[8192];
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

static double now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

/* The host never called setlocale: the process's locale is "C" whatever LANG says, before and after the
 * FMU starts Python in it (0 if it is "C" after instantiation and after free, else -2). */
static int locale_unchanged(void) {
    char before[256], after[256], freed[256];
    snprintf(before, sizeof before, "%s", setlocale(LC_ALL, NULL));
    fmi2Component c = instantiate(fmi2False);
    snprintf(after, sizeof after, "%s", setlocale(LC_ALL, NULL));
    fmi2FreeInstance_(c);
    snprintf(freed, sizeof freed, "%s", setlocale(LC_ALL, NULL));
    const char *lang = getenv("LANG"), *all = getenv("LC_ALL");
    note("LANG=%s LC_ALL=%s locale before=%s after-instantiate=%s after-free=%s", lang ? lang : "(unset)",
         all ? all : "(unset)", before, after, freed);
    return c && strcmp(before, "C") == 0 && strcmp(after, "C") == 0 && strcmp(freed, "C") == 0 ? 0 : -2;
}

static void host_handler(int signal) { (void)signal; }

/* Environment, signal dispositions and signal mask as the host set them (its own handlers on SIGINT and
 * SIGTERM, the defaults elsewhere), after instantiation, a step and free (0 if unchanged, else -2). */
static int host_state_unchanged(void) {
    static host_state before, after, freed; /* 64 KiB each: not on the stack */
    struct sigaction mine, old_int, old_term;
    memset(&mine, 0, sizeof mine);
    mine.sa_handler = host_handler;
    sigemptyset(&mine.sa_mask);
    sigaction(SIGINT, &mine, &old_int);
    sigaction(SIGTERM, &mine, &old_term);
    sigset_t mask_before, mask_after, mask_freed;
    pthread_sigmask(SIG_SETMASK, NULL, &mask_before);
    snapshot(&before);
    fmi2Component c = instantiate(fmi2False);
    int ok = c && fmi2SetupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK &&
             fmi2EnterInitializationMode_(c) == fmi2OK && fmi2ExitInitializationMode_(c) == fmi2OK &&
             fmi2DoStep_(c, 0.0, 0.01, fmi2True) == fmi2OK;
    snapshot(&after);
    pthread_sigmask(SIG_SETMASK, NULL, &mask_after);
    fmi2FreeInstance_(c);
    snapshot(&freed);
    pthread_sigmask(SIG_SETMASK, NULL, &mask_freed);
    int same_after = unchanged(&before, &after), same_freed = unchanged(&before, &freed);
    int same_mask = 1;
    for (int k = 1; k < 65; k++)
        same_mask &= sigismember(&mask_before, k) == sigismember(&mask_after, k) &&
                     sigismember(&mask_before, k) == sigismember(&mask_freed, k);
    for (size_t k = 0; k < N_SIGNALS; k++)
        if (before.actions[k].sa_handler != after.actions[k].sa_handler ||
            before.actions[k].sa_handler != freed.actions[k].sa_handler)
            note("signal %d: handler %p before, %p after instantiation, %p after free", SIGNALS[k],
                 (void *)before.actions[k].sa_handler, (void *)after.actions[k].sa_handler,
                 (void *)freed.actions[k].sa_handler);
    if (strcmp(before.environment, after.environment) != 0) note("the environment changed at instantiation");
    if (strcmp(before.environment, freed.environment) != 0) note("the environment changed by free");
    for (int k = 1; k < 65; k++)
        if (sigismember(&mask_before, k) != sigismember(&mask_after, k) ||
            sigismember(&mask_before, k) != sigismember(&mask_freed, k))
            note("signal %d (%s): blocked %d before, %d after instantiation, %d after free", k, strsignal(k),
                 sigismember(&mask_before, k), sigismember(&mask_after, k), sigismember(&mask_freed, k));
    note("stepped %d environment-and-handlers unchanged %d %d mask unchanged %d", ok, same_after, same_freed,
         same_mask);
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    return ok && same_after && same_freed && same_mask ? 0 : -2;
}

/* stdio's locks, tried from another thread (a FILE lock is recursive: the thread holding it would get it). */
typedef struct {
    int err, out;
} lock_try;
static void *try_stdio_locks(void *data) {
    lock_try *t = data;
    t->err = ftrylockfile(stderr);
    if (t->err == 0) funlockfile(stderr);
    t->out = ftrylockfile(stdout);
    if (t->out == 0) funlockfile(stdout);
    return NULL;
}
/* After fmi2Instantiate returns, stderr and stdout are not locked (0 if another thread gets both). */
static int stdio_unlocked_after_instantiate(void) {
    fmi2Component c = instantiate(fmi2False);
    lock_try t = {-1, -1};
    pthread_t thread;
    pthread_create(&thread, NULL, try_stdio_locks, &t);
    pthread_join(thread, NULL);
    fmi2FreeInstance_(c);
    note("ftrylockfile from another thread after fmi2Instantiate: stderr %d stdout %d", t.err, t.out);
    return c && t.err == 0 && t.out == 0 ? 0 : -2;
}

/* A thread that writes to stderr in a loop, each line with its time, while the host instantiates. */
#define MAX_WRITES 400000
static volatile int writer_running;
static double *write_times;
static int n_writes;
static void *stderr_writer(void *unused) {
    (void)unused;
    while (writer_running && n_writes < MAX_WRITES) {
        fprintf(stderr, "stderr-writer %.3f ms\n", now_ms());
        write_times[n_writes++] = now_ms();
        usleep(500);
    }
    return NULL;
}
/* (Own process: its lines go to stderr.) The longest time between two of the writer's lines while the
 * first fmi2Instantiate of the process runs ("  info gap-ms G instantiate-ms T writes N"); 0 if the
 * writer wrote during the instantiation, else -2 (the test compares G with T). */
static int stderr_writable_while_instantiating(void) {
    write_times = calloc(MAX_WRITES, sizeof *write_times);
    writer_running = 1;
    pthread_t thread;
    pthread_create(&thread, NULL, stderr_writer, NULL);
    usleep(20000);
    double start = now_ms();
    fmi2Component c = instantiate(fmi2False);
    double end = now_ms();
    usleep(20000);
    writer_running = 0;
    pthread_join(thread, NULL);
    double gap = 0, last = start;
    int inside = 0;
    for (int k = 0; k < n_writes; k++) {
        double t = write_times[k];
        if (t < start) continue;
        double until = t < end ? t : end;
        if (until - last > gap) gap = until - last;
        if (t >= end) break;
        last = t, inside++;
    }
    if (end - last > gap) gap = end - last;
    note("gap-ms %.3f instantiate-ms %.3f writes %d", gap, end - start, inside);
    fmi2FreeInstance_(c);
    free(write_times);
    return c && inside > 0 ? 0 : -2;
}

/* ---------------------------------------------------------------- folders, URIs, another FMU's resources */

static const char *fmu_dir;                                 /* DIR */
static const char *other_dir, *other_identifier, *other_guid; /* other_dir= other_id= other_guid= */

/* `path` as a file URI, every byte but unreserved ones and '/' %-escaped. */
static void file_uri(const char *path, char *uri, size_t size) {
    size_t n = (size_t)snprintf(uri, size, "file://");
    for (const unsigned char *p = (const unsigned char *)path; *p && n + 4 < size; p++) {
        if ((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || strchr("/-._~", *p))
            uri[n++] = (char)*p;
        else
            n += (size_t)snprintf(uri + n, size - n, "%%%02X", *p);
    }
    uri[n] = '\0';
}

/* Instantiate with `location`, initialise, 10 steps, free: the first status that is not OK (0 if none,
 * -1 if no instance). */
static int run_at(const char *location) {
    fmi2Component c = fmi2Instantiate_("t", fmi2CoSimulation, guid, location, &callbacks, fmi2False, fmi2False);
    if (!c) return -1;
    int s = fmi2SetupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    if (s == fmi2OK) s = fmi2EnterInitializationMode_(c);
    if (s == fmi2OK) s = fmi2ExitInitializationMode_(c);
    for (int k = 0; s == fmi2OK && k < 10; k++) s = fmi2DoStep_(c, k * 0.01, 0.01, fmi2True);
    fmi2FreeInstance_(c);
    return s;
}
/* The FMU in DIR (a folder with non-ASCII bytes in its name, for the test), its resources named as a
 * %-escaped file URI, as a file URI with the bytes as they are, and as a plain path: 1 if every one
 * instantiates and steps, else 0. */
static int non_ascii_folder(void) {
    char escaped[8192], raw[8192], plain[8192], folder[4200];
    snprintf(folder, sizeof folder, "%s/resources", fmu_dir);
    file_uri(folder, escaped, sizeof escaped);
    snprintf(raw, sizeof raw, "file://%s", folder);
    snprintf(plain, sizeof plain, "%s", folder);
    int a = run_at(escaped), b = run_at(raw), d = run_at(plain);
    note("escaped %s: %d; raw %s: %d; plain path: %d", escaped, a, raw, b, d);
    return a == 0 && b == 0 && d == 0;
}

/* (Own process: other_dir=, other_id=, other_guid= name the Suspension FMU.) This FMU's GUID with the
 * other FMU's resources: refused (0 for NULL). */
static int foreign_resources(void) {
    if (!other_dir) return -3;
    char location[4200];
    snprintf(location, sizeof location, "file://%s/resources", other_dir);
    return instance_or_null(fmi2Instantiate_("t", fmi2CoSimulation, guid, location, &callbacks, 0, 0));
}
/* The other FMU's binary and GUID with this FMU's resources: refused (0 for NULL). */
static int foreign_resources_reverse(void) {
    if (!other_dir || !other_identifier || !other_guid) return -3;
    char path[4200];
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", other_dir, other_identifier);
    void *other = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!other) return -4;
    fmi2InstantiateTYPE *inst = (fmi2InstantiateTYPE *)dlsym(other, "fmi2Instantiate");
    fmi2FreeInstanceTYPE *release = (fmi2FreeInstanceTYPE *)dlsym(other, "fmi2FreeInstance");
    fmi2Component c = inst("t", fmi2CoSimulation, other_guid, resources, &callbacks, 0, 0);
    if (c) release(c);
    dlclose(other);
    return c ? 1 : 0;
}

/* ------------------------------------------------------------------------------ reentrant loggers */

/* What every logger of the probes records. */
static void record_log(int status, const char *text) {
    pthread_mutex_lock(&log_lock);
    if (n_logs < MAX_LOGS) {
        snprintf(logs[n_logs], LOG_SIZE, "%s", text);
        for (char *p = logs[n_logs]; *p; p++)
            if (*p == '\n') *p = ' ';
        log_status[n_logs++] = status;
    }
    pthread_mutex_unlock(&log_lock);
}
#define FORMAT_MESSAGE(text)                                                                                      \
    char text[LOG_SIZE];                                                                                          \
    va_list args_;                                                                                                \
    va_start(args_, message);                                                                                     \
    vsnprintf(text, sizeof text, message, args_);                                                                 \
    va_end(args_)

/* A logger that, while an error is logged, instantiates (valid arguments), steps and frees an instance. */
static int inner_made = -1, inner_stepped = -1;
static void instantiating_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                                 fmi2String category, fmi2String message, ...) {
    (void)env, (void)instance, (void)category;
    FORMAT_MESSAGE(text);
    record_log((int)status, text);
    static int depth;
    if (status != fmi2Error || depth) return;
    depth++;
    fmi2Component inner = instantiate(fmi2False);
    inner_made = inner != NULL;
    if (inner) {
        inner_stepped = fmi2SetupExperiment_(inner, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK &&
                        fmi2EnterInitializationMode_(inner) == fmi2OK &&
                        fmi2ExitInitializationMode_(inner) == fmi2OK && fmi2DoStep_(inner, 0.0, 0.01, fmi2True) == fmi2OK;
        fmi2FreeInstance_(inner);
    }
    depth--;
}
/* A wrong GUID whose error line reaches that logger: 0 if the instantiation was refused and the logger's
 * own instance was made and stepped, else -2 (alarm: a hang ends the host). */
static int reentrant_logger_instantiates(void) {
    const fmi2CallbackFunctions mine = {instantiating_logger, calloc, free, NULL, NULL};
    inner_made = inner_stepped = -1;
    alarm(60);
    fmi2Component c = fmi2Instantiate_("outer", fmi2CoSimulation, "{wrong}", resources, &mine, 0, 0);
    alarm(0);
    note("outer %s, inner instantiated %d stepped %d", c ? "instantiated" : "NULL", inner_made, inner_stepped);
    if (c) fmi2FreeInstance_(c);
    return !c && inner_made == 1 && inner_stepped == 1 ? 0 : -2;
}

/* A logger that frees the very instance whose error it is given (its environment points to it). */
static int freed_by_logger;
static void freeing_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                           fmi2String message, ...) {
    (void)instance, (void)category;
    FORMAT_MESSAGE(text);
    record_log((int)status, text);
    fmi2Component *target = env;
    if (status == fmi2Error && *target) {
        fmi2Component c = *target;
        *target = NULL;
        fmi2FreeInstance_(c);
        freed_by_logger++;
    }
}
/* The status of the call whose error the logger answers by freeing the instance (the instance is not used
 * after), -2 if the logger was not called once. */
static fmi2Component freeing_target;
static const fmi2CallbackFunctions freeing_callbacks = {freeing_logger, calloc, free, NULL, &freeing_target};
static int reentrant_logger_frees_during_set_real(void) {
    freed_by_logger = 0;
    alarm(60);
    freeing_target = fmi2Instantiate_("freed", fmi2CoSimulation, guid, resources, &freeing_callbacks, 0, 0);
    fmi2Component c = freeing_target;
    if (!c) return -1;
    fmi2Real v = NAN;
    int s = fmi2SetReal_(c, &PHI1_0, 1, &v); /* an error of the Python side, logged after the call */
    alarm(0);
    if (freeing_target) fmi2FreeInstance_(freeing_target), freeing_target = NULL;
    return freed_by_logger == 1 ? s : -2;
}
static int reentrant_logger_frees_during_illegal_call(void) {
    freed_by_logger = 0;
    alarm(60);
    freeing_target = fmi2Instantiate_("freed", fmi2CoSimulation, guid, resources, &freeing_callbacks, 0, 0);
    fmi2Component c = freeing_target;
    if (!c) return -1;
    int s = fmi2DoStep_(c, 0.0, 0.01, fmi2True); /* the state machine's error, logged by the loader */
    alarm(0);
    if (freeing_target) fmi2FreeInstance_(freeing_target), freeing_target = NULL;
    return freed_by_logger == 1 ? s : -2;
}

/* A logger that frees an FMU state when the FMU's debug line about a state arrives (logAll): the call that
 * uses the state must not read it afterwards (ASan's session checks that), and must say it was freed. */
static fmi2Component state_owner;
static fmi2FMUstate state_to_free;
static int states_freed_by_logger;
static void state_freeing_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                                 fmi2String category, fmi2String message, ...) {
    (void)env, (void)instance, (void)category;
    FORMAT_MESSAGE(text);
    record_log((int)status, text);
    if (status == fmi2OK && state_to_free && strstr(text, "FMU state")) {
        fmi2FMUstate s = state_to_free;
        state_to_free = NULL;
        if (fmi2FreeFMUstate_(state_owner, &s) == fmi2OK && !s) states_freed_by_logger++;
    }
}
static const fmi2CallbackFunctions state_freeing_callbacks = {state_freeing_logger, calloc, free, NULL, NULL};
/* An instance logging everything, stepped to 0.125 s, its state in *state: NULL if it cannot be made. */
static fmi2Component logging_everything(fmi2FMUstate *state) {
    fmi2Component c = fmi2Instantiate_("states", fmi2CoSimulation, guid, resources, &state_freeing_callbacks, 0, 1);
    if (!c) return NULL;
    fmi2String all[] = {"logAll"};
    fmi2SetDebugLogging_(c, fmi2True, 1, all);
    fmi2SetupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode_(c);
    fmi2ExitInitializationMode_(c);
    fmi2DoStep_(c, 0.0, 0.125, fmi2True);
    *state = NULL;
    if (fmi2GetFMUstate_(c, state) != fmi2OK) return fmi2FreeInstance_(c), NULL;
    return c;
}
/* The status of `call` on a state the logger frees during it; -2 unless the logger freed it exactly once. */
#define STATE_FREED_DURING(name, call)                                                                            \
    static int name(void) {                                                                                       \
        fmi2FMUstate state;                                                                                       \
        fmi2Component c = logging_everything(&state);                                                            \
        if (!c) return -1;                                                                                        \
        size_t size = 0;                                                                                          \
        fmi2Byte bytes[64];                                                                                       \
        (void)size, (void)bytes;                                                                                  \
        state_owner = c, state_to_free = state, states_freed_by_logger = 0;                                       \
        int s = call;                                                                                             \
        state_to_free = NULL;                                                                                     \
        fmi2FreeInstance_(c);                                                                                     \
        return states_freed_by_logger == 1 ? s : -2;                                                              \
    }
STATE_FREED_DURING(logger_frees_the_state_during_serialized_size, fmi2SerializedFMUstateSize_(c, state, &size))
STATE_FREED_DURING(logger_frees_the_state_during_get_state, fmi2GetFMUstate_(c, &state))
STATE_FREED_DURING(logger_frees_the_state_during_set_state, fmi2SetFMUstate_(c, state))

/* ---------------------------------------------------------------------------------- large times */

/* Start time 1e9 s: a doStep half a second off is refused, with both times in full. */
static int large_start_time_wrong_point(void) {
    fmi2Component c = instantiate(fmi2False);
    fmi2SetupExperiment_(c, fmi2False, 0.0, 1e9, fmi2False, 0.0);
    fmi2EnterInitializationMode_(c);
    fmi2ExitInitializationMode_(c);
    int s = fmi2DoStep_(c, 1e9 + 0.5, 0.01, fmi2True);
    fmi2FreeInstance_(c);
    return s;
}
/* 100 steps of 1 ms from 1e9 s, the host's time a sum t += h: the first status that is not OK (0 if none). */
static int large_start_time_steps(void) {
    fmi2Component c = instantiate(fmi2False);
    fmi2SetupExperiment_(c, fmi2False, 0.0, 1e9, fmi2False, 0.0);
    fmi2EnterInitializationMode_(c);
    fmi2ExitInitializationMode_(c);
    int s = fmi2OK, k = 0;
    double t = 1e9, h = 0.001, last = -1;
    for (; k < 100 && s == fmi2OK; k++, t += h) s = fmi2DoStep_(c, t, h, fmi2True);
    fmi2GetRealStatus_(c, fmi2LastSuccessfulTime, &last);
    note("steps %d host t %.17g FMU lastSuccessfulTime %.17g", k, t, last);
    fmi2FreeInstance_(c);
    return s;
}

/* ------------------------------------------------------------------------------------ FMU states */

/* fmu_state.c's state_header, as a host sees its bytes: what comes before the Python side's JSON. */
typedef struct {
    char magic[8], token[64], interface[16];
    int32_t state, wants_to_terminate;
    double time, last_successful_time;
    uint64_t payload_size;
} state_header_view;
#define STATE_HEADER sizeof(state_header_view)

/* The serialized form of a state of an instance after one step (malloc'ed; NULL on failure). */
static fmi2Byte *serialized_after_a_step(fmi2Component c, size_t *size) {
    fmi2FMUstate state = NULL;
    fmi2DoStep_(c, 0.0, 0.25, fmi2True);
    if (fmi2GetFMUstate_(c, &state) != fmi2OK || fmi2SerializedFMUstateSize_(c, state, size) != fmi2OK) return NULL;
    fmi2Byte *bytes = malloc(*size);
    if (fmi2SerializeFMUstate_(c, state, bytes, *size) != fmi2OK) return free(bytes), NULL;
    fmi2FreeFMUstate_(c, &state);
    return bytes;
}
/* The offset of the first digit of a number in the JSON after the header (one of the state's numbers). */
static size_t first_number(const fmi2Byte *bytes, size_t size) {
    for (size_t k = STATE_HEADER + 1; k < size; k++)
        if (bytes[k] >= '0' && bytes[k] <= '9' && strchr("[ ,:-", bytes[k - 1])) return k;
    return 0;
}
/* Deserialise `size` bytes into a new state of c: the status. */
static int deserialize(fmi2Component c, const fmi2Byte *bytes, size_t size) {
    fmi2FMUstate state = NULL;
    int s = fmi2DeSerializeFMUstate_(c, bytes, size, &state);
    if (state) fmi2FreeFMUstate_(c, &state);
    return s;
}
/* A digit of the JSON replaced by a letter. */
static int tampered_state_payload(void) {
    FRESH(c);
    size_t size = 0;
    fmi2Byte *bytes = serialized_after_a_step(c, &size);
    size_t at = bytes ? first_number(bytes, size) : 0;
    if (!at) return fmi2FreeInstance_(c), free(bytes), -3;
    note("header %zu bytes, payload starts with '%c', digit at %zu replaced", STATE_HEADER, bytes[STATE_HEADER], at);
    bytes[at] = 'x';
    int s = deserialize(c, bytes, size);
    free(bytes);
    fmi2FreeInstance_(c);
    return s;
}
/* Valid JSON of the wrong shape: a number of the state replaced by a string, the header's size adjusted. */
static int tampered_state_wrong_type(void) {
    FRESH(c);
    size_t size = 0;
    fmi2Byte *bytes = serialized_after_a_step(c, &size);
    size_t at = bytes ? first_number(bytes, size) : 0;
    if (!at) return fmi2FreeInstance_(c), free(bytes), -3;
    size_t end = at;
    while (end < size && strchr("0123456789.eE+-", bytes[end])) end++;
    fmi2Byte *changed = malloc(size + 8);
    memcpy(changed, bytes, at);
    memcpy(changed + at, "\"x\"", 3);
    memcpy(changed + at + 3, bytes + end, size - end);
    size_t new_size = at + 3 + (size - end);
    state_header_view header;
    memcpy(&header, changed, sizeof header);
    header.payload_size = new_size - STATE_HEADER;
    memcpy(changed, &header, sizeof header);
    int s = deserialize(c, changed, new_size);
    free(bytes), free(changed);
    fmi2FreeInstance_(c);
    return s;
}
/* The last 10 bytes cut off. */
static int tampered_state_truncated(void) {
    FRESH(c);
    size_t size = 0;
    fmi2Byte *bytes = serialized_after_a_step(c, &size);
    if (!bytes) return fmi2FreeInstance_(c), -3;
    int s = deserialize(c, bytes, size - 10);
    free(bytes);
    fmi2FreeInstance_(c);
    return s;
}
/* Cut inside the header. */
static int tampered_state_truncated_header(void) {
    FRESH(c);
    size_t size = 0;
    fmi2Byte *bytes = serialized_after_a_step(c, &size);
    if (!bytes) return fmi2FreeInstance_(c), -3;
    int s = deserialize(c, bytes, STATE_HEADER - 20);
    free(bytes);
    fmi2FreeInstance_(c);
    return s;
}

/* Instance A's FMU state given to instance B: B's status, if A can still set, size, serialise and free it
 * afterwards (else -2). WHAT is B's call. */
#define ANOTHER_INSTANCE_PROBE(name, WHAT)                                                                        \
    static int name(void) {                                                                                       \
        FRESH(a);                                                                                                 \
        FRESH(b);                                                                                                 \
        fmi2FMUstate state = NULL;                                                                                \
        size_t size = 0;                                                                                          \
        fmi2GetFMUstate_(a, &state);                                                                              \
        int s = WHAT;                                                                                             \
        int usable = state && fmi2SetFMUstate_(a, state) == fmi2OK &&                                             \
                     fmi2SerializedFMUstateSize_(a, state, &size) == fmi2OK && size > STATE_HEADER &&              \
                     fmi2DoStep_(a, 0.0, 0.01, fmi2True) == fmi2OK && fmi2FreeFMUstate_(a, &state) == fmi2OK &&    \
                     state == NULL;                                                                               \
        fmi2FreeInstance_(a);                                                                                     \
        fmi2FreeInstance_(b);                                                                                     \
        return usable ? s : -2;                                                                                   \
    }
ANOTHER_INSTANCE_PROBE(state_of_another_instance_set, fmi2SetFMUstate_(b, state))
ANOTHER_INSTANCE_PROBE(state_of_another_instance_free, fmi2FreeFMUstate_(b, &state))
ANOTHER_INSTANCE_PROBE(state_of_another_instance_size, fmi2SerializedFMUstateSize_(b, state, &size))

/* ------------------------------------------------------------------------------------ the matrix */

/* Every function with valid arguments in every state of the co-simulation state machine that a fixed call
 * sequence reaches, each on a fresh instance: "matrix STATE FUNCTION STATUS" and its log lines. */
enum { M_INSTANTIATED, M_INITIALIZATION, M_STEP_COMPLETE, M_STEP_FAILED, M_TERMINATED, M_ERROR, M_STATES };
static const char *const MATRIX_STATES[] = {"Instantiated", "InitializationMode", "StepComplete", "StepFailed",
                                            "Terminated", "Error"};

typedef struct {
    fmi2Component c;
    int state;
    double t;            /* the FMU's time: where the next doStep starts */
    fmi2FMUstate fmu;    /* a state of this instance, got in Instantiated */
    size_t fmu_size;     /* its serialized size */
} cell;

static fmi2Byte *matrix_bytes; /* a serialized state of another instance, in Instantiated */
static size_t matrix_bytes_size;

/* A fresh instance in `state` (c NULL if the sequence did not get there). */
static cell reach(int state) {
    cell x = {instantiate(fmi2False), state, 0.0, NULL, 0};
    if (!x.c) return x;
    int ok = fmi2GetFMUstate_(x.c, &x.fmu) == fmi2OK && fmi2SerializedFMUstateSize_(x.c, x.fmu, &x.fmu_size) == fmi2OK;
    if (state == M_STEP_FAILED) {
        ok = ok && step_until_discard(x.c, &x.t) == fmi2Discard;
    } else if (state != M_INSTANTIATED) {
        ok = ok && fmi2SetupExperiment_(x.c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK &&
             fmi2EnterInitializationMode_(x.c) == fmi2OK;
        if (state >= M_STEP_COMPLETE) ok = ok && fmi2ExitInitializationMode_(x.c) == fmi2OK;
        if (state == M_TERMINATED)
            ok = ok && fmi2DoStep_(x.c, 0.0, 0.01, fmi2True) == fmi2OK && fmi2Terminate_(x.c) == fmi2OK, x.t = 0.01;
        if (state == M_ERROR) ok = ok && fmi2DoStep_(x.c, 0.0, -1.0, fmi2True) == fmi2Error;
    }
    if (!ok) fmi2FreeInstance_(x.c), x.c = NULL;
    return x;
}

static const char *const MATRIX_FUNCTIONS[] = {
    "fmi2SetDebugLogging", "fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode",
    "fmi2Terminate", "fmi2Reset", "fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2GetString",
    "fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean", "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate",
    "fmi2FreeFMUstate", "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative", "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives",
    "fmi2DoStep", "fmi2CancelStep", "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus", "fmi2GetStringStatus", NULL};

/* Function `f` of the matrix on x, with valid arguments for x's state where there are any. */
static int matrix_call(int f, cell *x) {
    fmi2Component c = x->c;
    /* before initialisation a parameter (initial = exact), after it an input (FMI 2.0.4, 4.2.4: conditions
     * 1, 3 and 6); Boolean and String variables are parameters only: none to set after initialisation */
    int early = x->state == M_INSTANTIATED || x->state == M_INITIALIZATION;
    fmi2ValueReference real_vr = early ? PHI1_0 : PIVOT_AX;
    fmi2Real real = early ? 1.0 : 0.1, r = 0, dv = 1;
    fmi2Integer i = 0, order = 1;
    fmi2Boolean b = fmi2False;
    fmi2String text = "dop853";
    fmi2String categories[] = {"logStatusError"};
    fmi2Status st;
    size_t n = 0;
    fmi2FMUstate fresh = NULL;
    size_t named = x->state == M_INITIALIZATION ? 0 : 1; /* Initialization Mode: outputs only (condition 2) */
    switch (f) {
    case 0: return fmi2SetDebugLogging_(c, fmi2True, 1, categories);
    case 1: return fmi2SetupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    case 2: return fmi2EnterInitializationMode_(c);
    case 3: return fmi2ExitInitializationMode_(c);
    case 4: return fmi2Terminate_(c);
    case 5: return fmi2Reset_(c);
    case 6: return fmi2GetReal_(c, &PHI1, 1, &r);
    case 7: return fmi2GetInteger_(c, &PHI1, 0, &i); /* no Integer variables */
    case 8: return fmi2GetBoolean_(c, &AIR_DRAG, named, &b);
    case 9: return fmi2GetString_(c, &SOLVER, named, &text);
    case 10: return fmi2SetReal_(c, &real_vr, 1, &real);
    case 11: return fmi2SetInteger_(c, &PHI1_0, 0, &i);
    case 12: return fmi2SetBoolean_(c, &AIR_DRAG, early ? 1 : 0, &b);
    case 13: return fmi2SetString_(c, &SOLVER, early ? 1 : 0, &text);
    case 14: {
        int s = fmi2GetFMUstate_(c, &fresh);
        if (fresh) fmi2FreeFMUstate_(c, &fresh);
        return s;
    }
    case 15: return fmi2SetFMUstate_(c, x->fmu);
    case 16: return fmi2FreeFMUstate_(c, &x->fmu);
    case 17: return fmi2SerializedFMUstateSize_(c, x->fmu, &n);
    case 18: {
        fmi2Byte *bytes = malloc(x->fmu_size);
        int s = fmi2SerializeFMUstate_(c, x->fmu, bytes, x->fmu_size);
        free(bytes);
        return s;
    }
    case 19: {
        int s = fmi2DeSerializeFMUstate_(c, matrix_bytes, matrix_bytes_size, &fresh);
        if (fresh) fmi2FreeFMUstate_(c, &fresh);
        return s;
    }
    case 20: return fmi2GetDirectionalDerivative_(c, &PHI1, 1, &PIVOT_AX, 1, &dv, &r);
    case 21: return fmi2SetRealInputDerivatives_(c, &PIVOT_AX, 1, &order, &dv);
    case 22: return fmi2GetRealOutputDerivatives_(c, &PHI1, 1, &order, &r);
    case 23: return fmi2DoStep_(c, x->t, 0.01, fmi2True);
    case 24: return fmi2CancelStep_(c);
    case 25: return fmi2GetStatus_(c, fmi2DoStepStatus, &st);
    case 26: return fmi2GetRealStatus_(c, fmi2LastSuccessfulTime, &r);
    case 27: return fmi2GetIntegerStatus_(c, fmi2DoStepStatus, &i);
    case 28: return fmi2GetBooleanStatus_(c, fmi2Terminated, &b);
    case 29: return fmi2GetStringStatus_(c, fmi2PendingStatus, &text);
    }
    return -100;
}

static void run_matrix(void) {
    cell helper = reach(M_INSTANTIATED);
    if (helper.c && helper.fmu) {
        matrix_bytes_size = helper.fmu_size;
        matrix_bytes = malloc(matrix_bytes_size);
        fmi2SerializeFMUstate_(helper.c, helper.fmu, matrix_bytes, matrix_bytes_size);
        fmi2FreeInstance_(helper.c);
    }
    for (int state = 0; state < M_STATES; state++) {
        for (int f = 0; MATRIX_FUNCTIONS[f]; f++) {
            cell x = reach(state);
            n_logs = 0;
            int s = x.c ? matrix_call(f, &x) : -9; /* -9: the state was not reached */
            printf("matrix %s %s %d\n", MATRIX_STATES[state], MATRIX_FUNCTIONS[f], s);
            for (int j = 0; j < n_logs; j++) printf("  log %d %s\n", log_status[j], logs[j]);
            fflush(stdout);
            if (x.c) fmi2FreeInstance_(x.c);
        }
    }
    free(matrix_bytes);
}

/* A probe with `own` set runs only when named: in a process of its own (the first instantiation of the
 * process, an environment of its own, stderr output, or arguments the other probes do not get). */
static const struct {
    const char *name;
    probe_fn run;
    int own;
} PROBES[] = {
#define P(name) {#name, name, 0},
#define OWN(name) {#name, name, 1},
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
    P(get_real_huge_count) P(set_real_huge_count) P(get_integer_huge_count) P(get_string_huge_count)
    P(get_real_more_references_than_variables)
    P(set_string_null_element) P(set_string_not_utf8) P(debug_logging_null_categories) P(debug_logging_unknown_category)
    P(debug_logging_null_category) P(errors_silenced_by_set_debug_logging) P(get_fmu_state_null)
    P(set_fmu_state_null) P(set_fmu_state_foreign_pointer) P(free_fmu_state_null_pointer)
    P(free_fmu_state_null_state) P(serialized_size_null) P(deserialize_garbage) P(deserialize_null_bytes)
    P(real_status_null_value) P(real_status_unknown_kind) P(status_kind_not_given) P(last_successful_time)
    P(directional_derivative) P(input_derivatives) P(output_derivatives) P(cancel_step) P(null_instance_do_step)
    P(null_instance_set_real) P(null_instance_free) P(freed_instance_used) P(freed_twice)
    P(fmu_state_restores_the_time) P(serialized_state_in_a_new_instance) P(tampered_state_header_time) P(tampered_state_last_successful_time)
    P(tampered_state_payload_time) P(discarded_step_then_terminate) P(do_step_after_discard)
    P(locale_unchanged) P(host_state_unchanged) P(stdio_unlocked_after_instantiate)
    OWN(stderr_writable_while_instantiating) P(non_ascii_folder) OWN(foreign_resources)
    OWN(foreign_resources_reverse) P(reentrant_logger_instantiates) P(reentrant_logger_frees_during_set_real)
    P(reentrant_logger_frees_during_illegal_call) P(logger_frees_the_state_during_serialized_size)
    P(logger_frees_the_state_during_get_state) P(logger_frees_the_state_during_set_state) P(large_start_time_wrong_point) P(large_start_time_steps)
    P(tampered_state_payload) P(tampered_state_wrong_type) P(tampered_state_truncated)
    P(tampered_state_truncated_header) P(state_of_another_instance_set) P(state_of_another_instance_free)
    P(state_of_another_instance_size)
#undef P
#undef OWN
};

/* Every probe, or only the one named `only` (not NULL). */
static void run_probes(const char *only) {
    for (size_t k = 0; k < sizeof PROBES / sizeof PROBES[0]; k++) {
        if (only ? strcmp(only, PROBES[k].name) != 0 : PROBES[k].own) continue;
        n_logs = 0;
        info[0] = '\0';
        int status = PROBES[k].run();
        printf("probe %s %d\n", PROBES[k].name, status);
        for (int j = 0; j < n_logs; j++) printf("  log %d %s\n", log_status[j], logs[j]);
        fputs(info, stdout);
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

/* ------------------------------------------------------------------------------------ fork */

#define FORK_WAIT_S 60 /* a child that has not ended by then hangs (it is killed) */

static fmi2Component busy_instance;
static volatile int busy_inside, busy_stop;

static void *keep_stepping(void *unused) {
    (void)unused;
    double t = 0.0;
    while (!busy_stop) {
        busy_inside = 1;
        int s = fmi2DoStep_(busy_instance, t, 0.5, fmi2True);
        busy_inside = 0;
        if (s != fmi2OK) break;
        t += 0.5;
    }
    return NULL;
}

/* In a child: the busy instance's time and next step (it was inside fmi2DoStep in a thread the child does not have,
 * unless the fork fell between two steps), then a new instance's case. Exit status: bit 0 the new case differs from `reference`, bit 1 the busy instance's step was
 * refused (Error) with a log line that says the process forked, bit 2 it was refused without that line. */
static void forked_child(double reference) {
    n_logs = 0;
    double t = NAN; /* where the busy instance is, if the fork fell between two of its steps */
    int s = fmi2GetRealStatus_(busy_instance, fmi2LastSuccessfulTime, &t);
    if (s == fmi2OK) s = fmi2DoStep_(busy_instance, t, 0.01, fmi2True);
    int said = 0;
    for (int k = 0; k < n_logs; k++) said |= strstr(logs[k], "forked") != NULL;
    thread_case fresh = {.start = 0.5};
    run_case(&fresh);
    int code = memcmp(&fresh.phi1, &reference, sizeof reference) != 0 || isnan(fresh.phi1);
    if (s == fmi2Error) code |= said ? 2 : 4;
    else if (s != fmi2OK) code |= 4;
    fmi2FreeInstance_(busy_instance);
    fflush(stdout);
    _exit(code);
}

/* fork N: a thread runs 0.5 s steps on one instance while the main thread forks N times, each time while that thread
 * is inside fmi2DoStep (or about to enter or leave it). Each child runs forked_child; the parent waits for it up to
 * FORK_WAIT_S and kills it if it has not ended. Prints "fork-children N", "fork-hung H" (killed), "fork-crashed C"
 * (ended by a signal), "fork-identical I" (the new case bit for bit as before the forks), "fork-refused R" (the busy
 * instance refused with its line) and "fork-bad B" (refused without a line, or another status). */
static void run_fork(int n) {
    thread_case reference = {.start = 0.5};
    run_case(&reference);
    busy_instance = initialised();
    pthread_t thread;
    if (!busy_instance || pthread_create(&thread, NULL, keep_stepping, NULL) != 0) {
        printf("fork-setup-failed 1\n");
        return;
    }
    int hung = 0, crashed = 0, identical = 0, refused = 0, bad = 0;
    for (int k = 0; k < n; k++) {
        while (!busy_inside) sched_yield();
        struct timespec pause = {0, 1000000L * (k % 5)}; /* 0 to 4 ms into the step */
        nanosleep(&pause, NULL);
        fflush(stdout);
        pid_t child = fork();
        if (child == 0) forked_child(reference.phi1);
        int status = 0, ended = 0;
        for (int waited = 0; child > 0 && waited < FORK_WAIT_S * 100 && !ended; waited++) {
            ended = waitpid(child, &status, WNOHANG) == child;
            if (!ended) nanosleep(&(struct timespec){0, 10000000L}, NULL);
        }
        if (child > 0 && !ended) {
            kill(child, SIGKILL);
            waitpid(child, &status, 0);
            hung++;
        } else if (child > 0 && WIFSIGNALED(status)) {
            crashed++;
        } else if (child > 0) {
            int code = WEXITSTATUS(status);
            identical += !(code & 1);
            refused += (code & 2) != 0;
            bad += (code & 4) != 0;
        }
    }
    busy_stop = 1;
    pthread_join(thread, NULL);
    fmi2FreeInstance_(busy_instance);
    printf("fork-children %d\nfork-hung %d\nfork-crashed %d\nfork-identical %d\nfork-refused %d\nfork-bad %d\n", n,
           hung, crashed, identical, refused, bad);
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

/* Cycles between "rss" lines: `every` if given (> 0), else N/20. */
static int rss_every(int cycles, int every) {
    return every > 0 ? every : cycles >= 20 ? cycles / 20 : 1;
}

static void run_soak(int cycles, int every) {
    every = rss_every(cycles, every);
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

/* N cycles of dlopen, fmi2Instantiate, fmi2FreeInstance, dlclose of the FMU's binary at `path` (the host
 * holds no other handle on it); print "rss CYCLE KIB" every `every` cycles (rss_every) and at cycle 50. */
static void run_reload(const char *path, int cycles, int every) {
    every = rss_every(cycles, every);
    for (int k = 1; k <= cycles; k++) {
        void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
        if (!library) {
            printf("reload-failed %d %s\n", k, dlerror());
            return;
        }
        fmi2InstantiateTYPE *inst = (fmi2InstantiateTYPE *)dlsym(library, "fmi2Instantiate");
        fmi2FreeInstanceTYPE *release = (fmi2FreeInstanceTYPE *)dlsym(library, "fmi2FreeInstance");
        fmi2Component c = inst("reload", fmi2CoSimulation, guid, resources, &callbacks, fmi2False, fmi2False);
        if (!c) {
            printf("reload-failed %d instantiate\n", k);
            return;
        }
        release(c);
        dlclose(library);
        if (k % every == 0 || k == 50) printf("rss %d %ld\n", k, rss_kib());
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
    fmu_dir = dir;
    guid = argv[3];
    char path[4096];
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", dir, identifier);
    snprintf(resources, sizeof resources, "file://%s/resources", dir);
    int k = 4;
    for (; k < argc && strchr(argv[k], '='); k++) {
        char name[64];
        unsigned int vr;
        if (strncmp(argv[k], "other_dir=", 10) == 0) { other_dir = argv[k] + 10; continue; }
        if (strncmp(argv[k], "other_id=", 9) == 0) { other_identifier = argv[k] + 9; continue; }
        if (strncmp(argv[k], "other_guid=", 11) == 0) { other_guid = argv[k] + 11; continue; }
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
    else if (strcmp(mode, "soak") == 0 && k + 1 < argc) run_soak(atoi(argv[k + 1]), k + 2 < argc ? atoi(argv[k + 2]) : 0);
    else if (strcmp(mode, "matrix") == 0) run_matrix();
    else if (strcmp(mode, "fork") == 0 && k + 1 < argc) run_fork(atoi(argv[k + 1]));
    else if (strcmp(mode, "reload") == 0 && k + 1 < argc) {
        dlclose(library); /* the cycles' handles are the only ones */
        library = NULL;
        run_reload(path, atoi(argv[k + 1]), k + 2 < argc ? atoi(argv[k + 2]) : 0);
    }
    else if (strcmp(mode, "neighbour") == 0 && k + 3 < argc) {
        thread_case before = {.start = 1.3}, after = {.start = 1.3};
        run_case(&before);
        printf("neighbour-ran %d\n", run_neighbour(argv[k + 1], argv[k + 2], argv[k + 3]));
        run_case(&after);
        printf("neighbour-identical %d\n", !isnan(before.phi1) && before.phi1 == after.phi1);
    }
    else return 2;
    if (library) dlclose(library);
    printf("end\n");
    return 0;
}
