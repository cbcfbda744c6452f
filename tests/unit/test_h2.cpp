// H² engine: strong-admissibility block partition and compression of K = [H, G] against the
// dense operator.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/compress/compression.hpp"
#include "hssbem/core/dense_ops.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hss_test_helpers.hpp"
#include "test_shapes.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

using namespace hssbem;
using namespace hssbem::test; // dense_k, matvec_error, rel

namespace {

struct Loaded {
  SurfaceMesh mesh;
  std::unique_ptr<Discretization> disc;
  std::unique_ptr<BemOperator> op;
};

std::unique_ptr<Loaded> load(SurfaceMesh mesh)
{
  auto L = std::make_unique<Loaded>();
  L->mesh = std::move(mesh);
  std::vector<std::string> notices;
  validate_and_orient(L->mesh, notices);
  L->disc = std::make_unique<Discretization>(L->mesh, 40.0);
  L->op = std::make_unique<BemOperator>(*L->disc, Material::from_young(1.0, 0.3));
  return L;
}

std::unique_ptr<Loaded> load(const std::string &name) { return load(read_mesh(std::string(HSSBEM_MESHES) + "/" + name)); }

/// 1/|x − y| between m points in the unit cube and n points in the cube shifted by `gap` along
/// x: a smooth block of numerically low rank.
DenseMatrix smooth_block(int m, int n, double gap, std::mt19937 &gen)
{
  std::uniform_real_distribution<double> U01;
  std::vector<Vec3> x(m), y(n);
  for (Vec3 &p : x) p = {U01(gen), U01(gen), U01(gen)};
  for (Vec3 &p : y) p = {gap + U01(gen), U01(gen), U01(gen)};
  DenseMatrix A(m, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < m; ++i) A(i, j) = 1.0 / norm(x[i] - y[j]);
  return A;
}

void print_stats(const H2Matrix &K)
{
  const H2Stats &st = K.stats();
  std::printf("  memory %.1f MB (bases %.1f, far %.1f, near %.1f), %ld far and %ld near blocks, entries %.3g\n", st.memory_bytes / 1e6, st.basis_bytes / 1e6,
              st.far_bytes / 1e6, st.near_bytes / 1e6, st.far_blocks, st.near_blocks, double(st.entries_evaluated));
  for (size_t l = 0; l < st.levels.size(); ++l)
    std::printf("  level %zu: %d bases, row rank max %d mean %.0f, col rank max %d mean %.0f, %ld far blocks\n", l, st.levels[l].clusters,
                st.levels[l].max_row_rank, st.levels[l].mean_row_rank, st.levels[l].max_col_rank, st.levels[l].mean_col_rank, st.levels[l].far_blocks);
}

TEST(H2Partition, EveryEntryInExactlyOneBlockAndSymmetric)
{
  auto L = load("sphere_l1.msh");
  const ClusterTree tree(collocation_points(*L->disc), ClusterTreeOptions{16});
  std::vector<double> radius(tree.num_clusters());
  for (int c = 0; c < tree.num_clusters(); ++c) radius[c] = tree.cluster(c).radius;
  const BlockPartition p = strong_block_partition(tree, radius, 0.5);
  const int n = tree.num_points();
  std::vector<int> cover(static_cast<size_t>(n) * n, 0);
  long far = 0, near = 0;
  for (int a = 0; a < tree.num_clusters(); ++a) {
    const Cluster &ca = tree.cluster(a);
    for (int b : p.far[a]) {
      const Cluster &cb = tree.cluster(b);
      EXPECT_TRUE(tree.admissible(a, b, 0.5)); // the tree's own test, with the same radii
      EXPECT_TRUE(p.is_far(b, a));
      for (int i = ca.begin; i < ca.end; ++i)
        for (int j = cb.begin; j < cb.end; ++j) ++cover[static_cast<size_t>(i) * n + j];
      ++far;
    }
    for (int b : p.near[a]) {
      const Cluster &cb = tree.cluster(b);
      EXPECT_TRUE(tree.is_leaf(a) && tree.is_leaf(b));
      EXPECT_TRUE(p.is_close(b, a));
      for (int i = ca.begin; i < ca.end; ++i)
        for (int j = cb.begin; j < cb.end; ++j) ++cover[static_cast<size_t>(i) * n + j];
      ++near;
    }
  }
  for (int v : cover) ASSERT_EQ(v, 1);
  std::printf("%d clusters: %ld far blocks, %ld near blocks\n", tree.num_clusters(), far, near);
  EXPECT_GT(far, 4 * near / 10); // strong admissibility leaves most of the matrix to far blocks
  EXPECT_FALSE(p.has_far[0]);
  EXPECT_THROW(strong_block_partition(tree, radius, -1), std::invalid_argument);
}

struct Case {
  const char *mesh;
  double tol;
  int leaf;
  double eta;
};

class H2Accuracy : public ::testing::TestWithParam<Case> {};

TEST_P(H2Accuracy, MatvecMatchesDenseOperator)
{
  const Case c = GetParam();
  auto L = load(c.mesh);
  H2Options o;
  o.rel_tol = c.tol;
  o.leaf_size = c.leaf;
  o.eta = c.eta;
  o.single_precision = false;
  o.pressure_columns = true;
  H2Matrix K = compress_bem_operator_h2(*L->op, o);
  const auto Kd = dense_k(*L->op, K.col_block());
  const double err = matvec_error(K, Kd, 7);
  std::printf("%s tol %.0e leaf %d eta %.2f: error %.2e\n", c.mesh, c.tol, c.leaf, c.eta, err);
  print_stats(K);
  EXPECT_LE(err, 10 * c.tol);
  // Not a dense matrix in disguise: the far blocks carry a real part of K. (On meshes this small
  // the leaves' ranks are full, so it saves no memory; benchmarks/ measures that on large ones.)
  EXPECT_GT(K.stats().far_blocks, 0);
  for (int a = 0; a < K.tree().num_clusters(); ++a)
    for (H2Block &B : K.far_blocks(a)) B.clear();
  const double err_near = matvec_error(K, Kd, 7);
  std::printf("  without the far blocks: error %.2e\n", err_near);
  EXPECT_GT(err_near, 10 * c.tol); // so the bound above would fail without them
}

INSTANTIATE_TEST_SUITE_P(Meshes, H2Accuracy,
                         ::testing::Values(Case{"sphere_l1.msh", 1e-3, 16, 0.0}, Case{"sphere_l1.msh", 1e-6, 16, 0.0}, Case{"sphere_l1.msh", 1e-9, 16, 0.0},
                                           Case{"sphere_l1.msh", 1e-6, 32, 0.5}, Case{"cardioid_832.msh", 1e-3, 16, 0.0},
                                           Case{"cardioid_832.msh", 1e-6, 16, 0.0}, Case{"cardioid_832.msh", 1e-9, 16, 0.0}));

TEST(H2Accuracy, FarBlocksCarryWhatNearBlocksMiss)
{
  // Dropping the far blocks must be visibly wrong, so the accuracy test above cannot pass by
  // storing near blocks only.
  auto L = load("sphere_l1.msh");
  H2Options o;
  o.rel_tol = 1e-6, o.single_precision = false; // a tighter tolerance than the driver's, in double
  o.leaf_size = 32;
  H2Matrix K = compress_bem_operator_h2(*L->op, o);
  const auto Kd = dense_k(*L->op, K.col_block());
  const double err = matvec_error(K, Kd, 3);
  for (int c = 0; c < K.tree().num_clusters(); ++c)
    for (H2Block &B : K.far_blocks(c)) B.clear();
  const double err_near = matvec_error(K, Kd, 3);
  std::printf("error %.2e, without far blocks %.2e\n", err, err_near);
  EXPECT_LE(err, 1e-5);
  EXPECT_GT(err_near, 1e-3);
}

TEST(H2Accuracy, SinglePrecisionBlocksHalveTheMemory)
{
  auto L = load("sphere_l1.msh");
  H2Options o;
  o.rel_tol = 1e-6, o.single_precision = false; // a tighter tolerance than the driver's, in double
  o.leaf_size = 16;
  o.eta = 0;
  const H2Matrix Kd = compress_bem_operator_h2(*L->op, o);
  o.single_precision = true;
  o.low_rank_far = false; // the precision alone
  const H2Matrix Ks = compress_bem_operator_h2(*L->op, o);
  const auto dense = dense_k(*L->op, Kd.col_block());
  const double ed = matvec_error(Kd, dense, 4), es = matvec_error(Ks, dense, 4);
  const double blocks_d = Kd.stats().far_bytes + Kd.stats().near_bytes, blocks_s = Ks.stats().far_bytes + Ks.stats().near_bytes;
  std::printf("double: error %.2e, blocks %.1f MB; single: error %.2e, blocks %.1f MB\n", ed, blocks_d / 1e6, es, blocks_s / 1e6);
  EXPECT_LE(es, 1e-5); // 10·tol
  EXPECT_GT(es, ed);   // the blocks really are rounded
  EXPECT_NEAR(blocks_s / blocks_d, 0.5, 0.02);
}

TEST(H2Accuracy, LowRankSinglePrecisionBlocksKeepTheTolerance)
{
  // The default storage (single precision, far and near blocks in low-rank form, the near ones
  // truncated against their leaf's own block) stays within 10·tol of dense K, takes no more
  // than the dense single-precision blocks (less at a loose tolerance), and does hold low-rank
  // near blocks.
  auto L = load("cardioid_832.msh");
  const auto dense = dense_k(*L->op, 7);
  for (const double tol : {1e-3, 1e-5}) {
    H2Options o;
    o.rel_tol = tol;
    o.leaf_size = 16;
    o.pressure_columns = true;
    o.single_precision = true;
    const H2Matrix K = compress_bem_operator_h2(*L->op, o);
    o.low_rank_far = o.low_rank_near = false;
    const H2Matrix Ks = compress_bem_operator_h2(*L->op, o);
    long low_rank_near = 0;
    for (int c : K.tree().leaves())
      for (const H2Block &B : K.near_blocks(c)) low_rank_near += B.is_low_rank() && B.rank < std::min(B.M.m, B.M.n);
    const double e = matvec_error(K, dense, 7), es = matvec_error(Ks, dense, 7);
    const double blocks = K.stats().far_bytes + K.stats().near_bytes, blocks_s = Ks.stats().far_bytes + Ks.stats().near_bytes;
    std::printf("tol %.0e: error %.2e (dense single blocks %.2e), blocks %.2f MB against %.2f MB, %ld low-rank near blocks\n", tol, e, es, blocks / 1e6,
                blocks_s / 1e6, low_rank_near);
    EXPECT_LE(e, 10 * tol);
    EXPECT_LE(blocks, blocks_s); // a block takes the low-rank form only where it saves memory
    if (tol >= 1e-3) EXPECT_LT(blocks, 0.85 * blocks_s); // at 1e-5 this mesh is too small to save much (3 %)
    EXPECT_GT(low_rank_near, 0);
  }
}

TEST(H2Block, SingleBlockProductWidensEachEntry)
{
  // The one-column product of a single-precision block (its own kernel) against the widened
  // entries times x in double, for widths that do and do not fill its four-column steps.
  std::mt19937 gen(8);
  std::normal_distribution<double> N01;
  for (const int n : {1, 4, 7, 53}) {
    H2Block B;
    B.col_cluster = 0;
    B.M = DenseMatrix(37, n);
    for (double &v : B.M.a) v = N01(gen);
    B.demote();
    ASSERT_TRUE(B.is_single());
    for (const int nrhs : {1, 3}) {
      std::vector<double> X(static_cast<std::size_t>(n) * nrhs), Y(37L * nrhs, 1.0), Yref(Y), buf;
      for (double &v : X) v = N01(gen);
      B.multiply_add(X.data(), n, Y.data(), 37, nrhs, buf);
      for (int k = 0; k < nrhs; ++k)
        for (int i = 0; i < 37; ++i)
          for (int j = 0; j < n; ++j) Yref[i + 37L * k] += B.entry(i, j) * X[j + static_cast<std::size_t>(n) * k];
      EXPECT_LE(rel(Y, Yref), 1e-14) << n << " columns, " << nrhs << " right-hand sides";
      EXPECT_GT(rel(Y, std::vector<double>(Y.size(), 1.0)), 0.1); // the product did add something
    }
  }
}

TEST(H2Block, LowRankBlockMatchesItsEntries)
{
  // A smooth block (1/|x − y| between separated clouds) stored in low-rank form: its entries are
  // within the requested tolerance of the true ones, products with 1 and 3 columns match the
  // expanded entries, data() expands them, it takes less memory than single precision, and a
  // block that does not pay stays dense.
  std::mt19937 gen(9);
  std::normal_distribution<double> N01;
  for (const auto [m, n] : {std::pair{60, 90}, std::pair{90, 60}}) {
    H2Block B;
    B.M = smooth_block(m, n, 3, gen);
    const DenseMatrix ref = B.M;
    B.compress(1e-6);
    ASSERT_TRUE(B.is_low_rank());
    EXPECT_LT(B.bytes(), 4.0 * m * n);
    double e = 0, s = 0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < m; ++i) e += std::pow(B.entry(i, j) - ref(i, j), 2), s += ref(i, j) * ref(i, j);
    EXPECT_LE(std::sqrt(e / s), 1e-5);
    std::vector<double> buf;
    const double *full = B.data(buf);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < m; ++i) ASSERT_NEAR(full[i + static_cast<std::size_t>(j) * m], B.entry(i, j), 1e-12);
    for (const int nrhs : {1, 3}) {
      std::vector<double> X(static_cast<std::size_t>(n) * nrhs), Y(static_cast<std::size_t>(m) * nrhs, 1.0), Yref(Y);
      for (double &v : X) v = N01(gen);
      B.multiply_add(X.data(), n, Y.data(), m, nrhs, buf);
      for (int k = 0; k < nrhs; ++k)
        for (int i = 0; i < m; ++i)
          for (int j = 0; j < n; ++j) Yref[i + static_cast<std::size_t>(m) * k] += B.entry(i, j) * X[j + static_cast<std::size_t>(n) * k];
      EXPECT_LE(rel(Y, Yref), 1e-12) << nrhs << " right-hand sides";
    }
    EXPECT_THROW(B.add(0, 0, 1.0), std::logic_error);
    B.clear();
    EXPECT_EQ(B.entry(3, 4), 0.0);
  }
  H2Block R;
  R.M = DenseMatrix(20, 20);
  for (double &v : R.M.a) v = N01(gen); // full rank: stays dense, in single precision
  R.compress(1e-6);
  EXPECT_FALSE(R.is_low_rank());
  EXPECT_TRUE(R.is_single());
}

TEST(H2Block, InterpolativeFormStoresNoUnitRows)
{
  // The low-rank form keeps the skeleton side's true entries and only the redundant rows of the
  // interpolation matrix: rank·(m + n − rank) floats and one slot per position of the other
  // side. Both orientations (a column ID when n ≤ m, a row ID otherwise).
  std::mt19937 gen(12);
  for (const auto [m, n] : {std::pair{80, 50}, std::pair{50, 80}}) {
    H2Block B;
    B.M = smooth_block(m, n, 2.5, gen);
    const DenseMatrix ref = B.M;
    B.compress(1e-7);
    ASSERT_TRUE(B.is_low_rank());
    const int k = B.rank, other = n <= m ? n : m;
    EXPECT_EQ(B.lr_rows, n > m);
    EXPECT_GT(k, 5);             // a real decomposition, not a tiny one
    EXPECT_LT(k, std::min(m, n)); // and it did compress
    EXPECT_EQ(B.bytes(), sizeof(float) * static_cast<std::size_t>(k) * (m + n - k) + sizeof(std::int16_t) * static_cast<std::size_t>(other));
    // the skeleton side holds true entries (rounded to float)
    int skeletons = 0;
    for (int p = 0; p < other; ++p) {
      if (B.lr_slot[p] < 0) continue;
      ++skeletons;
      for (int q = 0; q < (n <= m ? m : n); ++q) {
        const int i = n <= m ? q : p, j = n <= m ? p : q;
        ASSERT_EQ(B.entry(i, j), static_cast<double>(static_cast<float>(ref(i, j))));
      }
    }
    EXPECT_EQ(skeletons, k);
  }
}

TEST(H2Block, ScaleFloorTruncatesAgainstAReferenceNorm)
{
  // compress(rel_tol, row_scale, col_scale): pivots below rel_tol·scale are dropped even where
  // the block alone would keep them, so a block that is weak against the reference keeps a lower
  // rank (within rel_tol·scale of its entries), and one entirely below it keeps rank 0.
  std::mt19937 gen(13);
  for (const auto [m, n] : {std::pair{70, 40}, std::pair{40, 70}}) {
    const DenseMatrix A = smooth_block(m, n, 2, gen);
    const bool by_cols = n <= m;
    const double p1 = by_cols ? dense::largest_col_norm(A) : dense::largest_row_norm(A);
    const auto compressed = [&](double scale) {
      H2Block B;
      B.M = A;
      B.compress(1e-8, by_cols ? 0.0 : scale, by_cols ? scale : 0.0);
      return B;
    };
    const H2Block own = compressed(0), floored = compressed(1e3 * p1), wrong_side = [&] {
      H2Block B;
      B.M = A;
      B.compress(1e-8, by_cols ? 1e3 * p1 : 0.0, by_cols ? 0.0 : 1e3 * p1); // the other side's scale is not used
      return B;
    }();
    ASSERT_TRUE(own.is_low_rank() && floored.is_low_rank() && wrong_side.is_low_rank());
    EXPECT_EQ(wrong_side.rank, own.rank);
    EXPECT_LT(floored.rank, own.rank - 3);
    EXPECT_GT(floored.rank, 0);
    const auto max_error = [&](const H2Block &B) {
      double e = 0;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < m; ++i) e = std::max(e, std::abs(B.entry(i, j) - A(i, j)));
      return e;
    };
    const double err = max_error(floored);
    EXPECT_LE(err, 1e-8 * 1e3 * p1 * std::sqrt(double(std::min(m, n)))) << "rank " << floored.rank;
    EXPECT_GT(err, 10 * max_error(own)); // it did drop what the block alone would have kept
    const H2Block gone = compressed(1e9 * p1);
    EXPECT_EQ(gone.rank, 0);
    EXPECT_EQ(gone.entry(m - 1, n - 1), 0.0);
    std::vector<double> X(n, 1.0), Y(m, 2.0), buf;
    gone.multiply_add(X.data(), n, Y.data(), m, 1, buf);
    EXPECT_EQ(Y, std::vector<double>(m, 2.0));
    EXPECT_LT(gone.bytes(), sizeof(float) * 8);
  }
}

TEST(H2Block, TransposedProductInEveryForm)
{
  // X += Bᵀ Y for a block dense in double, dense in single and of low rank, with 1 and 3
  // right-hand sides, against the block's (stored) entries.
  std::mt19937 gen(10);
  std::normal_distribution<double> N01;
  const int m = 45, n = 70;
  const DenseMatrix A = smooth_block(m, n, 3, gen);
  for (int form = 0; form < 3; ++form) {
    H2Block B;
    B.M = A;
    if (form == 1) B.demote();
    if (form == 2) B.compress(1e-6);
    ASSERT_EQ(B.is_single(), form == 1);
    ASSERT_EQ(B.is_low_rank(), form == 2);
    for (const int nrhs : {1, 3}) {
      std::vector<double> Y(static_cast<std::size_t>(m) * nrhs), X(static_cast<std::size_t>(n) * nrhs, 1.0), Xref(X), buf;
      for (double &v : Y) v = N01(gen);
      B.multiply_add_transposed(Y.data(), m, X.data(), n, nrhs, buf);
      for (int k = 0; k < nrhs; ++k)
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < m; ++i) Xref[j + static_cast<std::size_t>(n) * k] += B.entry(i, j) * Y[i + static_cast<std::size_t>(m) * k];
      EXPECT_LE(rel(X, Xref), 1e-12) << "form " << form << ", " << nrhs << " right-hand sides";
      EXPECT_GT(rel(X, std::vector<double>(X.size(), 1.0)), 0.1); // the product did add something
    }
  }
}

TEST(H2Matrix, BasisAccessorGivesTheBasesTheProductUses)
{
  // basis(c) rebuilds U and V in double (candidates × skeleton, interpolative form) from the
  // stored form; a product written with them alone, level by level, equals apply().
  auto L = load("sphere_l1.msh");
  for (const bool single : {false, true}) {
    H2Options o;
    o.rel_tol = 1e-6;
    o.leaf_size = 16;
    o.single_precision = single;
    const H2Matrix K = compress_bem_operator_h2(*L->op, o);
    const ClusterTree &tree = K.tree();
    const int nc = tree.num_clusters();
    std::vector<NestedBasis> B(nc);
    for (int c = 0; c < nc; ++c) B[c] = K.basis(c);
    for (int c = 0; c < nc; ++c) {
      if (!K.partition().has_far[c]) continue;
      EXPECT_EQ(B[c].row_skel, K.row_skeleton(c));
      EXPECT_EQ(B[c].col_skel, K.col_skeleton(c));
      const std::vector<int> rows = basis_candidates(tree, B, c, 3, true), cols = basis_candidates(tree, B, c, K.col_block(), false);
      ASSERT_EQ(B[c].U.m, static_cast<int>(rows.size()));
      ASSERT_EQ(B[c].U.n, static_cast<int>(B[c].row_skel.size()));
      ASSERT_EQ(B[c].V.m, static_cast<int>(cols.size()));
      for (int t = 0; t < B[c].U.n; ++t) {
        const int p = static_cast<int>(std::find(rows.begin(), rows.end(), B[c].row_skel[t]) - rows.begin());
        for (int u = 0; u < B[c].U.n; ++u) EXPECT_EQ(B[c].U(p, u), t == u ? 1.0 : 0.0);
      }
    }
    // y = K x from the double bases and the blocks' entries.
    const int n = tree.num_points(), w = K.col_block();
    std::mt19937 gen(3);
    std::normal_distribution<double> N01;
    std::vector<double> x(static_cast<std::size_t>(w) * n), y(3L * n), yref(3L * n, 0.0);
    for (double &v : x) v = N01(gen);
    K.apply(x.data(), w * n, y.data(), 3 * n);
    std::vector<std::vector<double>> xh(nc), yh(nc);
    for (int l = tree.levels() - 1; l >= 1; --l)
      for (int c : tree.clusters_at_level(l)) {
        if (!K.partition().has_far[c]) continue;
        const std::vector<int> cols = basis_candidates(tree, B, c, w, false);
        const Cluster &cl = tree.cluster(c);
        std::vector<double> xc(cols.size());
        for (std::size_t p = 0; p < cols.size(); ++p) {
          if (cl.left < 0) xc[p] = x[cols[p]];
          else {
            const int na = static_cast<int>(B[cl.left].col_skel.size());
            xc[p] = static_cast<int>(p) < na ? xh[cl.left][p] : xh[cl.right][p - na];
          }
        }
        xh[c].assign(B[c].V.n, 0.0);
        for (int t = 0; t < B[c].V.n; ++t)
          for (int p = 0; p < B[c].V.m; ++p) xh[c][t] += B[c].V(p, t) * xc[p];
      }
    for (int a = 0; a < nc; ++a) {
      yh[a].assign(B[a].U.n, 0.0);
      for (std::size_t f = 0; f < K.partition().far[a].size(); ++f) {
        const H2Block &F = K.far_blocks(a)[f];
        for (int i = 0; i < F.M.m; ++i)
          for (int j = 0; j < F.M.n; ++j) yh[a][i] += F.entry(i, j) * xh[F.col_cluster][j];
      }
    }
    for (int l = 1; l < tree.levels(); ++l)
      for (int c : tree.clusters_at_level(l)) {
        if (B[c].U.n == 0) continue;
        const Cluster &cl = tree.cluster(c);
        std::vector<double> yc(B[c].U.m, 0.0);
        for (int t = 0; t < B[c].U.n; ++t)
          for (int p = 0; p < B[c].U.m; ++p) yc[p] += B[c].U(p, t) * yh[c][t];
        if (cl.left < 0) {
          for (int p = 0; p < B[c].U.m; ++p) yref[3L * cl.begin + p] += yc[p];
        } else {
          const int na = static_cast<int>(B[cl.left].row_skel.size());
          for (int p = 0; p < B[c].U.m; ++p) (p < na ? yh[cl.left][p] : yh[cl.right][p - na]) += yc[p];
        }
      }
    for (int a : tree.leaves())
      for (const H2Block &D : K.near_blocks(a))
        for (int i = 0; i < D.M.m; ++i)
          for (int j = 0; j < D.M.n; ++j) yref[3L * tree.cluster(a).begin + i] += D.entry(i, j) * x[static_cast<std::size_t>(w) * tree.cluster(D.col_cluster).begin + j];
    EXPECT_LE(rel(y, yref), 1e-12) << (single ? "single" : "double");
  }
}

SurfaceMesh scaled(SurfaceMesh m, Vec3 s)
{
  for (Vec3 &v : m.vertices) v = {s[0] * v[0], s[1] * v[1], s[2] * v[2]};
  return m;
}

void check_shape(SurfaceMesh mesh, int leaf, const char *what)
{
  auto L = load(std::move(mesh));
  H2Options o;
  o.rel_tol = 1e-6, o.single_precision = false; // a tighter tolerance than the driver's, in double
  o.leaf_size = leaf;
  const H2Matrix K = compress_bem_operator_h2(*L->op, o);
  const double err = matvec_error(K, dense_k(*L->op, K.col_block()), 5);
  std::printf("%s: %d nodes, %d levels, error %.2e\n", what, L->op->num_nodes(), K.tree().levels(), err);
  EXPECT_LE(err, 1e-5);
}

TEST(H2Degenerate, MeshSmallerThanOneLeaf) { check_shape(test::icosphere(1), 1000, "one leaf"); }
TEST(H2Degenerate, LeavesOfOneNode) { check_shape(test::icosphere(1), 1, "leaf size 1"); }
TEST(H2Degenerate, ElongatedBody) { check_shape(scaled(test::icosphere(3), {8, 1, 1}), 16, "cigar 8:1:1"); }
TEST(H2Degenerate, FlatBody) { check_shape(scaled(test::icosphere(3), {1, 1, 0.05}), 16, "disk 1:1:0.05"); }
TEST(H2Degenerate, TwoDisjointSurfaces) { check_shape(read_mesh(std::string(HSSBEM_MESHES) + "/hollow_sphere_l0.msh"), 16, "hollow sphere"); }

TEST(H2OptionsCheck, RejectsBadOptions)
{
  auto L = load("sphere_l0.msh");
  H2Options o;
  o.rel_tol = 0;
  EXPECT_THROW(compress_bem_operator_h2(*L->op, o), std::invalid_argument);
  o = H2Options{};
  o.eta = -0.1;
  EXPECT_THROW(compress_bem_operator_h2(*L->op, o), std::invalid_argument);
  o = H2Options{};
  o.leaf_size = 0;
  EXPECT_THROW(compress_bem_operator_h2(*L->op, o), std::invalid_argument);
  QuadratureOptions q;
  q.far_ratio = 8;
  BemOperator far(*L->disc, Material::from_young(1.0, 0.3), q);
  EXPECT_THROW(compress_bem_operator_h2(far, H2Options{}), std::invalid_argument);
}

} // namespace
