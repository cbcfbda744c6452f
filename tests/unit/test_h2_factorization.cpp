// H² factorization (strong recursive skeletonization) against dense LU of the same system.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/compress/pattern_columns.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/size_limits.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"
#include "hss_test_helpers.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <ostream>
#include <random>
#include <string>

using namespace hssbem;
using namespace hssbem::test; // dense_k, dense_a, random_pattern, rel, case_name

namespace {

struct Loaded {
  SurfaceMesh mesh;
  std::unique_ptr<Discretization> disc;
  std::unique_ptr<BemOperator> op;
};

std::unique_ptr<Loaded> load(const std::string &name, double nu = 0.3)
{
  auto L = std::make_unique<Loaded>();
  L->mesh = read_mesh(std::string(HSSBEM_MESHES) + "/" + name);
  std::vector<std::string> notices;
  validate_and_orient(L->mesh, notices);
  L->disc = std::make_unique<Discretization>(L->mesh, 40.0);
  L->op = std::make_unique<BemOperator>(*L->disc, Material::from_young(1.0, nu));
  return L;
}

/// The H² matrix of L's operator in double precision at rel_tol (0: 1e-6) with leaves of `leaf`
/// nodes (0: H2Options' default).
H2Matrix compress(const Loaded &L, double rel_tol, int leaf)
{
  H2Options o;
  o.rel_tol = rel_tol > 0 ? rel_tol : 1e-6;
  o.single_precision = false;
  if (leaf > 0) o.leaf_size = leaf;
  return compress_bem_operator_h2(*L.op, o);
}

SystemSelection selection(int n, std::vector<std::array<bool, 3>> known)
{
  SystemSelection s;
  s.displacement_known = std::move(known);
  s.known.assign(n, Vec3{0, 0, 0});
  return s;
}

std::vector<double> random_vector(std::size_t n, int seed)
{
  std::mt19937 gen(seed);
  std::normal_distribution<double> N01;
  std::vector<double> v(n);
  for (double &x : v) x = N01(gen);
  return v;
}

/// x = A⁻¹ b by dense LU, A column-major N × N.
std::vector<double> dense_solve(std::vector<double> A, std::vector<double> b)
{
  const int N = static_cast<int>(b.size());
  std::vector<int> piv(N);
  EXPECT_EQ(lapack::getrf(N, A.data(), N, piv.data()), 0);
  lapack::getrs('N', N, 1, A.data(), N, piv.data(), b.data(), N);
  return b;
}

void print_stats(const H2FactorStats &st)
{
  for (const H2FactorLevelStats &l : st.levels)
    std::printf("  level %d: %d boxes, candidates %.0f (max %d), rank %.0f (max %d), %lld eliminated, %.1f MB\n", l.level, l.boxes, l.mean_candidates,
                l.max_candidates, l.mean_rank, l.max_rank, l.eliminated, l.bytes / 1e6);
  std::printf("  top %d, factors %.1f MB, %.2f s (sketch %.2f, init %.2f, skeletons %.2f, eliminations %.2f, merges %.2f, top %.2f)\n", st.top_size, st.bytes / 1e6,
              st.seconds(), st.time_sketch, st.time_init, st.time_skeleton, st.time_eliminate, st.time_merge, st.time_top);
}

struct Case {
  const char *mesh;
  double tol;
  int leaf;
  double p_known;        ///< probability that a component's displacement is known (traction unknown)
  double min_eliminated; ///< fraction of the unknowns the levels must eliminate (the rest is the dense top; cube_l1: 48 % measured)
  double max_error;      ///< bound on the error against dense LU: 3x the measured value
  double max_inverse;    ///< bound on the ||I - A F^-1|| estimate: likewise
};

void PrintTo(const Case &c, std::ostream *os) { *os << case_name(c.mesh, c.tol, c.leaf); }

class H2FactorAccuracy : public ::testing::TestWithParam<Case> {};

TEST_P(H2FactorAccuracy, SolveMatchesDenseLU)
{
  const Case c = GetParam();
  auto L = load(c.mesh);
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, c.tol / 100, c.leaf); // the factorization's error dominates the product's
  const auto known = random_pattern(n, c.p_known, 17);
  const SystemSelection sel = selection(n, known);
  H2FactorCache cache(K);
  H2FactorOptions fo;
  fo.rel_tol = c.tol;
  fo.top_size = 0;       // factor every level that has a far field,
  fo.top_when_cheaper = false;
  fo.leaf_size = c.leaf; // from the H² leaves up (by default, below 1e-5, from their parents)
  const H2Factorization F(cache, sel, fo);
  const std::vector<double> b = random_vector(3L * n, 5);
  std::vector<double> x(b.size());
  solve_mesh_order(F, b.data(), x.data());
  const std::vector<double> xd = dense_solve(dense_a(dense_k(*L->op, 6), n, 6, known), b);
  const double err = rel(x, xd);
  const H2FactorStats &st = F.stats();
  std::printf("%s tol %.0e leaf %d, %.0f%% u known: error vs dense LU %.2e\n", c.mesh, c.tol, c.leaf, 100 * c.p_known, err);
  print_stats(st);
  EXPECT_LE(err, c.max_error);
  // Not a dense LU in disguise: the levels eliminated a good part of A before the dense top.
  ASSERT_FALSE(st.levels.empty());
  long long eliminated = 0;
  for (const H2FactorLevelStats &l : st.levels) eliminated += l.eliminated;
  EXPECT_EQ(eliminated + st.top_size, 3LL * n);
  EXPECT_GE(eliminated, c.min_eliminated * 3 * n);
  // The estimate of ‖I − A F⁻¹‖ (with the H² product) follows the tolerance too.
  std::vector<double> in_mesh(3L * n), out_mesh(3L * n);
  const double inv_err = estimate_inverse_error(F, [&](const double *in, double *out) { // cluster order, as F.solve()
    K.tree().to_mesh_order(in, in_mesh.data(), 3);
    apply_compressed_k(K, pattern_product_input(sel, in_mesh.data(), n, K.col_block()), out_mesh.data());
    K.tree().to_cluster_order(out_mesh.data(), out, 3);
  });
  std::printf("  ||I - A F^-1|| ~ %.2e\n", inv_err);
  EXPECT_LE(inv_err, c.max_inverse);
}

INSTANTIATE_TEST_SUITE_P(Meshes, H2FactorAccuracy,
                         // error and ||I - A F^-1|| measured (2 threads): 1.10e-3, 3.64e-3; 2.66e-7, 1.70e-6; 7.87e-11,
                         // 7.44e-10; 6.17e-7, 1.58e-6; 1.27e-3, 2.69e-3; 8.49e-7, 1.97e-6; 3.02e-7, 5.48e-7; the
                         // hollow sphere (nearly all of it in the dense top) 1.6e-15, 1.2e-15: rounding level
                         ::testing::Values(Case{"sphere_l1.msh", 1e-3, 16, 0.3, 0.8, 3.3e-3, 1.1e-2}, Case{"sphere_l1.msh", 1e-6, 16, 0.3, 0.6, 8e-7, 5.1e-6},
                                           Case{"sphere_l1.msh", 1e-9, 16, 0.3, 0.5, 2.4e-10, 2.3e-9}, Case{"sphere_l1.msh", 1e-6, 32, 0.7, 0.6, 1.9e-6, 4.8e-6},
                                           Case{"cardioid_fine.msh", 1e-3, 32, 0.5, 0.5, 3.9e-3, 8.1e-3}, Case{"cardioid_fine.msh", 1e-6, 32, 0.5, 0.3, 2.6e-6, 6e-6},
                                           Case{"cube_l1.msh", 1e-6, 16, 0.3, 0.45, 9.1e-7, 1.7e-6}, Case{"hollow_sphere_l0.msh", 1e-6, 16, 0.3, 0.05, 1e-14, 1e-14}),
                         [](const ::testing::TestParamInfo<Case> &info) { return case_name(info.param.mesh, info.param.tol, info.param.leaf); });

TEST(H2FactorSchedule, TwoThreadsGiveTheSameFactorsEveryTimeAndTheOneThreadOnesToTheTolerance)
{
  // A level's boxes run as a dependency graph on the threads, in an order that depends on their
  // timing: any order the graph allows must give the same factors, bit for bit.
  auto L = load("sphere_l1.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 1e-8, 16);
  const auto known = random_pattern(n, 0.3, 29);
  const SystemSelection sel = selection(n, known);
  H2FactorCache cache(K);
  H2FactorOptions fo;
  fo.rel_tol = 1e-6;
  fo.top_size = 0;
  fo.top_when_cheaper = false;
  fo.leaf_size = 16;
  const std::vector<double> b = random_vector(3L * n, 11);
  const int threads = omp_get_max_threads();
  const auto solve = [&](int nt) {
    omp_set_num_threads(nt);
    const H2Factorization F(cache, sel, fo);
    std::vector<double> x(b.size());
    solve_mesh_order(F, b.data(), x.data());
    int most = 0; // boxes on the widest level: more than the threads, or nothing ran at once
    for (const H2FactorLevelStats &l : F.stats().levels) most = std::max(most, l.boxes);
    EXPECT_GE(most, 4);
    return x;
  };
  const std::vector<double> x1 = solve(2), x2 = solve(2), x3 = solve(2), xs = solve(1);
  omp_set_num_threads(threads);
  EXPECT_EQ(x1, x2);
  EXPECT_EQ(x1, x3);
  // One thread: the same steps, but BLAS threaded where two threads ran it serially (rounding).
  const double diff = rel(x1, xs);
  std::printf("two threads, three runs: identical; one thread: relative difference %.2e\n", diff);
  EXPECT_LE(diff, 3.5e-10); // measured 1.1e-10
}

TEST(H2FactorAccuracy, LooseToleranceIsApproximate)
{
  // The bound above must mean something: at 1e-2 the factorization is visibly inexact.
  auto L = load("sphere_l1.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 1e-8, 16);
  const auto known = random_pattern(n, 0.3, 17);
  H2FactorCache cache(K);
  H2FactorOptions fo;
  fo.rel_tol = 1e-2;
  fo.top_size = 0;
  fo.top_when_cheaper = false;
  const H2Factorization F(cache, selection(n, known), fo);
  const std::vector<double> b = random_vector(3L * n, 5);
  std::vector<double> x(b.size());
  solve_mesh_order(F, b.data(), x.data());
  const double err = rel(x, dense_solve(dense_a(dense_k(*L->op, 6), n, 6, known), b));
  std::printf("tol 1e-2: error %.2e\n", err);
  EXPECT_GT(err, 4e-3); // measured 1.3e-2
  EXPECT_LE(err, 4e-2);
}

TEST(H2FactorMemory, SinglePrecisionWorkingBlocksHalveTheStore)
{
  // At a loose tolerance the working blocks rest in single precision between the steps that
  // change them (with the panels): the factorization's largest working store falls to about half
  // and the solution moves by far less than the tolerance.
  auto L = load("cardioid_fine.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 1e-6, 32);
  const SystemSelection sel = selection(n, random_pattern(n, 0.5, 17));
  H2FactorCache cache(K);
  H2FactorOptions fo;
  fo.rel_tol = 1e-4;
  fo.top_size = 0;
  fo.top_when_cheaper = false;
  fo.single_panels = 0;
  const H2Factorization Fd(cache, sel, fo);
  fo.single_panels = 1;
  const H2Factorization Fs(cache, sel, fo);
  const std::vector<double> b = random_vector(3L * n, 5);
  std::vector<double> xd(b.size()), xs(b.size());
  solve_mesh_order(Fd, b.data(), xd.data());
  solve_mesh_order(Fs, b.data(), xs.data());
  const double moved = rel(xs, xd), err = rel(xs, dense_solve(dense_a(dense_k(*L->op, 6), n, 6, sel.displacement_known), b));
  const std::size_t wd = Fd.stats().workspace_bytes, ws = Fs.stats().workspace_bytes;
  std::printf("working store %.2f MB in double, %.2f MB at rest in single; solutions differ by %.2e, error vs dense LU %.2e\n", wd / 1e6, ws / 1e6, moved, err);
  EXPECT_GT(ws, 0u);
  EXPECT_LT(ws, 0.65 * wd);
  EXPECT_GT(ws, 0.4 * wd); // a merge holds both levels, blocks being worked on are in double
  EXPECT_LE(moved, 6.7e-7); // measured 2.2e-7
  EXPECT_LE(err, 3.3e-4);   // measured 1.1e-4
}

TEST(H2FactorPatterns, TwoPatternsOneCompression)
{
  // One H² matrix (and one cached sketch) serves a second pattern with 30 % of the vertices
  // switched, without evaluating a kernel entry.
  auto L = load("cardioid_832.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 1e-8, 16);
  const long long entries = K.stats().entries_evaluated;
  const auto Kd = dense_k(*L->op, 6);
  auto known = random_pattern(n, 0.5, 3);
  H2FactorCache cache(K);
  H2FactorOptions fo;
  fo.rel_tol = 1e-6;
  fo.top_size = 0;
  fo.top_when_cheaper = false;
  const std::vector<double> b = random_vector(3L * n, 9);
  for (int pass = 0; pass < 2; ++pass) {
    const H2Factorization F(cache, selection(n, known), fo);
    std::vector<double> x(b.size());
    solve_mesh_order(F, b.data(), x.data());
    const double err = rel(x, dense_solve(dense_a(Kd, n, 6, known), b));
    std::printf("pattern %d: error %.2e, sketch %.3f s\n", pass, err, F.stats().time_sketch);
    EXPECT_LE(err, 4e-7); // measured 4.5e-8, 1.3e-7
    if (pass == 1) EXPECT_EQ(F.stats().time_sketch, 0.0); // the cached sketch
    std::mt19937 gen(11);
    std::bernoulli_distribution flip(0.3);
    for (auto &k : known)
      if (flip(gen)) k = {!k[0], !k[1], !k[2]};
  }
  EXPECT_EQ(K.stats().entries_evaluated, entries);
}

TEST(H2FactorPureTraction, RegularisedMatchesDense)
{
  // All tractions known: A = H is singular (rigid modes); A + c Φ Φᵀ is not.
  auto L = load("sphere_l1.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 1e-9, 16);
  const std::vector<std::array<bool, 3>> known(n, {false, false, false});
  const std::vector<double> modes = orthonormal_rigid_modes(*L->disc);
  std::vector<double> A = dense_a(dense_k(*L->op, 6), n, 6, known);
  const std::size_t N = 3L * n;
  for (std::size_t i = 0; i < N; ++i)
    for (std::size_t j = 0; j < N; ++j) {
      double s = 0;
      for (int q = 0; q < 6; ++q) s += modes[i * 6 + q] * modes[j * 6 + q];
      A[i + j * N] += rigid_regularization_weight * s;
    }
  const std::vector<double> b = random_vector(N, 21);
  const std::vector<double> xd = dense_solve(A, b);
  H2FactorCache cache(K);
  for (const double tol : {1e-3, 1e-7}) {
    H2FactorOptions fo;
    fo.rel_tol = tol;
    fo.top_size = 0;
    fo.top_when_cheaper = false;
    const H2Factorization F(cache, selection(n, known), fo, &modes);
    std::vector<double> x(N);
    solve_mesh_order(F, b.data(), x.data());
    const double err = rel(x, xd);
    std::printf("pure traction, tol %.0e: error %.2e, top %d\n", tol, err, F.stats().top_size);
    EXPECT_LE(err, tol > 1e-5 ? 1.1e-3 : 7.4e-9); // measured 3.5e-4 (1e-3), 2.5e-9 (1e-7)
    EXPECT_GT(F.stats().levels.size(), 0u);
  }
}

TEST(H2FactorPureTraction, UnregularisedBreaksDown)
{
  // Without the regularisation the translations are exact null vectors of the H² matrix (its
  // rigid-body terms are built so): factored densely, the top block is singular.
  auto L = load("sphere_l0.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 0, 16);
  H2FactorCache cache(K);
  H2FactorOptions fo;
  fo.top_size = 3 * n; // all of it in the top
  for (int mixed : {0, 1}) { // the single-precision LU does not hide it: its refinement stalls, the double LU's test fires
    fo.single_top_from = mixed;
    EXPECT_THROW(H2Factorization(cache, selection(n, std::vector<std::array<bool, 3>>(n, {false, false, false})), fo), H2Breakdown);
    EXPECT_NO_THROW(H2Factorization(cache, selection(n, random_pattern(n, 0.5, 2)), fo));
  }
}

TEST(H2FactorTop, MixedPrecisionTopSolvesLikeTheDoubleLU)
{
  // The whole system in the top: its LU in single precision with refinement in double must give
  // the double LU's solution to rounding level, not single precision's (~1e-7 · cond).
  auto L = load("cardioid_fine.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 1e-8, 32);
  H2FactorCache cache(K);
  const SystemSelection sel = selection(n, random_pattern(n, 0.5, 9));
  H2FactorOptions fo;
  fo.top_size = 3 * n;
  fo.single_top_from = 0;
  const H2Factorization plain(cache, sel, fo);
  fo.single_top_from = 3 * n; // from exactly this size on
  const H2Factorization mixed(cache, sel, fo);
  EXPECT_FALSE(plain.stats().top_mixed);
  ASSERT_TRUE(mixed.stats().top_mixed);
  EXPECT_EQ(mixed.stats().top_size, 3 * n);
  // The double block is kept beside the single-precision LU: 1.5 times the bytes.
  EXPECT_NEAR(static_cast<double>(mixed.stats().top_bytes) / plain.stats().top_bytes, 1.5, 0.01);
  // The size model (core/size_limits.hpp, the one model of the top) takes the kind the
  // factorization took (the panels are stored in single precision only below a top, and here
  // everything is the top) and counts what this top keeps: the double block and the single LU.
  const H2TopKind kind = h2_top_kind(mixed.stats().top_size, mixed.stats().single_panels && 3 * n > fo.top_size, fo.single_top_from, fo.spread_top, 1);
  EXPECT_EQ(kind, H2TopKind::Mixed);
  const double model = h2_top_bytes(kind, mixed.stats().top_size, MachineLimits{});
  EXPECT_GE(model, static_cast<double>(mixed.stats().top_bytes));
  EXPECT_LE(model, 1.1 * static_cast<double>(mixed.stats().top_bytes));
  const std::vector<double> b = random_vector(3L * n, 3);
  std::vector<double> x1(b.size()), x2(b.size());
  solve_mesh_order(plain, b.data(), x1.data());
  solve_mesh_order(mixed, b.data(), x2.data());
  const double diff = rel(x2, x1);
  std::printf("cardioid, %d unknowns in the top: mixed against double LU %.2e\n", 3 * n, diff);
  EXPECT_LE(diff, 1e-12);
  fo.single_top_from = 3 * n + 1; // one above: double
  EXPECT_FALSE(H2Factorization(cache, sel, fo).stats().top_mixed);
}

TEST(H2FactorTop, SinglePanelsTopIsALinearOperatorInAThirdOfTheMemory)
{
  // Panels in single precision (the default tolerance): a top of single_top_from unknowns or more
  // is factored in single precision alone, n² floats where the mixed LU keeps n² floats and the
  // n² doubles of the block. Its solves run in double arithmetic on the rounded factors, so the
  // preconditioner stays one fixed linear operator: rounding the right-hand side to single
  // precision instead (sgetrs) breaks linearity at ~1e-7, and GMRES then stalls there.
  auto L = load("cardioid_fine.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 1e-8, 32);
  H2FactorCache cache(K);
  const SystemSelection sel = selection(n, random_pattern(n, 0.5, 9));
  H2FactorOptions fo;
  fo.top_size = 0;
  fo.top_when_cheaper = false; // the same levels whatever the top's LU
  fo.single_top_from = 1;
  const H2Factorization single(cache, sel, fo);
  fo.single_top_from = 0;
  const H2Factorization plain(cache, sel, fo);
  ASSERT_TRUE(single.stats().single_panels);
  ASSERT_TRUE(single.stats().top_single);
  EXPECT_FALSE(single.stats().top_mixed);
  EXPECT_FALSE(plain.stats().top_single);
  ASSERT_EQ(single.stats().top_size, plain.stats().top_size);
  ASSERT_GT(single.stats().top_size, 100);
  EXPECT_NEAR(static_cast<double>(single.stats().top_bytes) / plain.stats().top_bytes, 0.5, 0.01);
  // The size model (core/size_limits.hpp, the one model of the top), for the kinds the
  // factorization took: the single top counts what it keeps (its LU, 4 n²); the double top
  // twice what it keeps (its LU, 8 n², and the rows arriving beside the block, which the
  // measured peaks hold: docs/limits.md).
  const H2TopKind single_kind = h2_top_kind(single.stats().top_size, single.stats().single_panels, 1, fo.spread_top, 1);
  const H2TopKind plain_kind = h2_top_kind(plain.stats().top_size, plain.stats().single_panels, 0, fo.spread_top, 1);
  EXPECT_EQ(single_kind, H2TopKind::Single);
  EXPECT_EQ(plain_kind, H2TopKind::Double);
  EXPECT_NEAR(h2_top_bytes(single_kind, single.stats().top_size, MachineLimits{}) / single.stats().top_bytes, 1.0, 0.05);
  EXPECT_NEAR(h2_top_bytes(plain_kind, plain.stats().top_size, MachineLimits{}) / plain.stats().top_bytes, 2.0, 0.05);
  EXPECT_LT(single.top_trial(), fo.rel_tol);
  const std::vector<double> b1 = random_vector(3L * n, 3), b2 = random_vector(3L * n, 4);
  std::vector<double> b3(b1.size()), x1(b1.size()), x2(b1.size()), x3(b1.size()), xp(b1.size()), sum(b1.size());
  for (std::size_t i = 0; i < b1.size(); ++i) b3[i] = b1[i] + 3 * b2[i];
  solve_mesh_order(single, b1.data(), x1.data());
  solve_mesh_order(single, b2.data(), x2.data());
  solve_mesh_order(single, b3.data(), x3.data());
  for (std::size_t i = 0; i < b1.size(); ++i) sum[i] = x1[i] + 3 * x2[i];
  const double nonlinear = rel(x3, sum);
  solve_mesh_order(plain, b1.data(), xp.data());
  const double against_double = rel(x1, xp);
  std::printf("cardioid, top %d: trial %.1e, linearity %.1e, against the double top %.1e\n", single.stats().top_size, single.top_trial(), nonlinear, against_double);
  EXPECT_LT(nonlinear, 1.2e-14);     // measured 3.7e-15: rounding
  EXPECT_LT(against_double, 2.7e-7); // the single LU's error through the steps, measured 8.9e-8
  EXPECT_GT(against_double, 0.0);  // and not the double LU itself
}

TEST(H2FactorOptionsCheck, LeafSizeStartsHigherAndBadOptionsThrow)
{
  auto L = load("sphere_l1.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress(*L, 1e-8, 16);
  H2FactorCache cache(K);
  const SystemSelection sel = selection(n, random_pattern(n, 0.3, 4));
  H2FactorOptions fo;
  fo.rel_tol = 1e-6;
  fo.top_size = 0;
  fo.top_when_cheaper = false;
  fo.leaf_size = 16; // the H² leaves (14-16 nodes)
  const H2Factorization fine(cache, sel, fo);
  fo.leaf_size = 64; // boxes of up to 64 nodes: two levels above the H² leaves
  const H2Factorization coarse(cache, sel, fo);
  ASSERT_FALSE(fine.stats().levels.empty());
  ASSERT_FALSE(coarse.stats().levels.empty());
  const int leaves = K.tree().levels() - 1;
  EXPECT_EQ(fine.stats().levels.front().level, leaves);
  EXPECT_EQ(coarse.stats().levels.front().level, leaves - 2);
  // Leaf size 0: the leaves from tolerance 1e-5 on, their parents below (a leaf's skeleton would
  // keep most of it).
  fo.leaf_size = 0;
  EXPECT_EQ(H2Factorization(cache, sel, fo).stats().levels.front().level, leaves - 1);
  fo.rel_tol = 1e-5;
  EXPECT_EQ(H2Factorization(cache, sel, fo).stats().levels.front().level, leaves);
  fo.rel_tol = 1e-6;
  const std::vector<double> b = random_vector(3L * n, 2);
  std::vector<double> x1(b.size()), x2(b.size());
  solve_mesh_order(fine, b.data(), x1.data());
  solve_mesh_order(coarse, b.data(), x2.data());
  std::printf("leaves of 16 and 64 nodes at 1e-6: solutions differ by %.2e\n", rel(x2, x1));
  EXPECT_LE(rel(x2, x1), 1e-4);
  fo = H2FactorOptions{};
  fo.rel_tol = 0;
  EXPECT_THROW(H2Factorization(cache, sel, fo), std::invalid_argument);
  fo = H2FactorOptions{};
  fo.leaf_size = -1;
  EXPECT_THROW(H2Factorization(cache, sel, fo), std::invalid_argument);
}

} // namespace
