/* The FMU's binary for FMI 2.0 co-simulation: forwards every FMI function to pythonfmu's library,
 * which lies beside it as libpythonfmu-export.so, after python_runtime.c has made a CPython
 * available in the process.  fmi2Instantiate loads both on its first call; if no usable Python is
 * found it returns NULL and says why in one line, through the host's logger and on stderr. */
#include <dlfcn.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "python_runtime.h"

#define BACKEND_FILE "libpythonfmu-export.so"

/* The functions pythonfmu's library exports, besides fmi2GetTypesPlatform and fmi2GetVersion. */
#define FMI2_FORWARDED(X)                                                                                         \
    X(fmi2SetDebugLogging) X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment)                       \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate) X(fmi2Reset) X(fmi2GetReal)   \
    X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString) X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean)      \
    X(fmi2SetString) X(fmi2GetFMUstate) X(fmi2SetFMUstate) X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize)     \
    X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate) X(fmi2GetDirectionalDerivative)                         \
    X(fmi2SetRealInputDerivatives) X(fmi2GetRealOutputDerivatives) X(fmi2DoStep) X(fmi2CancelStep)              \
    X(fmi2GetStatus) X(fmi2GetRealStatus) X(fmi2GetIntegerStatus) X(fmi2GetBooleanStatus) X(fmi2GetStringStatus)

#define DECLARE(name) static name##TYPE *backend_##name;
FMI2_FORWARDED(DECLARE)

static int resolve(void *backend, char *error, size_t size) {
#define RESOLVE(name)                                                                                             \
    backend_##name = (name##TYPE *)dlsym(backend, #name);                                                        \
    if (!backend_##name) {                                                                                        \
        snprintf(error, size, "pythonfmu's library lacks %s", #name);                                          \
        return 0;                                                                                                 \
    }
    FMI2_FORWARDED(RESOLVE)
    return 1;
}

/* One line through the host's logger (its message is a format: '%' doubled) and on stderr. */
static void report(const fmi2CallbackFunctions *functions, fmi2String instance_name, const char *message) {
    char escaped[4096];
    size_t n = 0;
    for (const char *p = message; *p && n + 2 < sizeof escaped; p++) {
        if (*p == '%') escaped[n++] = '%';
        escaped[n++] = *p;
    }
    escaped[n] = '\0';
    const char *name = instance_name ? instance_name : "?";
    fprintf(stderr, "[%s] %s\n", name, message);
    fflush(stderr);
    if (functions && functions->logger)
        functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError", escaped);
}

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn) {
    char error[4096] = "";
    void *backend = python_runtime_load_backend(fmuResourceLocation, BACKEND_FILE, error, sizeof error);
    if (!backend || (!backend_fmi2Instantiate && !resolve(backend, error, sizeof error))) {
        report(functions, instanceName, error);
        return NULL;
    }
    return backend_fmi2Instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation, functions, visible,
                                   loggingOn);
}

/* Every other function: the instance came from pythonfmu's library, so it is loaded and resolved. */
#define FORWARD(name, parameters, arguments)                                                                      \
    FMI2_Export fmi2Status name parameters { return backend_##name ? backend_##name arguments : fmi2Error; }

FMI2_Export void fmi2FreeInstance(fmi2Component c) {
    if (backend_fmi2FreeInstance) backend_fmi2FreeInstance(c);
}

FORWARD(fmi2SetDebugLogging, (fmi2Component c, fmi2Boolean on, size_t n, const fmi2String categories[]),
        (c, on, n, categories))
FORWARD(fmi2SetupExperiment, (fmi2Component c, fmi2Boolean tol_defined, fmi2Real tol, fmi2Real start,
                              fmi2Boolean stop_defined, fmi2Real stop),
        (c, tol_defined, tol, start, stop_defined, stop))
FORWARD(fmi2EnterInitializationMode, (fmi2Component c), (c))
FORWARD(fmi2ExitInitializationMode, (fmi2Component c), (c))
FORWARD(fmi2Terminate, (fmi2Component c), (c))
FORWARD(fmi2Reset, (fmi2Component c), (c))
FORWARD(fmi2GetReal, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]), (c, vr, n, v))
FORWARD(fmi2GetInteger, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]), (c, vr, n, v))
FORWARD(fmi2GetBoolean, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]), (c, vr, n, v))
FORWARD(fmi2GetString, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]), (c, vr, n, v))
FORWARD(fmi2SetReal, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]), (c, vr, n, v))
FORWARD(fmi2SetInteger, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]),
        (c, vr, n, v))
FORWARD(fmi2SetBoolean, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]),
        (c, vr, n, v))
FORWARD(fmi2SetString, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]),
        (c, vr, n, v))
FORWARD(fmi2GetFMUstate, (fmi2Component c, fmi2FMUstate *s), (c, s))
FORWARD(fmi2SetFMUstate, (fmi2Component c, fmi2FMUstate s), (c, s))
FORWARD(fmi2FreeFMUstate, (fmi2Component c, fmi2FMUstate *s), (c, s))
FORWARD(fmi2SerializedFMUstateSize, (fmi2Component c, fmi2FMUstate s, size_t *size), (c, s, size))
FORWARD(fmi2SerializeFMUstate, (fmi2Component c, fmi2FMUstate s, fmi2Byte bytes[], size_t size), (c, s, bytes, size))
FORWARD(fmi2DeSerializeFMUstate, (fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *s),
        (c, bytes, size, s))
FORWARD(fmi2GetDirectionalDerivative, (fmi2Component c, const fmi2ValueReference unknowns[], size_t n_unknowns,
                                       const fmi2ValueReference knowns[], size_t n_knowns, const fmi2Real dv_known[],
                                       fmi2Real dv_unknown[]),
        (c, unknowns, n_unknowns, knowns, n_knowns, dv_known, dv_unknown))
FORWARD(fmi2SetRealInputDerivatives, (fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Integer order[], const fmi2Real value[]),
        (c, vr, n, order, value))
FORWARD(fmi2GetRealOutputDerivatives, (fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], fmi2Real value[]),
        (c, vr, n, order, value))
FORWARD(fmi2DoStep, (fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior), (c, t, h, no_prior))
FORWARD(fmi2CancelStep, (fmi2Component c), (c))
FORWARD(fmi2GetStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Status *value), (c, s, value))
FORWARD(fmi2GetRealStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Real *value), (c, s, value))
FORWARD(fmi2GetIntegerStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Integer *value), (c, s, value))
FORWARD(fmi2GetBooleanStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value), (c, s, value))
FORWARD(fmi2GetStringStatus, (fmi2Component c, const fmi2StatusKind s, fmi2String *value), (c, s, value))
