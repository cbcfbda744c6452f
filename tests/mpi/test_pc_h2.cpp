// PC h2 (the H² factorization) on 1, 2 and 4 ranks: as the H² matrix's default GMRES
// preconditioner, as a direct solver, on the dense and HSS matrices, on a regularised
// pure-traction problem, its breakdown reported as a PC failure, and its option checks.
#include "solve_helpers.hpp"
#include "vec_compare.hpp"
#include "test_shapes.hpp"

#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/petsc/pc_h2.h"
#include "hssbem/petsc/system.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <unistd.h>
#include <string>

using namespace hssbem;
using namespace hssbem::test;

namespace {

/// A problem on sphere_l1 (2994 unknowns; H² leaves of 16 nodes, so the factorization has levels
/// below its dense top) as dense and H² systems (and HSS on request).
struct Systems {
  ProblemSetup setup;
  std::unique_ptr<BemOperator> op;
  std::vector<double> modes;
  Mat A[3] = {nullptr, nullptr, nullptr};
  Vec b[3] = {nullptr, nullptr, nullptr};
  Vec xd = nullptr;

  Systems(const ProblemSpec &spec, bool regularise, bool with_hss = false) : setup(setup_problem(spec, ProblemOverrides{}))
  {
    op = std::make_unique<BemOperator>(*setup.disc, setup.material);
    if (setup.pure_traction && regularise) modes = orthonormal_rigid_modes(*setup.disc);
    const std::vector<double> *m = modes.empty() ? nullptr : &modes;
    const char *types[3] = {HSSBEM_MAT_DENSE, HSSBEM_MAT_HSS, HSSBEM_MAT_H2};
    for (int t = 0; t < 3; ++t)
      if (t != 1 || with_hss) PetscCallAbort(PETSC_COMM_WORLD, HssbemCreateSystem(PETSC_COMM_WORLD, *op, setup.selection, m, types[t], &A[t], &b[t]));
    if (!(setup.pure_traction && !regularise)) xd = dense_lu(A[0], b[0]);
  }
  ~Systems()
  {
    for (int t = 0; t < 3; ++t) {
      MatDestroy(&A[t]);
      VecDestroy(&b[t]);
    }
    VecDestroy(&xd);
  }
  static Vec dense_lu(Mat Ad, Vec bd)
  {
    KSP ksp;
    Vec x;
    Mat Ac;
    PetscCallAbort(PETSC_COMM_WORLD, MatConvert(Ad, MATDENSE, MAT_INITIAL_MATRIX, &Ac));
    PetscCallAbort(PETSC_COMM_WORLD, HssbemKSPCreate(PETSC_COMM_WORLD, HSSBEM_MAT_DENSE, &ksp));
    PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(bd, &x));
    HssbemSolveInfo info;
    PetscCallAbort(PETSC_COMM_WORLD, HssbemSolveSystem(ksp, &Ac, bd, x, &info));
    PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
    PetscCallAbort(PETSC_COMM_WORLD, MatDestroy(&Ac));
    return x;
  }
};

struct Outcome {
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  PetscInt its = 0;
  double diff = 0; ///< against the dense LU solution
};

/// One solve with `options` (prefix "t_"), which are removed again afterwards.
Outcome ksp_solve(Mat A, Vec b, Vec x_ref, const char *options)
{
  KSP ksp;
  Vec x;
  Outcome o;
  PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsInsertString(NULL, options));
  PetscCallAbort(PETSC_COMM_WORLD, KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetOptionsPrefix(ksp, "t_"));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetOperators(ksp, A, A));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetFromOptions(ksp));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(b, &x));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSolve(ksp, b, x));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetConvergedReason(ksp, &o.reason));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetIterationNumber(ksp, &o.its));
  if (o.reason > 0 && x_ref) o.diff = rel_diff(A, x, x_ref);
  PetscCallAbort(PETSC_COMM_WORLD, PetscPrintf(PETSC_COMM_WORLD, "  %s: %s after %d iterations, difference from dense LU %.2e\n", options, KSPConvergedReasons[o.reason], (int)o.its, o.diff));
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&x));
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
  // Remove only what this solve set: the program's own options (leaf sizes) stay.
  for (const char *key : {"-t_ksp_type", "-t_ksp_rtol", "-t_pc_type", "-t_pc_h2_rel_tol", "-t_pc_h2_top_size", "-t_pc_h2_top_when_cheaper", "-t_pc_h2_leaf_size", "-t_ksp_pc_side", "-t_pc_h2_single_top_from"})
    PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsClearValue(NULL, key));
  return o;
}

ProblemSpec kelvin_mixed()
{
  const KelvinField k{Material{1000.0, 0.3}, {1.2, 0.9, 1.0}, {1.0, -2.0, 0.5}};
  return kelvin_mixed_spec("sphere_l1.msh", k);
}

/// Leaves of 16 nodes: sphere_l1 then has 64 leaves and far blocks from level 3 on. The H² matrix
/// at 1e-9 in double precision (the driver defaults to 1e-5 in single): exact enough to compare
/// the factorization with dense LU, and exactly singular for a pure-traction problem.
class SmallLeaves : public ::testing::Environment {
public:
  void SetUp() override { PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsInsertString(NULL, "-mat_hss_leaf_size 32 -mat_h2_leaf_size 16 -mat_h2_eta 0 -mat_h2_rel_tol 1e-9 -mat_h2_single_precision false")); }
};
::testing::Environment *const small_leaves = ::testing::AddGlobalTestEnvironment(new SmallLeaves);

class PCH2Test : public ::testing::Test {
protected:
  static void SetUpTestSuite() { mixed = new Systems(kelvin_mixed(), true, true); }
  static void TearDownTestSuite() { delete mixed; }
  static Systems *mixed;
};
Systems *PCH2Test::mixed = nullptr;

TEST_F(PCH2Test, DefaultSolverOfTheH2Matrix)
{
  // HssbemKSPCreate's defaults for the H² matrix: GMRES, right-preconditioned, with PC h2 at its
  // default tolerance on any number of ranks (distributed like the matrix on several; the true
  // residual reaches the tolerance within a few iterations).
  KSP ksp;
  Vec x;
  Mat A = mixed->A[2];
  PetscCallAbort(PETSC_COMM_WORLD, PetscObjectReference((PetscObject)A));
  PetscCallAbort(PETSC_COMM_WORLD, HssbemKSPCreate(PETSC_COMM_WORLD, HSSBEM_MAT_H2, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetTolerances(ksp, 1e-10, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(mixed->b[2], &x));
  HssbemSolveInfo info;
  PetscCallAbort(PETSC_COMM_WORLD, HssbemSolveSystem(ksp, &A, mixed->b[2], x, &info));
  const double diff = rel_diff(A, x, mixed->xd);
  PetscCallAbort(PETSC_COMM_WORLD, PetscPrintf(PETSC_COMM_WORLD, "  default: %s/%s, %d iterations, residual %.2e, difference from dense LU %.2e\n", info.ksp_type.c_str(), info.pc_type.c_str(),
                                               (int)info.iterations, info.residual, diff));
  EXPECT_EQ(info.pc_type, "h2"); // on any number of ranks
  EXPECT_LE(info.residual, 1e-10);
  EXPECT_GE(info.iterations, 2); // a loose factorization, not an exact inverse
  EXPECT_LE(info.iterations, 12); // PC h2 at its default (Jacobi: 49 at 2 ranks)
  EXPECT_LE(diff, 4e-9); // measured at 1, 2, 3, 4, 6 ranks: 2.3e-11, 1.4e-9, 5.4e-11, 2.0e-11, 1.1e-9 (H² at 1e-9, GMRES to 1e-10)
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
  PetscCallAbort(PETSC_COMM_WORLD, MatDestroy(&A));
  VecDestroy(&x);
}

TEST_F(PCH2Test, DirectSolveAtTightTolerance)
{
  // preonly + PC h2 at 1e-7 on the H² matrix (at 1e-9): the solution is the direct solve's (every
  // level with a far field eliminated: on this small mesh the dense top would be cheaper).
  const Outcome o = ksp_solve(mixed->A[2], mixed->b[2], mixed->xd, "-t_ksp_type preonly -t_pc_type h2 -t_pc_h2_rel_tol 1e-7 -t_pc_h2_top_size 200 -t_pc_h2_top_when_cheaper false");
  EXPECT_GT(o.reason, 0);
  EXPECT_LE(o.diff, 5e-6); // measured at 1, 2, 3, 4, 6 ranks: 8.3e-7, 1.6e-6, 1.3e-6, 9.0e-7, 3.2e-11 (6 ranks: the top holds nearly all)
  // ... and at 1e-3 it is visibly a preconditioner only (measured 3.9e-2 to 5.5e-2).
  const Outcome loose = ksp_solve(mixed->A[2], mixed->b[2], mixed->xd, "-t_ksp_type preonly -t_pc_type h2 -t_pc_h2_rel_tol 1e-3 -t_pc_h2_top_size 200");
  EXPECT_GT(loose.diff, 1e-2);
  EXPECT_LE(loose.diff, 1.6e-1);
}

TEST_F(PCH2Test, PreconditionerOnTheDenseAndHssMatrices)
{
  // On the dense and HSS matrices PC h2 compresses its own H² matrix at its tolerance.
  for (int t : {0, 1}) {
    const Outcome o = ksp_solve(mixed->A[t], mixed->b[t], mixed->xd, "-t_ksp_type gmres -t_ksp_pc_side right -t_ksp_rtol 1e-10 -t_pc_type h2 -t_pc_h2_top_size 200");
    EXPECT_GT(o.reason, 0);
    EXPECT_GE(o.its, 2);
    EXPECT_LE(o.its, 12);
    // Measured: 5.2e-10 on every rank count (dense; the compression on rank 0), 2.1e-8 to 3.3e-8
    // (HSS, at 1e-8).
    EXPECT_LE(o.diff, t == 0 ? 1.6e-9 : 1e-7);
  }
}

TEST_F(PCH2Test, PreconditionerOnTheDistributedH2Matrix)
{
  // GMRES + PC h2 at its default tolerance on the H² matrix: on several ranks the factorization
  // is distributed like the matrix (each rank its part's subtree, rank 0 the top).
  const Outcome o = ksp_solve(mixed->A[2], mixed->b[2], mixed->xd, "-t_ksp_type gmres -t_ksp_pc_side right -t_ksp_rtol 1e-10 -t_pc_type h2");
  EXPECT_GT(o.reason, 0);
  EXPECT_GE(o.its, 2); // a loose factorization, not an exact inverse
  EXPECT_LE(o.its, 12);
  EXPECT_LE(o.diff, 4e-9); // as the default solver's
}

/// What viewing A's PC h2 says (its ASCII view, through a file, on every rank) once it is set
/// up with `options` (prefix "t_"), which are removed again afterwards.
std::string pc_view_after(Mat A, const char *options)
{
  KSP ksp;
  PC pc;
  PetscViewer v;
  char name[64] = "/tmp/hssbem-pc-view-XXXXXX";
  PetscMPIInt rank;
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  if (rank == 0) close(mkstemp(name));
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Bcast(name, sizeof name, MPI_CHAR, 0, PETSC_COMM_WORLD));
  PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsInsertString(NULL, options));
  PetscCallAbort(PETSC_COMM_WORLD, KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetOptionsPrefix(ksp, "t_"));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetOperators(ksp, A, A));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetFromOptions(ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetUp(ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetPC(ksp, &pc));
  PetscCallAbort(PETSC_COMM_WORLD, PetscViewerASCIIOpen(PETSC_COMM_WORLD, name, &v));
  PetscCallAbort(PETSC_COMM_WORLD, PCView(pc, v));
  PetscCallAbort(PETSC_COMM_WORLD, PetscViewerDestroy(&v));
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
  for (const char *key : {"-t_ksp_type", "-t_ksp_rtol", "-t_ksp_pc_side", "-t_pc_type", "-t_pc_h2_single_top_from", "-t_pc_h2_top_size", "-t_pc_h2_top_when_cheaper"})
    PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsClearValue(NULL, key));
  std::ifstream in(name);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Barrier(PETSC_COMM_WORLD)); // every rank has read it
  if (rank == 0) std::remove(name);
  return text;
}

TEST_F(PCH2Test, PreconditionerWithTheTopSpreadOverTheRanks)
{
  // The mesh's top (a few hundred unknowns at the default tolerance) lies below the size from
  // which a single-precision top is spread over the ranks (-pc_h2_single_top_from 4000): forced here,
  // with every level the parts allow eliminated, the spread top (ScaLAPACK on several ranks; the
  // single-precision LU on one) preconditions GMRES as well as the others.
  const char *spread = "-t_ksp_type gmres -t_ksp_pc_side right -t_ksp_rtol 1e-10 -t_pc_type h2 -t_pc_h2_single_top_from 1 -t_pc_h2_top_size 0 -t_pc_h2_top_when_cheaper false";
  const Outcome o = ksp_solve(mixed->A[2], mixed->b[2], mixed->xd, spread);
  EXPECT_GT(o.reason, 0);
  EXPECT_GE(o.its, 2);
  EXPECT_LE(o.its, 12);
  EXPECT_LE(o.diff, 6.5e-9); // measured at 1, 2, 3, 4, 6 ranks: 2.7e-11, 2.1e-9, 6.1e-11, 2.1e-11, 1.1e-9
  PetscMPIInt size;
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Comm_size(PETSC_COMM_WORLD, &size));
  const std::string view = pc_view_after(mixed->A[2], spread);
  if (size > 1) EXPECT_NE(view.find("top spread over " + std::to_string(size) + " ranks"), std::string::npos) << view;
  else EXPECT_NE(view.find("LU in single precision like the panels"), std::string::npos) << view;
}

TEST(PCH2Pure, RegularisedPressureProblemMatchesDense)
{
  Systems s(pressure_spec("sphere_l1.msh", 1000.0, 0.3, 100.0), true);
  ASSERT_TRUE(s.setup.pure_traction);
  const Outcome o = ksp_solve(s.A[2], s.b[2], s.xd, "-t_ksp_type preonly -t_pc_type h2 -t_pc_h2_rel_tol 1e-8 -t_pc_h2_top_size 200 -t_pc_h2_top_when_cheaper false");
  EXPECT_GT(o.reason, 0);
  EXPECT_LE(o.diff, 7.5e-9); // measured at 1, 2, 3, 4, 6 ranks: 2.9e-10, 2.4e-9, 2.3e-10, 1.5e-10, 3.1e-11
}

TEST(PCH2Pure, UnregularisedBreakdownIsAPcFailure)
{
  // Without the regularisation the H² matrix of a pure-traction problem has the translations as
  // exact null vectors; factored densely (the whole of it in the top) it is singular.
  Systems s(pressure_spec("sphere_l0.msh", 1000.0, 0.3, 100.0), false);
  const Outcome o = ksp_solve(s.A[2], s.b[2], nullptr, "-t_ksp_type gmres -t_pc_type h2 -t_pc_h2_top_size 100000");
  EXPECT_EQ(o.reason, KSP_DIVERGED_PC_FAILED);
}

TEST(PCH2Options, BadValuesAreErrors)
{
  KSP ksp;
  PC pc;
  PetscCallAbort(PETSC_COMM_WORLD, KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetPC(ksp, &pc));
  PetscCallAbort(PETSC_COMM_WORLD, PCSetType(pc, PCH2));
  PetscCallAbort(PETSC_COMM_WORLD, PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  EXPECT_NE(PCH2SetRelTol(pc, 2.0), 0);
  EXPECT_NE(PCH2SetLeafSize(pc, -1), 0);
  EXPECT_NE(PCH2SetTopSize(pc, -3), 0);
  EXPECT_NE(PCH2SetSketchSize(pc, -1), 0);
  EXPECT_NE(PCH2SetSketchSize(pc, 100000), 0); // beyond any tolerance's need (at most 4096)
  EXPECT_NE(PCH2SetEstimateError(pc, 1000000), 0);
  EXPECT_EQ(PCH2SetRelTol(pc, 1e-4), 0);
  EXPECT_EQ(PCH2SetLeafSize(pc, 128), 0);
  EXPECT_EQ(PCH2SetSketchSize(pc, 4096), 0);
  // Through the options database, checked at PCSetFromOptions.
  PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsInsertString(NULL, "-pc_h2_sketch_size 5000"));
  EXPECT_NE(PCSetFromOptions(pc), 0);
  PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsClearValue(NULL, "-pc_h2_sketch_size"));
  PetscCallAbort(PETSC_COMM_WORLD, PetscPopErrorHandler());
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
}

} // namespace
