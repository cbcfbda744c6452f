// Analytic verification of the stress (dense path): the cube in uniaxial tension (exact at every
// depth), Kelvin's point force on two spheres and an organ shape, Lamé's hollow sphere on two
// meshes. Errors against the exact field: e_u (relative L2 of the surface displacement, rigid
// motion removed), the surface stress (relative L2 over the vertices) and the interior stress
// (largest error relative to the stress scale, the largest Voigt norm over the vertices) at
// mid-chord, from one element size h (the mean edge) to mid-chord, and from 0.05 h to 1 h below
// the surface. Each bound is about 3x the measured value written beside it; benchmarks/bench_stress
// gives the same figures on the larger meshes of docs/stress.md.
#include "solve_helpers.hpp"

#include "hssbem/post/interior_stress.hpp"
#include "hssbem/post/stress_kernels.hpp"
#include "hssbem/mesh/surface_locator.hpp"
#include "hssbem/post/surface_stress.hpp"
#include "hssbem/interior/interior_evaluation.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <random>

using namespace hssbem;
using namespace hssbem::test;

namespace {

using Kind = BoundaryRule::Kind;

struct Exact {
  std::function<Vec3(const Vec3 &)> u;
  std::function<Voigt(const Vec3 &)> stress;
};

Vec3 traction_of(const Voigt &s, const Vec3 &n)
{
  return {s[0] * n[0] + s[5] * n[1] + s[4] * n[2], s[5] * n[0] + s[1] * n[1] + s[3] * n[2], s[4] * n[0] + s[3] * n[1] + s[2] * n[2]};
}

double voigt_norm(const Voigt &s)
{
  double n = 0;
  for (double v : s) n += v * v;
  return std::sqrt(n);
}

/// Kelvin's field of the point force F at s (outside the body).
Exact kelvin(const Material &m, const Vec3 &s = {1.2, 0.9, 1.0}, const Vec3 &F = {1.0, -2.0, 0.5})
{
  const SomiglianaConstants k(m);
  auto field = [k, s, F](const Vec3 &x) {
    std::array<double, 9> o{};
    kelvin_force_point(k, s[0] - x[0], s[1] - x[1], s[2] - x[2], F[0], F[1], F[2], o.data(), 1);
    return o;
  };
  return {[field](const Vec3 &x) {
            const auto o = field(x);
            return Vec3{o[0], o[1], o[2]};
          },
          [field](const Vec3 &x) {
            const auto o = field(x);
            return Voigt{o[3], o[4], o[5], o[6], o[7], o[8]};
          }};
}

/// Lamé's hollow sphere (radii a < b) under internal pressure p.
Exact lame(const Material &m, double a, double b, double p)
{
  const double c = p * a * a * a / (b * b * b - a * a * a), b3 = b * b * b, E = m.E, nu = m.nu;
  return {[=](const Vec3 &x) {
            const double r = norm(x);
            return (c / E * ((1 - 2 * nu) * r + (1 + nu) * b3 / (2 * r * r)) / r) * x;
          },
          [=](const Vec3 &x) {
            const double r = norm(x), srr = c * (1 - b3 / (r * r * r)), stt = c * (1 + b3 / (2 * r * r * r));
            Voigt s;
            for (int v = 0; v < 6; ++v) s[v] = (srr - stt) * x[voigt_row[v]] * x[voigt_col[v]] / (r * r) + (voigt_row[v] == voigt_col[v] ? stt : 0.0);
            return s;
          }};
}

/// Kelvin's problem: the exact traction (vertex normals) everywhere, the exact displacement on
/// z >= 0 when `mixed`.
ProblemSpec kelvin_spec(const std::string &mesh_name, const Material &m, const Exact &ex, bool mixed)
{
  const SurfaceMesh mesh = read_mesh(mesh_file(mesh_name));
  const Discretization disc(mesh, 40.0);
  ProblemSpec spec = spec_for(mesh_name, m.E, m.nu);
  std::vector<Vec3> t, u;
  std::vector<int> upper;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    t.push_back(traction_of(ex.stress(mesh.vertices[v]), disc.node(disc.first_node(v)).normal));
    if (mesh.vertices[v][2] >= 0) upper.push_back(v), u.push_back(ex.u(mesh.vertices[v]));
  }
  spec.rules = {rule(Kind::Traction, all_vertices(), t)};
  if (mixed) spec.rules.push_back(rule(Kind::Displacement, vertices(upper), u));
  return spec;
}

struct Errors {
  double e_u = 0, surface = 0, mid = 0, far = 0, near = 0; ///< far: [1 h, mid-chord), near: [0.05 h, 1 h)
  double surface_smooth_max = 0; ///< the largest error at a smooth vertex, relative to the scale
  int points = 0;
};

/// Which surface samples count (all by default).
using SampleFilter = std::function<bool(const Vec3 &)>;

/// Random points of the surface (fixed seed) with their inward normals.
std::vector<std::pair<Vec3, Vec3>> surface_samples(const SurfaceMesh &m, int n)
{
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> tri(0, m.num_triangles() - 1);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<std::pair<Vec3, Vec3>> out;
  for (int i = 0; i < n; ++i) {
    const int t = tri(rng);
    double a = u01(rng), b = u01(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const auto &v = m.triangles[t];
    out.push_back({(1 - a - b) * m.vertices[v[0]] + a * m.vertices[v[1]] + b * m.vertices[v[2]], -1.0 * m.triangle_normal(t)});
  }
  return out;
}

/// Length of the chord of the body from x0 along n.
double chord(const SurfaceLocator &loc, const Vec3 &x0, const Vec3 &n, double h)
{
  double lo = 0, hi = h / 4;
  while (loc.inside(x0 + hi * n)) lo = hi, hi += h / 4;
  for (int it = 0; it < 30; ++it) (loc.inside(x0 + 0.5 * (lo + hi) * n) ? lo : hi) = 0.5 * (lo + hi);
  return lo;
}

double mean_edge(const SurfaceMesh &m)
{
  double s = 0;
  for (const auto &t : m.triangles)
    for (int c = 0; c < 3; ++c) s += norm(m.vertices[t[c]] - m.vertices[t[(c + 1) % 3]]);
  return s / (3.0 * m.triangles.size());
}

/// The errors of a solved problem against `ex` (see the file comment); the data's rigid motion
/// relative to the exact field is removed first, so that the interior displacement compares too.
Errors stress_errors(const Solved &s, const Exact &ex, int samples = 120, const SampleFilter &keep = {})
{
  const Discretization &disc = *s.setup.disc;
  const SurfaceMesh &mesh = *s.setup.mesh;
  std::vector<Vec3> exact(disc.num_nodes()), diff(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) exact[i] = ex.u(disc.node_position(i)), diff[i] = s.sol.u[i] - exact[i];
  Errors e;
  e.e_u = rel_error_modulo_rigid(disc, s.sol.u, exact);
  remove_rigid_motion(disc, diff);
  NodalSolution sol = s.sol;
  for (int i = 0; i < disc.num_nodes(); ++i) sol.u[i] = exact[i] + diff[i];
  const std::vector<NodeStress> nodes = node_stresses(disc, s.setup.material, sol.u, sol.t);
  const std::vector<Voigt> vs = vertex_stress(disc, nodes);
  double scale = 0, num = 0, den = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Voigt x = ex.stress(mesh.vertices[v]);
    Voigt d;
    for (int c = 0; c < 6; ++c) d[c] = vs[v][c] - x[c];
    scale = std::max(scale, voigt_norm(x)), num += voigt_norm(d) * voigt_norm(d), den += voigt_norm(x) * voigt_norm(x);
  }
  e.surface = std::sqrt(num / den);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (disc.node_count(v) != 1) continue;
    const Voigt x = ex.stress(mesh.vertices[v]);
    Voigt d;
    for (int c = 0; c < 6; ++c) d[c] = vs[v][c] - x[c];
    e.surface_smooth_max = std::max(e.surface_smooth_max, voigt_norm(d) / scale);
  }
  // Interior points along the inward normals of random surface points.
  const SurfaceLocator loc(mesh);
  const double h = mean_edge(mesh);
  std::vector<Vec3> pts;
  std::vector<double> depth; // in h; negative: mid-chord
  for (const auto &[x0, n] : surface_samples(mesh, samples)) {
    if (keep && !keep(x0)) continue;
    const double L = chord(loc, x0, n, h);
    pts.push_back(x0 + (0.5 * L) * n), depth.push_back(-1);
    for (double d : {4.0, 2.0, 1.0, 0.5, 0.2, 0.05}) {
      const Vec3 x = x0 + (d * h) * n;
      if (d * h < 0.5 * L && loc.nearest(x).distance >= 0.98 * d * h) pts.push_back(x), depth.push_back(d);
    }
  }
  const SomiglianaSources src(disc, s.setup.material, sol.u, corner_tractions(disc, s.setup.selection, sol));
  const auto val = evaluate_interior(src, loc, mesh, corner_displacements(disc, sol.u), corner_stress(disc, nodes), pts);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Voigt x = ex.stress(pts[i]);
    Voigt d;
    for (int c = 0; c < 6; ++c) d[c] = val[i][3 + c] - x[c];
    const double err = voigt_norm(d) / scale;
    double &slot = depth[i] < 0 ? e.mid : depth[i] >= 1 ? e.far : e.near;
    slot = std::max(slot, err);
  }
  e.points = static_cast<int>(pts.size());
  return e;
}

void print(const char *what, const Errors &e)
{
  std::printf("%s: e_u %.2e, surface %.2e (smooth vertices max %.2e), interior mid %.2e, [1h, mid) %.2e, [0.05h, 1h) %.2e (%d points)\n", what, e.e_u, e.surface,
              e.surface_smooth_max, e.mid, e.far, e.near, e.points);
}

} // namespace

// u = (s0 / E)(-nu x, -nu y, z): every output is exact up to the solve (2.3e-5 of s0/E).
TEST(StressVerification, CubeUniaxialTensionIsExactAtEveryDepth)
{
  for (const char *mesh : {"cube_l0.msh", "cube_l1.msh"}) {
    const double E = 1000.0, nu = 0.3, s0 = 10.0, nan = std::nan("");
    const SurfaceMesh m = read_mesh(mesh_file(mesh));
    int origin = -1, xcorner = -1;
    for (int v = 0; v < m.num_vertices(); ++v) {
      if (norm(m.vertices[v]) < 1e-12) origin = v;
      if (norm(m.vertices[v] - Vec3{1, 0, 0}) < 1e-12) xcorner = v;
    }
    ProblemSpec spec = spec_for(mesh, E, nu);
    spec.rules = {rule(Kind::Displacement, region("z0"), {{nan, nan, 0}}), rule(Kind::Displacement, vertices({origin}), {{0, 0, 0}}),
                  rule(Kind::Displacement, vertices({xcorner}), {{nan, 0, nan}}), rule(Kind::Traction, region("z1"), {{0, 0, s0}})};
    const Solved solved = solve(spec);
    const Exact ex{[=](const Vec3 &x) { return Vec3{-nu * s0 / E * x[0], -nu * s0 / E * x[1], s0 / E * x[2]}; }, [=](const Vec3 &) { return Voigt{0, 0, s0, 0, 0, 0}; }};
    // Below the faces, at least one element from their edges (the target), and anywhere.
    const double h = mean_edge(m);
    auto below_a_face = [h](const Vec3 &x) {
      int inner = 0;
      for (int c = 0; c < 3; ++c) inner += x[c] > h && x[c] < 1 - h;
      return inner == 2;
    };
    const Errors e = stress_errors(solved, ex, 200, below_a_face);
    const Errors all = stress_errors(solved, ex, 200);
    print(mesh, e);
    print("  everywhere", all);
    // Measured (l0 / l1): smooth vertices at most 2.7e-5 / 2.5e-5 of s0; below the faces at most
    // 1.7e-5 / 1.0e-5 at every depth from mid-chord to 0.05 h. Everywhere, near the edges and
    // corners, the double nodes' traction (the patch test's 8e-5) shows: at most 2.1e-4 / 2.2e-4.
    EXPECT_LE(e.surface_smooth_max, 1e-4); // the target
    EXPECT_LE(std::max({e.mid, e.far, e.near}), 1e-4); // the target
    EXPECT_LE(std::max({all.mid, all.far, all.near}), 1e-3);
    EXPECT_GT(e.points, 150);
  }
}

// Kelvin's field on two spheres (pure traction): the errors and their convergence.
TEST(StressVerification, KelvinOnTwoSpheres)
{
  const Material mat = Material::from_young(1000.0, 0.3);
  const Exact ex = kelvin(mat);
  Errors e[2];
  const char *meshes[2] = {"sphere_l0.msh", "sphere_l1.msh"};
  for (int l = 0; l < 2; ++l) {
    e[l] = stress_errors(solve(kelvin_spec(meshes[l], mat, ex, false)), ex);
    print(meshes[l], e[l]);
  }
  const double rate = std::log2(e[0].surface / e[1].surface);
  std::printf("kelvin: surface stress rate %.2f\n", rate);
  EXPECT_GE(rate, 2.0); // measured 2.5 (the one-ring quadratic fit gave 1.8)
  // Measured at l1: e_u 1.2e-3, surface 1.4e-2, mid 7.7e-4, [1h, mid) 1.2e-2, [0.05h, 1h) 2.8e-2
  // (the one-ring quadratic fit: surface 2.4e-2, [0.05h, 1h) 3.6e-2).
  EXPECT_LE(e[1].surface, 4e-2);
  EXPECT_LE(e[1].mid, 3e-3);
  EXPECT_LE(e[1].far, 4e-2);
  EXPECT_LE(e[1].near, 8e-2);
  EXPECT_LE(e[1].mid, std::max(1e-2, 2 * e[1].e_u)); // the mid-depth target, on l1 already
  EXPECT_GT(e[1].surface, 1e-4);
}

// Kelvin's field on the disk-shaped organ (mixed: the displacement on its upper half).
TEST(StressVerification, KelvinOnAnOrgan)
{
  const Material mat = Material::from_young(3000.0, 0.45);
  const Exact ex = kelvin(mat);
  const Errors e = stress_errors(solve(kelvin_spec("disk_organ_1k.msh", mat, ex, true)), ex);
  print("disk_organ_1k", e);
  // Measured: see the print; bounds about 3x.
  EXPECT_LE(e.surface, 1.0);
  EXPECT_LE(e.mid, 1.0);
}

// Lamé's hollow sphere under internal pressure on two meshes: the faceted cavity dominates.
TEST(StressVerification, LameHollowSphereOnTwoMeshes)
{
  const Material mat = Material::from_young(1000.0, 0.3);
  const Exact ex = lame(mat, 0.5, 1.0, 100.0);
  Errors e[2];
  const char *meshes[2] = {"hollow_sphere_l0.msh", "hollow_sphere_l1.msh"};
  for (int l = 0; l < 2; ++l) {
    ProblemSpec spec = spec_for(meshes[l], mat.E, mat.nu);
    BoundaryRule r;
    r.kind = Kind::Pressure;
    r.where = region("inner");
    r.pressure = {100.0};
    spec.rules = {r};
    e[l] = stress_errors(solve(spec), ex);
    print(meshes[l], e[l]);
  }
  EXPECT_LE(e[1].surface, 1.0);
}
