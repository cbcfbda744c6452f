// HSS engine: compression of K = [H, G] against the dense operator.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/hss/hss_compression.hpp"
#include "hssbem/hss/ulv.hpp"
#include "hssbem/hss/hss_system.hpp"
#include "test_shapes.hpp"
#include "hss_test_helpers.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/timer.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

using namespace hssbem;
using namespace hssbem::test; // dense_k, dense_a, matvec_error, random_pattern, rel, ulv_solve

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

struct Case {
  const char *mesh;
  double tol;
  int leaf;
};

class HssAccuracy : public ::testing::TestWithParam<Case> {};

TEST_P(HssAccuracy, MatvecMatchesDenseOperator)
{
  const Case c = GetParam();
  auto L = load(c.mesh);
  HssOptions o;
  o.rel_tol = c.tol;
  o.leaf_size = c.leaf;
  o.pressure_columns = true;
  const Timer tc_timer;
  HssMatrix K = compress_bem_operator_hss(*L->op, o);
  const double tc = tc_timer.seconds();
  const auto Kd = dense_k(*L->op, K.col_block());
  const double err = matvec_error(K, Kd, 7);
  std::printf("%s tol %.0e: error %.2e, compress %.2f s, max rank row %d col %d, memory %.1f MB (dense %.1f MB)\n", c.mesh, c.tol, err, tc,
              K.stats().max_row_rank(), K.stats().max_col_rank(), K.stats().memory_bytes / 1e6, 8.0 * Kd.size() / 1e6);
  const HssStats &st = K.stats();
  std::printf("  tree %.2f near %.2f ids %.2f couplings %.2f leaves %.2f rigid %.2f; entries %.3g; proxies %d\n", st.time_tree, st.time_near_field,
              st.time_ids, st.time_couplings, st.time_leaves, st.time_rigid, double(st.entries_evaluated), st.proxy_points);
  for (size_t l = 0; l < st.levels.size(); ++l)
    std::printf("  level %zu: %d clusters, row rank max %d mean %.0f, col rank max %d mean %.0f\n", l, st.levels[l].clusters, st.levels[l].max_row_rank,
                st.levels[l].mean_row_rank, st.levels[l].max_col_rank, st.levels[l].mean_col_rank);
  EXPECT_LE(err, 10 * c.tol);
}

INSTANTIATE_TEST_SUITE_P(Meshes, HssAccuracy,
                         ::testing::Values(Case{"sphere_l1.msh", 1e-3, 64}, Case{"sphere_l1.msh", 1e-6, 64}, Case{"sphere_l1.msh", 1e-9, 64},
                                           Case{"cardioid_832.msh", 1e-3, 32}, Case{"cardioid_832.msh", 1e-6, 32},
                                           Case{"cardioid_832.msh", 1e-9, 32}));

struct SolveCase {
  const char *mesh;
  double tol;
  int leaf;
  double known_fraction;
};

class HssSolve : public ::testing::TestWithParam<SolveCase> {};

TEST_P(HssSolve, UlvSolveMatchesDenseSolve)
{
  const SolveCase c = GetParam();
  auto L = load(c.mesh);
  HssOptions o;
  o.rel_tol = c.tol;
  o.leaf_size = c.leaf;
  HssMatrix K = compress_bem_operator_hss(*L->op, o);
  const int n = L->op->num_nodes(), w = K.col_block();
  const auto Kd = dense_k(*L->op, w);
  const auto known = random_pattern(n, c.known_fraction, 3);
  const Timer tf_timer;
  UlvFactorization F(K, known);
  const double tf = tf_timer.seconds();
  std::mt19937 gen(5);
  std::normal_distribution<double> N01;
  std::vector<double> b(3L * n);
  for (double &v : b) v = N01(gen);
  const std::vector<double> x = ulv_solve(K, F, b);
  auto A = dense_a(Kd, n, w, known);
  std::vector<double> xd(b);
  ASSERT_EQ(lapack::gesv(3 * n, 1, A.data(), xd.data()), 0);
  const double err = rel(x, xd);
  std::printf("%s tol %.0e: solve difference %.2e, factor %.2f s, front %d, factor memory %.1f MB\n", c.mesh, c.tol, err, tf, F.max_front(),
              F.memory_bytes() / 1e6);
  EXPECT_LE(err, 100 * c.tol);
}

INSTANTIATE_TEST_SUITE_P(Meshes, HssSolve,
                         ::testing::Values(SolveCase{"sphere_l0.msh", 1e-6, 16, 0.5}, SolveCase{"cardioid_832.msh", 1e-3, 32, 0.3},
                                           SolveCase{"cardioid_832.msh", 1e-9, 32, 0.7}, SolveCase{"cube_l1.msh", 1e-6, 32, 0.5}));

/// A selection with the given pattern and arbitrary known values.
SystemSelection selection(const std::vector<std::array<bool, 3>> &known)
{
  SystemSelection sel;
  sel.displacement_known = known;
  sel.known.assign(known.size(), Vec3{0.1, -0.2, 0.3});
  return sel;
}

/// Dense solve of the selection's A x = b (A row-major from fill_system_block).
std::vector<double> dense_solve(const BemOperator &op, const SystemSelection &sel, std::vector<double> b)
{
  const int n = op.num_nodes();
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  std::vector<double> A(9L * n * n);
  fill_system_block(op, sel, all, all, A.data(), 3L * n, nullptr);
  std::vector<int> piv(3 * n);
  EXPECT_EQ(lapack::getrf(3 * n, A.data(), 3 * n, piv.data()), 0);
  EXPECT_EQ(lapack::getrs('T', 3 * n, 1, A.data(), 3 * n, piv.data(), b.data(), 3 * n), 0); // row-major A: solve with the transpose
  return b;
}


/// Matvec and solve of one pattern through the system against the dense matrix.
void check_pattern(const HssBemSystem &sys, const SystemSelection &sel, double tol, const char *what)
{
  const BemOperator &op = sys.op();
  const int n = op.num_nodes();
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  std::vector<double> A(9L * n * n);
  fill_system_block(op, sel, all, all, A.data(), 3L * n, nullptr);
  std::mt19937 gen(11);
  std::normal_distribution<double> N01;
  std::vector<double> x(3L * n), y(3L * n), yd(3L * n, 0.0);
  for (double &v : x) v = N01(gen);
  sys.apply(sel, x.data(), y.data());
  for (long i = 0; i < 3L * n; ++i)
    for (long j = 0; j < 3L * n; ++j) yd[i] += A[i * 3 * n + j] * x[j];
  const double em = rel(y, yd);
  const auto F = sys.factor(sel);
  const double es = rel(sys.solve(*F, x), dense_solve(op, sel, x));
  std::printf("%s: matvec error %.2e, solve difference %.2e (tol %.0e)\n", what, em, es, tol);
  EXPECT_LE(em, 10 * tol);
  EXPECT_LE(es, 100 * tol);
  EXPECT_GT(em, 0.0); // a compressed operator is not exact: the comparison did run
}

TEST(HssPatterns, OneCompressionServesAnyBoundaryConditionPattern)
{
  auto L = load("cardioid_832.msh");
  HssOptions o;
  o.rel_tol = 1e-6;
  o.leaf_size = 32;
  const HssBemSystem sys(*L->op, o);
  const long long entries = sys.matrix().stats().entries_evaluated;
  const int n = L->op->num_nodes();
  auto known = random_pattern(n, 0.5, 21);
  check_pattern(sys, selection(known), o.rel_tol, "cardioid, pattern 1");
  // Swap displacement and traction on 30 % of the vertices (all their nodes and components).
  std::mt19937 gen(4);
  std::bernoulli_distribution swap(0.3);
  int swapped = 0;
  for (int v = 0; v < L->mesh.num_vertices(); ++v) {
    if (!swap(gen)) continue;
    ++swapped;
    for (int i = L->disc->first_node(v); i < L->disc->first_node(v) + L->disc->node_count(v); ++i)
      for (bool &b : known[i]) b = !b;
  }
  EXPECT_GT(swapped, L->mesh.num_vertices() / 5);
  check_pattern(sys, selection(known), o.rel_tol, "cardioid, 30 % of the vertices swapped");
  EXPECT_EQ(sys.matrix().stats().entries_evaluated, entries); // nothing evaluated again
}

/// Compression, product and solve on shapes and trees that stress the tree construction.
void check_shape(const SurfaceMesh &mesh_in, int leaf, double tol, const char *what)
{
  SurfaceMesh mesh = mesh_in;
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material::from_young(1.0, 0.3));
  HssOptions o;
  o.rel_tol = tol;
  o.leaf_size = leaf;
  const HssBemSystem sys(op, o);
  std::printf("%s: %d nodes, %d levels; ", what, op.num_nodes(), sys.matrix().tree().levels());
  check_pattern(sys, selection(random_pattern(op.num_nodes(), 0.5, 9)), tol, what);
}

SurfaceMesh scaled(SurfaceMesh m, Vec3 s)
{
  for (Vec3 &v : m.vertices) v = {s[0] * v[0], s[1] * v[1], s[2] * v[2]};
  return m;
}

TEST(HssDegenerate, MeshSmallerThanOneLeaf)
{
  check_shape(test::icosphere(1), 1000, 1e-6, "one leaf");
}

TEST(HssDegenerate, LeavesOfOneNode)
{
  check_shape(test::icosphere(1), 1, 1e-6, "leaf size 1");
}

TEST(HssDegenerate, ElongatedBody)
{
  check_shape(scaled(test::icosphere(3), {8, 1, 1}), 32, 1e-6, "cigar 8:1:1");
}

TEST(HssDegenerate, FlatBody)
{
  check_shape(scaled(test::icosphere(3), {1, 1, 0.05}), 32, 1e-6, "disk 1:1:0.05");
}

TEST(HssDegenerate, TwoDisjointSurfaces)
{
  check_shape(read_mesh(std::string(HSSBEM_MESHES) + "/hollow_sphere_l0.msh"), 32, 1e-6, "hollow sphere");
}

TEST(HssOptionsCheck, RejectsBadOptions)
{
  auto L = load("sphere_l0.msh");
  HssOptions o;
  o.rel_tol = 0;
  EXPECT_THROW(compress_bem_operator_hss(*L->op, o), std::invalid_argument);
  o = HssOptions{};
  o.leaf_size = 0;
  EXPECT_THROW(compress_bem_operator_hss(*L->op, o), std::invalid_argument);
  QuadratureOptions q;
  q.far_ratio = 8;
  BemOperator far(*L->disc, Material::from_young(1.0, 0.3), q);
  EXPECT_THROW(compress_bem_operator_hss(far, HssOptions{}), std::invalid_argument);
}

} // namespace
