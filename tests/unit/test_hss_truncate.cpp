// Entries-free truncation of an HSS matrix (truncate_hss) against the dense operator.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/hss/hss_compression.hpp"
#include "hssbem/hss/truncate.hpp"
#include "hssbem/hss/ulv.hpp"

#include "hss_test_helpers.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <string>

using namespace hssbem;
using namespace hssbem::test; // dense_k, dense_a, matvec_error, random_pattern, rel, ulv_solve

namespace {

/// A mesh, its operator, the HSS compression of K at the original tolerance and the dense K.
struct Compressed {
  SurfaceMesh mesh;
  std::unique_ptr<Discretization> disc;
  std::unique_ptr<BemOperator> op;
  std::unique_ptr<HssMatrix> K;
  std::vector<double> Kd; ///< row-major 3n × w n, mesh order, rigid-body terms included
  double tol = 0, seconds = 0;
};

/// The compression of a mesh at tol with the given leaf size, made once per test program.
const Compressed &compressed(const std::string &name, int leaf, double tol)
{
  static std::map<std::string, std::unique_ptr<Compressed>> cache;
  auto &slot = cache[name + "/" + std::to_string(leaf) + "/" + std::to_string(tol)];
  if (slot) return *slot;
  slot = std::make_unique<Compressed>();
  Compressed &C = *slot;
  C.mesh = read_mesh(std::string(HSSBEM_MESHES) + "/" + name);
  std::vector<std::string> notices;
  validate_and_orient(C.mesh, notices);
  C.disc = std::make_unique<Discretization>(C.mesh, 40.0);
  C.op = std::make_unique<BemOperator>(*C.disc, Material::from_young(1.0, 0.3));
  HssOptions o;
  o.rel_tol = tol;
  o.leaf_size = leaf;
  const Timer timer;
  C.K = std::make_unique<HssMatrix>(compress_bem_operator_hss(*C.op, o));
  C.seconds = timer.seconds();
  C.tol = tol;
  C.Kd = dense_k(*C.op, 6);
  return C;
}

void print_ranks(const HssMatrix &K, const HssMatrix &T)
{
  const HssStats &a = K.stats(), &b = T.stats();
  for (size_t l = 1; l < a.levels.size(); ++l)
    std::printf("  level %zu (%3d clusters): row rank max %3d -> %3d mean %5.1f -> %5.1f, col rank max %3d -> %3d mean %5.1f -> %5.1f\n", l,
                a.levels[l].clusters, a.levels[l].max_row_rank, b.levels[l].max_row_rank, a.levels[l].mean_row_rank, b.levels[l].mean_row_rank,
                a.levels[l].max_col_rank, b.levels[l].max_col_rank, a.levels[l].mean_col_rank, b.levels[l].mean_col_rank);
}

TEST(Truncation, MatvecMatchesDenseOperatorWithSmallerRanks)
{
  const Compressed &C = compressed("cardioid_832.msh", 32, 1e-8);
  const double e0 = matvec_error(*C.K, C.Kd, 7);
  for (double tol : {1e-3, 1e-5}) {
    const Timer timer;
    const HssMatrix T = truncate_hss(*C.K, tol);
    const double tt = timer.seconds(), err = matvec_error(T, C.Kd, 7);
    std::printf("cardioid, leaf 32: tol 1e-8 -> %.0e: error %.2e -> %.2e, memory %.2f -> %.2f MB, compress %.2f s, truncate %.2f s\n", tol, e0,
                err, C.K->stats().memory_bytes / 1e6, T.stats().memory_bytes / 1e6, C.seconds, tt);
    print_ranks(*C.K, T);
    EXPECT_LE(err, 10 * tol);
    EXPECT_GT(err, 10 * e0); // it did truncate: the error grew well beyond the original's
    for (int l = 1; l <= 2; ++l) {
      EXPECT_LT(T.stats().levels[l].max_row_rank, C.K->stats().levels[l].max_row_rank) << "level " << l;
      EXPECT_LT(T.stats().levels[l].max_col_rank, C.K->stats().levels[l].max_col_rank) << "level " << l;
    }
    EXPECT_LT(T.stats().memory_bytes, C.K->stats().memory_bytes);
    EXPECT_EQ(T.stats().entries_evaluated, C.K->stats().entries_evaluated); // kept: how the original was built
  }
}

TEST(Truncation, SameToleranceKeepsTheOriginalAccuracy)
{
  const Compressed &C = compressed("sphere_l0.msh", 16, 1e-8);
  const HssMatrix T = truncate_hss(*C.K, 1e-8);
  const double e0 = matvec_error(*C.K, C.Kd, 3), err = matvec_error(T, C.Kd, 3);
  std::printf("sphere_l0, leaf 16: tol 1e-8 -> 1e-8: error %.2e -> %.2e\n", e0, err);
  print_ranks(*C.K, T);
  EXPECT_LE(err, 10 * 1e-8);
  EXPECT_LE(T.stats().max_row_rank(), C.K->stats().max_row_rank());
  EXPECT_LE(T.stats().max_col_rank(), C.K->stats().max_col_rank());
}

TEST(Truncation, UlvOfTruncatedMatrixMatchesDenseSolve)
{
  const Compressed &C = compressed("sphere_l0.msh", 16, 1e-8);
  const int n = C.op->num_nodes();
  const auto known = random_pattern(n, 0.5, 3);
  std::mt19937 gen(5);
  std::normal_distribution<double> N01;
  std::vector<double> b(3L * n);
  for (double &v : b) v = N01(gen);
  auto A = dense_a(C.Kd, n, 6, known);
  std::vector<double> xd(b);
  ASSERT_EQ(lapack::gesv(3 * n, 1, A.data(), xd.data()), 0);
  for (double tol : {1e-3, 1e-5}) {
    const HssMatrix T = truncate_hss(*C.K, tol);
    const UlvFactorization F(T, known);
    const double err = rel(ulv_solve(T, F, b), xd);
    std::printf("sphere_l0 truncated to %.0e: solve difference %.2e\n", tol, err);
    EXPECT_LE(err, 100 * tol);
  }
}

int total_forced(const HssMatrix &K)
{
  int f = 0;
  for (int c = 0; c < K.tree().num_clusters(); ++c) f += K.cluster(c).row_forced + K.cluster(c).col_forced;
  return f;
}

TEST(Truncation, RigidBodyEntriesSurvive)
{
  const Compressed &C = compressed("cube_l0.msh", 16, 1e-6);
  ASSERT_GT(total_forced(*C.K), 0); // double nodes at the edges: rigid-body terms cross clusters
  const double tol = 1e-3;
  const HssMatrix T = truncate_hss(*C.K, tol);
  for (int c = 1; c < T.tree().num_clusters(); ++c) {
    const HssCluster &a = C.K->cluster(c), &b = T.cluster(c);
    ASSERT_EQ(b.row_forced, a.row_forced);
    ASSERT_EQ(b.col_forced, a.col_forced);
    EXPECT_TRUE(std::equal(a.row_skel.begin(), a.row_skel.begin() + a.row_forced, b.row_skel.begin())) << "cluster " << c;
    EXPECT_TRUE(std::equal(a.col_skel.begin(), a.col_skel.begin() + a.col_forced, b.col_skel.begin())) << "cluster " << c;
  }
  const double e0 = matvec_error(*C.K, C.Kd, 9), err = matvec_error(T, C.Kd, 9);
  std::printf("cube_l0, %d forced entries, 1e-6 -> %.0e: error %.2e -> %.2e, max row rank %d -> %d\n", total_forced(*C.K), tol, e0, err,
              C.K->stats().max_row_rank(), T.stats().max_row_rank());
  EXPECT_LE(err, 10 * tol);
  EXPECT_GT(err, 10 * e0);
}

TEST(Truncation, SkeletonsRespectTheRankCap)
{
  const Compressed &C = compressed("cube_l0.msh", 16, 1e-6);
  const int cap = 12;
  const HssMatrix T = truncate_hss(*C.K, 1e-6, cap);
  for (int c = 1; c < T.tree().num_clusters(); ++c) {
    const HssCluster &h = T.cluster(c);
    EXPECT_LE(static_cast<int>(h.row_skel.size()), std::max(cap, h.row_forced)) << "cluster " << c;
    EXPECT_LE(static_cast<int>(h.col_skel.size()), std::max(cap, h.col_forced)) << "cluster " << c;
    EXPECT_EQ(h.U.n, static_cast<int>(h.row_skel.size()));
    EXPECT_EQ(h.V.n, static_cast<int>(h.col_skel.size()));
  }
  EXPECT_GT(C.K->stats().max_row_rank(), 2 * cap); // the cap binds
  const double err = matvec_error(T, C.Kd, 2);
  std::printf("cube_l0, rank cap %d: max row rank %d -> %d, error %.2e\n", cap, C.K->stats().max_row_rank(), T.stats().max_row_rank(), err);
  EXPECT_TRUE(std::isfinite(err));
  EXPECT_LT(err, 1.0);
}

TEST(Truncation, RejectsBadArguments)
{
  const HssMatrix K(ClusterTree(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, ClusterTreeOptions{1}), 3, 6);
  EXPECT_THROW(truncate_hss(K, 0.0), std::invalid_argument);
  EXPECT_THROW(truncate_hss(K, 1.0), std::invalid_argument);
  EXPECT_THROW(truncate_hss(K, 1e-3, 0), std::invalid_argument);
}

} // namespace
