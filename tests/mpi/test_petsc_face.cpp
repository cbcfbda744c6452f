// The PETSc face of the HSS and H² engines on 1, 2 and 4 ranks: the HSS and H² MatShells
// against the dense matrix (product, right-hand side, diagonal), PC hss as a direct solver and as
// a GMRES preconditioner on the HSS, H² and dense matrices, the H² matrix's default Krylov
// solver, and a breakdown reported as a PC failure.
#include "solve_helpers.hpp"
#include "vec_compare.hpp"
#include "test_shapes.hpp"

#include "hssbem/petsc/pc_hss.h"
#include "hssbem/petsc/system.h"

#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>
#include <fstream>
#include <unistd.h>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

using namespace hssbem;
using namespace hssbem::test;

namespace {

/// A problem with its dense and HSS systems (-mat_hss_rel_tol at its default, 1e-8).
struct Systems {
  ProblemSetup setup;
  std::unique_ptr<BemOperator> op;
  std::vector<double> modes;
  Mat Ad = nullptr, Ah = nullptr, A2 = nullptr;
  Vec bd = nullptr, bh = nullptr, b2 = nullptr;

  explicit Systems(const ProblemSpec &spec, bool regularise = true) : setup(setup_problem(spec, ProblemOverrides{}))
  {
    op = std::make_unique<BemOperator>(*setup.disc, setup.material);
    if (setup.pure_traction && regularise) modes = orthonormal_rigid_modes(*setup.disc);
    const std::vector<double> *m = modes.empty() ? nullptr : &modes;
    PetscCallAbort(PETSC_COMM_WORLD, HssbemCreateSystem(PETSC_COMM_WORLD, *op, setup.selection, m, HSSBEM_MAT_DENSE, &Ad, &bd));
    PetscCallAbort(PETSC_COMM_WORLD, HssbemCreateSystem(PETSC_COMM_WORLD, *op, setup.selection, m, HSSBEM_MAT_HSS, &Ah, &bh));
    PetscCallAbort(PETSC_COMM_WORLD, HssbemCreateSystem(PETSC_COMM_WORLD, *op, setup.selection, m, HSSBEM_MAT_H2, &A2, &b2));
  }
  ~Systems()
  {
    MatDestroy(&Ad);
    MatDestroy(&Ah);
    MatDestroy(&A2);
    VecDestroy(&bd);
    VecDestroy(&bh);
    VecDestroy(&b2);
  }
};

ProblemSpec kelvin_mixed()
{
  const KelvinField k{Material{1000.0, 0.3}, {1.2, 0.9, 1.0}, {1.0, -2.0, 0.5}};
  return kelvin_mixed_spec("sphere_l0.msh", k);
}

ProblemSpec sphere_pressure() { return pressure_spec("sphere_l0.msh", 1000.0, 0.3, 100.0); }

/// Removes from the options database exactly the keys in `options` ("-key value ..."): the
/// options the test program set for every test (small leaves) stay.
void clear_options(const char *options)
{
  std::istringstream in(options);
  for (std::string token; in >> token;)
    if (token.size() > 1 && token[0] == '-' && !std::isdigit((unsigned char)token[1]) && token[1] != '.') PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsClearValue(NULL, token.c_str()));
}

/// What MatView or PCView prints to an ASCII viewer, as one string (rank 0's; empty elsewhere).
template <class Obj>
std::string view_text(Obj obj, PetscErrorCode (*view)(Obj, PetscViewer))
{
  PetscViewer v;
  PetscMPIInt rank;
  long long   pid = ::getpid();
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Bcast(&pid, 1, MPI_LONG_LONG, 0, PETSC_COMM_WORLD));
  const std::string file = "/tmp/hssbem_petsc_face_view_" + std::to_string(pid) + ".txt";
  PetscCallAbort(PETSC_COMM_WORLD, PetscViewerASCIIOpen(PETSC_COMM_WORLD, file.c_str(), &v));
  PetscCallAbort(PETSC_COMM_WORLD, view(obj, v));
  PetscCallAbort(PETSC_COMM_WORLD, PetscViewerDestroy(&v));
  if (rank != 0) return "";
  std::ifstream      in(file);
  std::ostringstream text;
  text << in.rdbuf();
  std::remove(file.c_str());
  return text.str();
}

/// Levels of the compression behind an HSS matrix (rank 0; 0 elsewhere): more than 1 when
/// something is compressed at all.
int hss_levels(Mat A)
{
  const std::string text = view_text(A, MatView);
  std::smatch       m;
  if (!std::regex_search(text, m, std::regex("(\\d+) rows, (\\d+) levels"))) return 0;
  return std::stoi(m[2]);
}

/// Outcome of one KSP solve with the options in `options` (prefix "t_").
struct Outcome {
  KSPConvergedReason reason;
  PetscInt its;
  double diff; ///< against x_ref
};

Outcome ksp_solve(Mat A, Vec b, Vec x_ref, const char *options)
{
  KSP ksp;
  Vec x;
  Outcome o{};
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
  clear_options(options);
  return o;
}

/// Dense LU solution: the reference.
Vec dense_solution(Mat Ad, Vec bd)
{
  KSP ksp;
  Vec x;
  Mat A;
  PetscCallAbort(PETSC_COMM_WORLD, MatConvert(Ad, MATDENSE, MAT_INITIAL_MATRIX, &A));
  PetscCallAbort(PETSC_COMM_WORLD, HssbemKSPCreate(PETSC_COMM_WORLD, HSSBEM_MAT_DENSE, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(bd, &x));
  HssbemSolveInfo info;
  PetscCallAbort(PETSC_COMM_WORLD, HssbemSolveSystem(ksp, &A, bd, x, &info));
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
  PetscCallAbort(PETSC_COMM_WORLD, MatDestroy(&A));
  return x;
}

/// sphere_l0 (251 nodes) would fit in one default leaf (256 nodes); leaves of 32 nodes give these
/// tests a tree with three levels of skeletons. For H², leaves of 8 nodes and eta = 0 give it 452
/// far blocks (the default leaf size, 64, leaves a mesh this small all near field), at 1e-6 in
/// double precision (the driver's default is 1e-5 in single) for comparisons with dense LU.
class SmallLeaves : public ::testing::Environment {
public:
  void SetUp() override
  {
    PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsInsertString(NULL, "-mat_hss_leaf_size 32 -mat_h2_leaf_size 8 -mat_h2_eta 0 -mat_h2_rel_tol 1e-6 -mat_h2_single_precision false"));
  }
};
::testing::Environment *const small_leaves = ::testing::AddGlobalTestEnvironment(new SmallLeaves);

class PetscFace : public ::testing::Test {
protected:
  static void SetUpTestSuite()
  {
    mixed = new Systems(kelvin_mixed());
    xd    = dense_solution(mixed->Ad, mixed->bd);
  }
  static void TearDownTestSuite()
  {
    VecDestroy(&xd);
    delete mixed;
    mixed = nullptr;
  }
  static Systems *mixed;
  static Vec xd; ///< dense LU solution
};
Systems *PetscFace::mixed = nullptr;
Vec PetscFace::xd = nullptr;

/// b, A x for a random x and the diagonal of a compressed matrix A against the dense system:
/// each within `bound` (relative).
void expect_matches_dense(Mat A, Vec b, const Systems &sys, double bound)
{
  EXPECT_LE(rel_diff(A, b, sys.bd), bound);
  Vec x, yd, xa, ya;
  PetscRandom rnd;
  PetscCallAbort(PETSC_COMM_WORLD, PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
  PetscCallAbort(PETSC_COMM_WORLD, MatCreateVecs(sys.Ad, &x, &yd));
  PetscCallAbort(PETSC_COMM_WORLD, MatCreateVecs(A, &xa, &ya));
  PetscCallAbort(PETSC_COMM_WORLD, VecSetRandom(x, rnd));
  PetscCallAbort(PETSC_COMM_WORLD, MatMult(sys.Ad, x, yd));
  PetscCallAbort(PETSC_COMM_WORLD, HssbemVecFromMeshOrder(A, x, xa)); // A's rows may be in cluster order
  PetscCallAbort(PETSC_COMM_WORLD, MatMult(A, xa, ya));
  EXPECT_LE(rel_diff(A, ya, yd), bound);
  // The diagonal: true entries, except the rigid-body terms, which come from a fast product.
  PetscCallAbort(PETSC_COMM_WORLD, MatGetDiagonal(sys.Ad, yd));
  PetscCallAbort(PETSC_COMM_WORLD, MatGetDiagonal(A, ya));
  EXPECT_LE(rel_diff(A, ya, yd), bound);
  PetscCallAbort(PETSC_COMM_WORLD, PetscRandomDestroy(&rnd));
  VecDestroy(&x);
  VecDestroy(&yd);
  VecDestroy(&xa);
  VecDestroy(&ya);
}

TEST_F(PetscFace, HssMatrixMatchesDense)
{
  PetscBool compressed, shell;
  PetscInt bs;
  ASSERT_EQ(HssbemMatIsCompressed(mixed->Ah, &compressed), 0);
  EXPECT_TRUE(compressed);
  PetscCallAbort(PETSC_COMM_WORLD, PetscObjectTypeCompare((PetscObject)mixed->Ah, MATSHELL, &shell));
  EXPECT_TRUE(shell);
  PetscCallAbort(PETSC_COMM_WORLD, MatGetBlockSize(mixed->Ah, &bs));
  EXPECT_EQ(bs, 3);
  expect_matches_dense(mixed->Ah, mixed->bh, *mixed, 1e-7); // tol 1e-8: 10·tol
}

/// A solve that converged within [min_its, max_its] iterations to within max_diff of dense LU.
void expect_solved(const Outcome &o, double max_diff, int min_its = 1, int max_its = 1)
{
  EXPECT_GT(o.reason, 0);
  EXPECT_GE(o.its, min_its);
  EXPECT_LE(o.its, max_its);
  EXPECT_LE(o.diff, max_diff);
}

TEST_F(PetscFace, DirectSolveReusesTheMatrixCompression)
{
  expect_solved(ksp_solve(mixed->Ah, mixed->bh, xd, "-t_ksp_type preonly -t_pc_type hss"), 5e-8); // measured 1.0e-8 (tol 1e-8)
}

/// b (mesh order, the dense system's layout) in A's layout (cluster order on several ranks).
Vec in_layout(Mat A, Vec b)
{
  Vec x;
  PetscCallAbort(PETSC_COMM_WORLD, MatCreateVecs(A, NULL, &x));
  PetscCallAbort(PETSC_COMM_WORLD, HssbemVecFromMeshOrder(A, b, x));
  return x;
}

TEST_F(PetscFace, DirectSolveAtATighterTolerance)
{
  // 1e-9 is tighter than the matrix's 1e-8: the PC compresses anew; the rhs is the dense one,
  // so the answer is checked against 100 · 1e-9.
  Vec b = in_layout(mixed->Ah, mixed->bd);
  expect_solved(ksp_solve(mixed->Ah, b, xd, "-t_ksp_type preonly -t_pc_type hss -t_pc_hss_rel_tol 1e-9"), 2e-9); // measured 3.5e-10
  VecDestroy(&b);
}

TEST_F(PetscFace, GmresWithTruncatedHssPreconditioner)
{
  // A 1e-3 factorization is not a direct solve: GMRES must iterate (at least 2), at most 15 times.
  expect_solved(ksp_solve(mixed->Ah, mixed->bh, xd, "-t_ksp_type gmres -t_ksp_rtol 1e-10 -t_pc_type hss -t_pc_hss_rel_tol 1e-3"), 5e-8, 2, 15); // measured 1.0e-8: the matrix's tolerance
}

TEST_F(PetscFace, GmresWithHssPreconditionerOnTheDenseMatrix)
{
  expect_solved(ksp_solve(mixed->Ad, mixed->bd, xd, "-t_ksp_type gmres -t_ksp_rtol 1e-10 -t_pc_type hss -t_pc_hss_rel_tol 1e-3 -t_pc_hss_leaf_size 32"), 5e-11, 2, 15); // measured 5.2e-12
}

TEST_F(PetscFace, H2MatrixMatchesDense)
{
  PetscBool compressed;
  ASSERT_EQ(HssbemMatIsCompressed(mixed->A2, &compressed), 0);
  EXPECT_TRUE(compressed);
  expect_matches_dense(mixed->A2, mixed->b2, *mixed, 1e-5); // -mat_h2_rel_tol 1e-6: 10·tol
}

TEST_F(PetscFace, H2MatrixDefaultSolverIsGmresWithH2OnOneRankJacobiOnSeveral)
{
  KSP ksp;
  Vec x;
  Mat A = mixed->A2;
  PetscCallAbort(PETSC_COMM_WORLD, PetscObjectReference((PetscObject)A));
  PetscCallAbort(PETSC_COMM_WORLD, HssbemKSPCreate(PETSC_COMM_WORLD, HSSBEM_MAT_H2, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetTolerances(ksp, 1e-10, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(mixed->b2, &x));
  HssbemSolveInfo info;
  PetscCallAbort(PETSC_COMM_WORLD, HssbemSolveSystem(ksp, &A, mixed->b2, x, &info));
  const double diff = rel_diff(A, x, xd);
  PetscCallAbort(PETSC_COMM_WORLD, PetscPrintf(PETSC_COMM_WORLD, "  H2 default: %s/%s, %d iterations, difference from dense LU %.2e\n", info.ksp_type.c_str(), info.pc_type.c_str(), (int)info.iterations, diff));
  // PC h2 on any number of ranks (distributed like the matrix on several)
  EXPECT_EQ(info.ksp_type, "gmres");
  EXPECT_EQ(info.pc_type, "h2");
  EXPECT_GE(info.iterations, 1);
  EXPECT_LE(info.iterations, 12); // the H² factorization at its default tolerance (Jacobi: 37 at 2 ranks)
  EXPECT_LE(diff, 1e-8); // measured 4.3e-14 with PC h2: on this small mesh the factorization is exact (rtol 1e-10)
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
  PetscCallAbort(PETSC_COMM_WORLD, MatDestroy(&A));
  VecDestroy(&x);
}

TEST_F(PetscFace, GmresWithHssPreconditionerOnTheH2Matrix)
{
  // On the H² matrix PC hss compresses HSS anew (here at 1e-3, its default there).
  expect_solved(ksp_solve(mixed->A2, mixed->b2, xd, "-t_ksp_type gmres -t_ksp_rtol 1e-10 -t_pc_type hss -t_pc_hss_leaf_size 32"), 1e-10, 2, 15); // measured 5.2e-12
}

TEST(PetscFacePure, RegularisedPressureProblemMatchesDense)
{
  Systems s(sphere_pressure());
  ASSERT_TRUE(s.setup.pure_traction);
  PetscMPIInt rank;
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  const int levels = hss_levels(s.Ah); // collective
  if (rank == 0) EXPECT_GE(levels, 3); // leaves of 32 nodes: compressed, not one leaf
  Vec xd = dense_solution(s.Ad, s.bd);
  expect_solved(ksp_solve(s.Ah, s.bh, xd, "-t_ksp_type preonly -t_pc_type hss"), 2e-8); // measured 3.8e-9 (tol 1e-8)
  VecDestroy(&xd);
}

TEST(PetscFacePure, OneLeafPerPartRegularisedMatchesDense)
{
  // Leaves as large as the mesh. On one rank the whole mesh is one leaf (the root): the
  // rigid-mode term enters its dense block directly, and nothing is compressed. On several ranks
  // each METIS part is one leaf below the partition's top: the term goes through the parts'
  // bases into the top's blocks, and the skeletons between the parts are at 1e-8.
  PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsInsertString(NULL, "-mat_hss_leaf_size 100000"));
  Systems s(sphere_pressure());
  PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsInsertString(NULL, "-mat_hss_leaf_size 32"));
  PetscMPIInt size, rank;
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  const int levels = hss_levels(s.Ah); // collective
  if (rank == 0) EXPECT_EQ(levels, size == 1 ? 1 : size == 2 ? 2 : 3); // one leaf, or one leaf per part below log2(P) levels
  Vec xd = dense_solution(s.Ad, s.bd);
  expect_solved(ksp_solve(s.Ah, s.bh, xd, "-t_ksp_type preonly -t_pc_type hss"), size == 1 ? 1e-13 : 2e-8); // measured 1.8e-15 on one rank (true entries), 2.2e-9 on 2 (tol 1e-8)
  VecDestroy(&xd);
}

TEST(PetscFacePure, BreakdownIsAPreconditionerFailure)
{
  // Pure traction without the rigid-mode regularisation: A is singular (the translations are
  // in its null space to round-off), and the factorization must say so, not crash.
  Systems s(sphere_pressure(), false);
  ASSERT_TRUE(s.setup.pure_traction);
  PetscMPIInt rank;
  PetscCallAbort(PETSC_COMM_WORLD, MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  const int levels = hss_levels(s.Ah); // collective
  if (rank == 0) EXPECT_GE(levels, 3); // a tree of clusters, not one leaf (at 1e-8 their skeletons are still full, so the root block is where the singularity shows)
  KSP ksp;
  Vec x;
  PC  pc;
  KSPConvergedReason reason;
  PetscCallAbort(PETSC_COMM_WORLD, KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetType(ksp, KSPPREONLY));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetPC(ksp, &pc));
  PetscCallAbort(PETSC_COMM_WORLD, PCSetType(pc, PCHSS));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSetOperators(ksp, s.Ah, s.Ah));
  PetscCallAbort(PETSC_COMM_WORLD, VecDuplicate(s.bh, &x));
  PetscCallAbort(PETSC_COMM_WORLD, KSPSolve(ksp, s.bh, x));
  PetscCallAbort(PETSC_COMM_WORLD, KSPGetConvergedReason(ksp, &reason));
  EXPECT_EQ(reason, KSP_DIVERGED_PC_FAILED);
  const std::string view = view_text(pc, PCView);
  if (rank == 0) {
    std::printf("  breakdown: %s\n", view.substr(view.find("factorization failed")).c_str());
    EXPECT_NE(view.find("factorization failed: HSS factorization broke down"), std::string::npos) << view;
  }
  PetscCallAbort(PETSC_COMM_WORLD, VecDestroy(&x));
  PetscCallAbort(PETSC_COMM_WORLD, KSPDestroy(&ksp));
}

} // namespace
