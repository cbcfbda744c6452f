/* The H² preconditioner and direct solver, PC type "h2" (registered by HssbemInitializePackage()):
   the H² factorization of the system matrix, distributed like the matrix. How it chooses the H²
   matrix it factors, its options and its failures: the manual page PCH2 (src/petsc/pc_h2.cxx);
   the method: docs/h2-factorization.md. */
#pragma once

#include "hssbem/petsc/compat.h"
#include "hssbem/core/option_table.hpp"

#include <petscpc.h>

#define PCH2 "h2"

/* The PC's default factorization tolerance (-pc_h2_rel_tol's, core/option_table.def): a
   preconditioner for GMRES around the H² product (chosen by measurement, see
   docs/h2-factorization.md). */
#define HSSBEM_PC_H2_DEFAULT_REL_TOL (hssbem::option_default::pc_h2_rel_tol)

PETSC_EXTERN PetscErrorCode PCCreate_H2(PC);

/* Setters of the options, one per -pc_h2_* key (before PCSetUp; each checks its value). */
PETSC_EXTERN PetscErrorCode PCH2SetRelTol(PC, PetscReal);
PETSC_EXTERN PetscErrorCode PCH2SetLeafSize(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCH2SetTopSize(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCH2SetTopWhenCheaper(PC, PetscBool);
PETSC_EXTERN PetscErrorCode PCH2SetSingleTopFrom(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCH2SetSpreadTop(PC, PetscBool);
PETSC_EXTERN PetscErrorCode PCH2SetSketchSize(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCH2SetEstimateError(PC, PetscInt);
