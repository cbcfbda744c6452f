/* The H² preconditioner and direct solver, PC type "h2" (registered by HssbemInitializePackage()):
   the H² factorization of the system matrix, distributed like the matrix. How it chooses the H²
   matrix it factors, its options and its failures: the manual page PCH2 (src/petsc/pc_h2.cxx);
   the method: docs/h2-factorization.md. */
#pragma once

#include "hssbem/petsc/compat.h"
#include "hssbem/core/option_table.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"

#include <petscpc.h>

#include <functional>
#include <memory>

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

/* Persistence (session/h2_file.hpp). The factorization a PC h2 holds after its set-up and whether
   it factors the matrix's own H² compression (NULL and PETSC_FALSE before the set-up, after a
   breakdown, or on another PC type). */
PetscErrorCode HssbemPCH2GetFactorization(PC pc, const hssbem::H2Factorization **F, PetscBool *of_matrix);
/* At its next set-up on the matrix's own H² compression, the PC takes the factorization `load`
   returns for that system (a saved one; called on every rank, collectively) instead of factoring;
   once. Refused at the set-up when the PC would factor a compression of its own (a tolerance
   tighter than the matrix's). Nothing on another PC type. */
PetscErrorCode HssbemPCH2SetFactorSource(PC pc, std::function<std::unique_ptr<hssbem::H2Factorization>(const hssbem::H2DistributedSystem &)> load);
