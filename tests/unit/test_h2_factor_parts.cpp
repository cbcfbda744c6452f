// The H² factorization with its tree's parts eliminated separately (H2FactorOptions::
// within_parts: the distributed factorization's rule, simulated on one rank) against dense LU of
// the same system, and the structure that makes it distributable: no step reaches two parts,
// cross blocks exist where the parts meet, and the levels still eliminate most unknowns.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/node_partition.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"
#include "hss_test_helpers.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

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

std::unique_ptr<Loaded> load(const std::string &name)
{
  auto L = std::make_unique<Loaded>();
  L->mesh = read_mesh(std::string(HSSBEM_MESHES) + "/" + name);
  std::vector<std::string> notices;
  validate_and_orient(L->mesh, notices);
  L->disc = std::make_unique<Discretization>(L->mesh, 40.0);
  L->op = std::make_unique<BemOperator>(*L->disc, Material::from_young(1.0, 0.3));
  return L;
}

/// The H² matrix on a tree whose top levels are `parts` METIS parts (one rank holds it all).
H2Matrix compress_parts(const Loaded &L, double rel_tol, int leaf, int parts)
{
  H2Options o;
  o.rel_tol = rel_tol;
  o.leaf_size = leaf;
  o.single_precision = false;
  return compress_bem_operator_h2(*L.op, o, partition_nodes(*L.disc, parts), SerialComm());
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

std::vector<double> dense_solve(std::vector<double> A, std::vector<double> b)
{
  const int N = static_cast<int>(b.size());
  std::vector<int> piv(N);
  EXPECT_EQ(lapack::getrf(N, A.data(), N, piv.data()), 0);
  lapack::getrs('N', N, 1, A.data(), N, piv.data(), b.data(), N);
  return b;
}

/// The factorization's structure with parts: none of its steps reaches two parts, the first
/// level has cross blocks, and the levels eliminate at least `min_eliminated` of the unknowns.
void expect_parts_structure(const H2Factorization &F, int parts, int n, double min_eliminated)
{
  const H2FactorStats &st = F.stats();
  EXPECT_EQ(st.parts, parts);
  EXPECT_EQ(F.steps_crossing_parts(), 0);
  ASSERT_FALSE(st.levels.empty());
  EXPECT_GT(st.levels.front().cross_blocks, 0);
  EXPECT_GT(st.levels.front().cross_bytes, 0u);
  long long eliminated = 0;
  for (const H2FactorLevelStats &l : st.levels) {
    std::printf("  level %d: %d boxes, candidates %.0f, rank %.0f (max %d), %lld eliminated, %lld cross blocks (%.2f MB)\n", l.level, l.boxes, l.mean_candidates, l.mean_rank,
                l.max_rank, l.eliminated, l.cross_blocks, l.cross_bytes / 1e6);
    eliminated += l.eliminated;
  }
  std::printf("  top %d of %d unknowns\n", st.top_size, 3 * n);
  EXPECT_EQ(eliminated + st.top_size, 3LL * n);
  EXPECT_GE(eliminated, min_eliminated * 3 * n);
}

struct Case {
  const char *mesh;
  double tol;
  int leaf;
  int parts;
  double min_eliminated;
};

void PrintTo(const Case &c, std::ostream *os) { *os << case_name(c.mesh, c.tol, c.leaf) << "_parts" << c.parts; }

class H2FactorParts : public ::testing::TestWithParam<Case> {};

TEST_P(H2FactorParts, SolveMatchesDenseLU)
{
  const Case c = GetParam();
  auto L = load(c.mesh);
  const int n = L->op->num_nodes();
  const H2Matrix K = compress_parts(*L, c.tol / 100, c.leaf, c.parts);
  ASSERT_EQ(K.tree().num_parts(), c.parts);
  const auto known = random_pattern(n, 0.4, 17);
  const SystemSelection sel = selection(n, known);
  H2FactorCache cache(K);
  H2FactorOptions fo;
  fo.rel_tol = c.tol;
  fo.top_size = 0;
  fo.top_when_cheaper = false;
  fo.leaf_size = c.leaf;
  fo.within_parts = true;
  const H2Factorization F(cache, sel, fo);
  const std::vector<double> b = random_vector(3L * n, 5);
  std::vector<double> x(b.size());
  solve_mesh_order(F, b.data(), x.data());
  const double err = rel(x, dense_solve(dense_a(dense_k(*L->op, 6), n, 6, known), b));
  std::printf("%s, %d parts, tol %.0e: error vs dense LU %.2e\n", c.mesh, c.parts, c.tol, err);
  expect_parts_structure(F, c.parts, n, c.min_eliminated);
  EXPECT_LE(err, 3 * c.tol); // measured up to 1.56 tol (cardioid_fine, 1e-3, 2 parts)
}

INSTANTIATE_TEST_SUITE_P(Meshes, H2FactorParts,
                         // eliminated below the top, measured: 0.69, 0.46, 0.47, 0.14, 0.75, 0.17, 0.23; 0.53, 0.04, 0.34, 0.31, 0.62, 0.30
                         ::testing::Values(Case{"sphere_l1.msh", 1e-3, 16, 2, 0.5}, Case{"sphere_l1.msh", 1e-6, 16, 2, 0.35}, Case{"sphere_l1.msh", 1e-3, 16, 4, 0.35},
                                           Case{"sphere_l1.msh", 1e-6, 16, 4, 0.1}, Case{"cardioid_fine.msh", 1e-3, 32, 2, 0.55}, Case{"cube_l1.msh", 1e-6, 16, 2, 0.12},
                                           Case{"cube_l1.msh", 1e-3, 16, 4, 0.15},
                                           // part counts that are no power of two: the parts' roots lie on two levels
                                           Case{"sphere_l1.msh", 1e-3, 16, 3, 0.3}, Case{"sphere_l1.msh", 1e-6, 16, 5, 0.03}, Case{"sphere_l1.msh", 1e-3, 16, 6, 0.2},
                                           Case{"sphere_l1.msh", 1e-3, 16, 7, 0.2}, Case{"cardioid_fine.msh", 1e-3, 32, 3, 0.3}, Case{"cube_l1.msh", 1e-3, 16, 3, 0.1}),
                         [](const ::testing::TestParamInfo<Case> &info) { return case_name(info.param.mesh, info.param.tol, info.param.leaf) + "_parts" + std::to_string(info.param.parts); });

TEST(H2FactorParts, WithoutTheRuleStepsCrossParts)
{
  // The same partitioned tree factored as one part: boxes at the parts' boundary eliminate into
  // their neighbours of the other part (what the check above rules out).
  auto L = load("sphere_l1.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress_parts(*L, 1e-5, 16, 2);
  H2FactorCache cache(K);
  H2FactorOptions fo;
  fo.rel_tol = 1e-3;
  fo.top_size = 0;
  fo.top_when_cheaper = false;
  const H2Factorization F(cache, selection(n, random_pattern(n, 0.4, 17)), fo);
  EXPECT_EQ(F.stats().parts, 1);
  EXPECT_GT(F.steps_crossing_parts(), 0);
  EXPECT_EQ(F.stats().levels.front().cross_blocks, 0);
}

TEST(H2FactorParts, PureTractionRegularisedMatchesDense)
{
  auto L = load("sphere_l1.msh");
  const int n = L->op->num_nodes();
  const H2Matrix K = compress_parts(*L, 1e-6, 16, 2);
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
  for (const double tol : {1e-3}) {
    H2FactorOptions fo;
    fo.rel_tol = tol;
    fo.top_size = 0;
    fo.top_when_cheaper = false;
    fo.within_parts = true;
    const H2Factorization F(cache, selection(n, known), fo, &modes);
    std::vector<double> x(N);
    solve_mesh_order(F, b.data(), x.data());
    const double err = rel(x, xd);
    std::printf("pure traction, 2 parts, tol %.0e: error %.2e\n", tol, err);
    expect_parts_structure(F, 2, n, 0.5); // measured 0.78
    EXPECT_LE(err, 3 * tol); // measured 0.95 tol
  }
}

} // namespace
