/* One FMU's identity: the only part of the loader compiled for each FMU (identity.c, from the macros the
 * build defines: MODEL_IDENTIFIER, FMU_GUID and, for FMI 3, N_CONTINUOUS_STATES).  Every other source is
 * the same for every FMU, so a process that builds several FMUs compiles it once
 * (src/double_pendulum/fmu/build/loader.py). */
#ifndef IDENTITY_H
#define IDENTITY_H

#include <stddef.h>

extern const char identity_model_identifier[]; /* the modelIdentifier */
extern const char identity_token[];            /* the guid (FMI 2) or instantiationToken (FMI 3) */
extern const size_t identity_continuous_states; /* FMI 3: the number of continuous states */

#endif
