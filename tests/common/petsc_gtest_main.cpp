// GoogleTest main for tests that need PETSc/MPI: a failure on any rank fails every rank, and only
// rank 0 prints.
#include "hssbem/petsc/log.h"

#include <gtest/gtest.h>

#include <cstdlib>

int main(int argc, char **argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(HssbemInitializePackage());
  PetscMPIInt rank;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  if (rank != 0 && !getenv("HSSBEM_TEST_ALL_RANKS")) {
    auto &listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int local = RUN_ALL_TESTS(), global = 0;
  PetscCallMPI(MPI_Allreduce(&local, &global, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(PetscFinalize());
  return global;
}
