/* The dense path: the collocation matrix assembled into a distributed PETSc dense matrix and
   solved with KSP (LU on one rank; ScaLAPACK or MUMPS on more; any Krylov method). */
#pragma once

#include "hssbem/petsc/compat.h"

#include "hssbem/bem/bem_operator.hpp"

#include <petscksp.h>

/* Outcome of a solve, for the result file. */
struct HssbemSolveInfo {
  PetscInt           iterations = 0;
  PetscReal          residual   = 0; /* ||b - A x|| / ||b|| with the assembled A */
  KSPConvergedReason reason     = KSP_CONVERGED_ITERATING;
  std::string        ksp_type, pc_type, solver_type;
};

/* Assemble A and b = -K E_known (rows split by node across the ranks of comm, 3 rows per node).
   With rigid_modes (orthonormal, row-major 3n x 6, see orthonormal_rigid_modes()), A gets
   + rigid_regularization_weight * Q Q^T: the pure-traction regularisation. */
PetscErrorCode HssbemAssembleDense(MPI_Comm comm, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, Mat *A, Vec *b);

/* The main KSP (no prefix): preonly + LU by default, then the options database. */
PetscErrorCode HssbemKSPCreate(MPI_Comm comm, KSP *ksp);

/* Solve A x = b with that KSP; A is converted in place when the factorization needs another
   format (ScaLAPACK for parallel LU, AIJ for MUMPS). */
PetscErrorCode HssbemSolveDense(KSP ksp, Mat *A, Vec b, Vec x, HssbemSolveInfo *info);
