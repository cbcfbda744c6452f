/* The HSS preconditioner and direct solver, PC type "hss" (registered by HssbemInitializePackage()):
   the ULV factorization of an HSS compression of the system matrix, distributed like the matrix.
   Which compression it factors, its options and its failures: the manual page PCHSS
   (src/petsc/pc_hss.cxx); the method: docs/hss.md. */
#pragma once

#include "hssbem/petsc/compat.h"

#include <petscpc.h>

#define PCHSS "hss"

PETSC_EXTERN PetscErrorCode PCCreate_HSS(PC);

/* Setters for the options (before PCSetUp); rel_tol 0, leaf size 0 and max rank -1 mean "the
   matrix's" (on a dense matrix: 1e-8, 256 and no cap; on an H² matrix: 1e-3, 256 and no cap). */
PETSC_EXTERN PetscErrorCode PCHSSSetRelTol(PC, PetscReal);
PETSC_EXTERN PetscErrorCode PCHSSSetLeafSize(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCHSSSetMaxRank(PC, PetscInt);
