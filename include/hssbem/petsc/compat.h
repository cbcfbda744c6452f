/* Version shims, so the PETSc layer builds against Debian's 3.18 and newer releases alike. */
#pragma once

#include <petscsys.h>

#if !PETSC_VERSION_GE(3, 19, 0)
  #define PETSC_SUCCESS ((PetscErrorCode)0)
#endif
