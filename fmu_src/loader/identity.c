/* One FMU's identity (identity.h), from the macros its build defines. */
#include "identity.h"

#ifndef FMU_GUID
#error "the build defines FMU_GUID, the guid (FMI 2) or instantiationToken (FMI 3) of the FMU's modelDescription.xml"
#endif
#ifndef MODEL_IDENTIFIER
#error "the build defines MODEL_IDENTIFIER"
#endif
#ifndef N_VARIABLES
#error "the build defines N_VARIABLES, the number of variables in the FMU's modelDescription.xml"
#endif
#ifndef BUNDLED_PYTHON_LIBRARY /* a lean FMU: it finds a Python on the machine */
#define BUNDLED_PYTHON_LIBRARY ""
#define BUNDLED_PYTHON_STDLIB ""
#define BUNDLED_PYTHON_MINOR 0
#endif
#ifndef BUNDLED_PYTHON_PRELOAD
#define BUNDLED_PYTHON_PRELOAD ""
#endif

const char identity_model_identifier[] = MODEL_IDENTIFIER;
const char identity_token[] = FMU_GUID;
const size_t identity_variables = N_VARIABLES;
#ifdef N_CONTINUOUS_STATES
const size_t identity_continuous_states = N_CONTINUOUS_STATES;
#endif
const char identity_python_library[] = BUNDLED_PYTHON_LIBRARY;
const char identity_python_stdlib[] = BUNDLED_PYTHON_STDLIB;
const int identity_python_minor = BUNDLED_PYTHON_MINOR;
const char identity_python_preload[] = BUNDLED_PYTHON_PRELOAD;
