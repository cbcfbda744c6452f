/* Log events and class id of hssbem, registered by HssbemInitializePackage(). */
#pragma once

#include "hssbem/petsc/compat.h"

#include <petscsys.h>

PETSC_EXTERN PetscClassId  HSSBEM_CLASSID;
PETSC_EXTERN PetscLogEvent BEM_Mesh, BEM_Problem, BEM_RigidBody, BEM_Assembly, BEM_Solve, BEM_Post, BEM_Interior, BEM_Output;

PETSC_EXTERN PetscErrorCode HssbemInitializePackage(void);
PETSC_EXTERN PetscErrorCode HssbemFinalizePackage(void);
