/* The dense path: the collocation matrix assembled into a distributed PETSc dense matrix
   (solved with KSP: LU on one rank; ScaLAPACK or MUMPS on more; any Krylov method). */
#pragma once

#include "hssbem/petsc/compat.h"

#include "hssbem/bem/bem_operator.hpp"

#include <petscksp.h>

/* Assemble A and b = -K E_known (rows split by node across the ranks of comm, 3 rows per node).
   With rigid_modes (orthonormal, row-major 3n x 6, see orthonormal_rigid_modes()), A gets
   + rigid_regularization_weight * Q Q^T: the pure-traction regularisation. */
PetscErrorCode HssbemAssembleDense(MPI_Comm comm, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, Mat *A, Vec *b);
