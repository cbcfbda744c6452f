// The operator primitive against Kelvin's solution, rigid motions and itself (blocks vs rows).
#include "hssbem/bem/bem_operator.hpp"
#include "test_shapes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <petscsys.h>
#include <petscblaslapack.h>

#include <numeric>

using namespace hssbem;
using hssbem::test::icosphere;
using hssbem::test::KelvinField;

namespace {

std::vector<int> iota(int n)
{
  std::vector<int> v(n);
  std::iota(v.begin(), v.end(), 0);
  return v;
}

struct Dense {
  int n;
  std::vector<double> H, G;
};

Dense dense_hg(const BemOperator &op)
{
  const int n = 3 * op.num_nodes();
  Dense d{n, std::vector<double>(size_t(n) * n), std::vector<double>(size_t(n) * n)};
  op.fill_hg(iota(op.num_nodes()), iota(op.num_nodes()), d.H.data(), d.G.data(), n);
  return d;
}

std::vector<double> matvec(const std::vector<double> &M, int n, const std::vector<double> &x)
{
  std::vector<double> y(n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) y[i] += M[size_t(i) * n + j] * x[j];
  return y;
}

double rel_l2(const std::vector<double> &a, const std::vector<double> &b)
{
  double num = 0, den = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    num += (a[i] - b[i]) * (a[i] - b[i]);
    den += b[i] * b[i];
  }
  return std::sqrt(num / den);
}

/// Solve the Dirichlet problem (u given everywhere) for the Kelvin field; returns the
/// relative L2 error of the traction at the nodes.
double kelvin_dirichlet_error(int levels)
{
  const SurfaceMesh mesh = icosphere(levels);
  const Discretization disc(mesh, 40.0);
  const Material mat{1000.0, 0.3};
  BemOperator op(disc, mat);
  const KelvinField k{mat, {1.2, 0.9, 1.0}, {1.0, -2.0, 0.5}};
  Dense d = dense_hg(op);
  std::vector<double> u(d.n), t(d.n);
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const Vec3 ui = k.displacement(disc.node(i).point), ti = k.traction(disc.node(i).point, disc.node(i).normal);
    for (int c = 0; c < 3; ++c) u[3 * i + c] = ui[c], t[3 * i + c] = ti[c];
  }
  std::vector<double> b = matvec(d.H, d.n, u);
  // LAPACK is column-major: solve G^T^T, i.e. transpose G first.
  std::vector<double> Gt(d.G.size());
  for (int i = 0; i < d.n; ++i)
    for (int j = 0; j < d.n; ++j) Gt[size_t(j) * d.n + i] = d.G[size_t(i) * d.n + j];
  PetscBLASInt n = d.n, one = 1, info = 0;
  std::vector<PetscBLASInt> piv(d.n);
  LAPACKgesv_(&n, &one, Gt.data(), &n, piv.data(), b.data(), &n, &info);
  EXPECT_EQ(info, 0);
  return rel_l2(b, t);
}

} // namespace

TEST(Operator, RigidMotionsGiveNoTraction)
{
  const SurfaceMesh mesh = icosphere(2);
  const Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material{1000.0, 0.3});
  Dense d = dense_hg(op);
  // translation: exact by construction; rotation about an axis through (0.1, 0.2, 0.3)
  std::vector<double> rot(d.n);
  double scale = 0;
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const Vec3 u = cross(Vec3{0.3, -0.5, 0.8}, disc.node(i).point - Vec3{0.1, 0.2, 0.3});
    for (int c = 0; c < 3; ++c) rot[3 * i + c] = u[c];
  }
  for (double v : d.H) scale = std::max(scale, std::abs(v));
  const std::vector<double> r = matvec(d.H, d.n, rot);
  double rmax = 0, umax = 0;
  for (int i = 0; i < d.n; ++i) rmax = std::max(rmax, std::abs(r[i])), umax = std::max(umax, std::abs(rot[i]));
  // the diagonal block is ~0.5; a rotation must be annihilated to quadrature/geometry accuracy
  EXPECT_LT(rmax / umax, 1e-4);
  EXPECT_GT(scale, 0.3);
}

TEST(Operator, KelvinDirichletConverges)
{
  const double e1 = kelvin_dirichlet_error(2), e2 = kelvin_dirichlet_error(3);
  std::printf("kelvin dirichlet traction error: %.3e %.3e order %.2f\n", e1, e2, std::log2(e1 / e2));
  EXPECT_LT(e2, 2.5e-2);
  EXPECT_GT(std::log2(e1 / e2), 1.5);
}

TEST(Operator, BlocksEqualTheFullMatrixWithSharpNodes)
{
  const SurfaceMesh mesh = hssbem::test::unit_cube(2);
  const Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material{1000.0, 0.3});
  const Dense d = dense_hg(op);
  op.compute_rigid_body_terms(iota(disc.num_nodes()));
  const std::vector<int> I = {0, 5, 7, 12, disc.num_nodes() - 1}, J = {1, 5, 9, 12, 20, 21};
  const long ld = 3 * J.size();
  std::vector<double> H(3 * I.size() * ld), G(H.size());
  op.fill_hg(I, J, H.data(), G.data(), ld);
  double err = 0, scale = 0;
  for (std::size_t r = 0; r < 3 * I.size(); ++r)
    for (std::size_t c = 0; c < 3 * J.size(); ++c) {
      const size_t R = 3 * I[r / 3] + r % 3, C = 3 * J[c / 3] + c % 3;
      err = std::max({err, std::abs(H[r * ld + c] - d.H[R * d.n + C]), std::abs(G[r * ld + c] - d.G[R * d.n + C])});
      scale = std::max({scale, std::abs(d.H[R * d.n + C]), std::abs(d.G[R * d.n + C])});
    }
  EXPECT_LT(err, 1e-13 * scale);
  EXPECT_GT(scale, 0.0);
}

TEST(Operator, SelectedEntriesEqualTheFullBlocks)
{
  // selected evaluates row points eight at a time (the 7-point rule with the points as SIMD
  // lanes, the singular and near-singular pairs one by one): every requested entry, for row
  // counts that leave a partial batch, sharp nodes and Gn columns, equals fill_hg's.
  const SurfaceMesh mesh = hssbem::test::unit_cube(2);
  const Discretization disc(mesh, 40.0);
  const BemOperator op(disc, Material{1000.0, 0.3});
  BemOperator::Workspace ws(op);
  const int nn = disc.num_nodes();
  std::vector<int> I, J;
  for (int i = 0; i < nn; i += 2) I.push_back(i); // 13 or more rows: one full batch and a partial one
  for (int j = 0; j < nn; j += 3) J.push_back(j);
  ASSERT_GT(I.size(), 9u);
  const long ld = 3 * static_cast<long>(J.size()), ldn = static_cast<long>(J.size());
  std::vector<double> H(3 * I.size() * ld), G(H.size()), Gn(3 * I.size() * ldn);
  op.fill_hg_without_rigid(I, J, H.data(), G.data(), ld, Gn.data(), ldn, ws);
  const auto reference = [&](const double *h, const double *g, const double *gn, std::size_t r, std::size_t jq, int kind) {
    return kind < 3 ? h[r * ld + 3 * jq + kind] : kind < 6 ? g[r * ld + 3 * jq + kind - 3] : gn[r * ldn + jq];
  };
  // Rows: every component of some nodes, one of others; columns: assorted kinds.
  EntrySelection sel;
  std::vector<std::pair<std::size_t, int>> rows, cols; // (position in I or J, component or kind)
  for (std::size_t p = 0; p < I.size(); ++p)
    for (int a = 0; a < 3; ++a)
      if (p % 3 == 0 || a == static_cast<int>(p % 3)) rows.push_back({p, a});
  for (std::size_t q = 0; q < J.size(); ++q)
    for (int k = 0; k < 7; ++k)
      if ((q + k) % 2 == 0) cols.push_back({q, k});
  for (std::size_t r = 0; r < rows.size(); ++r) sel.add_row(I[rows[r].first], rows[r].second, static_cast<int>(r));
  for (std::size_t c = 0; c < cols.size(); ++c) sel.add_col(J[cols[c].first], cols[c].second, static_cast<int>(c));
  sel.finish();
  const long rs = 1, cs = static_cast<long>(rows.size());
  // NaN where nothing is written: every entry of the selection must be.
  std::vector<double> out(rows.size() * cols.size(), std::nan(""));
  op.selected(sel, out.data(), rs, cs, ws);
  double err = 0, scale = 0;
  int unwritten = 0;
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t c = 0; c < cols.size(); ++c) {
      const double want = reference(H.data(), G.data(), Gn.data(), 3 * rows[r].first + rows[r].second, cols[c].first, cols[c].second);
      unwritten += std::isnan(out[r * rs + c * cs]);
      err = std::max(err, std::abs(out[r * rs + c * cs] - want));
      scale = std::max(scale, std::abs(want));
    }
  EXPECT_EQ(unwritten, 0);
  EXPECT_GT(scale, 0.0);
  EXPECT_LT(err, 1e-13 * scale);

  // Arbitrary points as rows: near a face (its triangles subdivided), on no node, and far away.
  std::vector<Vec3> X;
  for (int p = 0; p < 11; ++p) X.push_back(p % 3 == 0 ? Vec3{0.3 + 0.04 * p, 0.45, 1.02} : Vec3{2.0 + p, -1.5, 0.5 * p});
  std::vector<double> HX(3 * X.size() * ld), GX(HX.size()), GnX(3 * X.size() * ldn);
  op.fill_hg_at_points(X, J, HX.data(), GX.data(), ld, GnX.data(), ldn, ws);
  EntrySelection at;
  for (std::size_t c = 0; c < cols.size(); ++c) at.add_col(J[cols[c].first], cols[c].second, static_cast<int>(c));
  at.finish();
  std::vector<double> outX(3 * X.size() * cols.size(), std::nan(""));
  const long csx = static_cast<long>(3 * X.size());
  op.selected_at_points(X, at, outX.data(), 1, csx, ws);
  err = scale = 0;
  unwritten = 0;
  for (std::size_t r = 0; r < 3 * X.size(); ++r)
    for (std::size_t c = 0; c < cols.size(); ++c) {
      const double want = reference(HX.data(), GX.data(), GnX.data(), r, cols[c].first, cols[c].second);
      unwritten += std::isnan(outX[r + c * csx]);
      err = std::max(err, std::abs(outX[r + c * csx] - want));
      scale = std::max(scale, std::abs(want));
    }
  EXPECT_EQ(unwritten, 0);
  EXPECT_GT(scale, 0.0);
  EXPECT_LT(err, 1e-13 * scale);
}

TEST(Operator, SystemColumnsAreHWhereUIsUnknownAndMinusGWhereTIs)
{
  const SurfaceMesh mesh = icosphere(1);
  const Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material{1000.0, 0.3});
  const Dense d = dense_hg(op);
  SystemSelection sel{std::vector<std::array<bool, 3>>(disc.num_nodes()), std::vector<Vec3>(disc.num_nodes()), {}};
  for (int i = 0; i < disc.num_nodes(); ++i)
    for (int c = 0; c < 3; ++c) {
      sel.displacement_known[i][c] = (i * 3 + c) % 7 < 3; // a mixed pattern
      sel.known[i][c] = std::sin(1.0 + i + 0.3 * c);
    }
  std::vector<double> A(size_t(d.n) * d.n), b(d.n);
  fill_system_block(op, sel, iota(disc.num_nodes()), iota(disc.num_nodes()), A.data(), d.n, b.data());
  double err = 0;
  for (int r = 0; r < d.n; ++r) {
    double br = 0;
    for (int c = 0; c < d.n; ++c) {
      const bool uk = sel.displacement_known[c / 3][c % 3];
      const double expect = uk ? -d.G[size_t(r) * d.n + c] : d.H[size_t(r) * d.n + c];
      err = std::max(err, std::abs(A[size_t(r) * d.n + c] - expect));
      br += uk ? -d.H[size_t(r) * d.n + c] * sel.known[c / 3][c % 3] : d.G[size_t(r) * d.n + c] * sel.known[c / 3][c % 3];
    }
    err = std::max(err, std::abs(b[r] - br));
  }
  EXPECT_LT(err, 1e-12);
}
