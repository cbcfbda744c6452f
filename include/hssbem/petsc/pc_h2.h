/* The H² preconditioner and direct solver, PC type "h2" (registered by HssbemInitializePackage()).

   PCSetUp factors the system matrix of the operator's boundary-condition pattern by strong
   recursive skeletonization (include/hssbem/h2factor/h2_factorization.hpp) at -pc_h2_rel_tol,
   distributed over the ranks like the matrix (one rank is one part):
   - of the matrix's own H² compression when the matrix is the H² MatShell and the PC's tolerance
     is no tighter than the matrix's (no kernel entry is evaluated: the factorization reads the
     H² matrix's bases and blocks);
   - of an H² compression made at the PC's tolerance otherwise (on the matrix's partition; on a
     dense matrix on one of its own).
   PCApply solves with the factors. With GMRES and the default tolerance it is a preconditioner
   (a few iterations around the accurate product); with -ksp_type preonly and a tight tolerance
   (-pc_h2_rel_tol 1e-7) a direct solver accurate to about that tolerance. A new pattern on the
   same H² matrix refactors without evaluating kernel entries (and reuses the far-field sketch).
   A pivot block singular to working precision sets PC_FACTOR_NUMERIC_ZEROPIVOT (KSP:
   DIVERGED_PC_FAILED). */
#pragma once

#include "hssbem/petsc/compat.h"

#include <petscpc.h>

#define PCH2 "h2"

/* The PC's default factorization tolerance: a preconditioner for GMRES around the H² product
   (chosen by measurement, see docs/h2-factorization.md). */
#define HSSBEM_PC_H2_DEFAULT_REL_TOL 2e-3

PETSC_EXTERN PetscErrorCode PCCreate_H2(PC);

/* Setters for the options (before PCSetUp; each checks its value): the factorization's relative
   tolerance; dof nodes per box at the first level factored (0: the H² matrix's leaves, their
   parents below tolerance 1e-5); unknowns factored densely at the top; whether a level that would
   cost more than the dense top of what is left ends the levels too; the top size from which the
   top's LU runs in single precision (≤ 0: never); whether such a top is spread over the ranks;
   random vectors of the far-field sketch (0: from the tolerance); power iterations of the
   ‖I − A F⁻¹‖ estimate that -ksp_view reports (0: none). */
PETSC_EXTERN PetscErrorCode PCH2SetRelTol(PC, PetscReal);
PETSC_EXTERN PetscErrorCode PCH2SetLeafSize(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCH2SetTopSize(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCH2SetTopWhenCheaper(PC, PetscBool);
PETSC_EXTERN PetscErrorCode PCH2SetSingleTopFrom(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCH2SetSpreadTop(PC, PetscBool);
PETSC_EXTERN PetscErrorCode PCH2SetSketchSize(PC, PetscInt);
PETSC_EXTERN PetscErrorCode PCH2SetEstimateError(PC, PetscInt);
