// GMRES preconditioned by a 1e-3 HSS factorization (PC hss) reaches rtol 1e-10 in at most 15
// iterations on the ~8k-triangle sphere (sphere_l2, 11 958 unknowns) and on the disk organ
// (disk_organ_4k, 6 066 unknowns), a soft body (nu = 0.45) clamped below mid-height and pressed
// from above; the counts of -pc_type none and jacobi are printed beside it.
#include "hssbem/petsc/system.h"
#include "hssbem/problem/benchmark_problem.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <string>

using namespace hssbem;

namespace {

/// Iterations of GMRES(100) to rtol 1e-10 (at most 1000) with the given PC options, the converged
/// reason and the true relative residual.
PetscInt gmres_iterations(Mat A, Vec b, const std::string &pc_options, KSPConvergedReason *reason_out, double *true_residual)
{
  KSP ksp;
  Vec x, r;
  PetscInt its;
  KSPConvergedReason reason;
  PetscReal rn, bn;
  PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsInsertString(NULL, ("-it_ksp_type gmres -it_ksp_gmres_restart 100 -it_ksp_rtol 1e-10 -it_ksp_max_it 1000 " + pc_options).c_str()));
  PetscCallAbort(PETSC_COMM_WORLD, KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetOptionsPrefix(ksp, "it_"));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetOperators(ksp, A, A));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetFromOptions(ksp));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(b, &x));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(b, &r));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSolve(ksp, b, x));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetIterationNumber(ksp, &its));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetConvergedReason(ksp, &reason));
  *reason_out = reason;
  PetscCallAbort(PETSC_COMM_WORLD, MatMult(A, x, r));
  PetscCallAbort(PETSC_COMM_WORLD, VecAYPX(r, -1.0, b));
  PetscCallAbort(PETSC_COMM_WORLD, VecNorm(r, NORM_2, &rn));
  PetscCallAbort(PETSC_COMM_WORLD, VecNorm(b, NORM_2, &bn));
  *true_residual = rn / bn;
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&x));
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&r));
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
  PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsClear(NULL));
  PetscCallAbort(PETSC_COMM_WORLD, PetscPrintf(PETSC_COMM_WORLD, "  gmres %s: %s after %d iterations, true relative residual %.1e\n", pc_options.c_str(), KSPConvergedReasons[reason], (int)its, *true_residual));
  return its;
}

class PcHssIterations : public ::testing::TestWithParam<const char *> {};

TEST_P(PcHssIterations, GmresWithHss1e3ConvergesInAtMost15Iterations)
{
  SurfaceMesh mesh = read_mesh(std::string(HSSBEM_MESHES) + "/" + GetParam());
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material::from_young(3000.0, 0.45));
  const SystemSelection sel = clamped_lower_half(disc, {0, 0, -100.0});
  Mat A;
  Vec b;
  PetscCallAbort(PETSC_COMM_WORLD, HssbemCreateSystem(PETSC_COMM_WORLD, op, sel, nullptr, HSSBEM_MAT_DENSE, &A, &b));
  PetscCallAbort(PETSC_COMM_WORLD, PetscPrintf(PETSC_COMM_WORLD, "%s: %d unknowns\n", GetParam(), 3 * disc.num_nodes()));
  double res;
  KSPConvergedReason reason;
  const PetscInt its = gmres_iterations(A, b, "-it_pc_type hss -it_pc_hss_rel_tol 1e-3", &reason, &res);
  EXPECT_GT(reason, 0);
  EXPECT_LE(its, 15);
  EXPECT_GE(its, 2); // a 1e-3 factorization is not exact
  EXPECT_LE(res, 1e-8);
  // The counts the issue asks to report beside it (GMRES without a preconditioner may stall:
  // the H and G columns differ in scale by about 1/mu).
  const PetscInt its_jacobi = gmres_iterations(A, b, "-it_pc_type jacobi", &reason, &res);
  EXPECT_GT(its_jacobi, its);
  const PetscInt its_none = gmres_iterations(A, b, "-it_pc_type none", &reason, &res);
  EXPECT_TRUE(reason <= 0 || its_none > its);
  PetscCallAbort(PETSC_COMM_WORLD, MatDestroy(&A));
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&b));
}

INSTANTIATE_TEST_SUITE_P(Meshes, PcHssIterations, ::testing::Values("sphere_l2.msh", "disk_organ_4k.msh"));

} // namespace
