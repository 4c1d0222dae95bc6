/* One FMU's identity: the only part of the loader compiled for each FMU (identity.c, from the macros its
 * build defines: MODEL_IDENTIFIER, FMU_GUID, N_VARIABLES, for FMI 3 N_CONTINUOUS_STATES, and for a self-contained FMU the
 * files of the CPython it carries beside the binary).  Every other source is the same for every FMU, so a
 * process that builds several FMUs compiles it once (src/double_pendulum/fmu/build/loader.py). */
#ifndef IDENTITY_H
#define IDENTITY_H

#include <stddef.h>

extern const char identity_model_identifier[]; /* the modelIdentifier */
extern const char identity_token[];            /* the guid (FMI 2) or instantiationToken (FMI 3) */
extern const size_t identity_continuous_states; /* FMI 3: the number of continuous states */
/* The number of variables in modelDescription.xml: every one is a scalar, so no get or set call names more value
 * references than this (a larger count is refused before any byte length is computed from it). */
extern const size_t identity_variables;
/* The CPython a self-contained FMU carries in its binaries folder ("" in a lean FMU): its shared library
 * (libpython3.11.so.1.0, python311.dll), its zipped standard library (python311.zip) and its minor version. */
extern const char identity_python_library[];
extern const char identity_python_stdlib[];
extern const int identity_python_minor;
extern const char identity_python_preload[]; /* libraries its extension modules need, ':'-separated ("" none) */

#endif
