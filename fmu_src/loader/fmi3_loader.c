/* The FMU's binary for FMI 3.0 (Model Exchange and Co-Simulation): forwards the FMI functions to
 * pythonfmu3's library, which lies beside it as libpythonfmu3-export.so, after python_runtime.c has
 * made a CPython available in the process (as fmi2_loader.c does for pythonfmu).
 *
 * fmi3InstantiateModelExchange/CoSimulation load both on their first call; if no usable Python is
 * found they return NULL and say why in one line, through the host's logger and on stderr. Where
 * pythonfmu3 0.3.4 falls short of the standard, the loader stands in:
 *  - fmi3UpdateDiscreteStates, fmi3DoStep and fmi3CompletedIntegratorStep: every out-argument is
 *    initialised to its "nothing to do" value (no discrete-state update, no termination, nothing
 *    changed, no next event time; no event handling, no early return, the step's end reached)
 *    before pythonfmu3 writes what it writes: it leaves some of them unwritten, and a strict host
 *    that initialised discreteStatesNeedUpdate = true then iterates its Event Mode forever;
 *  - fmi3EnterInitializationMode: pythonfmu3 drops the start time, so the loader passes it on
 *    through fmi3SetTime first (the adapter takes it as the start time before initialisation);
 *  - the functions pythonfmu3 implements by throwing a C++ exception (the variable types this FMU
 *    does not have, clocks, binaries, dependencies, adjoint derivatives, Scheduled Execution),
 *    which would abort the host: they return fmi3Error and say so through the host's logger. */
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "python_runtime.h"

#define BACKEND_FILE "libpythonfmu3-export.so"

/* The functions forwarded to pythonfmu3's library. */
#define FMI3_FORWARDED(X)                                                                                         \
    X(fmi3SetDebugLogging) X(fmi3InstantiateModelExchange) X(fmi3InstantiateCoSimulation) X(fmi3FreeInstance)    \
    X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode) X(fmi3EnterEventMode) X(fmi3Terminate)          \
    X(fmi3Reset) X(fmi3GetFloat64) X(fmi3GetInt32) X(fmi3GetInt64) X(fmi3GetUInt64) X(fmi3GetBoolean)             \
    X(fmi3GetString) X(fmi3SetFloat64) X(fmi3SetInt32) X(fmi3SetInt64) X(fmi3SetUInt64) X(fmi3SetBoolean)        \
    X(fmi3SetString) X(fmi3GetFMUState) X(fmi3SetFMUState) X(fmi3FreeFMUState) X(fmi3SerializedFMUStateSize)    \
    X(fmi3SerializeFMUState) X(fmi3DeserializeFMUState) X(fmi3GetDirectionalDerivative)                         \
    X(fmi3EnterConfigurationMode) X(fmi3ExitConfigurationMode) X(fmi3UpdateDiscreteStates)                      \
    X(fmi3EnterContinuousTimeMode) X(fmi3CompletedIntegratorStep) X(fmi3SetTime) X(fmi3SetContinuousStates)      \
    X(fmi3GetContinuousStateDerivatives) X(fmi3GetEventIndicators) X(fmi3GetContinuousStates)                   \
    X(fmi3GetNominalsOfContinuousStates) X(fmi3GetNumberOfEventIndicators) X(fmi3GetNumberOfContinuousStates)   \
    X(fmi3EnterStepMode) X(fmi3GetOutputDerivatives) X(fmi3DoStep)

#define DECLARE(name) static name##TYPE *backend_##name;
FMI3_FORWARDED(DECLARE)

static pthread_mutex_t resolve_lock = PTHREAD_MUTEX_INITIALIZER;
static int resolved;

static int resolve(void *backend, char *error, size_t size) {
    pthread_mutex_lock(&resolve_lock);
    if (!resolved) {
#define RESOLVE(name)                                                                                             \
    backend_##name = (name##TYPE *)dlsym(backend, #name);                                                        \
    if (!backend_##name) snprintf(error, size, "pythonfmu3's library lacks %s", #name);
        FMI3_FORWARDED(RESOLVE)
        resolved = !error[0];
    }
    int ok = resolved;
    pthread_mutex_unlock(&resolve_lock);
    return ok;
}

/* ------------------------------------------------------- the instances' loggers, for our messages */

typedef struct logger_entry {
    fmi3Instance instance;
    char name[128];
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log;
    struct logger_entry *next;
} logger_entry;

static pthread_mutex_t loggers_lock = PTHREAD_MUTEX_INITIALIZER;
static logger_entry *loggers;

static void remember_logger(fmi3Instance instance, fmi3String name, fmi3InstanceEnvironment environment,
                            fmi3LogMessageCallback log) {
    logger_entry *entry = malloc(sizeof *entry);
    if (!entry) return;
    *entry = (logger_entry){instance, "", environment, log, NULL};
    snprintf(entry->name, sizeof entry->name, "%s", name ? name : "");
    pthread_mutex_lock(&loggers_lock);
    entry->next = loggers;
    loggers = entry;
    pthread_mutex_unlock(&loggers_lock);
}

static void forget_logger(fmi3Instance instance) {
    pthread_mutex_lock(&loggers_lock);
    for (logger_entry **at = &loggers; *at; at = &(*at)->next) {
        if ((*at)->instance == instance) {
            logger_entry *gone = *at;
            *at = gone->next;
            free(gone);
            break;
        }
    }
    pthread_mutex_unlock(&loggers_lock);
}

/* One line through the logger (FMI 3 messages are plain text, no format) and on stderr. */
static void report(fmi3InstanceEnvironment environment, fmi3LogMessageCallback log, fmi3String name,
                   const char *message) {
    fprintf(stderr, "[%s] %s\n", name ? name : "?", message);
    fflush(stderr);
    if (log) log(environment, fmi3Error, "logStatusError", message);
}

static fmi3Status unsupported(fmi3Instance instance, const char *function, const char *why) {
    char message[512];
    snprintf(message, sizeof message, "%s is not supported by this FMU (%s)", function, why);
    logger_entry found = {instance, "?", NULL, NULL, NULL};
    pthread_mutex_lock(&loggers_lock);
    for (logger_entry *entry = loggers; entry; entry = entry->next)
        if (entry->instance == instance) {
            found = *entry;
            break;
        }
    pthread_mutex_unlock(&loggers_lock);
    report(found.environment, found.log, found.name, message);
    return fmi3Error;
}

/* ----------------------------------------------------------------------------- instantiation */

FMI3_Export const char *fmi3GetVersion(void) { return fmi3Version; }

/* Load Python and pythonfmu3's library; NULL (said through the logger) if that fails. */
static void *backend_for(fmi3String name, fmi3String resources, fmi3InstanceEnvironment environment,
                         fmi3LogMessageCallback log) {
    char error[4096] = "";
    void *backend = python_runtime_load_backend(resources, BACKEND_FILE, error, sizeof error);
    if (!backend || !resolve(backend, error, sizeof error)) {
        report(environment, log, name, error);
        return NULL;
    }
    return backend;
}

FMI3_Export fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                                                      fmi3LogMessageCallback logMessage) {
    if (!backend_for(instanceName, resourcePath, environment, logMessage)) return NULL;
    fmi3Instance instance = backend_fmi3InstantiateModelExchange(instanceName, instantiationToken, resourcePath,
                                                                 visible, loggingOn, environment, logMessage);
    if (instance) remember_logger(instance, instanceName, environment, logMessage);
    return instance;
}

FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
    const fmi3ValueReference requiredIntermediateVariables[], size_t nRequiredIntermediateVariables,
    fmi3InstanceEnvironment environment, fmi3LogMessageCallback logMessage,
    fmi3IntermediateUpdateCallback intermediateUpdate) {
    if (!backend_for(instanceName, resourcePath, environment, logMessage)) return NULL;
    fmi3Instance instance = backend_fmi3InstantiateCoSimulation(
        instanceName, instantiationToken, resourcePath, visible, loggingOn, eventModeUsed, earlyReturnAllowed,
        requiredIntermediateVariables, nRequiredIntermediateVariables, environment, logMessage, intermediateUpdate);
    if (instance) remember_logger(instance, instanceName, environment, logMessage);
    return instance;
}

FMI3_Export fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3InstanceEnvironment environment, fmi3LogMessageCallback logMessage,
    fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
    fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    report(environment, logMessage, instanceName,
           "fmi3InstantiateScheduledExecution: this FMU offers Model Exchange and Co-Simulation only");
    return NULL;
}

FMI3_Export void fmi3FreeInstance(fmi3Instance instance) {
    if (!instance || !backend_fmi3FreeInstance) return;
    forget_logger(instance);
    backend_fmi3FreeInstance(instance);
}

/* ------------------------------------------------------------------------ guarded functions */

FMI3_Export fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance, fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    if (!instance || !backend_fmi3EnterInitializationMode) return fmi3Error;
    fmi3Status status = backend_fmi3SetTime(instance, startTime); /* the start time, which pythonfmu3 drops */
    if (status > fmi3Warning) return status;
    return backend_fmi3EnterInitializationMode(instance, toleranceDefined, tolerance, startTime, stopTimeDefined,
                                               stopTime);
}

#define COPY_OUT(pointer, value)                                                                                  \
    if (pointer) *(pointer) = (value)

FMI3_Export fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    fmi3Boolean update = fmi3False, terminate = fmi3False, nominals = fmi3False, values = fmi3False;
    fmi3Boolean defined = fmi3False;
    fmi3Float64 next = 0.0;
    fmi3Status status = fmi3Error;
    if (instance && backend_fmi3UpdateDiscreteStates)
        status = backend_fmi3UpdateDiscreteStates(instance, &update, &terminate, &nominals, &values, &defined, &next);
    COPY_OUT(discreteStatesNeedUpdate, update);
    COPY_OUT(terminateSimulation, terminate);
    COPY_OUT(nominalsOfContinuousStatesChanged, nominals);
    COPY_OUT(valuesOfContinuousStatesChanged, values);
    COPY_OUT(nextEventTimeDefined, defined);
    COPY_OUT(nextEventTime, defined ? next : 0.0);
    return status;
}

FMI3_Export fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    fmi3Boolean event = fmi3False, terminate = fmi3False;
    fmi3Status status = fmi3Error;
    if (instance && backend_fmi3CompletedIntegratorStep)
        status = backend_fmi3CompletedIntegratorStep(instance, noSetFMUStatePriorToCurrentPoint, &event, &terminate);
    COPY_OUT(enterEventMode, event);
    COPY_OUT(terminateSimulation, terminate);
    return status;
}

FMI3_Export fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                                  fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
    fmi3Float64 reached = currentCommunicationPoint;
    fmi3Status status = fmi3Error;
    if (instance && backend_fmi3DoStep)
        status = backend_fmi3DoStep(instance, currentCommunicationPoint, communicationStepSize,
                                    noSetFMUStatePriorToCurrentPoint, &event, &terminate, &early, &reached);
    COPY_OUT(eventHandlingNeeded, event);
    COPY_OUT(terminateSimulation, terminate);
    COPY_OUT(earlyReturn, early);
    COPY_OUT(lastSuccessfulTime, reached);
    return status;
}

/* ------------------------------------------------------------------------- plain forwarding */

/* The instance came from pythonfmu3's library, so it is loaded and resolved. */
#define FORWARD(name, parameters, arguments)                                                                      \
    FMI3_Export fmi3Status name parameters {                                                                      \
        return instance && backend_##name ? backend_##name arguments : fmi3Error;                                \
    }
#define VR const fmi3ValueReference vr[], size_t nvr /* the value references of a get or set */
#define GET(name, type) FORWARD(name, (fmi3Instance instance, VR, type v[], size_t n), (instance, vr, nvr, v, n))
#define SET(name, type) FORWARD(name, (fmi3Instance instance, VR, const type v[], size_t n), (instance, vr, nvr, v, n))
#define MODE(name) FORWARD(name, (fmi3Instance instance), (instance))
#define VECTOR(name, type) FORWARD(name, (fmi3Instance instance, type v[], size_t n), (instance, v, n))

FORWARD(fmi3SetDebugLogging, (fmi3Instance instance, fmi3Boolean on, size_t n, const fmi3String categories[]),
        (instance, on, n, categories))
MODE(fmi3ExitInitializationMode)
MODE(fmi3EnterEventMode)
MODE(fmi3Terminate)
MODE(fmi3Reset)
MODE(fmi3EnterConfigurationMode)
MODE(fmi3ExitConfigurationMode)
MODE(fmi3EnterContinuousTimeMode)
MODE(fmi3EnterStepMode)
GET(fmi3GetFloat64, fmi3Float64)
GET(fmi3GetInt32, fmi3Int32)
GET(fmi3GetInt64, fmi3Int64)
GET(fmi3GetUInt64, fmi3UInt64)
GET(fmi3GetBoolean, fmi3Boolean)
GET(fmi3GetString, fmi3String)
SET(fmi3SetFloat64, fmi3Float64)
SET(fmi3SetInt32, fmi3Int32)
SET(fmi3SetInt64, fmi3Int64)
SET(fmi3SetUInt64, fmi3UInt64)
SET(fmi3SetBoolean, fmi3Boolean)
SET(fmi3SetString, fmi3String)
FORWARD(fmi3GetFMUState, (fmi3Instance instance, fmi3FMUState *s), (instance, s))
FORWARD(fmi3SetFMUState, (fmi3Instance instance, fmi3FMUState s), (instance, s))
FORWARD(fmi3FreeFMUState, (fmi3Instance instance, fmi3FMUState *s), (instance, s))
FORWARD(fmi3SerializedFMUStateSize, (fmi3Instance instance, fmi3FMUState s, size_t *size), (instance, s, size))
FORWARD(fmi3SerializeFMUState, (fmi3Instance instance, fmi3FMUState s, fmi3Byte bytes[], size_t size),
        (instance, s, bytes, size))
FORWARD(fmi3DeserializeFMUState, (fmi3Instance instance, const fmi3Byte bytes[], size_t size, fmi3FMUState *s),
        (instance, bytes, size, s))
FORWARD(fmi3GetDirectionalDerivative, (fmi3Instance instance, const fmi3ValueReference unknowns[], size_t n_unknowns,
                                       const fmi3ValueReference knowns[], size_t n_knowns, const fmi3Float64 seed[],
                                       size_t n_seed, fmi3Float64 sensitivity[], size_t n_sensitivity),
        (instance, unknowns, n_unknowns, knowns, n_knowns, seed, n_seed, sensitivity, n_sensitivity))
FORWARD(fmi3SetTime, (fmi3Instance instance, fmi3Float64 time), (instance, time))
FORWARD(fmi3SetContinuousStates, (fmi3Instance instance, const fmi3Float64 x[], size_t n), (instance, x, n))
VECTOR(fmi3GetContinuousStateDerivatives, fmi3Float64)
VECTOR(fmi3GetEventIndicators, fmi3Float64)
VECTOR(fmi3GetContinuousStates, fmi3Float64)
VECTOR(fmi3GetNominalsOfContinuousStates, fmi3Float64)
FORWARD(fmi3GetNumberOfEventIndicators, (fmi3Instance instance, size_t *n), (instance, n))
FORWARD(fmi3GetNumberOfContinuousStates, (fmi3Instance instance, size_t *n), (instance, n))
FORWARD(fmi3GetOutputDerivatives, (fmi3Instance instance, VR, const fmi3Int32 orders[], fmi3Float64 v[], size_t n),
        (instance, vr, nvr, orders, v, n))

/* ------------------------------------------------------- what pythonfmu3 answers with a throw */

#define NO_TYPE "it has Float64, Boolean and String variables only"
#define NO_CLOCKS "it has no clocks"
#define UNSUPPORTED(name, parameters, why)                                                                        \
    FMI3_Export fmi3Status name parameters { return unsupported(instance, #name, why); }
#define UNSUPPORTED_GET(name, type) UNSUPPORTED(name, (fmi3Instance instance, VR, type v[], size_t n), NO_TYPE)
#define UNSUPPORTED_SET(name, type) UNSUPPORTED(name, (fmi3Instance instance, VR, const type v[], size_t n), NO_TYPE)

UNSUPPORTED_GET(fmi3GetFloat32, fmi3Float32)
UNSUPPORTED_GET(fmi3GetInt8, fmi3Int8)
UNSUPPORTED_GET(fmi3GetUInt8, fmi3UInt8)
UNSUPPORTED_GET(fmi3GetInt16, fmi3Int16)
UNSUPPORTED_GET(fmi3GetUInt16, fmi3UInt16)
UNSUPPORTED_GET(fmi3GetUInt32, fmi3UInt32)
UNSUPPORTED_SET(fmi3SetFloat32, fmi3Float32)
UNSUPPORTED_SET(fmi3SetInt8, fmi3Int8)
UNSUPPORTED_SET(fmi3SetUInt8, fmi3UInt8)
UNSUPPORTED_SET(fmi3SetInt16, fmi3Int16)
UNSUPPORTED_SET(fmi3SetUInt16, fmi3UInt16)
UNSUPPORTED_SET(fmi3SetUInt32, fmi3UInt32)
UNSUPPORTED(fmi3GetBinary, (fmi3Instance instance, VR, size_t sizes[], fmi3Binary v[], size_t n), NO_TYPE)
UNSUPPORTED(fmi3SetBinary, (fmi3Instance instance, VR, const size_t sizes[], const fmi3Binary v[], size_t n), NO_TYPE)
UNSUPPORTED(fmi3GetClock, (fmi3Instance instance, VR, fmi3Clock v[]), NO_CLOCKS)
UNSUPPORTED(fmi3SetClock, (fmi3Instance instance, VR, const fmi3Clock v[]), NO_CLOCKS)
UNSUPPORTED(fmi3GetIntervalDecimal, (fmi3Instance instance, VR, fmi3Float64 v[], fmi3IntervalQualifier q[]), NO_CLOCKS)
UNSUPPORTED(fmi3GetIntervalFraction,
            (fmi3Instance instance, VR, fmi3UInt64 c[], fmi3UInt64 r[], fmi3IntervalQualifier q[]), NO_CLOCKS)
UNSUPPORTED(fmi3GetShiftDecimal, (fmi3Instance instance, VR, fmi3Float64 v[]), NO_CLOCKS)
UNSUPPORTED(fmi3GetShiftFraction, (fmi3Instance instance, VR, fmi3UInt64 c[], fmi3UInt64 r[]), NO_CLOCKS)
UNSUPPORTED(fmi3SetIntervalDecimal, (fmi3Instance instance, VR, const fmi3Float64 v[]), NO_CLOCKS)
UNSUPPORTED(fmi3SetIntervalFraction, (fmi3Instance instance, VR, const fmi3UInt64 c[], const fmi3UInt64 r[]),
            NO_CLOCKS)
UNSUPPORTED(fmi3SetShiftDecimal, (fmi3Instance instance, VR, const fmi3Float64 v[]), NO_CLOCKS)
UNSUPPORTED(fmi3SetShiftFraction, (fmi3Instance instance, VR, const fmi3UInt64 c[], const fmi3UInt64 r[]), NO_CLOCKS)
UNSUPPORTED(fmi3EvaluateDiscreteStates, (fmi3Instance instance), "it has no discrete states")
UNSUPPORTED(fmi3ActivateModelPartition, (fmi3Instance instance, fmi3ValueReference clock, fmi3Float64 time),
            "Scheduled Execution is not offered")
UNSUPPORTED(fmi3GetNumberOfVariableDependencies, (fmi3Instance instance, fmi3ValueReference v, size_t *n),
            "the dependencies are in the modelDescription")
UNSUPPORTED(fmi3GetVariableDependencies,
            (fmi3Instance instance, fmi3ValueReference dependent, size_t element_of_dependent[],
             fmi3ValueReference independents[], size_t element_of_independents[], fmi3DependencyKind kinds[],
             size_t n),
            "the dependencies are in the modelDescription")
UNSUPPORTED(fmi3GetAdjointDerivative,
            (fmi3Instance instance, const fmi3ValueReference unknowns[], size_t n_unknowns,
             const fmi3ValueReference knowns[], size_t n_knowns, const fmi3Float64 seed[], size_t n_seed,
             fmi3Float64 sensitivity[], size_t n_sensitivity),
            "it provides no adjoint derivatives")
