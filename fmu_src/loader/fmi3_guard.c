/* The FMU's binary for FMI 3.0 (Model Exchange and Co-Simulation): a guard in front of pythonfmu3's
 * library, which lies beside it as libpythonfmu3-export.so (python_runtime.c makes a CPython
 * available first).  What it guarantees is what fmi2_guard.c does for FMI 2, after FMI 3.0
 * (sections 2.2.4, 3.2 and 4.2: the Model Exchange and Co-Simulation state machines): the state
 * machine of the interface the instance was made for, argument checks (NULL arrays, nValues against
 * the value references, String values that are not UTF-8, the step size and communication point, every
 * out-argument), instantiation checks (instantiation token, instance name, resource path), the host's
 * logger given text, errors logged from instantiation on, Error instead of pythonfmu3's Fatal,
 * instantiation and reset serialised across threads.  Where pythonfmu3 0.3.4 falls short it also stands in:
 *  - fmi3UpdateDiscreteStates, fmi3DoStep and fmi3CompletedIntegratorStep: every out-argument is
 *    given its "nothing to do" value first (pythonfmu3 leaves some unwritten, and a strict host that
 *    initialised discreteStatesNeedUpdate = true would iterate its Event Mode forever);
 *  - fmi3EnterInitializationMode: pythonfmu3 drops the start time, so the guard passes it on
 *    through fmi3SetTime first (the adapter takes it as the start time before initialisation);
 *  - what this FMU does not have (other variable types, clocks, binaries, structural parameters,
 *    dependencies, derivatives, Scheduled Execution, Event Mode in Co-Simulation): fmi3Error and a
 *    log line, where pythonfmu3 throws a C++ exception that aborts the host. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "guard.h"
#include "python_runtime.h"

#ifndef FMU_GUID
#error "the build defines FMU_GUID, the instantiationToken of the FMU's modelDescription.xml"
#endif
#ifndef MODEL_IDENTIFIER
#error "the build defines MODEL_IDENTIFIER"
#endif
#ifndef N_CONTINUOUS_STATES
#error "the build defines N_CONTINUOUS_STATES"
#endif
#define N_EVENT_INDICATORS 0 /* a smooth right-hand side (component/model_exchange.py) */

#define BACKEND_FILE "libpythonfmu3-export.so"
#define STATE_MAGIC "DPFMU3S1"

/* ------------------------------------------------------------------------ pythonfmu3's library */

#define FMI3_FORWARDED(X)                                                                                         \
    X(fmi3InstantiateModelExchange) X(fmi3InstantiateCoSimulation) X(fmi3FreeInstance)                           \
    X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode) X(fmi3EnterEventMode) X(fmi3Terminate)          \
    X(fmi3Reset) X(fmi3GetFloat64) X(fmi3GetInt32) X(fmi3GetInt64) X(fmi3GetUInt64) X(fmi3GetBoolean)             \
    X(fmi3GetString) X(fmi3SetFloat64) X(fmi3SetInt32) X(fmi3SetInt64) X(fmi3SetUInt64) X(fmi3SetBoolean)        \
    X(fmi3SetString) X(fmi3GetFMUState) X(fmi3SetFMUState) X(fmi3FreeFMUState) X(fmi3SerializedFMUStateSize)    \
    X(fmi3SerializeFMUState) X(fmi3DeserializeFMUState) X(fmi3UpdateDiscreteStates)                             \
    X(fmi3EnterContinuousTimeMode) X(fmi3CompletedIntegratorStep) X(fmi3SetTime) X(fmi3SetContinuousStates)      \
    X(fmi3GetContinuousStateDerivatives) X(fmi3GetEventIndicators) X(fmi3GetContinuousStates)                   \
    X(fmi3GetNominalsOfContinuousStates) X(fmi3EnterStepMode) X(fmi3DoStep)

#define DECLARE(name) static name##TYPE *backend_##name;
FMI3_FORWARDED(DECLARE)
static pthread_mutex_t resolve_lock = PTHREAD_MUTEX_INITIALIZER;
static int resolved;

static int resolve(void *backend, char *error, size_t size) {
    pthread_mutex_lock(&resolve_lock);
    if (!resolved) {
        error[0] = '\0';
#define RESOLVE(name)                                                                                             \
    backend_##name = (name##TYPE *)dlsym(backend, #name);                                                        \
    if (!backend_##name) guard_format(error, size, "pythonfmu3's library lacks %s", #name);
        FMI3_FORWARDED(RESOLVE)
        resolved = !error[0];
    }
    int ok = resolved;
    pthread_mutex_unlock(&resolve_lock);
    return ok;
}

/* Instantiation and reset run the Python side's imports and its sys.path hygiene: one at a time. */
static pthread_mutex_t python_lock = PTHREAD_MUTEX_INITIALIZER;

/* ----------------------------------------------------------------------------------- states */

enum {
    INSTANTIATED = 1 << 0,
    CONFIGURATION = 1 << 1,
    INITIALIZATION = 1 << 2,
    EVENT = 1 << 3,           /* Model Exchange */
    CONTINUOUS_TIME = 1 << 4, /* Model Exchange */
    STEP = 1 << 5,            /* Co-Simulation */
    STEP_DISCARDED = 1 << 6,  /* Co-Simulation: doStep returned fmi3Discard */
    TERMINATED = 1 << 7,
    ERROR_STATE = 1 << 8, /* a call returned fmi3Error */
};
#define ANY_STATE                                                                                                 \
    (INSTANTIATED | CONFIGURATION | INITIALIZATION | EVENT | CONTINUOUS_TIME | STEP | STEP_DISCARDED | TERMINATED | \
     ERROR_STATE)

static const char *state_name(int state) {
    switch (state) {
    case INSTANTIATED: return "Instantiated";
    case CONFIGURATION: return "Configuration Mode";
    case INITIALIZATION: return "Initialization Mode";
    case EVENT: return "Event Mode";
    case CONTINUOUS_TIME: return "Continuous-Time Mode";
    case STEP: return "Step Mode";
    case STEP_DISCARDED: return "Step Mode after fmi3Discard";
    case TERMINATED: return "Terminated";
    default: return "Error (after fmi3Error: only get, FMU states, reset and free)";
    }
}

/* Where each function may be called (FMI 3.0.2: 3.2 Model Exchange, 4.2 Co-Simulation). */
#define MASK_SetDebugLogging ANY_STATE
#define MASK_EnterInitializationMode INSTANTIATED
#define MASK_ExitInitializationMode INITIALIZATION
#define MASK_EnterEventMode CONTINUOUS_TIME /* Co-Simulation: Event Mode is not offered */
#define MASK_Terminate (EVENT | CONTINUOUS_TIME | STEP | STEP_DISCARDED)
#define MASK_Reset ANY_STATE
#define MASK_GET (CONFIGURATION | INITIALIZATION | EVENT | CONTINUOUS_TIME | STEP | STEP_DISCARDED | TERMINATED | \
                  ERROR_STATE)
#define MASK_SET_FLOAT64 (INSTANTIATED | CONFIGURATION | INITIALIZATION | EVENT | CONTINUOUS_TIME | STEP)
#define MASK_SET (INSTANTIATED | CONFIGURATION | INITIALIZATION | EVENT | STEP)
#define MASK_FMU_STATE ANY_STATE
#define MASK_DERIVATIVES (INITIALIZATION | EVENT | CONTINUOUS_TIME | STEP | STEP_DISCARDED | TERMINATED | ERROR_STATE)
#define MASK_EnterConfigurationMode INSTANTIATED
#define MASK_ExitConfigurationMode CONFIGURATION
#define MASK_UpdateDiscreteStates EVENT
#define MASK_EnterContinuousTimeMode EVENT
#define MASK_CompletedIntegratorStep CONTINUOUS_TIME
#define MASK_SetTime (EVENT | CONTINUOUS_TIME)
#define MASK_SetContinuousStates CONTINUOUS_TIME
#define MASK_STATE_VECTORS (INITIALIZATION | EVENT | CONTINUOUS_TIME | TERMINATED | ERROR_STATE)
#define MASK_NUMBERS ANY_STATE
#define MASK_EnterStepMode EVENT /* not reached: without Event Mode Co-Simulation goes to Step Mode */
#define MASK_GetOutputDerivatives (STEP | STEP_DISCARDED | TERMINATED | ERROR_STATE)
#define MASK_DoStep STEP
#define MASK_ANY ANY_STATE

enum { MODEL_EXCHANGE = 1, CO_SIMULATION = 2, BOTH = 3 };

/* --------------------------------------------------------------------------------- instances */

typedef struct {
    guard_instance common; /* first: a guarded* is a guard_instance* */
    fmi3Instance backend;
    int interface;                    /* MODEL_EXCHANGE or CO_SIMULATION */
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback host_logger; /* may be NULL: errors then go to stderr */
} guarded;

static void host_log(guard_instance *common, int status, const char *category, const char *message) {
    guarded *g = (guarded *)common;
    if (g->host_logger) g->host_logger(g->environment, (fmi3Status)status, category, message);
    else if (status >= fmi3Error) guard_orphan(MODEL_IDENTIFIER, common->name, "%s", message);
}

/* The logger pythonfmu3 gets (its environment is the guarded instance). */
static void library_logger(fmi3InstanceEnvironment environment, fmi3Status status, fmi3String category,
                           fmi3String message) {
    if (environment) guard_library_message_logged(environment, (int)status, category, message);
}

#define fail guard_fail
#define settle(g, status) ((fmi3Status)guard_settle(&(g)->common, (int)(status)))

static const char *interface_name(int interface) {
    return interface == MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation";
}

/* Begin function F (fmi3F) of interface(s) INTERFACE on instance: look it up, check interface and state. */
#define BEGIN_FOR(F, MASK, INTERFACE)                                                                             \
    guarded *g = (guarded *)guard_lookup(instance, MODEL_IDENTIFIER, "fmi3" #F);                                  \
    if (!g) return fmi3Error;                                                                                     \
    if (!(g->interface & (INTERFACE)))                                                                            \
        return (fmi3Status)fail(&g->common, "fmi3" #F ": not a function of %s, which this instance was made for", \
                                interface_name(g->interface));                                                  \
    if (!(g->common.at.state & (MASK)))                                                                           \
        return (fmi3Status)fail(&g->common, "fmi3" #F ": illegal call sequence: not allowed in state %s",        \
                                state_name(g->common.at.state));                                                 \
    g->common.function = "fmi3" #F
#define BEGIN(F) BEGIN_FOR(F, MASK_##F, BOTH)

#define REQUIRE(condition, ...)                                                                                   \
    if (!(condition)) return (fmi3Status)fail(&g->common, __VA_ARGS__)

/* ---------------------------------------------------------------------- creation and destruction */

FMI3_Export const char *fmi3GetVersion(void) { return fmi3Version; }

static void free_guarded(guarded *g) {
    free(g->common.name);
    free(g);
}

/* A guarded instance for the host (NULL and a line on stderr if out of memory). */
static guarded *new_guarded(fmi3String name, int interface, fmi3Boolean loggingOn,
                            fmi3InstanceEnvironment environment, fmi3LogMessageCallback logger) {
    guarded *g = calloc(1, sizeof *g);
    char *copy = strdup(name && name[0] && guard_utf8_error(name) < 0 ? name : "?");
    if (!g || !copy) {
        guard_orphan(MODEL_IDENTIFIER, "fmi3Instantiate", "out of memory");
        free(g), free(copy);
        return NULL;
    }
    g->common = (guard_instance){.at = {INSTANTIATED, 0.0, 0.0, 0}, .error_state = ERROR_STATE,
                                 .categories = loggingOn ? CATEGORIES_EVERY : CATEGORIES_ERRORS,
                                 .function = "fmi3Instantiate", .name = copy, .log = host_log};
    g->interface = interface;
    g->environment = environment;
    g->host_logger = logger;
    return g;
}

/* Check what every fmi3Instantiate* is given and load the library; 0 (logged) if that fails. */
static int ready_to_instantiate(guarded *g, fmi3String name, fmi3String token, fmi3String resourcePath,
                                const char *function) {
    char why[2048] = "", resources[4096], marker[4200];
    void *backend = NULL;
    long bad;
    if (!name || !name[0]) guard_format(why, sizeof why, "instanceName is %s", name ? "empty" : "NULL");
    else if ((bad = guard_utf8_error(name)) >= 0)
        guard_format(why, sizeof why, "instanceName is not UTF-8 (byte %ld is 0x%02x; an fmi3String is UTF-8 encoded)",
                     bad, (unsigned char)name[bad]);
    else if (!token || strcmp(token, FMU_GUID) != 0)
        guard_format(why, sizeof why,
                     "instantiationToken %s%.100s%s is not this FMU's %s: the binary and its modelDescription.xml "
                     "come from different builds", token ? "\"" : "", token ? token : "NULL", token ? "\"" : "",
                     FMU_GUID);
    else if (!resourcePath || !resourcePath[0])
        guard_format(why, sizeof why, "resourcePath is %s: the FMU needs its resources folder",
                     resourcePath ? "empty" : "NULL");
    else if (!guard_uri_to_path(resourcePath, resources, sizeof resources) || !guard_is_directory(resources))
        guard_format(why, sizeof why, "resourcePath \"%.1000s\": there is no such folder", resourcePath);
    else if (guard_format(marker, sizeof marker, "%s/slavemodule.txt", resources), !guard_is_file(marker))
        guard_format(why, sizeof why, "resourcePath \"%.1000s\" is not this FMU's resources folder (no "
                     "slavemodule.txt in it)", resourcePath);
    else if ((bad = guard_utf8_error(resourcePath)) >= 0)
        guard_format(why, sizeof why, "resourcePath \"%.1000s\" is not UTF-8 (byte %ld; an fmi3String is UTF-8 "
                     "encoded)", resourcePath, bad);
    else if ((backend = python_runtime_load_backend(resourcePath, BACKEND_FILE, why, sizeof why)) &&
             resolve(backend, why, sizeof why))
        return 1;
    fail(&g->common, "%s: %s", function, why);
    return 0;
}

/* Register the library's instance, or free everything (logged) if the library made none. */
static fmi3Instance registered(guarded *g, fmi3Instance backend, const char *function) {
    g->backend = backend;
    if (backend && guard_register(&g->common)) return g;
    fail(&g->common, "%s: the FMU's Python side could not be instantiated%s", function,
         backend ? " (out of memory)" : " (the message before says why)");
    if (backend) backend_fmi3FreeInstance(backend);
    free_guarded(g);
    return NULL;
}

FMI3_Export fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                                                      fmi3LogMessageCallback logMessage) {
    guarded *g = new_guarded(instanceName, MODEL_EXCHANGE, loggingOn, environment, logMessage);
    if (!g) return NULL;
    if (!ready_to_instantiate(g, instanceName, instantiationToken, resourcePath, "fmi3InstantiateModelExchange")) {
        free_guarded(g);
        return NULL;
    }
    guard_lock_python(&python_lock);
    fmi3Instance backend = backend_fmi3InstantiateModelExchange(instanceName, instantiationToken, resourcePath,
                                                                visible, fmi3True, g, library_logger);
    pthread_mutex_unlock(&python_lock);
    return registered(g, backend, "fmi3InstantiateModelExchange");
}

FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
    const fmi3ValueReference requiredIntermediateVariables[], size_t nRequiredIntermediateVariables,
    fmi3InstanceEnvironment environment, fmi3LogMessageCallback logMessage,
    fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)earlyReturnAllowed, (void)intermediateUpdate; /* no intermediate updates, never an early return */
    guarded *g = new_guarded(instanceName, CO_SIMULATION, loggingOn, environment, logMessage);
    if (!g) return NULL;
    const char *function = "fmi3InstantiateCoSimulation";
    if (eventModeUsed || nRequiredIntermediateVariables > 0) {
        fail(&g->common, "%s: %s", function,
             eventModeUsed ? "eventModeUsed = true, but this FMU has no Event Mode in Co-Simulation (hasEventMode = "
                             "false)"
                           : "nRequiredIntermediateVariables > 0, but this FMU provides no intermediate updates");
        free_guarded(g);
        return NULL;
    }
    if (!ready_to_instantiate(g, instanceName, instantiationToken, resourcePath, function)) {
        free_guarded(g);
        return NULL;
    }
    guard_lock_python(&python_lock);
    fmi3Instance backend = backend_fmi3InstantiateCoSimulation(
        instanceName, instantiationToken, resourcePath, visible, fmi3True, fmi3False, fmi3False,
        requiredIntermediateVariables, 0, g, library_logger, NULL);
    pthread_mutex_unlock(&python_lock);
    return registered(g, backend, function);
}

FMI3_Export fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3InstanceEnvironment environment, fmi3LogMessageCallback logMessage,
    fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
    fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    guarded *g = new_guarded(instanceName, CO_SIMULATION, fmi3False, environment, logMessage);
    if (g) {
        fail(&g->common, "fmi3InstantiateScheduledExecution: this FMU offers Model Exchange and Co-Simulation only");
        free_guarded(g);
    }
    return NULL;
}

static void free_state(guarded *g, guard_state *s) {
    guard_state_forget(s);
    if (s->backend) backend_fmi3FreeFMUState(g->backend, (fmi3FMUState *)&s->backend);
    free(s);
}

FMI3_Export void fmi3FreeInstance(fmi3Instance instance) {
    if (!instance) return;
    if (!guard_unregister(instance)) {
        guard_orphan(MODEL_IDENTIFIER, "fmi3FreeInstance", "%p is not a live instance of this FMU (freed twice?)",
                     instance);
        return;
    }
    guarded *g = (guarded *)instance;
    g->common.function = "fmi3FreeInstance";
    while (g->common.states) free_state(g, g->common.states); /* the FMU states the host did not free */
    backend_fmi3FreeInstance(g->backend);
    free_guarded(g);
}

FMI3_Export fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                                           const fmi3String categories[]) {
    BEGIN(SetDebugLogging);
    return (fmi3Status)guard_set_debug_logging(&g->common, loggingOn, nCategories, categories,
                                               "fmi3SetDebugLogging");
}

/* --------------------------------------------------------------------------------- the modes */

FMI3_Export fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance, fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    BEGIN(EnterInitializationMode);
    REQUIRE(isfinite(startTime), "fmi3EnterInitializationMode: startTime = %g s must be finite", startTime);
    REQUIRE(!stopTimeDefined || (isfinite(stopTime) && stopTime >= startTime),
            "fmi3EnterInitializationMode: stopTime = %g s must be finite and not before startTime = %g s", stopTime,
            startTime);
    REQUIRE(!toleranceDefined || (isfinite(tolerance) && tolerance > 0),
            "fmi3EnterInitializationMode: tolerance = %g must be finite and > 0", tolerance);
    fmi3Status status = settle(g, backend_fmi3SetTime(g->backend, startTime)); /* pythonfmu3 drops it */
    if (status > fmi3Warning) return status;
    status = settle(g, backend_fmi3EnterInitializationMode(g->backend, toleranceDefined, tolerance, startTime,
                                                            stopTimeDefined, stopTime));
    if (status <= fmi3Warning) g->common.at = (guard_position){INITIALIZATION, startTime, startTime, 0};
    return status;
}

FMI3_Export fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    BEGIN(ExitInitializationMode);
    fmi3Status status = settle(g, backend_fmi3ExitInitializationMode(g->backend));
    if (status <= fmi3Warning) g->common.at.state = g->interface == MODEL_EXCHANGE ? EVENT : STEP;
    return status;
}

FMI3_Export fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    BEGIN_FOR(EnterEventMode, MASK_EnterEventMode, MODEL_EXCHANGE);
    fmi3Status status = settle(g, backend_fmi3EnterEventMode(g->backend));
    if (status <= fmi3Warning) g->common.at.state = EVENT;
    return status;
}

FMI3_Export fmi3Status fmi3Terminate(fmi3Instance instance) {
    BEGIN(Terminate);
    fmi3Status status = settle(g, backend_fmi3Terminate(g->backend));
    if (status <= fmi3Warning) g->common.at.state = TERMINATED;
    return status;
}

FMI3_Export fmi3Status fmi3Reset(fmi3Instance instance) {
    BEGIN(Reset);
    guard_lock_python(&python_lock); /* the Python side is made anew */
    fmi3Status status = settle(g, backend_fmi3Reset(g->backend));
    pthread_mutex_unlock(&python_lock);
    if (status <= fmi3Warning) g->common.at = (guard_position){INSTANTIATED, 0.0, 0.0, 0};
    return status;
}

/* No structural parameters: Configuration Mode has nothing to configure, but its calls are legal. */
FMI3_Export fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    BEGIN(EnterConfigurationMode);
    g->common.at.state = CONFIGURATION;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    BEGIN(ExitConfigurationMode);
    g->common.at.state = INSTANTIATED;
    return fmi3OK;
}

/* ------------------------------------------------------------------------ getting and setting */

/* Every variable of this FMU is a scalar: nValues must equal nValueReferences. */
#define CHECK_ARRAYS(F)                                                                                           \
    if (nValueReferences == 0 && nValues == 0) return fmi3OK;                                                     \
    REQUIRE(valueReferences, "fmi3" #F ": valueReferences is NULL with nValueReferences = %zu", nValueReferences); \
    REQUIRE(values, "fmi3" #F ": values is NULL with nValues = %zu", nValues);                                    \
    REQUIRE(nValues == nValueReferences,                                                                          \
            "fmi3" #F ": nValues = %zu, but %zu value references of scalar variables need %zu", nValues,          \
            nValueReferences, nValueReferences)

#define ACCESS(F, TYPE, MASK, VALUES_CONST, CHECK_VALUES)                                                        \
    FMI3_Export fmi3Status fmi3##F(fmi3Instance instance, const fmi3ValueReference valueReferences[],            \
                                   size_t nValueReferences, VALUES_CONST TYPE values[], size_t nValues) {        \
        BEGIN_FOR(F, MASK, BOTH);                                                                                 \
        CHECK_ARRAYS(F);                                                                                          \
        CHECK_VALUES                                                                                              \
        return settle(g, backend_fmi3##F(g->backend, valueReferences, nValueReferences, values, nValues));       \
    }
#define NO_CHECK
#define STRINGS_PRESENT                                                                                           \
    for (size_t k = 0; k < nValues; k++) {                                                                        \
        REQUIRE(values[k], "fmi3SetString: values[%zu] (valueReference %u) is NULL", k, valueReferences[k]);      \
        long bad = guard_utf8_error(values[k]);                                                                   \
        REQUIRE(bad < 0, "fmi3SetString: values[%zu] (valueReference %u) is not UTF-8 (byte %ld is 0x%02x; an "    \
                "fmi3String is UTF-8 encoded)", k, valueReferences[k], bad, (unsigned char)values[k][bad]);       \
    }

ACCESS(GetFloat64, fmi3Float64, MASK_GET, , NO_CHECK)
ACCESS(GetInt32, fmi3Int32, MASK_GET, , NO_CHECK)
ACCESS(GetInt64, fmi3Int64, MASK_GET, , NO_CHECK)
ACCESS(GetUInt64, fmi3UInt64, MASK_GET, , NO_CHECK)
ACCESS(GetBoolean, fmi3Boolean, MASK_GET, , NO_CHECK)
ACCESS(GetString, fmi3String, MASK_GET, , NO_CHECK)
ACCESS(SetFloat64, fmi3Float64, MASK_SET_FLOAT64, const, NO_CHECK)
ACCESS(SetInt32, fmi3Int32, MASK_SET, const, NO_CHECK)
ACCESS(SetInt64, fmi3Int64, MASK_SET, const, NO_CHECK)
ACCESS(SetUInt64, fmi3UInt64, MASK_SET, const, NO_CHECK)
ACCESS(SetBoolean, fmi3Boolean, MASK_SET, const, NO_CHECK)
ACCESS(SetString, fmi3String, MASK_SET, const, STRINGS_PRESENT)

/* -------------------------------------------------------------------------------- FMU states */

static fmi3Status deliver_state(guarded *g, fmi3FMUState *FMUState, fmi3FMUState backend, guard_position at) {
    guard_state *s = *FMUState;
    if (s) {
        if (s->backend) backend_fmi3FreeFMUState(g->backend, (fmi3FMUState *)&s->backend);
        s->backend = backend;
        s->at = at;
        return fmi3OK;
    }
    if (!(s = guard_state_new(&g->common, backend, at))) {
        backend_fmi3FreeFMUState(g->backend, &backend);
        return (fmi3Status)fail(&g->common, "%s: out of memory", g->common.function);
    }
    *FMUState = s;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    BEGIN_FOR(GetFMUState, MASK_FMU_STATE, BOTH);
    REQUIRE(FMUState, "fmi3GetFMUState: FMUState is NULL");
    if (*FMUState && !guard_state_known(&g->common, *FMUState, "fmi3GetFMUState")) return fmi3Error;
    fmi3FMUState backend = NULL;
    fmi3Status status = settle(g, backend_fmi3GetFMUState(g->backend, &backend));
    return status > fmi3Warning ? status : deliver_state(g, FMUState, backend, g->common.at);
}

FMI3_Export fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    BEGIN_FOR(SetFMUState, MASK_FMU_STATE, BOTH);
    guard_state *s = guard_state_known(&g->common, FMUState, "fmi3SetFMUState");
    if (!s) return fmi3Error;
    fmi3Status status = settle(g, backend_fmi3SetFMUState(g->backend, s->backend));
    if (status <= fmi3Warning) g->common.at = s->at;
    return status;
}

FMI3_Export fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    BEGIN_FOR(FreeFMUState, MASK_FMU_STATE, BOTH);
    REQUIRE(FMUState, "fmi3FreeFMUState: FMUState is NULL");
    if (!*FMUState) return fmi3OK; /* nothing to free */
    guard_state *s = guard_state_known(&g->common, *FMUState, "fmi3FreeFMUState");
    if (!s) return fmi3Error;
    free_state(g, s);
    *FMUState = NULL;
    return fmi3OK;
}

static fmi3Status backend_size(guarded *g, guard_state *s, size_t *size) {
    *size = 0;
    return settle(g, backend_fmi3SerializedFMUStateSize(g->backend, s->backend, size));
}

FMI3_Export fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    BEGIN_FOR(SerializedFMUStateSize, MASK_FMU_STATE, BOTH);
    REQUIRE(size, "fmi3SerializedFMUStateSize: size is NULL");
    guard_state *s = guard_state_known(&g->common, FMUState, "fmi3SerializedFMUStateSize");
    if (!s) return fmi3Error;
    size_t inner = 0;
    fmi3Status status = backend_size(g, s, &inner);
    if (status <= fmi3Warning) *size = sizeof(guard_state_header) + inner;
    return status;
}

FMI3_Export fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                             size_t size) {
    BEGIN_FOR(SerializeFMUState, MASK_FMU_STATE, BOTH);
    REQUIRE(serializedState, "fmi3SerializeFMUState: serializedState is NULL");
    guard_state *s = guard_state_known(&g->common, FMUState, "fmi3SerializeFMUState");
    if (!s) return fmi3Error;
    size_t inner = 0;
    fmi3Status status = backend_size(g, s, &inner);
    if (status > fmi3Warning) return status;
    REQUIRE(size == sizeof(guard_state_header) + inner,
            "fmi3SerializeFMUState: size = %zu, but fmi3SerializedFMUStateSize gives %zu", size,
            sizeof(guard_state_header) + inner);
    guard_state_header header;
    guard_header_write(&header, STATE_MAGIC, FMU_GUID, s->at);
    memcpy(serializedState, &header, sizeof header);
    return settle(g, backend_fmi3SerializeFMUState(g->backend, s->backend, serializedState + sizeof header, inner));
}

FMI3_Export fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                               fmi3FMUState *FMUState) {
    BEGIN_FOR(DeserializeFMUState, MASK_FMU_STATE, BOTH);
    REQUIRE(serializedState, "fmi3DeserializeFMUState: serializedState is NULL");
    REQUIRE(FMUState, "fmi3DeserializeFMUState: FMUState is NULL");
    if (*FMUState && !guard_state_known(&g->common, *FMUState, "fmi3DeserializeFMUState")) return fmi3Error;
    guard_state_header header;
    guard_position at;
    REQUIRE(size > sizeof header, "fmi3DeserializeFMUState: %zu bytes are not a serialized state of this FMU", size);
    memcpy(&header, serializedState, sizeof header);
    REQUIRE(guard_header_read(&header, STATE_MAGIC, FMU_GUID, ANY_STATE, &at),
            "fmi3DeserializeFMUState: the bytes are not a state serialized by this FMU (token %s)", FMU_GUID);
    fmi3FMUState backend = NULL;
    fmi3Status status = settle(g, backend_fmi3DeserializeFMUState(g->backend, serializedState + sizeof header,
                                                                   size - sizeof header, &backend));
    return status > fmi3Warning ? status : deliver_state(g, FMUState, backend, at);
}

/* ---------------------------------------------------------------------------- Model Exchange */

#define REQUIRE_OUT(F, pointer) REQUIRE(pointer, "fmi3" #F ": " #pointer " is NULL")

FMI3_Export fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    BEGIN_FOR(UpdateDiscreteStates, MASK_UpdateDiscreteStates, MODEL_EXCHANGE);
    REQUIRE_OUT(UpdateDiscreteStates, discreteStatesNeedUpdate);
    REQUIRE_OUT(UpdateDiscreteStates, terminateSimulation);
    REQUIRE_OUT(UpdateDiscreteStates, nominalsOfContinuousStatesChanged);
    REQUIRE_OUT(UpdateDiscreteStates, valuesOfContinuousStatesChanged);
    REQUIRE_OUT(UpdateDiscreteStates, nextEventTimeDefined);
    REQUIRE_OUT(UpdateDiscreteStates, nextEventTime);
    fmi3Boolean update = fmi3False, terminate = fmi3False, nominals = fmi3False, values = fmi3False;
    fmi3Boolean defined = fmi3False;
    fmi3Float64 next = 0.0;
    fmi3Status status = settle(g, backend_fmi3UpdateDiscreteStates(g->backend, &update, &terminate, &nominals,
                                                                    &values, &defined, &next));
    if (status > fmi3Warning) return status;
    *discreteStatesNeedUpdate = update, *terminateSimulation = terminate;
    *nominalsOfContinuousStatesChanged = nominals, *valuesOfContinuousStatesChanged = values;
    *nextEventTimeDefined = defined, *nextEventTime = defined ? next : 0.0;
    return status;
}

FMI3_Export fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    BEGIN_FOR(EnterContinuousTimeMode, MASK_EnterContinuousTimeMode, MODEL_EXCHANGE);
    fmi3Status status = settle(g, backend_fmi3EnterContinuousTimeMode(g->backend));
    if (status <= fmi3Warning) g->common.at.state = CONTINUOUS_TIME;
    return status;
}

FMI3_Export fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    BEGIN_FOR(CompletedIntegratorStep, MASK_CompletedIntegratorStep, MODEL_EXCHANGE);
    REQUIRE_OUT(CompletedIntegratorStep, enterEventMode);
    REQUIRE_OUT(CompletedIntegratorStep, terminateSimulation);
    fmi3Boolean event = fmi3False, terminate = fmi3False;
    fmi3Status status = settle(g, backend_fmi3CompletedIntegratorStep(g->backend, noSetFMUStatePriorToCurrentPoint,
                                                                       &event, &terminate));
    if (status <= fmi3Warning) *enterEventMode = event, *terminateSimulation = terminate;
    return status;
}

FMI3_Export fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    BEGIN_FOR(SetTime, MASK_SetTime, MODEL_EXCHANGE);
    REQUIRE(isfinite(time), "fmi3SetTime: time = %g s must be finite", time);
    return settle(g, backend_fmi3SetTime(g->backend, time));
}

/* A state vector of the host: not NULL, exactly `expected` long. */
#define CHECK_VECTOR(F, array, n, expected)                                                                       \
    REQUIRE(n == (expected), "fmi3" #F ": " #n " = %zu, but this FMU has %d", n, (int)(expected));                \
    REQUIRE(n == 0 || array, "fmi3" #F ": " #array " is NULL with " #n " = %zu", n)

FMI3_Export fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                               size_t nContinuousStates) {
    BEGIN_FOR(SetContinuousStates, MASK_SetContinuousStates, MODEL_EXCHANGE);
    CHECK_VECTOR(SetContinuousStates, continuousStates, nContinuousStates, N_CONTINUOUS_STATES);
    return settle(g, backend_fmi3SetContinuousStates(g->backend, continuousStates, nContinuousStates));
}

#define STATE_VECTOR(F, array, n, expected)                                                                       \
    FMI3_Export fmi3Status fmi3##F(fmi3Instance instance, fmi3Float64 array[], size_t n) {                       \
        BEGIN_FOR(F, MASK_STATE_VECTORS, MODEL_EXCHANGE);                                                         \
        CHECK_VECTOR(F, array, n, expected);                                                                      \
        return n == 0 ? fmi3OK : settle(g, backend_fmi3##F(g->backend, array, n));                               \
    }
STATE_VECTOR(GetContinuousStateDerivatives, derivatives, nContinuousStates, N_CONTINUOUS_STATES)
STATE_VECTOR(GetContinuousStates, continuousStates, nContinuousStates, N_CONTINUOUS_STATES)
STATE_VECTOR(GetNominalsOfContinuousStates, nominals, nContinuousStates, N_CONTINUOUS_STATES)
STATE_VECTOR(GetEventIndicators, eventIndicators, nEventIndicators, N_EVENT_INDICATORS)

FMI3_Export fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    BEGIN_FOR(GetNumberOfContinuousStates, MASK_NUMBERS, BOTH);
    REQUIRE_OUT(GetNumberOfContinuousStates, nContinuousStates);
    *nContinuousStates = N_CONTINUOUS_STATES;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    BEGIN_FOR(GetNumberOfEventIndicators, MASK_NUMBERS, BOTH);
    REQUIRE_OUT(GetNumberOfEventIndicators, nEventIndicators);
    *nEventIndicators = N_EVENT_INDICATORS;
    return fmi3OK;
}

/* ----------------------------------------------------------------------------- Co-Simulation */

FMI3_Export fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    BEGIN_FOR(EnterStepMode, MASK_EnterStepMode, CO_SIMULATION);
    fmi3Status status = settle(g, backend_fmi3EnterStepMode(g->backend));
    if (status <= fmi3Warning) g->common.at.state = STEP;
    return status;
}

FMI3_Export fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                                  fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    BEGIN_FOR(DoStep, MASK_DoStep, CO_SIMULATION);
    guard_position *at = &g->common.at;
    REQUIRE_OUT(DoStep, eventHandlingNeeded);
    REQUIRE_OUT(DoStep, terminateSimulation);
    REQUIRE_OUT(DoStep, earlyReturn);
    REQUIRE_OUT(DoStep, lastSuccessfulTime);
    REQUIRE(isfinite(communicationStepSize) && communicationStepSize > 0,
            "fmi3DoStep: communicationStepSize = %g s must be finite and > 0", communicationStepSize);
    REQUIRE(isfinite(currentCommunicationPoint) &&
                fabs(currentCommunicationPoint - at->time) <= 1e-9 * fmax(1.0, fabs(at->time)),
            "fmi3DoStep: currentCommunicationPoint = %.17g s is not the FMU's time %.17g s (the end of the last "
            "step, or of the FMU state set)", currentCommunicationPoint, at->time);
    fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
    fmi3Float64 reached = currentCommunicationPoint;
    fmi3Status status = backend_fmi3DoStep(g->backend, currentCommunicationPoint, communicationStepSize,
                                           noSetFMUStatePriorToCurrentPoint, &event, &terminate, &early, &reached);
    *eventHandlingNeeded = fmi3False, *earlyReturn = fmi3False;
    if (status == fmi3Discard) { /* the solver gave up: the FMU stays where the step began */
        at->state = STEP_DISCARDED;
        at->last_successful_time = at->time;
        at->wants_to_terminate = 1;
        *terminateSimulation = fmi3True, *lastSuccessfulTime = at->time;
        return fmi3Discard;
    }
    status = settle(g, status);
    if (status <= fmi3Warning) at->time = at->last_successful_time = currentCommunicationPoint + communicationStepSize;
    *terminateSimulation = fmi3False, *lastSuccessfulTime = at->last_successful_time;
    return status;
}

FMI3_Export fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                                size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                                size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)orders, (void)values, (void)nValues;
    BEGIN_FOR(GetOutputDerivatives, MASK_GetOutputDerivatives, CO_SIMULATION);
    return (fmi3Status)fail(&g->common, "fmi3GetOutputDerivatives: this FMU gives no output derivatives "
                                        "(maxOutputDerivativeOrder = 0)");
}

/* ------------------------------------------------------------------- what this FMU does not have */

#define NO_TYPE "it has Float64, Boolean and String variables only"
#define NO_CLOCKS "it has no clocks"
#define UNSUPPORTED(name, parameters, why)                                                                        \
    FMI3_Export fmi3Status fmi3##name parameters {                                                                \
        BEGIN_FOR(name, MASK_ANY, BOTH);                                                                          \
        return (fmi3Status)fail(&g->common, "fmi3" #name ": not supported by this FMU (%s)", why);               \
    }
#define VR const fmi3ValueReference vr[], size_t nvr
#define UNSUPPORTED_GET(name, type) UNSUPPORTED(name, (fmi3Instance instance, VR, type v[], size_t n), NO_TYPE)
#define UNSUPPORTED_SET(name, type) UNSUPPORTED(name, (fmi3Instance instance, VR, const type v[], size_t n), NO_TYPE)

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-parameter"
UNSUPPORTED_GET(GetFloat32, fmi3Float32)
UNSUPPORTED_GET(GetInt8, fmi3Int8)
UNSUPPORTED_GET(GetUInt8, fmi3UInt8)
UNSUPPORTED_GET(GetInt16, fmi3Int16)
UNSUPPORTED_GET(GetUInt16, fmi3UInt16)
UNSUPPORTED_GET(GetUInt32, fmi3UInt32)
UNSUPPORTED_SET(SetFloat32, fmi3Float32)
UNSUPPORTED_SET(SetInt8, fmi3Int8)
UNSUPPORTED_SET(SetUInt8, fmi3UInt8)
UNSUPPORTED_SET(SetInt16, fmi3Int16)
UNSUPPORTED_SET(SetUInt16, fmi3UInt16)
UNSUPPORTED_SET(SetUInt32, fmi3UInt32)
UNSUPPORTED(GetBinary, (fmi3Instance instance, VR, size_t sizes[], fmi3Binary v[], size_t n), NO_TYPE)
UNSUPPORTED(SetBinary, (fmi3Instance instance, VR, const size_t sizes[], const fmi3Binary v[], size_t n), NO_TYPE)
UNSUPPORTED(GetClock, (fmi3Instance instance, VR, fmi3Clock v[]), NO_CLOCKS)
UNSUPPORTED(SetClock, (fmi3Instance instance, VR, const fmi3Clock v[]), NO_CLOCKS)
UNSUPPORTED(GetIntervalDecimal, (fmi3Instance instance, VR, fmi3Float64 v[], fmi3IntervalQualifier q[]), NO_CLOCKS)
UNSUPPORTED(GetIntervalFraction, (fmi3Instance instance, VR, fmi3UInt64 c[], fmi3UInt64 r[], fmi3IntervalQualifier q[]),
            NO_CLOCKS)
UNSUPPORTED(GetShiftDecimal, (fmi3Instance instance, VR, fmi3Float64 v[]), NO_CLOCKS)
UNSUPPORTED(GetShiftFraction, (fmi3Instance instance, VR, fmi3UInt64 c[], fmi3UInt64 r[]), NO_CLOCKS)
UNSUPPORTED(SetIntervalDecimal, (fmi3Instance instance, VR, const fmi3Float64 v[]), NO_CLOCKS)
UNSUPPORTED(SetIntervalFraction, (fmi3Instance instance, VR, const fmi3UInt64 c[], const fmi3UInt64 r[]), NO_CLOCKS)
UNSUPPORTED(SetShiftDecimal, (fmi3Instance instance, VR, const fmi3Float64 v[]), NO_CLOCKS)
UNSUPPORTED(SetShiftFraction, (fmi3Instance instance, VR, const fmi3UInt64 c[], const fmi3UInt64 r[]), NO_CLOCKS)
UNSUPPORTED(EvaluateDiscreteStates, (fmi3Instance instance), "it has no discrete states")
UNSUPPORTED(ActivateModelPartition, (fmi3Instance instance, fmi3ValueReference clock, fmi3Float64 time),
            "Scheduled Execution is not offered")
UNSUPPORTED(GetNumberOfVariableDependencies, (fmi3Instance instance, fmi3ValueReference v, size_t *n),
            "the dependencies are in the modelDescription")
UNSUPPORTED(GetVariableDependencies,
            (fmi3Instance instance, fmi3ValueReference dependent, size_t element_of_dependent[],
             fmi3ValueReference independents[], size_t element_of_independents[], fmi3DependencyKind kinds[],
             size_t n),
            "the dependencies are in the modelDescription")
UNSUPPORTED(GetDirectionalDerivative,
            (fmi3Instance instance, const fmi3ValueReference unknowns[], size_t n_unknowns,
             const fmi3ValueReference knowns[], size_t n_knowns, const fmi3Float64 seed[], size_t n_seed,
             fmi3Float64 sensitivity[], size_t n_sensitivity),
            "providesDirectionalDerivatives = false")
UNSUPPORTED(GetAdjointDerivative,
            (fmi3Instance instance, const fmi3ValueReference unknowns[], size_t n_unknowns,
             const fmi3ValueReference knowns[], size_t n_knowns, const fmi3Float64 seed[], size_t n_seed,
             fmi3Float64 sensitivity[], size_t n_sensitivity),
            "providesAdjointDerivatives = false")
#pragma GCC diagnostic pop
