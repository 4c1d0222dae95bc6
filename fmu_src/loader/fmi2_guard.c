/* The FMU's binary for FMI 2.0 co-simulation: a guard in front of pythonfmu's library, which lies
 * beside it as libpythonfmu-export.so and runs the FMU's Python side (python_runtime.c makes a
 * CPython available first).
 *
 * Whatever the Python side does, the host sees the behaviour of FMI 2.0 (sections 2.1.3, 2.1.5,
 * 4.2.4; modelled on modelica/Reference-FMUs, written anew):
 *  - every instance follows the co-simulation state machine: a call the current state does not
 *    allow returns fmi2Error with one log line naming the function and the state; after an error
 *    only what the standard allows in its Error state (get values, FMU states, reset, free,
 *    setDebugLogging);
 *  - arguments are checked before anything is forwarded: the instance (NULL, freed, foreign), NULL
 *    arrays with n > 0, every pointer the standard requires, String values that are not UTF-8,
 *    doStep's step size (> 0, finite) and communication point (the FMU's time: the end of the last
 *    step, or of the FMU state set);
 *  - fmi2Instantiate refuses (NULL and one line; stderr where the host gave no logger) a wrong GUID,
 *    Model Exchange, a missing or non-UTF-8 instance name, a missing resource location, a folder that
 *    is not this FMU's;
 *  - the host's logger is only ever called with the constant format "%s" and the message as its
 *    argument; errors reach it from instantiation on, other messages only with debug logging on
 *    (fmi2SetDebugLogging as specified);
 *  - pythonfmu answers every Python exception with fmi2Fatal ("every instance is lost"); for this FMU
 *    such an error leaves the other instances untouched and this one resettable: fmi2Error;
 *  - instantiation and reset, which import and edit sys.path, are serialised across threads; every
 *    other call runs in parallel (different instances in different threads).
 * The FMU states the host gets are the guard's (guard.h): the library's state with the instance's
 * FMI state and time, so that fmi2SetFMUstate also restores where the next doStep starts. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "guard.h"
#include "python_runtime.h"

#ifndef FMU_GUID
#error "the build defines FMU_GUID, the guid of the FMU's modelDescription.xml"
#endif
#ifndef MODEL_IDENTIFIER
#error "the build defines MODEL_IDENTIFIER"
#endif

#define BACKEND_FILE "libpythonfmu-export.so"
#define STATE_MAGIC "DPFMU2S1"

/* ------------------------------------------------------------------------- pythonfmu's library */

#define FMI2_FORWARDED(X)                                                                                         \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment) X(fmi2EnterInitializationMode)                 \
    X(fmi2ExitInitializationMode) X(fmi2Terminate) X(fmi2Reset) X(fmi2GetReal) X(fmi2GetInteger)                \
    X(fmi2GetBoolean) X(fmi2GetString) X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean) X(fmi2SetString)     \
    X(fmi2GetFMUstate) X(fmi2SetFMUstate) X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize)                     \
    X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate) X(fmi2DoStep)

#define DECLARE(name) static name##TYPE *backend_##name;
FMI2_FORWARDED(DECLARE)
static pthread_mutex_t resolve_lock = PTHREAD_MUTEX_INITIALIZER;
static int resolved;

static int resolve(void *backend, char *error, size_t size) {
    pthread_mutex_lock(&resolve_lock);
    if (!resolved) {
        error[0] = '\0';
#define RESOLVE(name)                                                                                             \
    backend_##name = (name##TYPE *)dlsym(backend, #name);                                                        \
    if (!backend_##name) guard_format(error, size, "pythonfmu's library lacks %s", #name);
        FMI2_FORWARDED(RESOLVE)
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
#define MASK_STATUS (STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR_STATE)

/* --------------------------------------------------------------------------------- instances */

typedef struct {
    guard_instance common; /* first: a guarded* is a guard_instance* */
    fmi2Component backend;
    fmi2CallbackFunctions host;  /* the host's callbacks */
    fmi2CallbackFunctions inner; /* pythonfmu's: its messages come to library_logger */
} guarded;

/* The host's logger, with the message as data, never as a format. */
static void host_log(guard_instance *common, int status, const char *category, const char *message) {
    guarded *g = (guarded *)common;
    g->host.logger(g->host.componentEnvironment, common->name, (fmi2Status)status, category, "%s", message);
}

/* The logger pythonfmu gets: its message is text (it passes no arguments), never a format. */
static void library_logger(fmi2ComponentEnvironment environment, fmi2String instance_name, fmi2Status status,
                           fmi2String category, fmi2String message, ...) {
    (void)instance_name;
    if (environment) guard_library_message_logged(environment, (int)status, category, message);
}

#define fail guard_fail
#define settle(g, status) ((fmi2Status)guard_settle(&(g)->common, (int)(status)))

/* Begin function F (fmi2F) on instance c: look it up, check that its state allows it. */
#define BEGIN_MASKED(F, MASK)                                                                                     \
    guarded *g = (guarded *)guard_lookup(c, MODEL_IDENTIFIER, "fmi2" #F);                                         \
    if (!g) return fmi2Error;                                                                                     \
    if (!(g->common.at.state & (MASK)))                                                                           \
        return (fmi2Status)fail(&g->common, "fmi2" #F ": illegal call sequence: not allowed in state %s",        \
                                state_name(g->common.at.state));                                                 \
    g->common.function = "fmi2" #F
#define BEGIN(F) BEGIN_MASKED(F, MASK_##F)

#define REQUIRE(condition, ...)                                                                                   \
    if (!(condition)) return (fmi2Status)fail(&g->common, __VA_ARGS__)

/* ---------------------------------------------------------------------- creation and destruction */

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

/* Check the arguments of fmi2Instantiate; 0 and a message in `why` if they are wrong. */
static int instantiation_allowed(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                                 char *resources, size_t size, char *why, size_t why_size) {
    char marker[4200];
    long bad;
    if (!name || !name[0]) guard_format(why, why_size, "instanceName is %s", name ? "empty" : "NULL");
    else if ((bad = guard_utf8_error(name)) >= 0)
        guard_format(why, why_size, "instanceName is not UTF-8 (byte %ld is 0x%02x; an fmi2String is UTF-8 encoded)",
                     bad, (unsigned char)name[bad]);
    else if (type != fmi2CoSimulation)
        guard_format(why, why_size, "fmuType = %d: this FMU supports co-simulation (fmi2CoSimulation = %d) only",
                     (int)type, (int)fmi2CoSimulation);
    else if (!guid || strcmp(guid, FMU_GUID) != 0)
        guard_format(why, why_size,
                     "fmuGUID %s%.100s%s is not this FMU's %s: the binary and its modelDescription.xml come "
                     "from different builds", guid ? "\"" : "", guid ? guid : "NULL", guid ? "\"" : "", FMU_GUID);
    else if (!location || !location[0])
        guard_format(why, why_size, "fmuResourceLocation is %s: the FMU needs its resources folder",
                     location ? "empty" : "NULL");
    else if (!guard_uri_to_path(location, resources, size))
        guard_format(why, why_size, "fmuResourceLocation \"%.1000s\" is not a file URI of this machine", location);
    else if (!guard_is_directory(resources))
        guard_format(why, why_size, "fmuResourceLocation \"%.1000s\": there is no folder %.1000s", location,
                     resources);
    else if (guard_format(marker, sizeof marker, "%s/slavemodule.txt", resources), !guard_is_file(marker))
        guard_format(why, why_size, "fmuResourceLocation \"%.1000s\" is not this FMU's resources folder "
                     "(no slavemodule.txt in %.1000s)", location, resources);
    else if ((bad = guard_utf8_error(resources)) >= 0)
        guard_format(why, why_size, "fmuResourceLocation \"%.1000s\": the folder's path is not UTF-8 (byte %ld), "
                     "which the FMU's Python side cannot take", location, bad);
    else
        return 1;
    return 0;
}

static void free_guarded(guarded *g) {
    free(g->common.name);
    free(g);
}

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn) {
    if (!functions || !functions->logger) {
        guard_orphan(MODEL_IDENTIFIER, "fmi2Instantiate", "%s is NULL: the host must give a logger (FMI 2.0, "
                     "section 2.1.5)", functions ? "functions->logger" : "functions");
        return NULL;
    }
    char why[2048] = "", resources[4096];
    guarded *g = calloc(1, sizeof *g);
    char *uri = malloc(sizeof resources + 8);
    char *name = strdup(instanceName && instanceName[0] && guard_utf8_error(instanceName) < 0 ? instanceName : "?");
    if (!g || !uri || !name) {
        guard_orphan(MODEL_IDENTIFIER, "fmi2Instantiate", "out of memory");
        free(g), free(uri), free(name);
        return NULL;
    }
    g->common = (guard_instance){.at = {INSTANTIATED, 0.0, 0.0, 0}, .error_state = ERROR_STATE,
                                 .categories = loggingOn ? CATEGORIES_EVERY : CATEGORIES_ERRORS,
                                 .function = "fmi2Instantiate", .name = name, .log = host_log};
    g->host = g->inner = *functions;
    g->inner.logger = library_logger;
    g->inner.componentEnvironment = &g->common;
    void *backend = NULL;
    if (!instantiation_allowed(instanceName, fmuType, fmuGUID, fmuResourceLocation, resources, sizeof resources, why,
                               sizeof why) ||
        !(backend = python_runtime_load_backend(fmuResourceLocation, BACKEND_FILE, why, sizeof why)) ||
        !resolve(backend, why, sizeof why)) {
        fail(&g->common, "fmi2Instantiate: %s", why);
        free_guarded(g), free(uri);
        return NULL;
    }
    snprintf(uri, sizeof resources + 8, "file://%s", resources); /* the one form pythonfmu reads */
    guard_lock_python(&python_lock);
    /* logging on: every message comes to library_logger, which lets through what the host asked for */
    g->backend = backend_fmi2Instantiate(instanceName, fmuType, fmuGUID, uri, &g->inner, visible, fmi2True);
    pthread_mutex_unlock(&python_lock);
    free(uri);
    if (!g->backend || !guard_register(&g->common)) {
        fail(&g->common, "fmi2Instantiate: the FMU's Python side could not be instantiated%s",
             g->backend ? " (out of memory)" : " (the message before says why)");
        if (g->backend) backend_fmi2FreeInstance(g->backend);
        free_guarded(g);
        return NULL;
    }
    return g;
}

/* Forget state s and free it, with its library state. */
static void free_state(guarded *g, guard_state *s) {
    guard_state_forget(s);
    if (s->backend) backend_fmi2FreeFMUstate(g->backend, (fmi2FMUstate *)&s->backend);
    free(s);
}

FMI2_Export void fmi2FreeInstance(fmi2Component c) {
    if (!c) return;
    if (!guard_unregister(c)) {
        guard_orphan(MODEL_IDENTIFIER, "fmi2FreeInstance", "%p is not a live instance of this FMU (freed twice?)",
                     c);
        return;
    }
    guarded *g = (guarded *)c;
    g->common.function = "fmi2FreeInstance";
    while (g->common.states) free_state(g, g->common.states); /* the FMU states the host did not free */
    backend_fmi2FreeInstance(g->backend);
    free_guarded(g);
}

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[]) {
    BEGIN(SetDebugLogging);
    return (fmi2Status)guard_set_debug_logging(&g->common, loggingOn, nCategories, categories,
                                               "fmi2SetDebugLogging");
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
    fmi2Status status = settle(g, backend_fmi2SetupExperiment(g->backend, toleranceDefined, tolerance, startTime,
                                                               stopTimeDefined, stopTime));
    if (status <= fmi2Warning) g->common.at.time = g->common.at.last_successful_time = startTime;
    return status;
}

/* Run a mode change of the library; on success the instance is in state `next`. */
#define MODE_CHANGE(F, next)                                                                                      \
    FMI2_Export fmi2Status fmi2##F(fmi2Component c) {                                                             \
        BEGIN(F);                                                                                                 \
        fmi2Status status = settle(g, backend_fmi2##F(g->backend));                                              \
        if (status <= fmi2Warning) g->common.at.state = (next);                                                  \
        return status;                                                                                            \
    }
MODE_CHANGE(EnterInitializationMode, INITIALIZATION)
MODE_CHANGE(ExitInitializationMode, STEP_COMPLETE)
MODE_CHANGE(Terminate, TERMINATED)

FMI2_Export fmi2Status fmi2Reset(fmi2Component c) {
    BEGIN(Reset);
    guard_lock_python(&python_lock); /* the Python side is made anew */
    fmi2Status status = settle(g, backend_fmi2Reset(g->backend));
    pthread_mutex_unlock(&python_lock);
    if (status <= fmi2Warning) g->common.at = (guard_position){INSTANTIATED, 0.0, 0.0, 0};
    return status;
}

/* ------------------------------------------------------------------------ getting and setting */

#define ACCESS(F, TYPE, MASK, VALUES_CONST, CHECK_VALUES)                                                        \
    FMI2_Export fmi2Status fmi2##F(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,                  \
                                   VALUES_CONST TYPE value[]) {                                                  \
        BEGIN_MASKED(F, MASK);                                                                                    \
        if (nvr == 0) return fmi2OK;                                                                              \
        REQUIRE(vr, "fmi2" #F ": vr is NULL with nvr = %zu", nvr);                                                \
        REQUIRE(value, "fmi2" #F ": value is NULL with nvr = %zu", nvr);                                          \
        CHECK_VALUES                                                                                              \
        return settle(g, backend_fmi2##F(g->backend, vr, nvr, value));                                           \
    }
#define NO_CHECK
#define STRINGS_PRESENT                                                                                           \
    for (size_t k = 0; k < nvr; k++) {                                                                            \
        REQUIRE(value[k], "fmi2SetString: value[%zu] (vr = %u) is NULL", k, vr[k]);                               \
        long bad = guard_utf8_error(value[k]);                                                                    \
        REQUIRE(bad < 0, "fmi2SetString: value[%zu] (vr = %u) is not UTF-8 (byte %ld is 0x%02x; an fmi2String is " \
                "UTF-8 encoded)", k, vr[k], bad, (unsigned char)value[k][bad]);                                   \
    }

ACCESS(GetReal, fmi2Real, MASK_GET, , NO_CHECK)
ACCESS(GetInteger, fmi2Integer, MASK_GET, , NO_CHECK)
ACCESS(GetBoolean, fmi2Boolean, MASK_GET, , NO_CHECK)
ACCESS(GetString, fmi2String, MASK_GET, , NO_CHECK)
ACCESS(SetReal, fmi2Real, MASK_SET, const, NO_CHECK)
ACCESS(SetInteger, fmi2Integer, MASK_SET, const, NO_CHECK)
ACCESS(SetBoolean, fmi2Boolean, MASK_SET, const, NO_CHECK)
ACCESS(SetString, fmi2String, MASK_SET, const, STRINGS_PRESENT)

/* -------------------------------------------------------------------------------- FMU states */

/* Into *FMUstate (a new state if NULL, else a live one, overwritten) the library's state `backend`
 * at position `at`; `backend` is freed if that fails. */
static fmi2Status deliver_state(guarded *g, fmi2FMUstate *FMUstate, fmi2FMUstate backend, guard_position at) {
    guard_state *s = *FMUstate;
    if (s) {
        if (s->backend) backend_fmi2FreeFMUstate(g->backend, (fmi2FMUstate *)&s->backend);
        s->backend = backend;
        s->at = at;
        return fmi2OK;
    }
    if (!(s = guard_state_new(&g->common, backend, at))) {
        backend_fmi2FreeFMUstate(g->backend, &backend);
        return (fmi2Status)fail(&g->common, "%s: out of memory", g->common.function);
    }
    *FMUstate = s;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    BEGIN(GetFMUstate);
    REQUIRE(FMUstate, "fmi2GetFMUstate: FMUstate is NULL");
    if (*FMUstate && !guard_state_known(&g->common, *FMUstate, "fmi2GetFMUstate")) return fmi2Error;
    fmi2FMUstate backend = NULL;
    fmi2Status status = settle(g, backend_fmi2GetFMUstate(g->backend, &backend));
    return status > fmi2Warning ? status : deliver_state(g, FMUstate, backend, g->common.at);
}

FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    BEGIN(SetFMUstate);
    guard_state *s = guard_state_known(&g->common, FMUstate, "fmi2SetFMUstate");
    if (!s) return fmi2Error;
    fmi2Status status = settle(g, backend_fmi2SetFMUstate(g->backend, s->backend));
    if (status <= fmi2Warning) g->common.at = s->at;
    return status;
}

FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    BEGIN(FreeFMUstate);
    REQUIRE(FMUstate, "fmi2FreeFMUstate: FMUstate is NULL");
    if (!*FMUstate) return fmi2OK; /* nothing to free */
    guard_state *s = guard_state_known(&g->common, *FMUstate, "fmi2FreeFMUstate");
    if (!s) return fmi2Error;
    free_state(g, s);
    *FMUstate = NULL;
    return fmi2OK;
}

/* The size of the library's serialized state `s`. */
static fmi2Status backend_size(guarded *g, guard_state *s, size_t *size) {
    *size = 0;
    return settle(g, backend_fmi2SerializedFMUstateSize(g->backend, s->backend, size));
}

FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    BEGIN(SerializedFMUstateSize);
    REQUIRE(size, "fmi2SerializedFMUstateSize: size is NULL");
    guard_state *s = guard_state_known(&g->common, FMUstate, "fmi2SerializedFMUstateSize");
    if (!s) return fmi2Error;
    size_t inner = 0;
    fmi2Status status = backend_size(g, s, &inner);
    if (status <= fmi2Warning) *size = sizeof(guard_state_header) + inner;
    return status;
}

FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                             size_t size) {
    BEGIN(SerializeFMUstate);
    REQUIRE(serializedState, "fmi2SerializeFMUstate: serializedState is NULL");
    guard_state *s = guard_state_known(&g->common, FMUstate, "fmi2SerializeFMUstate");
    if (!s) return fmi2Error;
    size_t inner = 0;
    fmi2Status status = backend_size(g, s, &inner);
    if (status > fmi2Warning) return status;
    REQUIRE(size == sizeof(guard_state_header) + inner,
            "fmi2SerializeFMUstate: size = %zu, but fmi2SerializedFMUstateSize gives %zu", size,
            sizeof(guard_state_header) + inner);
    guard_state_header header;
    guard_header_write(&header, STATE_MAGIC, FMU_GUID, s->at);
    memcpy(serializedState, &header, sizeof header);
    return settle(g, backend_fmi2SerializeFMUstate(g->backend, s->backend, serializedState + sizeof header, inner));
}

FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                               fmi2FMUstate *FMUstate) {
    BEGIN(DeSerializeFMUstate);
    REQUIRE(serializedState, "fmi2DeSerializeFMUstate: serializedState is NULL");
    REQUIRE(FMUstate, "fmi2DeSerializeFMUstate: FMUstate is NULL");
    if (*FMUstate && !guard_state_known(&g->common, *FMUstate, "fmi2DeSerializeFMUstate")) return fmi2Error;
    guard_state_header header;
    guard_position at;
    REQUIRE(size > sizeof header, "fmi2DeSerializeFMUstate: %zu bytes are not a serialized state of this FMU", size);
    memcpy(&header, serializedState, sizeof header);
    REQUIRE(guard_header_read(&header, STATE_MAGIC, FMU_GUID, ANY_STATE, &at),
            "fmi2DeSerializeFMUstate: the bytes are not a state serialized by this FMU (GUID %s)", FMU_GUID);
    fmi2FMUstate backend = NULL;
    fmi2Status status = settle(g, backend_fmi2DeSerializeFMUstate(g->backend, serializedState + sizeof header,
                                                                   size - sizeof header, &backend));
    return status > fmi2Warning ? status : deliver_state(g, FMUstate, backend, at);
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
    REQUIRE(isfinite(communicationStepSize) && communicationStepSize > 0,
            "fmi2DoStep: communicationStepSize = %g s must be finite and > 0", communicationStepSize);
    REQUIRE(isfinite(currentCommunicationPoint) &&
                fabs(currentCommunicationPoint - at->time) <= 1e-9 * fmax(1.0, fabs(at->time)),
            "fmi2DoStep: currentCommunicationPoint = %.17g s is not the FMU's time %.17g s (the end of the last "
            "step, or of the FMU state set)", currentCommunicationPoint, at->time);
    fmi2Status status = backend_fmi2DoStep(g->backend, currentCommunicationPoint, communicationStepSize,
                                           noSetFMUStatePriorToCurrentPoint);
    if (status == fmi2Discard) { /* the solver gave up: the FMU stays where the step began */
        at->state = STEP_FAILED;
        at->last_successful_time = at->time;
        at->wants_to_terminate = 1;
        return fmi2Discard;
    }
    status = settle(g, status);
    if (status <= fmi2Warning) at->time = at->last_successful_time = currentCommunicationPoint + communicationStepSize;
    return status;
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
    guard_format(message, sizeof message, "%s: %s is not given by this function%s", g->common.function,
                 STATUS_KINDS[s], s <= fmi2PendingStatus ? " (this FMU never returns fmi2Pending)" : "");
    guard_emit(&g->common, fmi2Discard, "logStatusDiscard", message);
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
