// The H² matrix distributed over 1, 2 and 4 ranks (h2/h2_distributed.hpp) on a METIS partition
// (bem/node_partition.hpp): each rank's rows of the distributed product against the same rows of
// the whole matrix compressed on one rank with the same tree, the gathered matrix against it too,
// the distributed system's right-hand side and diagonal, the partition's quality, and the refusal
// of more ranks than the surface can feed.
#include "solve_helpers.hpp"
#include "test_shapes.hpp"

#include "hssbem/bem/node_partition.hpp"
#include "hssbem/compress/pattern_columns.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/h2factor/far_sketch.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"
#include "hssbem/petsc/mpi_comm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using namespace hssbem;
using namespace hssbem::test;

namespace {

struct Fixture {
  ProblemSetup setup;
  std::unique_ptr<BemOperator> op;
  HssbemMpiComm comm{PETSC_COMM_WORLD};
  std::vector<int> part;
  NodePartitionStats stats;
  H2Options opts;
  std::unique_ptr<H2DistributedSystem> dist; ///< over the ranks
  std::unique_ptr<H2Matrix> whole;           ///< the same tree, compressed on one rank
  std::optional<H2Matrix> gathered;          ///< rank 0: the distributed matrix gathered

  Fixture() : setup(setup_problem(kelvin_mixed_spec("sphere_l1.msh", KelvinField{Material{1000.0, 0.3}, {1.2, 0.9, 1.0}, {1.0, -2.0, 0.5}}), ProblemOverrides{}))
  {
    op = std::make_unique<BemOperator>(*setup.disc, setup.material);
    part = partition_nodes(*setup.disc, comm.size(), &stats);
    MPI_Bcast(part.data(), static_cast<int>(part.size()), MPI_INT, 0, PETSC_COMM_WORLD); // one partition, whatever METIS does per rank
    opts.rel_tol = 1e-6;
    opts.single_precision = false;
    opts.leaf_size = 16;
    dist = std::make_unique<H2DistributedSystem>(*op, opts, part, comm);
    whole = std::make_unique<H2Matrix>(compress_bem_operator_h2(*op, opts, part, SerialComm()));
    gathered = gather_h2_matrix(dist->matrix(), comm);
  }
};

/// One problem and its two compressions for all the tests (they dominate the run time).
class H2Distributed : public ::testing::Test {
protected:
  static void SetUpTestSuite() { f = new Fixture; }
  static void TearDownTestSuite()
  {
    delete f;
    f = nullptr;
  }
  static Fixture *f;
};
Fixture *H2Distributed::f = nullptr;

double rel(const std::vector<double> &a, const std::vector<double> &b, MPI_Comm comm)
{
  double s[2] = {0, 0};
  for (std::size_t i = 0; i < a.size(); ++i) {
    s[0] += (a[i] - b[i]) * (a[i] - b[i]);
    s[1] += b[i] * b[i];
  }
  MPI_Allreduce(MPI_IN_PLACE, s, 2, MPI_DOUBLE, MPI_SUM, comm);
  EXPECT_GT(s[1], 0.0); // the reference is not zero: a product that did nothing fails
  return std::sqrt(s[0] / s[1]);
}

TEST_F(H2Distributed, PartitionIsBalancedAndConnected)
{
  const Fixture &f = *H2Distributed::f;
  EXPECT_EQ(f.stats.parts, f.comm.size());
  EXPECT_LE(f.stats.imbalance, 1.05);
  EXPECT_EQ(f.stats.disconnected_parts, 0);
  if (f.comm.size() > 1) {
    EXPECT_GT(f.stats.edge_cut, 0);
    EXPECT_LT(f.stats.edge_cut, f.stats.edges / 4); // a patch per part, not a scatter
  }
  EXPECT_THROW(partition_nodes(*f.setup.disc, f.setup.disc->num_nodes() / 2, nullptr), std::invalid_argument); // 2 nodes a rank
}

TEST_F(H2Distributed, ProductMatchesTheWholeMatrix)
{
  const Fixture &f = *H2Distributed::f;
  const H2DistributedSystem &dist = *f.dist;
  const H2Matrix &whole = *f.whole; // same tree, one rank
  const int n = whole.tree().num_points(), w = whole.col_block(), nrhs = 2;
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> X(static_cast<std::size_t>(w) * n * nrhs), Y(3L * n * nrhs);
  for (double &v : X) v = u(gen);
  whole.apply(X.data(), w * n, Y.data(), 3 * n, nrhs);

  const H2DistributedProduct &P = dist.product();
  const int m = P.num_points(), first = P.first_point();
  std::vector<double> Xl(static_cast<std::size_t>(w) * m * nrhs), Yl(3L * m * nrhs), Yref(Yl.size());
  for (int r = 0; r < nrhs; ++r) {
    std::copy_n(&X[static_cast<std::size_t>(w) * (first + static_cast<std::size_t>(r) * n)], w * m, &Xl[static_cast<std::size_t>(w) * m * r]);
    std::copy_n(&Y[3 * (first + static_cast<std::size_t>(r) * n)], 3 * m, &Yref[3L * m * r]);
  }
  P.apply(Xl.data(), w * m, Yl.data(), 3 * m, nrhs);
  EXPECT_LT(rel(Yl, Yref, PETSC_COMM_WORLD), 1e-12);
  long long points = m;
  MPI_Allreduce(MPI_IN_PLACE, &points, 1, MPI_LONG_LONG, MPI_SUM, PETSC_COMM_WORLD);
  EXPECT_EQ(points, n); // the ranks' rows cover K once
  if (f.comm.size() > 1) { // moments and boundary leaves cross (their growth with N: benchmarks/bench_h2_mpi)
    EXPECT_GT(P.values_sent(), 0);
    EXPECT_GT(P.messages_sent(), 0);
  }

  // The same matrix gathered on rank 0.
  const std::optional<H2Matrix> gathered = gather_h2_matrix(dist.matrix(), f.comm);
  ASSERT_EQ(gathered.has_value(), f.comm.rank() == 0);
  if (gathered) {
    std::vector<double> Yg(Y.size());
    gathered->apply(X.data(), w * n, Yg.data(), 3 * n, nrhs);
    double d = 0, s = 0;
    for (std::size_t i = 0; i < Y.size(); ++i) d += (Yg[i] - Y[i]) * (Yg[i] - Y[i]), s += Y[i] * Y[i];
    EXPECT_GT(s, 0.0);
    EXPECT_LT(std::sqrt(d / s), 1e-12);
    EXPECT_EQ(gathered->stats().near_blocks, whole.stats().near_blocks);
    EXPECT_EQ(gathered->stats().far_blocks, whole.stats().far_blocks);
  }
}

TEST_F(H2Distributed, FarFieldSketchMatchesTheOneRankSketch)
{
  // The factorization's far-field sketch through the distributed passes (potentials at the row
  // skeletons; the transposed pass with the far blocks sent to their column clusters' owners):
  // each rank's clusters' rows equal the one-rank sketch's of the same tree.
  const Fixture &f = *H2Distributed::f;
  const int p = 12;
  const FarFieldSketch local = far_field_sketch(f.dist->product(), p), whole = far_field_sketch(*f.whole, p);
  const H2Matrix &K = f.dist->matrix();
  double diff[2] = {0, 0}, norm[2] = {0, 0};
  long long held = 0, with_rows = 0;
  for (int c = 0; c < K.tree().num_clusters(); ++c) {
    const DenseMatrix *mine[2] = {&local.row[c], &local.col[c]}, *ref[2] = {&whole.row[c], &whole.col[c]};
    if (!K.holds(c)) {
      EXPECT_EQ(local.row[c].m + local.col[c].m, 0); // no other rank's rows
      continue;
    }
    ++held;
    with_rows += local.row[c].m > 0;
    for (int s = 0; s < 2; ++s) {
      ASSERT_EQ(mine[s]->m, ref[s]->m);
      ASSERT_EQ(mine[s]->n, ref[s]->n);
      for (std::size_t i = 0; i < ref[s]->a.size(); ++i) diff[s] += std::pow(mine[s]->a[i] - ref[s]->a[i], 2), norm[s] += std::pow(ref[s]->a[i], 2);
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, diff, 2, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, norm, 2, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  EXPECT_GT(held, 0);
  EXPECT_GT(with_rows, 0);
  EXPECT_GT(norm[0], 0.0);
  EXPECT_GT(norm[1], 0.0);
  const double rows = std::sqrt(diff[0] / norm[0]), cols = std::sqrt(diff[1] / norm[1]);
  if (f.comm.rank() == 0) std::printf("sketch on %d ranks vs one rank: rows %.1e, columns %.1e\n", f.comm.size(), rows, cols);
  EXPECT_LT(rows, 1e-12);
  EXPECT_LT(cols, 1e-12);
}

/// The distributed sketch of f's matrix with p columns, and the same gathered whole on every rank
/// (each cluster's rows from its owner).
FarFieldSketch gathered_sketch(const Fixture &f, int p)
{
  const FarFieldSketch local = far_field_sketch(f.dist->product(), p);
  const H2Matrix &K = f.dist->matrix();
  FarFieldSketch whole;
  whole.columns = p;
  whole.row.resize(K.tree().num_clusters());
  whole.col.resize(K.tree().num_clusters());
  for (int c = 0; c < K.tree().num_clusters(); ++c) {
    const int owner = K.owner(c);
    for (auto [mine, out] : {std::pair{&local.row[c], &whole.row[c]}, std::pair{&local.col[c], &whole.col[c]}}) {
      int m = mine->m;
      MPI_Bcast(&m, 1, MPI_INT, owner, PETSC_COMM_WORLD);
      *out = f.comm.rank() == owner ? *mine : DenseMatrix(m, p);
      if (m > 0) MPI_Bcast(out->data(), m * p, MPI_DOUBLE, owner, PETSC_COMM_WORLD);
    }
  }
  return whole;
}

/// x = A⁻¹ b by the distributed factorization and, on rank 0, by one rank simulating the parts on
/// the same matrix (gathered) with the same far-field sketch (gathered): the same steps on the
/// same numbers, so the same skeletons. The two solutions' relative difference, the distributed
/// one's residual, and whether every level eliminated as many unknowns in both.
void compare_factorizations(const Fixture &f, const SystemSelection &sel, const H2FactorOptions &fo, double *diff, double *residual, H2FactorStats *stats, bool *same_levels)
{
  const H2DistributedSystem &dist = *f.dist;
  const ClusterTree &tree = dist.matrix().tree();
  const int nn = f.op->num_nodes(), m = dist.num_points(), first = dist.first_point();
  const int p = fo.sketch_columns > 0 ? fo.sketch_columns : default_sketch_columns(fo.rel_tol);
  FarFieldSketch sketch = gathered_sketch(f, p);
  H2FactorCache cd(dist.product());
  const H2Factorization Fd(cd, sel, fo);
  std::vector<long long> eliminated;
  for (const H2FactorLevelStats &l : Fd.stats().levels) eliminated.push_back(l.eliminated);
  MPI_Allreduce(MPI_IN_PLACE, eliminated.data(), static_cast<int>(eliminated.size()), MPI_LONG_LONG, MPI_SUM, PETSC_COMM_WORLD);
  std::mt19937 gen(5);
  std::normal_distribution<double> N01;
  std::vector<double> b(3L * nn), x(3L * nn);
  for (double &v : b) v = N01(gen);
  int same = 0;
  if (f.gathered) { // rank 0
    H2FactorCache cw(*f.gathered);
    cw.adopt(std::move(sketch));
    H2FactorOptions fw = fo;
    fw.within_parts = true;
    const H2Factorization Fw(cw, sel, fw);
    EXPECT_EQ(Fw.stats().time_sketch, 0.0); // the adopted sketch
    same = Fw.stats().levels.size() == eliminated.size();
    for (std::size_t i = 0; same && i < eliminated.size(); ++i) same = Fw.stats().levels[i].eliminated == eliminated[i];
    solve_mesh_order(Fw, b.data(), x.data());
  }
  MPI_Bcast(&same, 1, MPI_INT, 0, PETSC_COMM_WORLD);
  MPI_Bcast(x.data(), static_cast<int>(x.size()), MPI_DOUBLE, 0, PETSC_COMM_WORLD);
  *same_levels = same != 0;
  std::vector<double> bl(3L * m), xl(3L * m), xref(3L * m), ax(3L * m);
  for (int k = 0; k < m; ++k)
    for (int c = 0; c < 3; ++c) {
      bl[3 * k + c] = b[3L * tree.perm()[first + k] + c];
      xref[3 * k + c] = x[3L * tree.perm()[first + k] + c];
    }
  Fd.solve(bl.data(), xl.data());
  *diff = rel(xl, xref, PETSC_COMM_WORLD);
  dist.apply(sel, xl.data(), ax.data());
  *residual = rel(ax, bl, PETSC_COMM_WORLD);
  *stats = Fd.stats();
  EXPECT_EQ(Fd.steps_crossing_parts(), 0);
}

TEST_F(H2Distributed, FactorizationEqualsTheOneRankOneWithParts)
{
  // Each rank eliminates its part's subtree, rank 0 the top: the same steps as one rank that
  // simulates the parts on the same tree, matrix and sketch, so the same skeletons and, but for
  // the top's LU, the same arithmetic.
  const Fixture &f = *H2Distributed::f;
  // At 1e-3 three times: the top's LU in double (below single_top_from, 4 000 by default), and in
  // single precision alone (single_top_from 1) spread over the ranks (ScaLAPACK) or on rank 0
  // (each rank sends its rows rounded, two floats to a value).
  struct Case {
    double tol;
    int mixed_from;
    bool spread;
    double bound; ///< on the difference from one rank
  };
  // Measured at 1, 2, 3, 4 and 6 ranks: 0 exactly (the same arithmetic; the bound leaves rounding
  // slack) but for the spread top, whose LU is ScaLAPACK's (another order of the same
  // single-precision arithmetic): 1.5e-7, 1.9e-7, 1.5e-7, 1.7e-7.
  for (const Case c : {Case{1e-3, 4000, true, 1e-12}, Case{1e-3, 1, true, 5e-7}, Case{1e-3, 1, false, 1e-12}, Case{1e-6, 4000, true, 1e-12}}) {
    const double tol = c.tol;
    H2FactorOptions fo;
    fo.rel_tol = tol;
    fo.top_size = 0;
    fo.top_when_cheaper = false; // eliminate every level the parts allow (a 3k-unknown top is cheaper)
    fo.leaf_size = 16;
    fo.single_top_from = c.mixed_from;
    fo.spread_top = c.spread;
    double diff = 1, residual = 1;
    H2FactorStats st;
    bool same_levels = false;
    compare_factorizations(f, f.setup.selection, fo, &diff, &residual, &st, &same_levels);
    long long eliminated = 0;
    for (const H2FactorLevelStats &l : st.levels) eliminated += l.eliminated;
    MPI_Allreduce(MPI_IN_PLACE, &eliminated, 1, MPI_LONG_LONG, MPI_SUM, PETSC_COMM_WORLD);
    if (f.comm.rank() == 0)
      std::printf("factorization at %.0e on %d ranks (top %s%s): against one rank with the parts %.1e, residual %.1e, top %d, %lld eliminated below it\n", tol, f.comm.size(),
                  st.top_single ? "single" : st.top_mixed ? "mixed" : "double", st.top_spread ? ", spread" : "", diff, residual, st.top_size, eliminated);
    if (f.comm.rank() == 0) EXPECT_EQ(st.top_single, c.mixed_from == 1); // single panels and a top of at least mixed_from
    EXPECT_EQ(st.top_spread, c.mixed_from == 1 && c.spread && f.comm.size() > 1 ? f.comm.size() : 0);
    EXPECT_TRUE(same_levels); // the same skeletons, level by level
    EXPECT_LT(diff, c.bound);
    // The residual, measured at 1, 2, 3, 4, 6 ranks: at 1e-3 1.6e-3, 1.3e-3, 1.2e-3, 9.1e-4, 1.0e-3;
    // at 1e-6 7.0e-7, 5.6e-7, 3.5e-7, 2.7e-7, 1.0e-7.
    EXPECT_LT(residual, tol > 1e-5 ? 4e-3 : 2e-6);
    EXPECT_GT(st.top_size, 0);
    EXPECT_EQ(eliminated + st.top_size, 3LL * f.op->num_nodes()); // every unknown once: below the top or in it
    // Eliminated below the top, measured at 1 to 8 ranks: at 1e-3 0.92, 0.70, 0.56, 0.49, 0.39,
    // 0.37, 0.34, 0.29; at 1e-6 0.77, 0.47, 0.25, 0.16, then 142, 81, 59, 10 unknowns (parts of
    // 125-200 nodes hardly compress at 1e-6).
    const double share = tol > 1e-5 ? 0.25 : f.comm.size() <= 4 ? 0.1 : 0.0;
    EXPECT_GE(eliminated, share * 3 * f.op->num_nodes());
    EXPECT_GT(eliminated, 0);
  }
}

TEST_F(H2Distributed, FactorizationBreakdownThrowsOnEveryRank)
{
  // Pure traction without the rigid-mode regularisation, all of it factored densely at the top
  // (the ranks' rows of it gathered on rank 0): the translations are null vectors of the H²
  // matrix, the top is singular on rank 0, and every rank throws H2Breakdown (none waits).
  const Fixture &f = *H2Distributed::f;
  SystemSelection sel = f.setup.selection;
  for (auto &k : sel.displacement_known) k = {false, false, false};
  H2FactorCache cd(f.dist->product());
  H2FactorOptions fo;
  fo.rel_tol = 1e-3;
  fo.top_size = 3 * f.op->num_nodes();
  EXPECT_THROW(H2Factorization(cd, sel, fo), H2Breakdown);
}

TEST_F(H2Distributed, SystemRowsMatchTheMeshOrderSystem)
{
  const Fixture &f = *H2Distributed::f;
  const H2DistributedSystem &dist = *f.dist;
  const H2BemSystem whole(*f.whole); // a copy in the mesh-order interface
  const SystemSelection &sel = f.setup.selection;
  const int nn = f.op->num_nodes();
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(3L * nn), y(3L * nn);
  for (double &v : x) v = u(gen);
  whole.apply(sel, x.data(), y.data());
  const std::vector<double> b = whole.rhs(sel), d = whole.diagonal(sel);

  const ClusterTree &tree = dist.matrix().tree();
  const int m = dist.num_points(), first = dist.first_point();
  std::vector<double> xl(3L * m), yref(3L * m), bref(3L * m), dref(3L * m), yl(3L * m);
  for (int k = 0; k < m; ++k)
    for (int c = 0; c < 3; ++c) {
      const int j = tree.perm()[first + k];
      xl[3 * k + c] = x[3L * j + c];
      yref[3 * k + c] = y[3L * j + c];
      bref[3 * k + c] = b[3L * j + c];
      dref[3 * k + c] = d[3L * j + c];
    }
  dist.apply(sel, xl.data(), yl.data());
  EXPECT_LT(rel(yl, yref, PETSC_COMM_WORLD), 1e-12);
  EXPECT_LT(rel(dist.rhs(sel), bref, PETSC_COMM_WORLD), 1e-12);
  EXPECT_LT(rel(dist.diagonal(sel), dref, PETSC_COMM_WORLD), 1e-14);
}

} // namespace
