/* One FMU's identity (identity.h), from the macros its build defines. */
#include "identity.h"

#ifndef FMU_GUID
#error "the build defines FMU_GUID, the guid (FMI 2) or instantiationToken (FMI 3) of the FMU's modelDescription.xml"
#endif
#ifndef MODEL_IDENTIFIER
#error "the build defines MODEL_IDENTIFIER"
#endif

const char identity_model_identifier[] = MODEL_IDENTIFIER;
const char identity_token[] = FMU_GUID;
#ifdef N_CONTINUOUS_STATES
const size_t identity_continuous_states = N_CONTINUOUS_STATES;
#endif
