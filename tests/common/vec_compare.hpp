// Relative differences of PETSc vectors, for the MPI tests that compare a system's solution with
// dense LU's.
#pragma once

#include "hssbem/petsc/system.h"

#include <petscvec.h>

namespace hssbem::test {

/// ‖a − b‖ / ‖b‖ for vectors of one layout.
inline double rel_diff(Vec a, Vec b)
{
  Vec d;
  PetscReal nd, nb;
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(a, &d));
  PetscCallAbort(PETSC_COMM_WORLD, VecWAXPY(d, -1.0, b, a));
  PetscCallAbort(PETSC_COMM_WORLD, VecNorm(d, NORM_2, &nd));
  PetscCallAbort(PETSC_COMM_WORLD, VecNorm(b, NORM_2, &nb));
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&d));
  return nd / nb;
}

/// ‖a − b‖ / ‖b‖ for a in A's layout (the distributed H² system's is cluster order) and b in
/// mesh order (the dense system's).
inline double rel_diff(Mat A, Vec a, Vec b)
{
  Vec am;
  PetscCallAbort(PETSC_COMM_WORLD, HssbemMatCreateMeshOrderVec(A, &am));
  PetscCallAbort(PETSC_COMM_WORLD, HssbemVecToMeshOrder(A, a, am));
  const double d = rel_diff(am, b);
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&am));
  return d;
}

} // namespace hssbem::test
