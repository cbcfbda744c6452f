/* The HSS preconditioner and direct solver, PC type "hss" (registered by HssbemInitializePackage()).

   PCSetUp factors the system matrix of the operator's boundary-condition pattern by ULV from an
   HSS compression at -pc_hss_rel_tol:
   - of the matrix itself when it is the HSS MatShell and the tolerance, leaf size and rank cap
     are the matrix's (no new work but the factorization);
   - truncated from the matrix's compression when the PC's tolerance is looser (or it has a rank
     cap): no kernel entry is evaluated again;
   - compressed from the operator otherwise (a dense or H² matrix, a tighter tolerance, another
     leaf size); on the H² matrix at 1e-3 unless -pc_hss_rel_tol says otherwise.
   PCApply solves with the factors. With -ksp_type preonly it is a direct solver to about
   -pc_hss_rel_tol; with GMRES at a loose tolerance (1e-2 .. 1e-4) a preconditioner.
   On a distributed matrix (HSS, or H² on several ranks) the compression and the factorization
   are distributed too: each rank its part's subtree, rank 0 the parts' roots' reduced blocks
   (the matrix's own compression, truncated on the ranks, or compressed anew on the matrix's
   METIS partition). On the dense matrix on several ranks they live on rank 0, which gathers
   each vector.
   A breakdown of the factorization sets PC_FACTOR_NUMERIC_ZEROPIVOT (KSP: DIVERGED_PC_FAILED). */
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
