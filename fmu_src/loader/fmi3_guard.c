/* The FMU's binary for FMI 3.0 (Model Exchange and Co-Simulation): the FMI functions, which call the
 * FMU's Python side (fmu_src/fmi_bridge.py) through bridge.c, in a CPython that python_runtime.c makes
 * available.  What it guarantees is what fmi2_guard.c does for FMI 2, after FMI 3.0 (sections 2.2.4, 3.2
 * and 4.2: the Model Exchange and Co-Simulation state machines): the state machine of the interface the
 * instance was made for, argument checks (NULL arrays, nValues against the value references, String
 * values that are not UTF-8, the step size and communication point, every out-argument, continuous
 * states that are not finite), instantiation checks (instantiation token, instance name, resource path
 * and whose resources they are), the host's logger given text with no lock held, errors logged from
 * instantiation on, an exception on the Python side an fmi3Error of this instance only.  Every
 * out-argument is written on success; derivatives that are not finite are fmi3Discard with a line that
 * says so; what this FMU does not have (other variable types, clocks, binaries, structural parameters,
 * dependencies, derivatives, Scheduled Execution, Event Mode in Co-Simulation) is fmi3Error and a log
 * line. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bridge.h"
#include "fmi3Functions.h"
#include "fmu_state.h"
#include "guard.h"
#include "text.h"

#include "identity.h"

#define MODEL_IDENTIFIER identity_model_identifier
#define FMU_GUID identity_token /* the instantiationToken of the FMU's modelDescription.xml */
#define N_CONTINUOUS_STATES identity_continuous_states
#define N_VARIABLES identity_variables
#define N_EVENT_INDICATORS 0 /* a smooth right-hand side (component/model_exchange.py) */

#define MODEL_EXCHANGE "ModelExchange"
#define CO_SIMULATION "CoSimulation"

/* ----------------------------------------------------------------------------------- states */

enum {
    INSTANTIATED = 1 << 0,
    CONFIGURATION = 1 << 1,
    INITIALIZATION = 1 << 2,
    EVENT = 1 << 3,           /* Model Exchange */
    CONTINUOUS_TIME = 1 << 4, /* Model Exchange */
    STEP = 1 << 5,            /* Co-Simulation */
    TERMINATED = 1 << 7,
    ERROR_STATE = 1 << 8, /* a call returned fmi3Error */
};
#define ANY_STATE                                                                                                 \
    (INSTANTIATED | CONFIGURATION | INITIALIZATION | EVENT | CONTINUOUS_TIME | STEP | TERMINATED | \
     ERROR_STATE)

static const char *state_name(int state) {
    switch (state) {
    case INSTANTIATED: return "Instantiated";
    case CONFIGURATION: return "Configuration Mode";
    case INITIALIZATION: return "Initialization Mode";
    case EVENT: return "Event Mode";
    case CONTINUOUS_TIME: return "Continuous-Time Mode";
    case STEP: return "Step Mode";
    case TERMINATED: return "Terminated";
    default: return "Error (after fmi3Error: only get, FMU states, reset and free)";
    }
}

/* Where each function may be called (FMI 3.0.2: 3.2 Model Exchange, 4.2 Co-Simulation). */
#define MASK_SetDebugLogging ANY_STATE
#define MASK_EnterInitializationMode INSTANTIATED
#define MASK_ExitInitializationMode INITIALIZATION
#define MASK_EnterEventMode CONTINUOUS_TIME /* Co-Simulation: Event Mode is not offered */
#define MASK_Terminate (EVENT | CONTINUOUS_TIME | STEP)
#define MASK_Reset ANY_STATE
/* start values are read in Instantiated (2.3.2); Configuration Mode is for structural parameters only (2.3.6) */
#define MASK_GET (INSTANTIATED | INITIALIZATION | EVENT | CONTINUOUS_TIME | STEP | TERMINATED | ERROR_STATE)
#define MASK_SET_FLOAT64 (INSTANTIATED | INITIALIZATION | EVENT | CONTINUOUS_TIME | STEP)
#define MASK_SET (INSTANTIATED | INITIALIZATION | EVENT | STEP)
#define MASK_FMU_STATE ANY_STATE
#define MASK_EnterConfigurationMode INSTANTIATED
#define MASK_ExitConfigurationMode CONFIGURATION
#define MASK_UpdateDiscreteStates EVENT
#define MASK_EnterContinuousTimeMode EVENT
#define MASK_CompletedIntegratorStep CONTINUOUS_TIME
#define MASK_SetTime (EVENT | CONTINUOUS_TIME)
#define MASK_SetContinuousStates CONTINUOUS_TIME
#define MASK_STATE_VECTORS (INITIALIZATION | EVENT | CONTINUOUS_TIME | TERMINATED | ERROR_STATE)
#define MASK_NUMBERS ANY_STATE /* Model Exchange only (2.3.2) */
#define MASK_EvaluateDiscreteStates EVENT
#define MASK_EnterStepMode EVENT /* not reached: without Event Mode Co-Simulation goes to Step Mode */
#define MASK_GetOutputDerivatives (STEP | TERMINATED | ERROR_STATE)
#define MASK_DoStep STEP
#define MASK_ANY ANY_STATE


#define ME_STATES (INSTANTIATED | CONFIGURATION | INITIALIZATION | EVENT | CONTINUOUS_TIME | TERMINATED | ERROR_STATE)
#define CS_STATES (INSTANTIATED | CONFIGURATION | INITIALIZATION | STEP | TERMINATED | ERROR_STATE)

static int state_allowed(const char *interface, int state) {
    return (state & (strcmp(interface, MODEL_EXCHANGE) == 0 ? ME_STATES : CS_STATES)) != 0;
}

static const guard_version FMI3 = {"fmi3", MODEL_IDENTIFIER, FMU_GUID, "instantiationToken", "resourcePath",
                                   ANY_STATE, ERROR_STATE, INSTANTIATED, "FMUState", "values", "valueReference",
                                   state_name, state_allowed};

/* --------------------------------------------------------------------------------- instances */

typedef struct {
    guard_instance common; /* first: a guarded* is a guard_instance* */
    int model_exchange;    /* 1: made for Model Exchange, 0: Co-Simulation */
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback host_logger; /* may be NULL: errors then go to stderr */
} guarded;

static void host_log(guard_instance *common, int status, const char *category, const char *message) {
    guarded *g = (guarded *)common;
    if (g->host_logger) g->host_logger(g->environment, (fmi3Status)status, category, message);
    else if (status >= fmi3Error) guard_orphan(MODEL_IDENTIFIER, common->name, "%s", message);
}

static void destroy(guard_instance *common) {
    guarded *g = (guarded *)common;
    guard_free_common(common);
    free(g);
}

#define fail guard_fail
#define settle(g, status) ((fmi3Status)guard_settle(&(g)->common, (int)(status)))
#define CALL(payload, ...) bridge_call(&g->common, payload, __VA_ARGS__)

enum { ME = 1, CS = 2, BOTH = 3 };

/* Begin function F (fmi3F) of interface(s) INTERFACE on instance: look it up (held until the function
 * returns), check interface and state. */
#define BEGIN_FOR(F, MASK, INTERFACE)                                                                             \
    guarded *g GUARD_CALL = (guarded *)guard_acquire(instance, MODEL_IDENTIFIER, "fmi3" #F);                      \
    if (!g) return fmi3Error;                                                                                     \
    guard_scope scope GUARD_SCOPE = guard_scope_begin(&g->common);                                                \
    (void)scope;                                                                                                  \
    g->common.function = "fmi3" #F;                                                                               \
    if (!((g->model_exchange ? ME : CS) & (INTERFACE)))                                                           \
        return (fmi3Status)fail(&g->common, "fmi3" #F ": not a function of %s, which this instance was made for", \
                                g->model_exchange ? "Model Exchange" : "Co-Simulation");                        \
    if (!(g->common.at.state & (MASK)))                                                                           \
        return (fmi3Status)guard_refuse_state(&g->common, "fmi3" #F, state_name(g->common.at.state))
#define BEGIN(F) BEGIN_FOR(F, MASK_##F, BOTH)

#define REQUIRE(condition, ...)                                                                                   \
    if (!(condition)) return (fmi3Status)fail(&g->common, __VA_ARGS__)

/* ---------------------------------------------------------------------- creation and destruction */

FMI3_Export const char *fmi3GetVersion(void) { return fmi3Version; }

/* A new instance for the host, or NULL (logged; stderr without a logger). `refusal` is a reason to refuse
 * that only the caller knows (or NULL). */
static guarded *instantiate(fmi3String name, fmi3String token, fmi3String resourcePath, fmi3Boolean visible,
                            fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                            fmi3LogMessageCallback logger, int model_exchange, const char *function,
                            const char *refusal) {
    guarded *g = calloc(1, sizeof *g);
    if (!g || !guard_init_instance(&g->common, &FMI3, model_exchange ? MODEL_EXCHANGE : CO_SIMULATION, name,
                                   loggingOn, host_log, destroy)) {
        guard_orphan(MODEL_IDENTIFIER, function, "out of memory");
        if (g) free(g->common.name), free(g);
        return NULL;
    }
    g->model_exchange = model_exchange;
    g->environment = environment;
    g->host_logger = logger;
    g->common.function = function;
    char why[2048] = "", resources[4096];
    if (refusal) text_format(why, sizeof why, "%s", refusal);
    else guard_check_instantiation(&FMI3, name, token, resourcePath, resources, sizeof resources, why, sizeof why);
    if (why[0]) fail(&g->common, "%s: %s", function, why);
    if (why[0] || !guard_start_python(&g->common, resources, visible)) {
        guard_deliver_interrupt(&g->common);
        destroy(&g->common);
        return NULL;
    }
    if (!guard_register(&g->common)) {
        fail(&g->common, "%s: out of memory", function);
        guard_deliver_interrupt(&g->common);
        destroy(&g->common);
        return NULL;
    }
    return g;
}

FMI3_Export fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                                                      fmi3LogMessageCallback logMessage) {
    return instantiate(instanceName, instantiationToken, resourcePath, visible, loggingOn, environment, logMessage, 1,
                       "fmi3InstantiateModelExchange", NULL);
}

FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
    const fmi3ValueReference requiredIntermediateVariables[], size_t nRequiredIntermediateVariables,
    fmi3InstanceEnvironment environment, fmi3LogMessageCallback logMessage,
    fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)earlyReturnAllowed, (void)intermediateUpdate, (void)requiredIntermediateVariables;
    const char *refusal =
        eventModeUsed ? "eventModeUsed = true, but this FMU has no Event Mode in Co-Simulation (hasEventMode = false)"
        : nRequiredIntermediateVariables > 0 ? "nRequiredIntermediateVariables > 0, but this FMU provides no "
                                               "intermediate updates"
                                             : NULL;
    return instantiate(instanceName, instantiationToken, resourcePath, visible, loggingOn, environment, logMessage, 0,
                       "fmi3InstantiateCoSimulation", refusal);
}

FMI3_Export fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3InstanceEnvironment environment, fmi3LogMessageCallback logMessage,
    fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
    fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)loggingOn, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    return instantiate(instanceName, instantiationToken, resourcePath, visible, fmi3False, environment, logMessage, 0,
                       "fmi3InstantiateScheduledExecution", "this FMU offers Model Exchange and Co-Simulation only");
}

FMI3_Export void fmi3FreeInstance(fmi3Instance instance) {
    if (instance && !guard_unregister(instance))
        guard_orphan(MODEL_IDENTIFIER, "fmi3FreeInstance", "%p is not a live instance of this FMU (freed twice?)",
                     instance);
}

FMI3_Export fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                                           const fmi3String categories[]) {
    BEGIN(SetDebugLogging);
    return (fmi3Status)guard_set_debug_logging(&g->common, loggingOn, nCategories, categories);
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
    fmi3Status status = settle(g, CALL(NO_PAYLOAD, "setup_experiment", "(didid)", startTime, (int)stopTimeDefined,
                                       stopTime, (int)toleranceDefined, tolerance));
    if (status > fmi3Warning) return status;
    status = settle(g, CALL(NO_PAYLOAD, "enter_initialization_mode", "()"));
    if (status <= fmi3Warning) g->common.at = (guard_position){INITIALIZATION, startTime, startTime, 0};
    return status;
}

/* Run a mode change of the Python side; on success the instance is in state `next`. */
#define MODE_CHANGE(F, INTERFACE, method, next)                                                                   \
    FMI3_Export fmi3Status fmi3##F(fmi3Instance instance) {                                                       \
        BEGIN_FOR(F, MASK_##F, INTERFACE);                                                                        \
        fmi3Status status = settle(g, CALL(NO_PAYLOAD, method, "()"));                                           \
        if (status <= fmi3Warning) g->common.at.state = (next);                                                  \
        return status;                                                                                            \
    }
MODE_CHANGE(ExitInitializationMode, BOTH, "exit_initialization_mode", g->model_exchange ? EVENT : STEP)
MODE_CHANGE(EnterEventMode, ME, "enter_event_mode", EVENT)
MODE_CHANGE(Terminate, BOTH, "terminate", TERMINATED)
MODE_CHANGE(EnterContinuousTimeMode, ME, "enter_continuous_time_mode", CONTINUOUS_TIME)
MODE_CHANGE(EnterStepMode, CS, "enter_step_mode", STEP)

FMI3_Export fmi3Status fmi3Reset(fmi3Instance instance) {
    BEGIN(Reset);
    return (fmi3Status)guard_reset(&g->common);
}

/* No structural parameters: Configuration Mode is not to be entered (2.3.2), its exit never reached. */
FMI3_Export fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    BEGIN(EnterConfigurationMode);
    return (fmi3Status)fail(&g->common, "fmi3EnterConfigurationMode: this FMU has no structural parameters, so "
                                        "there is nothing to configure (FMI 3.0, section 2.3.2)");
}

FMI3_Export fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    BEGIN(ExitConfigurationMode);
    g->common.at.state = INSTANTIATED;
    return fmi3OK;
}

/* ------------------------------------------------------------------------ getting and setting */

/* Every variable of this FMU is a scalar: nValues must equal nValueReferences, and neither exceeds the FMU's
 * variables (checked before any byte length is computed from them: a huge count would wrap). Values cross as
 * bytes of packed values, named by their FMI type. */
#define CHECK_ARRAYS(F)                                                                                           \
    if (nValueReferences == 0 && nValues == 0) return fmi3OK;                                                     \
    REQUIRE(nValueReferences <= N_VARIABLES, "fmi3" #F ": nValueReferences = %zu, but this FMU has %zu variables", \
            nValueReferences, N_VARIABLES);                                                                       \
    REQUIRE(valueReferences, "fmi3" #F ": valueReferences is NULL with nValueReferences = %zu", nValueReferences); \
    REQUIRE(values, "fmi3" #F ": values is NULL with nValues = %zu", nValues);                                    \
    REQUIRE(nValues == nValueReferences,                                                                          \
            "fmi3" #F ": nValues = %zu, but %zu value references of scalar variables need %zu", nValues,          \
            nValueReferences, nValueReferences)

#define GET(F, TYPE, MASK, NAME)                                                                                  \
    FMI3_Export fmi3Status fmi3##F(fmi3Instance instance, const fmi3ValueReference valueReferences[],            \
                                   size_t nValueReferences, TYPE values[], size_t nValues) {                    \
        BEGIN_FOR(F, MASK, BOTH);                                                                                 \
        CHECK_ARRAYS(F);                                                                                          \
        bridge_payload payload = {PAYLOAD_EXACT, values, nValues * sizeof *values, NULL, NULL, NULL};            \
        return settle(g, CALL(payload, "get", "(sy#)", NAME, (const char *)valueReferences,                       \
                              (ssize_t)(nValueReferences * sizeof *valueReferences)));                            \
    }
#define SET(F, TYPE, MASK, NAME)                                                                                  \
    FMI3_Export fmi3Status fmi3##F(fmi3Instance instance, const fmi3ValueReference valueReferences[],            \
                                   size_t nValueReferences, const TYPE values[], size_t nValues) {              \
        BEGIN_FOR(F, MASK, BOTH);                                                                                 \
        CHECK_ARRAYS(F);                                                                                          \
        return settle(g, CALL(NO_PAYLOAD, "set", "(sy#y#)", NAME, (const char *)valueReferences,                  \
                              (ssize_t)(nValueReferences * sizeof *valueReferences), (const char *)values,       \
                              (ssize_t)(nValues * sizeof *values)));                                             \
    }

GET(GetFloat64, fmi3Float64, MASK_GET, "Float64")
GET(GetInt32, fmi3Int32, MASK_GET, "Int32")
GET(GetInt64, fmi3Int64, MASK_GET, "Int64")
GET(GetUInt64, fmi3UInt64, MASK_GET, "UInt64")
GET(GetBoolean, fmi3Boolean, MASK_GET, "Boolean")
SET(SetFloat64, fmi3Float64, MASK_SET_FLOAT64, "Float64")
SET(SetInt32, fmi3Int32, MASK_SET, "Int32")
SET(SetInt64, fmi3Int64, MASK_SET, "Int64")
SET(SetUInt64, fmi3UInt64, MASK_SET, "UInt64")
SET(SetBoolean, fmi3Boolean, MASK_SET, "Boolean")

FMI3_Export fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                     size_t nValueReferences, fmi3String values[], size_t nValues) {
    BEGIN_FOR(GetString, MASK_GET, BOTH);
    CHECK_ARRAYS(GetString);
    return (fmi3Status)guard_get_strings(&g->common, valueReferences, nValues, values);
}

FMI3_Export fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                     size_t nValueReferences, const fmi3String values[], size_t nValues) {
    BEGIN_FOR(SetString, MASK_SET, BOTH);
    CHECK_ARRAYS(SetString);
    return (fmi3Status)guard_set_strings(&g->common, valueReferences, nValues, values);
}

/* -------------------------------------------------------------------------------- FMU states */

FMI3_Export fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    BEGIN_FOR(GetFMUState, MASK_FMU_STATE, BOTH);
    return (fmi3Status)guard_get_state(&g->common, FMUState);
}

FMI3_Export fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    BEGIN_FOR(SetFMUState, MASK_FMU_STATE, BOTH);
    return (fmi3Status)guard_set_state(&g->common, FMUState);
}

FMI3_Export fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    BEGIN_FOR(FreeFMUState, MASK_FMU_STATE, BOTH);
    return (fmi3Status)guard_free_state(&g->common, FMUState);
}

FMI3_Export fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    BEGIN_FOR(SerializedFMUStateSize, MASK_FMU_STATE, BOTH);
    return (fmi3Status)guard_serialized_size(&g->common, FMUState, size);
}

FMI3_Export fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                             size_t size) {
    BEGIN_FOR(SerializeFMUState, MASK_FMU_STATE, BOTH);
    return (fmi3Status)guard_serialize_state(&g->common, FMUState, serializedState, size);
}

FMI3_Export fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                               fmi3FMUState *FMUState) {
    BEGIN_FOR(DeserializeFMUState, MASK_FMU_STATE, BOTH);
    return (fmi3Status)guard_deserialize_state(&g->common, serializedState, size, FMUState);
}

/* ---------------------------------------------------------------------------- Model Exchange */

#define REQUIRE_OUT(F, pointer) REQUIRE(pointer, "fmi3" #F ": " #pointer " is NULL")

FMI3_Export fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    BEGIN_FOR(UpdateDiscreteStates, MASK_UpdateDiscreteStates, ME);
    REQUIRE_OUT(UpdateDiscreteStates, discreteStatesNeedUpdate);
    REQUIRE_OUT(UpdateDiscreteStates, terminateSimulation);
    REQUIRE_OUT(UpdateDiscreteStates, nominalsOfContinuousStatesChanged);
    REQUIRE_OUT(UpdateDiscreteStates, valuesOfContinuousStatesChanged);
    REQUIRE_OUT(UpdateDiscreteStates, nextEventTimeDefined);
    REQUIRE_OUT(UpdateDiscreteStates, nextEventTime);
    unsigned char answer[5 + sizeof(double)]; /* five flags, then the next event's time */
    bridge_payload payload = {PAYLOAD_EXACT, answer, sizeof answer, NULL, NULL, NULL};
    fmi3Status status = settle(g, CALL(payload, "update_discrete_states", "()"));
    if (status > fmi3Warning) return status;
    double next;
    memcpy(&next, answer + 5, sizeof next);
    *discreteStatesNeedUpdate = answer[0] != 0, *terminateSimulation = answer[1] != 0;
    *nominalsOfContinuousStatesChanged = answer[2] != 0, *valuesOfContinuousStatesChanged = answer[3] != 0;
    *nextEventTimeDefined = answer[4] != 0, *nextEventTime = answer[4] ? next : 0.0;
    return status;
}

FMI3_Export fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    BEGIN_FOR(CompletedIntegratorStep, MASK_CompletedIntegratorStep, ME);
    REQUIRE_OUT(CompletedIntegratorStep, enterEventMode);
    REQUIRE_OUT(CompletedIntegratorStep, terminateSimulation);
    unsigned char answer[2];
    bridge_payload payload = {PAYLOAD_EXACT, answer, sizeof answer, NULL, NULL, NULL};
    fmi3Status status = settle(g, CALL(payload, "completed_integrator_step", "(i)",
                                       (int)noSetFMUStatePriorToCurrentPoint));
    if (status <= fmi3Warning) *enterEventMode = answer[0] != 0, *terminateSimulation = answer[1] != 0;
    return status;
}

FMI3_Export fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    BEGIN_FOR(SetTime, MASK_SetTime, ME);
    REQUIRE(isfinite(time), "fmi3SetTime: time = %g s must be finite", time);
    return settle(g, CALL(NO_PAYLOAD, "set_time", "(d)", time));
}

/* A state vector of the host: not NULL, exactly `expected` long. */
#define CHECK_VECTOR(F, array, n, expected)                                                                       \
    REQUIRE(n == (expected), "fmi3" #F ": " #n " = %zu, but this FMU has %d", n, (int)(expected));                \
    REQUIRE(n == 0 || array, "fmi3" #F ": " #array " is NULL with " #n " = %zu", n)

FMI3_Export fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                               size_t nContinuousStates) {
    BEGIN_FOR(SetContinuousStates, MASK_SetContinuousStates, ME);
    CHECK_VECTOR(SetContinuousStates, continuousStates, nContinuousStates, N_CONTINUOUS_STATES);
    for (size_t k = 0; k < nContinuousStates; k++)
        REQUIRE(isfinite(continuousStates[k]), "fmi3SetContinuousStates: continuousStates[%zu] = %g is not finite", k,
                continuousStates[k]);
    return settle(g, CALL(NO_PAYLOAD, "set_continuous_states", "(y#)", (const char *)continuousStates,
                          (ssize_t)(nContinuousStates * sizeof *continuousStates)));
}

/* Get a vector of `n` values of the Python side into `array`. */
static fmi3Status get_vector(guarded *g, const char *method, fmi3Float64 array[], size_t n) {
    if (n == 0) return fmi3OK;
    bridge_payload payload = {PAYLOAD_EXACT, array, n * sizeof *array, NULL, NULL, NULL};
    return settle(g, CALL(payload, method, "()"));
}

FMI3_Export fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                                         size_t nContinuousStates) {
    BEGIN_FOR(GetContinuousStateDerivatives, MASK_STATE_VECTORS, ME);
    CHECK_VECTOR(GetContinuousStateDerivatives, derivatives, nContinuousStates, N_CONTINUOUS_STATES);
    fmi3Status status = get_vector(g, "get_continuous_state_derivatives", derivatives, nContinuousStates);
    for (size_t k = 0; status <= fmi3Warning && k < nContinuousStates; k++)
        if (!isfinite(derivatives[k])) { /* the states are outside the model's domain: the host steps back */
            char message[256];
            text_format(message, sizeof message, "fmi3GetContinuousStateDerivatives: derivatives[%zu] = %g is not "
                         "finite at these continuous states (outside the model's domain)", k, derivatives[k]);
            guard_emit(&g->common, fmi3Discard, "logStatusDiscard", message);
            return fmi3Discard;
        }
    return status;
}

#define STATE_VECTOR(F, method, array, n, expected)                                                               \
    FMI3_Export fmi3Status fmi3##F(fmi3Instance instance, fmi3Float64 array[], size_t n) {                       \
        BEGIN_FOR(F, MASK_STATE_VECTORS, ME);                                                                     \
        CHECK_VECTOR(F, array, n, expected);                                                                      \
        return get_vector(g, method, array, n);                                                                   \
    }
STATE_VECTOR(GetContinuousStates, "get_continuous_states", continuousStates, nContinuousStates, N_CONTINUOUS_STATES)
STATE_VECTOR(GetNominalsOfContinuousStates, "get_nominals_of_continuous_states", nominals, nContinuousStates,
             N_CONTINUOUS_STATES)
STATE_VECTOR(GetEventIndicators, "get_event_indicators", eventIndicators, nEventIndicators, N_EVENT_INDICATORS)

FMI3_Export fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    BEGIN_FOR(GetNumberOfContinuousStates, MASK_NUMBERS, ME);
    REQUIRE_OUT(GetNumberOfContinuousStates, nContinuousStates);
    *nContinuousStates = N_CONTINUOUS_STATES;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    BEGIN_FOR(GetNumberOfEventIndicators, MASK_NUMBERS, ME);
    REQUIRE_OUT(GetNumberOfEventIndicators, nEventIndicators);
    *nEventIndicators = N_EVENT_INDICATORS;
    return fmi3OK;
}

/* ----------------------------------------------------------------------------- Co-Simulation */

FMI3_Export fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                                  fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    BEGIN_FOR(DoStep, MASK_DoStep, CS);
    guard_position *at = &g->common.at;
    REQUIRE_OUT(DoStep, eventHandlingNeeded);
    REQUIRE_OUT(DoStep, terminateSimulation);
    REQUIRE_OUT(DoStep, earlyReturn);
    REQUIRE_OUT(DoStep, lastSuccessfulTime);
    if (!guard_check_step(&g->common, currentCommunicationPoint, communicationStepSize)) return fmi3Error;
    int status = CALL(NO_PAYLOAD, "do_step", "(ddi)", currentCommunicationPoint, communicationStepSize,
                      (int)noSetFMUStatePriorToCurrentPoint);
    *eventHandlingNeeded = fmi3False, *earlyReturn = fmi3False;
    if (status == fmi3Discard) { /* the solver gave up: the FMU stays where the step began, in Step Mode (2.2.3) */
        at->last_successful_time = at->time;
        at->wants_to_terminate = 1;
        *terminateSimulation = fmi3True, *lastSuccessfulTime = at->time;
        return fmi3Discard;
    }
    status = settle(g, status);
    if (status <= fmi3Warning) at->time = at->last_successful_time = currentCommunicationPoint + communicationStepSize;
    *terminateSimulation = fmi3False, *lastSuccessfulTime = at->last_successful_time;
    return (fmi3Status)status;
}

/* Without providesEvaluateDiscreteStates the call "is ignored" (2.3.5): there are no discrete states. */
FMI3_Export fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    BEGIN_FOR(EvaluateDiscreteStates, MASK_EvaluateDiscreteStates, BOTH);
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                                size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                                size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)orders, (void)values, (void)nValues;
    BEGIN_FOR(GetOutputDerivatives, MASK_GetOutputDerivatives, CS);
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
