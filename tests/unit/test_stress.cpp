// Stress kernels against finite differences of the displacement kernels, the surface stress on
// linear fields (exact, sharp vertices included), and the interior identities on a linear field.
#include "hssbem/post/interior_stress.hpp"
#include "hssbem/post/near_surface.hpp"
#include "hssbem/mesh/surface_locator.hpp"
#include "hssbem/post/surface_stress.hpp"
#include "hssbem/interior/interior_evaluation.hpp"
#include "hssbem/core/lapack.hpp"

#include "test_shapes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

using namespace hssbem;

namespace {

/// Displacement (3) and stress (6) at x of one source point y with force f, density m, normal n.
std::array<double, 9> point_field(const SomiglianaConstants &k, const Vec3 &x, const Vec3 &y, const Vec3 &f, const Vec3 &m, const Vec3 &n)
{
  std::array<double, 9> out{};
  const Vec3 d = y - x;
  somigliana_point(k, d[0], d[1], d[2], f[0], f[1], f[2], m[0], m[1], m[2], n[0], n[1], n[2], out.data(), 1);
  return out;
}

const Material steel{1000.0, 0.3};
const Mat3 G_lin{0.01, 0.002, -0.003, 0.004, -0.005, 0.001, 0.0, 0.003, 0.02};

Vec3 times(const Mat3 &M, const Vec3 &x)
{
  return {M[0] * x[0] + M[1] * x[1] + M[2] * x[2], M[3] * x[0] + M[4] * x[1] + M[5] * x[2], M[6] * x[0] + M[7] * x[1] + M[8] * x[2]};
}

Vec3 traction(const Voigt &s, const Vec3 &n)
{
  return {s[0] * n[0] + s[5] * n[1] + s[4] * n[2], s[5] * n[0] + s[1] * n[1] + s[3] * n[2], s[4] * n[0] + s[3] * n[1] + s[2] * n[2]};
}

double voigt_diff(const Voigt &a, const Voigt &b)
{
  double m = 0;
  for (int v = 0; v < 6; ++v) m = std::max(m, std::abs(a[v] - b[v]));
  return m;
}

} // namespace

// σ of the kernels is Hooke's law applied to the x-derivatives of their displacement.
TEST(StressKernels, MatchFiniteDifferencesOfTheDisplacementKernels)
{
  for (double nu : {0.0, 0.3, 0.49}) {
    const Material mat{1000.0, nu};
    const SomiglianaConstants k(mat);
    const Vec3 x{0.1, -0.2, 0.3}, y{0.7, 0.4, -0.1}, f{0.3, -1.1, 0.6}, m{0.02, 0.05, -0.04}, n = normalized(Vec3{0.2, 0.9, -0.4});
    const double h = 1e-5;
    Mat3 G{};
    for (int j = 0; j < 3; ++j) {
      Vec3 xp = x, xm = x;
      xp[j] += h;
      xm[j] -= h;
      const auto up = point_field(k, xp, y, f, m, n), um = point_field(k, xm, y, f, m, n);
      for (int i = 0; i < 3; ++i) G[3 * i + j] = (up[i] - um[i]) / (2 * h);
    }
    const Voigt fd = hooke_stress(mat, G);
    const auto out = point_field(k, x, y, f, m, n);
    double err = 0, scale = 0;
    for (int v = 0; v < 6; ++v) err = std::max(err, std::abs(out[3 + v] - fd[v])), scale = std::max(scale, std::abs(fd[v]));
    std::printf("nu %.2f: stress kernel vs finite differences %.2e (scale %.2e)\n", nu, err / scale, scale);
    EXPECT_LE(err / scale, 1e-7); // measured 1.9e-10 (nu 0) .. 9.3e-9 (nu 0.49, the finite differences' own error)
    EXPECT_GT(scale, 1e-3);
    // The force-only kernel is the same with m = 0.
    std::array<double, 9> q{};
    const Vec3 d = y - x;
    kelvin_force_point(k, d[0], d[1], d[2], f[0], f[1], f[2], q.data(), 1);
    const auto ref = point_field(k, x, y, f, Vec3{}, n);
    for (int c = 0; c < 9; ++c) EXPECT_NEAR(q[c], ref[c], 1e-14 * scale);
  }
}

TEST(StressTensor, VonMisesAndPrincipalStresses)
{
  const Voigt uniaxial{10, 0, 0, 0, 0, 0}, shear{0, 0, 0, 0, 0, 4};
  EXPECT_NEAR(von_mises(uniaxial), 10.0, 1e-12);
  EXPECT_NEAR(von_mises(shear), 4.0 * std::sqrt(3.0), 1e-12);
  const auto p = principal_stresses(Voigt{1, 2, 3, 0.5, -0.2, 0.7});
  EXPECT_GE(p[0], p[1]);
  EXPECT_GE(p[1], p[2]);
  EXPECT_NEAR(p[0] + p[1] + p[2], 6.0, 1e-12);
  const auto s = principal_stresses(shear);
  EXPECT_NEAR(s[0], 4.0, 1e-12);
  EXPECT_NEAR(s[2], -4.0, 1e-12);
}

class SurfaceStressLinear : public ::testing::TestWithParam<int> {};

// u = G x and t = σ n give σ at every node: smooth nodes (quadratic fit), and the double nodes of
// a cube's edges and corners (linear fit over each face group).
TEST_P(SurfaceStressLinear, IsExactForALinearField)
{
  const SurfaceMesh mesh = GetParam() == 0 ? test::icosphere(2) : test::unit_cube(4);
  const Discretization disc(mesh, 40.0);
  const Voigt exact = hooke_stress(steel, G_lin);
  std::vector<Vec3> u(disc.num_nodes()), t(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) {
    u[i] = times(G_lin, disc.node_position(i));
    t[i] = traction(exact, disc.node(i).normal);
  }
  const auto nodes = node_stresses(disc, steel, u, t);
  double err = 0, gerr = 0;
  for (const auto &s : nodes) {
    err = std::max(err, voigt_diff(s.stress, exact));
    for (int m = 0; m < 9; ++m) gerr = std::max(gerr, std::abs(s.gradient[m] - G_lin[m]));
  }
  std::printf("linear field on %s: max stress error %.2e (scale %.1f), gradient %.2e\n", GetParam() == 0 ? "icosphere" : "cube", err, von_mises(exact), gerr);
  EXPECT_LE(err, 1e-10 * von_mises(exact));
  EXPECT_LE(gerr, 1e-12);
  if (GetParam() == 1) EXPECT_EQ(disc.num_sharp_vertices(), 8 + 12 * 3);
  const auto corners = corner_stress(disc, nodes);
  for (const auto &tri : corners)
    for (const auto &s : tri) EXPECT_LE(voigt_diff(s, exact), 1e-10 * von_mises(exact));
}

INSTANTIATE_TEST_SUITE_P(Shapes, SurfaceStressLinear, ::testing::Values(0, 1));

// Somigliana's identities reproduce a linear field inside, at every depth the quadrature reaches.
TEST(InteriorStress, LinearFieldOnTheCube)
{
  const SurfaceMesh mesh = test::unit_cube(4);
  const Discretization disc(mesh, 40.0);
  const Voigt exact = hooke_stress(steel, G_lin);
  std::vector<Vec3> u(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) u[i] = times(G_lin, disc.node_position(i));
  std::vector<std::array<Vec3, 3>> t(mesh.triangles.size());
  for (int e = 0; e < mesh.num_triangles(); ++e)
    for (int c = 0; c < 3; ++c) t[e][c] = traction(exact, mesh.triangle_normal(e));
  const SomiglianaSources src(disc, steel, u, t);
  for (double depth : {0.5, 0.25, 0.1, 0.05, 0.01}) {
    const Vec3 x{0.37, 0.52, depth};
    double out[9] = {};
    src.add_all(x, out);
    const Vec3 ue = times(G_lin, x);
    double eu = 0, es = 0;
    for (int c = 0; c < 3; ++c) eu = std::max(eu, std::abs(out[c] - ue[c]));
    for (int v = 0; v < 6; ++v) es = std::max(es, std::abs(out[3 + v] - exact[v]));
    std::printf("cube, linear field, depth %.2f: displacement error %.2e, stress error %.2e (of %.1f)\n", depth, eu, es, von_mises(exact));
    // Measured with the default quadrature (near ratio 2): 1.4e-6 to 1.5e-5 of the stress, the
    // largest at depth 0.01 (0.04 element); ratio 3 gives 8e-8 to 5e-7, ratio 1.5 up to 5e-5.
    EXPECT_LE(es, 5e-5 * von_mises(exact));
    EXPECT_LE(eu, 1e-7);
  }
}

namespace {

/// Kelvin's field of a point force outside the unit sphere, as boundary data on a mesh: nodal
/// displacements and corner tractions with the triangles' normals.
struct KelvinData {
  std::vector<Vec3> u;
  std::vector<std::array<Vec3, 3>> t;
};

std::array<double, 9> kelvin_at(const SomiglianaConstants &k, const Vec3 &x)
{
  const Vec3 s{1.2, 0.9, 1.0}, F{1, -2, 0.5};
  std::array<double, 9> out{};
  kelvin_force_point(k, s[0] - x[0], s[1] - x[1], s[2] - x[2], F[0], F[1], F[2], out.data(), 1);
  return out;
}

KelvinData kelvin_data(const Discretization &disc, const SomiglianaConstants &k)
{
  const SurfaceMesh &mesh = disc.mesh();
  KelvinData d;
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const auto f = kelvin_at(k, disc.node_position(i));
    d.u.push_back({f[0], f[1], f[2]});
  }
  d.t.resize(mesh.triangles.size());
  for (int e = 0; e < mesh.num_triangles(); ++e)
    for (int c = 0; c < 3; ++c) {
      const auto f = kelvin_at(k, mesh.vertices[mesh.triangles[e][c]]);
      d.t[e][c] = traction(Voigt{f[3], f[4], f[5], f[6], f[7], f[8]}, mesh.triangle_normal(e));
    }
  return d;
}

std::vector<Vec3> random_points_in_ball(int n, double radius)
{
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> p;
  while (static_cast<int>(p.size()) < n) {
    const Vec3 x{u(rng), u(rng), u(rng)};
    if (norm(x) < 1) p.push_back(radius * x);
  }
  return p;
}

} // namespace

// The fast evaluation against the direct sums (every point against every triangle), with the
// source leaves' inner forces (the default) and without them: the inner forces take the place of
// particles near the leaves, at the same accuracy.
TEST(InteriorEvaluation, FastMatchesDirect)
{
  const SurfaceMesh mesh = test::icosphere(4); // 5120 triangles
  const Discretization disc(mesh, 40.0);
  const SomiglianaConstants k(steel);
  const KelvinData data = kelvin_data(disc, k);
  const SomiglianaSources src(disc, steel, data.u, data.t);
  const std::vector<Vec3> pts = random_points_in_ball(3000, 0.97);
  const std::vector<Vec3> sub(pts.begin(), pts.begin() + 200);
  InteriorEvaluationOptions direct;
  direct.direct = true;
  const std::vector<double> ref = InteriorEvaluator(src, direct).evaluate(sub);
  long long near_without = 0;
  for (const int inner : {0, InteriorEvaluationOptions{}.inner_points}) {
    InteriorEvaluationOptions fast;
    fast.inner_points = inner;
    const InteriorEvaluator evaluator(src, fast);
    const std::vector<double> v = evaluator.evaluate(pts);
    const InteriorEvaluationStats &st = evaluator.stats();
    EXPECT_GT(st.far_pairs, 100); // the far field is used
    if (inner == 0) {
      EXPECT_EQ(st.kernel_inner, 0);
      near_without = st.kernel_near;
    } else { // the inner forces are used, in place of particles
      EXPECT_GT(st.kernel_inner, 0);
      EXPECT_LT(st.kernel_near, 0.9 * near_without);
    }
    double eu = 0, nu = 0, es = 0, ns = 0;
    for (std::size_t i = 0; i < sub.size() * field_outputs; ++i) {
      const double d = v[i] - ref[i];
      (i % field_outputs < 3 ? eu : es) += d * d;
      (i % field_outputs < 3 ? nu : ns) += ref[i] * ref[i];
    }
    std::printf("inner points %d: fast vs direct: displacement %.2e, stress %.2e (relative L2); near particles %lld, inner kernels %lld\n", inner,
                std::sqrt(eu / nu), std::sqrt(es / ns), st.kernel_near, st.kernel_inner);
    EXPECT_LE(std::sqrt(eu / nu), 1.5e-6); // measured 4.0e-7 without inner forces, 4.4e-7 with
    EXPECT_LE(std::sqrt(es / ns), 6e-5); // measured 2.2e-5 without, 2.8e-5 with
    // A share of the points per rank: the shares add up to the whole, value for value.
    std::vector<double> sum(v.size(), 0.0);
    for (int part = 0; part < 3; ++part) {
      const std::vector<double> w = evaluator.evaluate(pts, part, 3);
      for (std::size_t i = 0; i < w.size(); ++i) sum[i] += w[i];
    }
    EXPECT_EQ(sum, v);
  }
  InteriorEvaluationOptions bad;
  bad.inner_ratio = bad.equivalent_ratio; // the inner check sphere must lie outside the equivalent sphere
  EXPECT_THROW(InteriorEvaluator(src, bad), std::invalid_argument);
}

// The fits' pseudo-inverses come from lapack::gesdd (divide and conquer): the same singular
// values as gesvd, and U diag(s) Vᵀ gives the matrix back.
TEST(InteriorEvaluation, GesddMatchesGesvd)
{
  const int m = 60, n = 45;
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  std::vector<double> A(static_cast<std::size_t>(m) * n);
  for (double &a : A) a = g(rng);
  std::vector<double> B = A, C = A, s(n), t(n), U(static_cast<std::size_t>(m) * n), Vt(static_cast<std::size_t>(n) * n), U2 = U, Vt2 = Vt;
  ASSERT_EQ(lapack::gesdd(m, n, B.data(), m, s.data(), U.data(), m, Vt.data(), n), 0);
  ASSERT_EQ(lapack::gesvd(m, n, C.data(), m, t.data(), U2.data(), m, Vt2.data(), n), 0);
  double ds = 0, dA = 0, nA = 0;
  for (int l = 0; l < n; ++l) ds = std::max(ds, std::abs(s[l] - t[l]) / t[0]);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < m; ++i) {
      double a = 0;
      for (int l = 0; l < n; ++l) a += U[static_cast<std::size_t>(l) * m + i] * s[l] * Vt[static_cast<std::size_t>(j) * n + l];
      dA = std::max(dA, std::abs(a - A[static_cast<std::size_t>(j) * m + i])), nA = std::max(nA, std::abs(A[static_cast<std::size_t>(j) * m + i]));
    }
  std::printf("gesdd against gesvd: singular values %.1e, reconstruction %.1e (relative)\n", ds, dA / nA);
  EXPECT_LE(ds, 1e-14); // measured 1.7e-15
  EXPECT_LE(dA / nA, 1e-14); // measured 2.5e-15
  EXPECT_GT(s[n - 1], 0.0); // a random matrix has full rank: every singular value was computed
}

TEST(SurfaceLocator, NearestPointAndWindingNumber)
{
  const SurfaceMesh mesh = test::unit_cube(4);
  const SurfaceLocator loc(mesh);
  EXPECT_NEAR(loc.winding_number({0.5, 0.5, 0.5}), 1.0, 1e-9);
  EXPECT_NEAR(loc.winding_number({0.01, 0.5, 0.98}), 1.0, 0.05);
  EXPECT_NEAR(loc.winding_number({1.3, 0.5, 0.5}), 0.0, 0.05);
  EXPECT_NEAR(loc.winding_number({-3, 4, 7}), 0.0, 0.05);
  const auto n = loc.nearest({0.3, 0.4, 0.93});
  EXPECT_NEAR(n.distance, 0.07, 1e-12);
  EXPECT_NEAR(n.point[2], 1.0, 1e-12);
  EXPECT_NEAR(n.bary[0] + n.bary[1] + n.bary[2], 1.0, 1e-12);
  EXPECT_EQ(loc.nearest({0.5, 0.5, 0.5}, 0.3).triangle, -1); // nothing within the limit
  const auto corner = loc.nearest({1.2, 1.1, -0.1});
  EXPECT_NEAR(corner.distance, std::sqrt(0.04 + 0.01 + 0.01), 1e-12);
}

// The flood fill of a grid agrees with the winding number at every point, on the cube (points on
// its faces are inside or outside by the winding number's rounding; they are left out) and on a
// sphere.
// Inside or outside from the nearest point's triangle (where it lies inside one) agrees with the
// winding number, near faces, edges and corners.
TEST(SurfaceLocator, InsideFromTheNearestPointMatchesTheWindingNumber)
{
  std::mt19937 rng(7);
  for (int shape = 0; shape < 2; ++shape) {
    const SurfaceMesh mesh = shape == 0 ? test::unit_cube(4) : test::icosphere(3);
    const SurfaceLocator loc(mesh);
    std::uniform_real_distribution<double> u(-1.3, 1.3);
    int inside = 0, checked = 0;
    while (checked < 2000) {
      const Vec3 x{u(rng), u(rng), u(rng)};
      const SurfaceLocator::Nearest n = loc.nearest(x, 0.1);
      if (n.triangle < 0 || n.distance < 1e-9) continue; // only points near the surface, not on it
      EXPECT_EQ(loc.inside(x, n), loc.inside(x)) << x[0] << " " << x[1] << " " << x[2];
      inside += loc.inside(x), ++checked;
    }
    EXPECT_GT(inside, checked / 10);
    EXPECT_LT(inside, checked - checked / 10);
  }
}

TEST(SurfaceLocator, GridInsideMatchesTheWindingNumber)
{
  for (int shape = 0; shape < 2; ++shape) {
    const SurfaceMesh mesh = shape == 0 ? test::unit_cube(4) : test::icosphere(3);
    const SurfaceLocator loc(mesh);
    const Vec3 origin = shape == 0 ? Vec3{-0.13, -0.11, -0.17} : Vec3{-1.2, -1.1, -1.15};
    const Vec3 step = shape == 0 ? Vec3{0.05, 0.06, 0.07} : Vec3{0.1, 0.09, 0.11};
    const std::array<int, 3> n = shape == 0 ? std::array<int, 3>{30, 25, 20} : std::array<int, 3>{25, 26, 22};
    const double deep_beyond = 0.1;
    const std::vector<signed char> side = grid_inside(loc, origin, step, n), marked = grid_inside(loc, origin, step, n, deep_beyond);
    int inside = 0, checked = 0, deep = 0;
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          const Vec3 x{origin[0] + i * step[0], origin[1] + j * step[1], origin[2] + k * step[2]};
          const double d = loc.nearest(x).distance;
          const int p = i + n[0] * (j + n[1] * k);
          // Marked deep: inside, and no surface within deep_beyond; else the same side.
          EXPECT_EQ(marked[p] == 2 ? 1 : marked[p], side[p]) << p;
          if (marked[p] == 2) {
            EXPECT_GE(d, deep_beyond) << x[0] << " " << x[1] << " " << x[2];
            ++deep;
          }
          if (d < 1e-9) continue;
          EXPECT_EQ(side[p], loc.inside(x) ? 1 : 0) << x[0] << " " << x[1] << " " << x[2];
          inside += side[p], ++checked;
        }
    EXPECT_GT(inside, checked / 10);
    EXPECT_LT(inside, checked);
    std::printf("grid %d: %d of %d inside points marked deep\n", shape, deep, inside);
    EXPECT_GT(deep, inside / 50); // the marking is used
  }
}

namespace {

/// The points of a regular grid, x fastest (grid_inside's numbering).
std::vector<Vec3> grid_points(const Vec3 &origin, const Vec3 &step, const std::array<int, 3> &n)
{
  std::vector<Vec3> pts;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) pts.push_back({origin[0] + i * step[0], origin[1] + j * step[1], origin[2] + k * step[2]});
  return pts;
}

} // namespace

// The plan of a grid is the same whether the sides come from the flood fill or from the winding
// number at every point: the same kinds, the same evaluation points in the same order (the plan
// is built in parallel and numbered afterwards).
TEST(InteriorPlan, GridSidesGiveTheSamePlan)
{
  const SurfaceMesh mesh = test::icosphere(3);
  const SurfaceLocator loc(mesh);
  const Vec3 origin{-1.05, -1.02, -1.07}, step{0.07, 0.08, 0.075};
  const std::array<int, 3> n{31, 27, 29};
  const std::vector<Vec3> pts = grid_points(origin, step, n);
  const std::vector<signed char> side = grid_inside(loc, origin, step, n);
  // The same with the points surely beyond the plan's search marked deep: no search for them.
  const std::vector<signed char> marked = grid_inside(loc, origin, step, n, InteriorPlan::search_reach(loc, mesh, {}));
  EXPECT_GT(std::count(marked.begin(), marked.end(), 2), 500);
  const InteriorPlan by_grid(loc, mesh, pts, {}, &side), by_marks(loc, mesh, pts, {}, &marked), by_winding(loc, mesh, pts);
  int band = 0;
  for (std::size_t p = 0; p < pts.size(); ++p) {
    EXPECT_EQ(by_grid.kind(p), by_winding.kind(p)) << p;
    EXPECT_EQ(by_marks.kind(p), by_winding.kind(p)) << p;
    band += by_grid.kind(p) == PointKind::Band;
  }
  EXPECT_GT(band, 500);
  EXPECT_EQ(by_grid.evaluation_points(), by_winding.evaluation_points());
  EXPECT_EQ(by_marks.evaluation_points(), by_winding.evaluation_points());
}

// The plan's staged search (the nearest surface point first within band × the 90th percentile
// of the longest edges, then among the longer triangles) gives the plan of one search within
// band × the longest edge, on a surface whose edges vary (a flattened, stretched sphere).
TEST(InteriorPlan, StagedSearchGivesTheSamePlan)
{
  SurfaceMesh mesh = test::icosphere(3);
  for (Vec3 &v : mesh.vertices) v = Vec3{1.6 * v[0], v[1], 0.35 * v[2]};
  const SurfaceLocator loc(mesh);
  const Vec3 origin{-1.65, -1.03, -0.37}, step{0.05, 0.045, 0.02};
  const std::array<int, 3> n{67, 47, 38};
  const std::vector<Vec3> pts = grid_points(origin, step, n);
  const std::vector<signed char> side = grid_inside(loc, origin, step, n);
  InteriorPlanOptions staged, single;
  single.staged_search = false;
  const InteriorPlan a(loc, mesh, pts, staged, &side), b(loc, mesh, pts, single, &side);
  int band = 0, deep = 0;
  for (std::size_t p = 0; p < pts.size(); ++p) {
    EXPECT_EQ(a.kind(p), b.kind(p)) << p;
    band += a.kind(p) == PointKind::Band, deep += a.kind(p) == PointKind::Deep;
  }
  std::printf("staged search: %d band and %d deep points, the same plan\n", band, deep);
  EXPECT_GT(band, 1000);
  EXPECT_GT(deep, 1000);
  EXPECT_EQ(a.evaluation_points(), b.evaluation_points());
}

// Points of the band take a quadratic through the surface value and two integrated points:
// exact for a linear field, on faces, near edges and at corners; outside points are NaN.
TEST(InteriorPlan, BandIsExactForALinearField)
{
  const SurfaceMesh mesh = test::unit_cube(4);
  const Discretization disc(mesh, 40.0);
  const SurfaceLocator loc(mesh);
  const Voigt exact = hooke_stress(steel, G_lin);
  const std::vector<Vec3> pts = {{0.5, 0.5, 0.99}, {0.01, 0.5, 0.99}, {0.02, 0.03, 0.01}, {0.5, 0.5, 0.5}, {0.3, 0.2, 1.0}, {1.5, 0.5, 0.5}};
  const InteriorPlan plan(loc, mesh, pts);
  EXPECT_EQ(plan.kind(0), PointKind::Band);
  EXPECT_EQ(plan.kind(3), PointKind::Deep);
  EXPECT_EQ(plan.kind(4), PointKind::Surface);
  EXPECT_EQ(plan.kind(5), PointKind::Outside);
  // The evaluation points get the exact field; the surface fields are exact.
  std::vector<double> values;
  for (const Vec3 &x : plan.evaluation_points()) {
    const Vec3 u = times(G_lin, x);
    values.insert(values.end(), u.begin(), u.end());
    values.insert(values.end(), exact.begin(), exact.end());
  }
  std::vector<std::array<Vec3, 3>> cu(mesh.triangles.size());
  std::vector<std::array<Voigt, 3>> cs(mesh.triangles.size());
  for (int e = 0; e < mesh.num_triangles(); ++e)
    for (int c = 0; c < 3; ++c) cu[e][c] = times(G_lin, mesh.vertices[mesh.triangles[e][c]]), cs[e][c] = exact;
  const std::vector<FieldValue> f = plan.finish(values, cu, cs);
  for (std::size_t p = 0; p + 1 < pts.size(); ++p) {
    const Vec3 u = times(G_lin, pts[p]);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[p][c], u[c], 1e-14) << p;
    for (int c = 0; c < 6; ++c) EXPECT_NEAR(f[p][3 + c], exact[c], 1e-12) << p;
  }
  EXPECT_TRUE(std::isnan(f[5][0]) && std::isnan(f[5][8]));
}
