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
   matrix's" (on a dense matrix: the -mat_hss_* defaults and no cap; on an H² matrix the same, at
   the tolerance option_default::pc_hss_rel_tol_on_h2: core/option_table.def). */
PETSC_EXTERN PetscErrorCode PCHSSSetRelTol(PC, PetscReal);
PETSC_EXTERN PetscErrorCode PCHSSSetLeafSize(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCHSSSetMaxRank(PC, PetscInt);
