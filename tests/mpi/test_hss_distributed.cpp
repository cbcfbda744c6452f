// The HSS matrix distributed over 1, 2 and 4 ranks (hss/hss_distributed.hpp) on a METIS partition:
// each rank holds only its part; each rank's rows of the distributed product, of the system's
// right-hand side and diagonal, and of the distributed ULV solve (plain, regularised, after a
// distributed truncation) against the same tree compressed and factored on one rank; the solve
// against dense LU; a breakdown on any rank stops every rank.
#include "hss_test_helpers.hpp"
#include "solve_helpers.hpp"
#include "test_shapes.hpp"

#include "hssbem/bem/node_partition.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/compress/pattern_columns.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/hss/hss_system.hpp"
#include "hssbem/hss/truncate.hpp"
#include "hssbem/petsc/mpi_comm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace hssbem;
using namespace hssbem::test;

namespace {

/// A problem compressed twice on the same tree (the METIS partition's top, geometric bisection
/// below): distributed over the ranks, and whole on every rank (the reference).
struct Fixture {
  ProblemSetup setup;
  std::unique_ptr<BemOperator> op;
  HssbemMpiComm comm{PETSC_COMM_WORLD};
  std::vector<int> part;
  HssOptions opts;
  std::unique_ptr<HssDistributedSystem> dist;
  std::unique_ptr<HssMatrix> whole;

  Fixture(const ProblemSpec &spec, double tol, int leaf) : setup(setup_problem(spec, ProblemOverrides{}))
  {
    op = std::make_unique<BemOperator>(*setup.disc, setup.material);
    part = partition_nodes(*setup.disc, comm.size());
    MPI_Bcast(part.data(), static_cast<int>(part.size()), MPI_INT, 0, PETSC_COMM_WORLD); // one partition, whatever METIS does per rank
    opts.rel_tol = tol;
    opts.leaf_size = leaf;
    dist = std::make_unique<HssDistributedSystem>(*op, opts, part, comm);
    whole = std::make_unique<HssMatrix>(compress_bem_operator_hss(*op, opts, part, SerialComm()));
  }
  int first() const { return dist->first_point(); }
  int count() const { return dist->num_points(); }
  /// This rank's entries (3 per local point) of a vector in cluster order.
  std::vector<double> local(const std::vector<double> &cluster_order) const
  {
    return std::vector<double>(cluster_order.begin() + 3L * first(), cluster_order.begin() + 3L * (first() + count()));
  }
};

ProblemSpec sphere_mixed()
{
  return kelvin_mixed_spec("sphere_l0.msh", KelvinField{Material{1000.0, 0.3}, {1.2, 0.9, 1.0}, {1.0, -2.0, 0.5}});
}

/// The cube clamped at z = 0 and pulled at z = 1: double nodes along its edges, whose rigid-body
/// terms couple the parts' rows to other parts' columns.
ProblemSpec cube_pulled()
{
  ProblemSpec spec = spec_for("cube_l1.msh", 1000.0, 0.3);
  spec.rules = {rule(BoundaryRule::Kind::Displacement, region("z0"), {{0, 0, 0}}), rule(BoundaryRule::Kind::Traction, region("z1"), {{0, 0, 10.0}})};
  return spec;
}

class HssDistributed : public ::testing::Test {
protected:
  static void SetUpTestSuite()
  {
    sphere = new Fixture(sphere_mixed(), 1e-6, 16);
    cube = new Fixture(cube_pulled(), 1e-6, 16);
  }
  static void TearDownTestSuite()
  {
    delete sphere;
    delete cube;
    sphere = cube = nullptr;
  }
  static Fixture *sphere, *cube;
};
Fixture *HssDistributed::sphere = nullptr;
Fixture *HssDistributed::cube = nullptr;

/// ‖a − b‖ / ‖b‖ over all ranks' entries.
double rel_all(const std::vector<double> &a, const std::vector<double> &b)
{
  double s[2] = {0, 0};
  for (std::size_t i = 0; i < a.size(); ++i) {
    s[0] += (a[i] - b[i]) * (a[i] - b[i]);
    s[1] += b[i] * b[i];
  }
  MPI_Allreduce(MPI_IN_PLACE, s, 2, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  EXPECT_GT(s[1], 0.0); // the reference is not zero: a step that did nothing fails
  return std::sqrt(s[0] / s[1]);
}

/// This rank's rows of the distributed product against the whole matrix's, for two columns.
double product_difference(const Fixture &f, const HssDistributedProduct &P, const HssMatrix &whole)
{
  const int n = whole.tree().num_points(), w = whole.col_block(), nrhs = 2, m = P.num_points(), first = P.first_point();
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> X(static_cast<std::size_t>(w) * n * nrhs), Y(3L * n * nrhs);
  for (double &v : X) v = u(gen);
  whole.apply(X.data(), w * n, Y.data(), 3 * n, nrhs);
  std::vector<double> Xl(static_cast<std::size_t>(w) * m * nrhs), Yl(3L * m * nrhs), Yref(Yl.size());
  for (int r = 0; r < nrhs; ++r) {
    std::copy_n(&X[static_cast<std::size_t>(w) * (first + static_cast<std::size_t>(r) * n)], w * m, &Xl[static_cast<std::size_t>(w) * m * r]);
    std::copy_n(&Y[3 * (first + static_cast<std::size_t>(r) * n)], 3 * m, &Yref[3L * m * r]);
  }
  P.apply(Xl.data(), w * m, Yl.data(), 3 * m, nrhs);
  (void)f;
  return rel_all(Yl, Yref);
}

TEST_F(HssDistributed, ProductMatchesTheWholeMatrix)
{
  for (const Fixture *f : {sphere, cube}) {
    const HssDistributedProduct &P = f->dist->product();
    const double d = product_difference(*f, P, *f->whole);
    PetscPrintf(PETSC_COMM_WORLD, "  %s: product against the whole matrix %.2e\n", f->setup.spec.file.c_str(), d);
    EXPECT_LT(d, 1e-12);
    long long points = P.num_points();
    MPI_Allreduce(MPI_IN_PLACE, &points, 1, MPI_LONG_LONG, MPI_SUM, PETSC_COMM_WORLD);
    EXPECT_EQ(points, f->whole->tree().num_points()); // the ranks' rows cover K once
    if (f->comm.size() > 1) { // the parts' roots' coefficients up and down: one message each way
      EXPECT_GT(P.values_sent(), 0);
      EXPECT_GE(P.messages_sent(), 1);
      EXPECT_LE(P.messages_sent(), 2 * (f->comm.size() - 1));
    }
  }
}

TEST_F(HssDistributed, RigidBodyTermsCrossTheParts)
{
  // The cube's double nodes couple rows of one part to columns of another through their
  // rigid-body terms; those terms land in couplings above the parts (rank 0's), and the product
  // test above checks that they arrived. Here: that such terms exist on several ranks.
  const Fixture &f = *cube;
  int crossing = 0;
  for (int i = 0; i < f.op->num_nodes(); ++i) {
    int cols[3];
    double wts[3];
    const int nc = f.op->rigid_body_columns(i, cols, wts);
    for (int a = 0; a < nc; ++a) crossing += f.part[i] != f.part[cols[a]];
  }
  PetscPrintf(PETSC_COMM_WORLD, "  rigid-body terms between parts: %d\n", crossing);
  if (f.comm.size() > 1) EXPECT_GT(crossing, 0);
  else EXPECT_EQ(crossing, 0);
}

TEST_F(HssDistributed, EachRankHoldsOnlyItsPart)
{
  const Fixture &f = *sphere;
  const HssMatrix &K = f.dist->matrix();
  const ClusterTree &tree = K.tree();
  const std::vector<int> owner = cluster_owners(tree, f.comm.size());
  int held_points = 0;
  for (int c = 0; c < tree.num_clusters(); ++c) {
    const HssCluster &h = K.cluster(c);
    EXPECT_EQ(K.holds(c), owner[c] == f.comm.rank()) << c;
    if (!K.holds(c)) { // another rank's generators are not here, its skeletons are
      EXPECT_TRUE(h.U.empty() && h.V.empty() && h.D.empty() && h.B12.empty() && h.B21.empty()) << c;
      if (c != 0) EXPECT_FALSE(h.row_skel.empty() || h.col_skel.empty()) << c;
      continue;
    }
    if (tree.is_leaf(c)) {
      EXPECT_FALSE(h.D.empty()) << c;
      held_points += tree.cluster(c).size();
      EXPECT_GE(tree.cluster(c).begin, f.first());
      EXPECT_LE(tree.cluster(c).end, f.first() + f.count());
    } else {
      EXPECT_FALSE(h.B12.empty() || h.B21.empty()) << c;
    }
  }
  EXPECT_EQ(held_points, f.count()); // this rank's leaves are its part, all of it
  // The ranks' memories add up to the whole matrix's; on several ranks none holds it all.
  double mem[2] = {static_cast<double>(K.stats().memory_bytes), static_cast<double>(K.stats().memory_bytes)};
  f.comm.sum(&mem[0], 1);
  mem[1] = f.comm.max(mem[1]);
  PetscPrintf(PETSC_COMM_WORLD, "  memory %.2f MB in all, %.2f MB on the largest rank\n", mem[0] / 1048576.0, mem[1] / 1048576.0);
  EXPECT_EQ(mem[0], static_cast<double>(f.whole->stats().memory_bytes));
  if (f.comm.size() > 1) EXPECT_LT(mem[1], 0.8 * mem[0]);
}

TEST_F(HssDistributed, SystemRowsMatchTheMeshOrderSystem)
{
  const Fixture &f = *sphere;
  const HssBemSystem whole(*f.op, HssMatrix(*f.whole));
  const SystemSelection &sel = f.setup.selection;
  const int nn = f.op->num_nodes();
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(3L * nn), y(3L * nn);
  for (double &v : x) v = u(gen);
  whole.apply(sel, x.data(), y.data());
  const std::vector<double> b = whole.rhs(sel), d = whole.diagonal(sel);
  const ClusterTree &tree = f.dist->tree();
  const int m = f.count();
  std::vector<double> xl(3L * m), yref(3L * m), bref(3L * m), dref(3L * m), yl(3L * m);
  for (int k = 0; k < m; ++k)
    for (int c = 0; c < 3; ++c) {
      const int j = tree.perm()[f.first() + k];
      xl[3 * k + c] = x[3L * j + c];
      yref[3 * k + c] = y[3L * j + c];
      bref[3 * k + c] = b[3L * j + c];
      dref[3 * k + c] = d[3L * j + c];
    }
  f.dist->apply(sel, xl.data(), yl.data());
  EXPECT_LT(rel_all(yl, yref), 1e-12);
  EXPECT_LT(rel_all(f.dist->rhs(sel), bref), 1e-12);
  EXPECT_LT(rel_all(f.dist->diagonal(sel), dref), 1e-14);
}

/// A random right-hand side in cluster order (the same on every rank).
std::vector<double> random_rhs(int n, int seed)
{
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> b(3L * n);
  for (double &v : b) v = u(gen);
  return b;
}

/// This rank's rows of the distributed solve against the whole factorization's (same tree).
double solve_difference(const Fixture &f, const UlvFactorization &F, const UlvFactorization &Fwhole)
{
  const std::vector<double> b = random_rhs(f.whole->tree().num_points(), 5);
  std::vector<double> x = b, xl = f.local(b);
  Fwhole.solve(x.data());
  F.solve(xl.data());
  return rel_all(xl, f.local(x));
}

TEST_F(HssDistributed, FactorizationMatchesTheWholeOneAndDenseLu)
{
  const Fixture &f = *sphere;
  const SystemSelection &sel = f.setup.selection;
  const std::unique_ptr<UlvFactorization> F = f.dist->factor(sel);
  const UlvFactorization Fwhole(*f.whole, sel.displacement_known);
  const double dw = solve_difference(f, *F, Fwhole);
  EXPECT_LT(dw, 1e-10);
  // Against dense LU of the same pattern's A (mesh order): within 100 tol, as the one-rank solve.
  const int n = f.op->num_nodes(), w = f.whole->col_block();
  std::vector<double> A = dense_a(dense_k(*f.op, w), n, w, sel.displacement_known);
  const std::vector<double> bc = random_rhs(n, 9);
  std::vector<double> bm(bc.size()), xl = f.local(bc), xc(bc.size());
  f.whole->tree().to_mesh_order(bc.data(), bm.data(), 3);
  std::vector<int> piv(3L * n);
  ASSERT_EQ(lapack::getrf(3 * n, A.data(), 3 * n, piv.data()), 0);
  lapack::getrs('N', 3 * n, 1, A.data(), 3 * n, piv.data(), bm.data(), 3 * n);
  f.whole->tree().to_cluster_order(bm.data(), xc.data(), 3);
  F->solve(xl.data());
  const double err = rel_all(xl, f.local(xc));
  PetscPrintf(PETSC_COMM_WORLD, "  ULV solve against the whole factorization %.2e, against dense LU %.2e (tol %.0e)\n", dw, err, f.opts.rel_tol);
  EXPECT_LT(err, 100 * f.opts.rel_tol);
  EXPECT_GT(F->memory_bytes(), 0u);
  if (f.comm.rank() == 0) EXPECT_GT(F->root_size(), 0); // the top's root block, on rank 0
  else EXPECT_EQ(F->root_size(), 0);
}

TEST_F(HssDistributed, TruncationMatchesTheWholeOne)
{
  const Fixture &f = *sphere;
  const HssMatrix T = truncate_hss(f.dist->matrix(), 1e-3, -1, f.comm);
  const HssMatrix Twhole = truncate_hss(*f.whole, 1e-3);
  const HssDistributedProduct P(T, f.comm);
  const double dp = product_difference(f, P, Twhole);
  EXPECT_LT(dp, 1e-12);
  EXPECT_LT(Twhole.stats().max_row_rank(), f.whole->stats().max_row_rank()); // it truncated something
  for (int c = 1; c < T.tree().num_clusters(); ++c) // every rank knows every new skeleton
    ASSERT_EQ(T.cluster(c).row_skel, Twhole.cluster(c).row_skel) << c;
  const SystemSelection &sel = f.setup.selection;
  const UlvFactorization F(T, f.comm, sel.displacement_known), Fwhole(Twhole, sel.displacement_known);
  const double ds = solve_difference(f, F, Fwhole);
  PetscPrintf(PETSC_COMM_WORLD, "  truncated to 1e-3 (max row rank %d -> %d): product %.2e, solve %.2e against the whole\n", f.whole->stats().max_row_rank(), Twhole.stats().max_row_rank(), dp, ds);
  EXPECT_LT(ds, 1e-10);
}

/// Uniform pressure on sphere_l0 (pure traction) at 1e-8 with leaves of 32 nodes: regularised,
/// it is solved; without the regularisation its root block is singular.
class HssDistributedPure : public ::testing::Test {
protected:
  static void SetUpTestSuite() { f = new Fixture(pressure_spec("sphere_l0.msh", 1000.0, 0.3, 100.0), 1e-8, 32); }
  static void TearDownTestSuite()
  {
    delete f;
    f = nullptr;
  }
  static Fixture *f;
};
Fixture *HssDistributedPure::f = nullptr;

TEST_F(HssDistributedPure, RegularisedFactorizationMatchesTheWholeOne)
{
  ASSERT_TRUE(f->setup.pure_traction);
  const std::vector<double> modes = orthonormal_rigid_modes(*f->setup.disc);
  const std::unique_ptr<UlvFactorization> F = f->dist->factor(f->setup.selection, &modes);
  const HssBemSystem whole(*f->op, HssMatrix(*f->whole));
  const std::unique_ptr<UlvFactorization> Fwhole = whole.factor(f->setup.selection, &modes);
  const double d = solve_difference(*f, *F, *Fwhole);
  PetscPrintf(PETSC_COMM_WORLD, "  regularised ULV solve against the whole factorization %.2e\n", d);
  EXPECT_LT(d, 1e-10);
}

TEST_F(HssDistributedPure, BreakdownStopsEveryRank)
{
  int breakdown = 0, peer = 0, none = 0;
  try {
    f->dist->factor(f->setup.selection);
    none = 1;
  } catch (const HssBreakdown &e) {
    breakdown = 1;
    EXPECT_NE(std::string(e.what()).find("broke down"), std::string::npos);
  } catch (const PeerFault &) {
    peer = 1;
  }
  EXPECT_EQ(none, 0); // no rank went on as if nothing happened
  EXPECT_EQ(peer, 0);  // the breakdown is agreed on: every rank throws it
  MPI_Allreduce(MPI_IN_PLACE, &breakdown, 1, MPI_INT, MPI_SUM, PETSC_COMM_WORLD);
  EXPECT_EQ(breakdown, f->comm.size());
}

} // namespace
