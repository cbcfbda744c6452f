// GMRES (rtol 1e-10, right-preconditioned: the true residual) with PC h2 at its default tolerance
// on the H² matrix (the driver's default solver for -bem_mat_type h2) converges in at most 12
// iterations on the ~8k-triangle sphere (sphere_l2, 11 958 unknowns) and on the disk organ
// (disk_organ_4k, 6 066 unknowns): a soft body (nu = 0.45) clamped below mid-height and pressed
// from above. Jacobi's count is printed beside it.
#include "hssbem/petsc/pc_h2.h"
#include "hssbem/petsc/system.h"
#include "hssbem/problem/benchmark_problem.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <string>

using namespace hssbem;

namespace {

struct Outcome {
  PetscInt its;
  KSPConvergedReason reason;
  double residual; ///< true relative residual with the matrix's product
};

Outcome gmres(Mat A, Vec b, const char *pc)
{
  KSP ksp;
  PC p;
  Vec x, r;
  Outcome o;
  PetscReal rn, bn;
  PetscCallAbort(PETSC_COMM_WORLD, KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetOperators(ksp, A, A));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetType(ksp, KSPGMRES));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGMRESSetRestart(ksp, 100));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetPCSide(ksp, PC_RIGHT));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetTolerances(ksp, 1e-10, PETSC_DEFAULT, PETSC_DEFAULT, 1000));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetPC(ksp, &p));
  PetscCallAbort(PETSC_COMM_WORLD, PCSetType(p, pc));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(b, &x));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(b, &r));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSolve(ksp, b, x));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetIterationNumber(ksp, &o.its));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetConvergedReason(ksp, &o.reason));
  PetscCallAbort(PETSC_COMM_WORLD, MatMult(A, x, r));
  PetscCallAbort(PETSC_COMM_WORLD, VecAYPX(r, -1.0, b));
  PetscCallAbort(PETSC_COMM_WORLD, VecNorm(r, NORM_2, &rn));
  PetscCallAbort(PETSC_COMM_WORLD, VecNorm(b, NORM_2, &bn));
  o.residual = rn / bn;
  PetscCallAbort(PETSC_COMM_WORLD, PetscPrintf(PETSC_COMM_WORLD, "  gmres + %s: %s after %d iterations, true relative residual %.1e\n", pc, KSPConvergedReasons[o.reason], (int)o.its, o.residual));
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&x));
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&r));
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
  return o;
}

class PcH2Iterations : public ::testing::TestWithParam<const char *> {};

TEST_P(PcH2Iterations, DefaultToleranceConvergesInAtMost12Iterations)
{
  SurfaceMesh mesh = read_mesh(std::string(HSSBEM_MESHES) + "/" + GetParam());
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material::from_young(3000.0, 0.45));
  const SystemSelection sel = clamped_lower_half(disc, {0, 0, -100.0});
  Mat A;
  Vec b;
  PetscCallAbort(PETSC_COMM_WORLD, HssbemCreateSystem(PETSC_COMM_WORLD, op, sel, nullptr, HSSBEM_MAT_H2, &A, &b));
  PetscCallAbort(PETSC_COMM_WORLD, PetscPrintf(PETSC_COMM_WORLD, "%s: %d unknowns\n", GetParam(), 3 * disc.num_nodes()));
  const Outcome h2 = gmres(A, b, PCH2);
  EXPECT_GT(h2.reason, 0);
  EXPECT_LE(h2.its, 12);
  EXPECT_GE(h2.its, 2); // the default tolerance makes a preconditioner, not an exact inverse
  EXPECT_LE(h2.residual, 1e-10);
  const Outcome jacobi = gmres(A, b, PCJACOBI);
  EXPECT_GT(jacobi.its, 3 * h2.its);
  PetscCallAbort(PETSC_COMM_WORLD, MatDestroy(&A));
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&b));
}

INSTANTIATE_TEST_SUITE_P(Meshes, PcH2Iterations, ::testing::Values("sphere_l2.msh", "disk_organ_4k.msh"));

} // namespace
