/* A minimal FMI 2.0 co-simulation host in C, for the tests (tests/test_c_host.py): no Python in it.
 *
 *   fmi2_host DIR IDENTIFIER GUID STEPS STEP_SIZE [ARG ...]
 *
 * DIR is an extracted FMU; the host loads DIR/binaries/linux64/IDENTIFIER.so (on Windows
 * DIR/binaries/win64/IDENTIFIER.dll, host_common.h), instantiates it (co-simulation, logging off),
 * applies the ARGs, sets up, initialises (inputs set in initialisation mode), runs STEPS doSteps of
 * STEP_SIZE from t = 0 (inputs set before each), reads the outputs, terminates and frees the instance,
 * and unloads the library.
 * ARGs: r:VR=VALUE (Real start value), b:VR=0|1 (Boolean), s:VR=TEXT (String), i:VR=VALUE (Real
 * input set before every doStep), f:PATH (an input table, host_common.h: its inputs interpolated at each
 * communication point and set in initialisation mode and before every doStep, as the FMI Compliance
 * Checker and fmpy set an _in.csv), o:VR (Real read at the end, printed as "VR VALUE" with 17 digits),
 * O:VR (Real read at every communication point from the start, printed as "row T VALUE ..." lines).
 * Log messages go to stdout as "log STATUS CATEGORY: MESSAGE". At the end the host prints
 * "startup-cpu-seconds T" (the process's CPU time from loading the library to the end of the first
 * doStep) and "host-unchanged 1" if its environment and its signal handlers (on Windows: its environment,
 * host_common.h) are as they were before it loaded the FMU, else "host-unchanged 0". Exit status: 0 on
 * success, 2 bad usage, 3 library not loaded, 4 instantiation failed, 5 a call failed, 9 a crash on
 * Windows (host_common.h; on Linux a crash ends the host by its signal).
 * On Windows the command line is read as UTF-16: DIR, PATH and TEXT may be any Unicode (host_common.h). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "host_common.h"

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)instance;
    va_list args;
    va_start(args, message);
    printf("log %d %s: ", (int)status, category ? category : "");
    vprintf(message, args);
    printf("\n");
    va_end(args);
    fflush(stdout);
}

int main(int argc, char **argv) {
    host_start(&argc, &argv);
    if (argc < 6) {
        fprintf(stderr, "usage: %s DIR IDENTIFIER GUID STEPS STEP_SIZE [ARG ...]\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1], *identifier = argv[2], *guid = argv[3];
    long steps = atol(argv[4]);
    double step_size = atof(argv[5]);
    char path[4096], resources[4096 * 3];
    if (!fmu_locations(dir, identifier, 2, path, sizeof path, resources, sizeof resources)) return 2;

    static host_state before, after;
    snapshot(&before);
    double start = cpu_seconds(), first_step = start;
    host_library library = load_library(path);
    if (!library) return 3;
    fmi2InstantiateTYPE *instantiate = (fmi2InstantiateTYPE *)symbol(library, "fmi2Instantiate");
    fmi2FreeInstanceTYPE *free_instance = (fmi2FreeInstanceTYPE *)symbol(library, "fmi2FreeInstance");
    fmi2SetupExperimentTYPE *setup = (fmi2SetupExperimentTYPE *)symbol(library, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter = (fmi2EnterInitializationModeTYPE *)symbol(library, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *exit_init = (fmi2ExitInitializationModeTYPE *)symbol(library, "fmi2ExitInitializationMode");
    fmi2SetRealTYPE *set_real = (fmi2SetRealTYPE *)symbol(library, "fmi2SetReal");
    fmi2SetBooleanTYPE *set_boolean = (fmi2SetBooleanTYPE *)symbol(library, "fmi2SetBoolean");
    fmi2SetStringTYPE *set_string = (fmi2SetStringTYPE *)symbol(library, "fmi2SetString");
    fmi2GetRealTYPE *get_real = (fmi2GetRealTYPE *)symbol(library, "fmi2GetReal");
    fmi2DoStepTYPE *do_step = (fmi2DoStepTYPE *)symbol(library, "fmi2DoStep");
    fmi2TerminateTYPE *terminate = (fmi2TerminateTYPE *)symbol(library, "fmi2Terminate");

    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = instantiate("host", fmi2CoSimulation, guid, resources, &callbacks, fmi2False, fmi2False);
    if (!c) {
        fprintf(stderr, "fmi2Instantiate returned NULL\n");
        return 4;
    }

    fmi2ValueReference inputs[MAX_ARGS], outputs[MAX_ARGS], recorded[MAX_ARGS];
    fmi2Real input_values[MAX_ARGS], table_values[MAX_ARGS], row[MAX_ARGS];
    size_t n_inputs = 0, n_outputs = 0, n_recorded = 0;
    static input_table table;
    for (int k = 6; k < argc && n_inputs < MAX_ARGS && n_outputs < MAX_ARGS && n_recorded < MAX_ARGS; k++) {
        host_argument a;
        if (!parse_argument(argv[k], &a) || a.kind == 'j' || a.kind == 'e') {
            fprintf(stderr, "bad argument %s\n", argv[k]);
            return 2;
        }
        fmi2ValueReference vr = a.vr;
        fmi2Boolean boolean = atoi(a.text) ? fmi2True : fmi2False;
        if (a.kind == 'o') outputs[n_outputs++] = vr;
        else if (a.kind == 'O') recorded[n_recorded++] = vr;
        else if (a.kind == 'f' && !read_input_table(a.text, &table)) {
            fprintf(stderr, "cannot read the input table %s\n", a.text);
            return 2;
        }
        else if (a.kind == 'f') continue;
        else if (a.kind == 'r') CHECK(set_real(c, &vr, 1, &a.real));
        else if (a.kind == 'b') CHECK(set_boolean(c, &vr, 1, &boolean));
        else if (a.kind == 's') CHECK(set_string(c, &vr, 1, &a.text));
        else inputs[n_inputs] = vr, input_values[n_inputs++] = a.real;
    }

#define SET_TABLE(t)                                                                                             \
    if (table.n_columns) {                                                                                        \
        interpolate_inputs(&table, (t), table_values);                                                            \
        CHECK(set_real(c, table.vr, table.n_columns, table_values));                                              \
    }
#define RECORD(t)                                                                                                \
    if (n_recorded) {                                                                                             \
        CHECK(get_real(c, recorded, n_recorded, row));                                                            \
        printf("row %.17g", (t));                                                                                 \
        for (size_t r = 0; r < n_recorded; r++) printf(" %.17g", row[r]);                                         \
        printf("\n");                                                                                             \
    }
    CHECK(setup(c, fmi2False, 0.0, 0.0, fmi2True, steps * step_size));
    CHECK(enter(c));
    if (n_inputs) CHECK(set_real(c, inputs, n_inputs, input_values));
    SET_TABLE(0.0);
    CHECK(exit_init(c));
    RECORD(0.0);
    for (long k = 0; k < steps; k++) { /* communication points k h, as fmpy's simulate_fmu steps */
        if (n_inputs) CHECK(set_real(c, inputs, n_inputs, input_values));
        SET_TABLE(k * step_size);
        CHECK(do_step(c, k * step_size, (k + 1) * step_size - k * step_size, fmi2True));
        if (k == 0) first_step = cpu_seconds();
        RECORD((k + 1) * step_size);
    }
    fmi2Real values[MAX_ARGS];
    if (n_outputs) CHECK(get_real(c, outputs, n_outputs, values));
    for (size_t k = 0; k < n_outputs; k++) printf("%u %.17g\n", outputs[k], values[k]);
    CHECK(terminate(c));
    free_instance(c);
    close_library(library);
    snapshot(&after);
    printf("startup-cpu-seconds %.6f\n", first_step - start);
    printf("host-unchanged %d\n", unchanged(&before, &after));
    return 0;
}
