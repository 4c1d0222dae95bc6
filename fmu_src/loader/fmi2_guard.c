/* The FMU's binary for FMI 2.0 co-simulation: the FMI functions, which call the FMU's Python side
 * (fmu_src/fmi_bridge.py) through bridge.c, in a CPython that python_runtime.c makes available.
 *
 * Whatever the Python side does, the host sees the behaviour of FMI 2.0 (sections 2.1.3, 2.1.5,
 * 4.2.4; modelled on modelica/Reference-FMUs, written anew):
 *  - every instance follows the co-simulation state machine: a call the current state does not
 *    allow returns fmi2Error with one log line naming the function and the state; after an error
 *    only what the standard allows in its Error state (get values, FMU states, reset, free,
 *    setDebugLogging);
 *  - arguments are checked before anything reaches Python: the instance (NULL, freed, foreign), NULL
 *    arrays with n > 0, every pointer the standard requires, String values that are not UTF-8,
 *    doStep's step size (> 0, finite) and communication point (the FMU's time: the end of the last
 *    step, or of the FMU state set, to a millionth of the step);
 *  - fmi2Instantiate refuses (NULL and one line; stderr where the host gave no logger) a wrong GUID,
 *    Model Exchange, a missing or non-UTF-8 instance name, a missing resource location, a folder that
 *    is not this FMU's (another FMU's resources are named as such);
 *  - the host's logger is only ever called with the constant format "%s" and the message as its
 *    argument, with no lock held (it may call the FMU again); errors and discarded steps reach it from
 *    instantiation on, other messages only with debug logging on (fmi2SetDebugLogging as specified);
 *  - an exception on the Python side is an error of this instance only, which a reset recovers:
 *    fmi2Error; a Ctrl-C inside a call is too, and is raised again for a Python host;
 *  - every call runs in parallel with calls on other instances (the GIL serialises the Python); an
 *    instance is freed only when no call is using it.
 * The FMU states the host gets are the shared ones of fmu_state.c. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bridge.h"
#include "fmi2Functions.h"
#include "fmu_state.h"
#include "guard.h"
#include "text.h"

#include "identity.h"

#define MODEL_IDENTIFIER identity_model_identifier
#define N_VARIABLES identity_variables
#define FMU_GUID identity_token /* the guid of the FMU's modelDescription.xml */

/* ----------------------------------------------------------------------------------- states */

enum {
    INSTANTIATED = 1 << 0,
    INITIALIZATION = 1 << 1,
    STEP_COMPLETE = 1 << 2,
    STEP_FAILED = 1 << 3, /* doStep returned fmi2Discard */
    TERMINATED = 1 << 4,
    ERROR_STATE = 1 << 5, /* a call returned fmi2Error */
};
#define ANY_STATE (INSTANTIATED | INITIALIZATION | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR_STATE)

static const char *state_name(int state) {
    switch (state) {
    case INSTANTIATED: return "Instantiated";
    case INITIALIZATION: return "Initialization Mode";
    case STEP_COMPLETE: return "Step Complete";
    case STEP_FAILED: return "Step Failed (after fmi2Discard)";
    case TERMINATED: return "Terminated";
    default: return "Error (after fmi2Error: only get, FMU states, reset and free)";
    }
}

/* Where each function may be called (FMI 2.0.4, section 4.2.4, co-simulation). */
#define MASK_SetDebugLogging ANY_STATE
#define MASK_SetupExperiment INSTANTIATED
#define MASK_EnterInitializationMode INSTANTIATED
#define MASK_ExitInitializationMode INITIALIZATION
#define MASK_Terminate (STEP_COMPLETE | STEP_FAILED)
#define MASK_Reset ANY_STATE
#define MASK_GET (INITIALIZATION | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR_STATE)
#define MASK_SET (INSTANTIATED | INITIALIZATION | STEP_COMPLETE)
#define MASK_GetFMUstate ANY_STATE
#define MASK_SetFMUstate ANY_STATE
#define MASK_FreeFMUstate ANY_STATE
#define MASK_SerializedFMUstateSize ANY_STATE
#define MASK_SerializeFMUstate ANY_STATE
#define MASK_DeSerializeFMUstate ANY_STATE
#define MASK_GetDirectionalDerivative (INITIALIZATION | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR_STATE)
#define MASK_SetRealInputDerivatives (INSTANTIATED | INITIALIZATION | STEP_COMPLETE)
#define MASK_GetRealOutputDerivatives (STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR_STATE)
#define MASK_DoStep STEP_COMPLETE
#define MASK_CancelStep 0 /* only while an asynchronous step is in progress: never here */
#define MASK_STATUS (STEP_COMPLETE | STEP_FAILED | TERMINATED) /* not in Error (4.2.4, its table) */

static int state_allowed(const char *interface, int state) {
    (void)interface;
    return (state & ANY_STATE) != 0;
}

static const guard_version FMI2 = {"fmi2", MODEL_IDENTIFIER, FMU_GUID, "fmuGUID", "fmuResourceLocation",
                                   ANY_STATE, ERROR_STATE, INSTANTIATED, "FMUstate", "value", "vr =", state_name,
                                   state_allowed};

/* --------------------------------------------------------------------------------- instances */

typedef struct {
    guard_instance common; /* first: a guarded* is a guard_instance* */
    fmi2CallbackFunctions host; /* the host's callbacks */
} guarded;

/* The host's logger, with the message as data, never as a format. */
static void host_log(guard_instance *common, int status, const char *category, const char *message) {
    guarded *g = (guarded *)common;
    g->host.logger(g->host.componentEnvironment, common->name, (fmi2Status)status, category, "%s", message);
}

static void destroy(guard_instance *common) {
    guarded *g = (guarded *)common;
    guard_free_common(common);
    free(g);
}

#define fail guard_fail
#define settle(g, status) ((fmi2Status)guard_settle(&(g)->common, (int)(status)))

/* Begin function F (fmi2F) on instance c: look it up (held until the function returns), check that its
 * state allows it. */
#define BEGIN_MASKED(F, MASK)                                                                                     \
    guarded *g GUARD_CALL = (guarded *)guard_acquire(c, MODEL_IDENTIFIER, "fmi2" #F);                             \
    if (!g) return fmi2Error;                                                                                     \
    guard_scope scope GUARD_SCOPE = guard_scope_begin(&g->common);                                                \
    (void)scope;                                                                                                  \
    g->common.function = "fmi2" #F;                                                                               \
    if (!(g->common.at.state & (MASK)))                                                                           \
        return (fmi2Status)guard_refuse_state(&g->common, "fmi2" #F, state_name(g->common.at.state))
#define BEGIN(F) BEGIN_MASKED(F, MASK_##F)

#define REQUIRE(condition, ...)                                                                                   \
    if (!(condition)) return (fmi2Status)fail(&g->common, __VA_ARGS__)

/* ---------------------------------------------------------------------- creation and destruction */

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn) {
    if (!functions || !functions->logger) {
        guard_orphan(MODEL_IDENTIFIER, "fmi2Instantiate", "%s is NULL: the host must give a logger (FMI 2.0, "
                     "section 2.1.5)", functions ? "functions->logger" : "functions");
        return NULL;
    }
    guarded *g = calloc(1, sizeof *g);
    if (!g || !guard_init_instance(&g->common, &FMI2, "CoSimulation", instanceName, loggingOn, host_log, destroy)) {
        guard_orphan(MODEL_IDENTIFIER, "fmi2Instantiate", "out of memory");
        if (g) free(g->common.name), free(g);
        return NULL;
    }
    g->host = *functions;
    g->common.function = "fmi2Instantiate";
    char why[2048] = "", resources[4096];
    if (fmuType != fmi2CoSimulation)
        text_format(why, sizeof why, "fmuType = %d: this FMU supports co-simulation (fmi2CoSimulation = %d) only",
                     (int)fmuType, (int)fmi2CoSimulation);
    else
        guard_check_instantiation(&FMI2, instanceName, fmuGUID, fmuResourceLocation, resources, sizeof resources, why,
                                  sizeof why);
    if (why[0]) fail(&g->common, "fmi2Instantiate: %s", why);
    if (why[0] || !guard_start_python(&g->common, resources, visible)) {
        guard_deliver_interrupt(&g->common);
        destroy(&g->common);
        return NULL;
    }
    if (!guard_register(&g->common)) {
        fail(&g->common, "fmi2Instantiate: out of memory");
        guard_deliver_interrupt(&g->common);
        destroy(&g->common);
        return NULL;
    }
    return g;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c) {
    if (c && !guard_unregister(c))
        guard_orphan(MODEL_IDENTIFIER, "fmi2FreeInstance", "%p is not a live instance of this FMU (freed twice?)",
                     c);
}

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[]) {
    BEGIN(SetDebugLogging);
    return (fmi2Status)guard_set_debug_logging(&g->common, loggingOn, nCategories, categories);
}

/* --------------------------------------------------------------------------------- the modes */

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                           fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    BEGIN(SetupExperiment);
    REQUIRE(isfinite(startTime), "fmi2SetupExperiment: startTime = %g s must be finite", startTime);
    REQUIRE(!stopTimeDefined || (isfinite(stopTime) && stopTime >= startTime),
            "fmi2SetupExperiment: stopTime = %g s must be finite and not before startTime = %g s", stopTime,
            startTime);
    REQUIRE(!toleranceDefined || (isfinite(tolerance) && tolerance > 0),
            "fmi2SetupExperiment: tolerance = %g must be finite and > 0", tolerance);
    fmi2Status status = settle(g, bridge_call(&g->common, NO_PAYLOAD, "setup_experiment", "(didid)", startTime,
                                              (int)stopTimeDefined, stopTime, (int)toleranceDefined, tolerance));
    if (status <= fmi2Warning) g->common.at.time = g->common.at.last_successful_time = startTime;
    return status;
}

/* Run a mode change of the Python side; on success the instance is in state `next`. */
#define MODE_CHANGE(F, method, next)                                                                              \
    FMI2_Export fmi2Status fmi2##F(fmi2Component c) {                                                             \
        BEGIN(F);                                                                                                 \
        fmi2Status status = settle(g, bridge_call(&g->common, NO_PAYLOAD, method, "()"));                         \
        if (status <= fmi2Warning) g->common.at.state = (next);                                                  \
        return status;                                                                                            \
    }
MODE_CHANGE(EnterInitializationMode, "enter_initialization_mode", INITIALIZATION)
MODE_CHANGE(ExitInitializationMode, "exit_initialization_mode", STEP_COMPLETE)
MODE_CHANGE(Terminate, "terminate", TERMINATED)

FMI2_Export fmi2Status fmi2Reset(fmi2Component c) {
    BEGIN(Reset);
    return (fmi2Status)guard_reset(&g->common);
}

/* ------------------------------------------------------------------------ getting and setting */

/* Every variable is a scalar: the values cross as bytes of `nvr` packed values (fmi2Integer and
 * fmi2Boolean are C ints, fmi2Real a double), named by their FMI type. `nvr` is checked against the FMU's
 * variables before any byte length is computed from it (a huge one would wrap). */
#define ACCESS_CHECKS(F)                                                                                          \
    if (nvr == 0) return fmi2OK;                                                                                  \
    REQUIRE(nvr <= N_VARIABLES, "fmi2" #F ": nvr = %zu, but this FMU has %zu variables", nvr, N_VARIABLES);      \
    REQUIRE(vr, "fmi2" #F ": vr is NULL with nvr = %zu", nvr);                                                    \
    REQUIRE(value, "fmi2" #F ": value is NULL with nvr = %zu", nvr)

#define GET(F, TYPE, NAME)                                                                                        \
    FMI2_Export fmi2Status fmi2##F(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, TYPE value[]) {  \
        BEGIN_MASKED(F, MASK_GET);                                                                                \
        ACCESS_CHECKS(F);                                                                                         \
        bridge_payload payload = {PAYLOAD_EXACT, value, nvr * sizeof *value, NULL, NULL, NULL};                  \
        return settle(g, bridge_call(&g->common, payload, "get", "(sy#)", NAME, (const char *)vr,                 \
                                     (ssize_t)(nvr * sizeof *vr)));                                              \
    }
#define SET(F, TYPE, NAME)                                                                                        \
    FMI2_Export fmi2Status fmi2##F(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,                  \
                                   const TYPE value[]) {                                                         \
        BEGIN_MASKED(F, MASK_SET);                                                                                \
        ACCESS_CHECKS(F);                                                                                         \
        return settle(g, bridge_call(&g->common, NO_PAYLOAD, "set", "(sy#y#)", NAME, (const char *)vr,            \
                                     (ssize_t)(nvr * sizeof *vr), (const char *)value,                           \
                                     (ssize_t)(nvr * sizeof *value)));                                           \
    }

GET(GetReal, fmi2Real, "Real")
GET(GetInteger, fmi2Integer, "Integer")
GET(GetBoolean, fmi2Boolean, "Boolean")
SET(SetReal, fmi2Real, "Real")
SET(SetInteger, fmi2Integer, "Integer")
SET(SetBoolean, fmi2Boolean, "Boolean")

FMI2_Export fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                     fmi2String value[]) {
    BEGIN_MASKED(GetString, MASK_GET);
    ACCESS_CHECKS(GetString);
    return (fmi2Status)guard_get_strings(&g->common, vr, nvr, value);
}

FMI2_Export fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                     const fmi2String value[]) {
    BEGIN_MASKED(SetString, MASK_SET);
    ACCESS_CHECKS(SetString);
    return (fmi2Status)guard_set_strings(&g->common, vr, nvr, value);
}

/* -------------------------------------------------------------------------------- FMU states */

FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    BEGIN(GetFMUstate);
    return (fmi2Status)guard_get_state(&g->common, FMUstate);
}

FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    BEGIN(SetFMUstate);
    return (fmi2Status)guard_set_state(&g->common, FMUstate);
}

FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    BEGIN(FreeFMUstate);
    return (fmi2Status)guard_free_state(&g->common, FMUstate);
}

FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    BEGIN(SerializedFMUstateSize);
    return (fmi2Status)guard_serialized_size(&g->common, FMUstate, size);
}

FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                             size_t size) {
    BEGIN(SerializeFMUstate);
    return (fmi2Status)guard_serialize_state(&g->common, FMUstate, (unsigned char *)serializedState, size);
}

FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                               fmi2FMUstate *FMUstate) {
    BEGIN(DeSerializeFMUstate);
    return (fmi2Status)guard_deserialize_state(&g->common, (const unsigned char *)serializedState, size, FMUstate);
}

/* ----------------------------------------------------------------- what this FMU does not offer */

FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                                    size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                                    size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown, (void)dvUnknown;
    BEGIN(GetDirectionalDerivative);
    return (fmi2Status)fail(&g->common, "fmi2GetDirectionalDerivative: not provided by this FMU "
                                        "(providesDirectionalDerivative = false)");
}

FMI2_Export fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                   const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    BEGIN(SetRealInputDerivatives);
    return (fmi2Status)fail(&g->common, "fmi2SetRealInputDerivatives: this FMU cannot interpolate inputs "
                                        "(canInterpolateInputs = false)");
}

FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[], fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    BEGIN(GetRealOutputDerivatives);
    return (fmi2Status)fail(&g->common, "fmi2GetRealOutputDerivatives: this FMU gives no output derivatives "
                                        "(maxOutputDerivativeOrder = 0)");
}

FMI2_Export fmi2Status fmi2CancelStep(fmi2Component c) {
    BEGIN(CancelStep); /* allowed in no state: this FMU's doStep is synchronous, never in progress */
    return (fmi2Status)fail(&g->common, "fmi2CancelStep: no step is in progress (doStep never returns fmi2Pending)");
}

/* ----------------------------------------------------------------------------- stepping */

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    BEGIN(DoStep);
    guard_position *at = &g->common.at;
    if (!guard_check_step(&g->common, currentCommunicationPoint, communicationStepSize)) return fmi2Error;
    int status = bridge_call(&g->common, NO_PAYLOAD, "do_step", "(ddi)", currentCommunicationPoint,
                             communicationStepSize, (int)noSetFMUStatePriorToCurrentPoint);
    if (status == fmi2Discard) { /* the solver gave up: the FMU stays where the step began */
        at->state = STEP_FAILED;
        at->last_successful_time = at->time;
        at->wants_to_terminate = 1;
        return fmi2Discard;
    }
    status = settle(g, status);
    if (status <= fmi2Warning) at->time = at->last_successful_time = currentCommunicationPoint + communicationStepSize;
    return (fmi2Status)status;
}

/* ----------------------------------------------------------------------------------- status */

static const char *const STATUS_KINDS[] = {"fmi2DoStepStatus", "fmi2PendingStatus", "fmi2LastSuccessfulTime",
                                           "fmi2Terminated"};

/* Check kind and value; a kind this function does not give is fmi2Discard (FMI 2.0, 4.2.3). */
#define STATUS_BEGIN(F)                                                                                           \
    BEGIN_MASKED(F, MASK_STATUS);                                                                                 \
    REQUIRE(value, "fmi2" #F ": value is NULL");                                                                  \
    REQUIRE((int)s >= (int)fmi2DoStepStatus && (int)s <= (int)fmi2Terminated,                                     \
            "fmi2" #F ": %d is not an fmi2StatusKind", (int)s)

static fmi2Status not_given(guarded *g, fmi2StatusKind s) {
    char message[256];
    text_format(message, sizeof message, "%s: %s is not given by this function%s", g->common.function,
                 STATUS_KINDS[s], s <= fmi2PendingStatus ? " (this FMU never returns fmi2Pending)" : "");
    guard_emit(&g->common, fmi2Discard, "logAll", message); /* informative: debug logging */
    return fmi2Discard;
}

FMI2_Export fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    STATUS_BEGIN(GetStatus);
    return not_given(g, s);
}

FMI2_Export fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    STATUS_BEGIN(GetRealStatus);
    if (s != fmi2LastSuccessfulTime) return not_given(g, s);
    *value = g->common.at.last_successful_time;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    STATUS_BEGIN(GetIntegerStatus);
    return not_given(g, s);
}

FMI2_Export fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    STATUS_BEGIN(GetBooleanStatus);
    if (s != fmi2Terminated) return not_given(g, s);
    *value = g->common.at.wants_to_terminate ? fmi2True : fmi2False;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    STATUS_BEGIN(GetStringStatus);
    return not_given(g, s);
}
