// Stress benchmark: surface and interior stress against analytic solutions, error against depth
// for the near-surface treatments, and the fast interior evaluation's speed against the direct sums.
//
//   bench_stress --case kelvin|lame|tension --mesh FILE [--bc traction|mixed] [--nu x]
//                [--samples n] [--band b] [--methods plain,band,subtract] [--csv FILE]
//                [--speed n] [--direct-speed n] [--mat-type dense|h2]
//
// Prints e_u (relative L2 error of the surface displacement, rigid motion removed), the surface
// stress error (relative L2 over the vertices), and per depth (in element sizes h, the mean edge
// length) the largest and RMS interior stress error over the sample points, relative to the
// stress scale (the largest Voigt norm of the exact stress over the vertices), for each method:
// plain (the identities integrated at the point), band (interpolated along the normal within the
// band, near_surface.hpp), subtract (the identities of the data minus the linear field of the
// surface stress at the nearest point, O(triangles) per point: a reference).
#include "bench_support.hpp"

#include "hssbem/session/static_session.hpp"
#include "hssbem/post/interior_stress.hpp"
#include "hssbem/post/near_surface.hpp"
#include "hssbem/post/post.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/mesh/surface_locator.hpp"
#include "hssbem/post/surface_stress.hpp"
#include "hssbem/interior/interior_evaluation.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/problem/setup.hpp"

#include <petscsys.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <cmath>
#include <ctime>
#include <cstdio>
#include <fstream>
#include <map>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace hssbem;

struct Args {
  std::string kase = "kelvin", mesh, bc = "traction", methods = "plain,band,subtract", csv, mat_type = "dense";
  double nu = 0.3, band = 1.0, near_ratio = 2.0;
  int samples = 200, speed = 0, direct_speed = 0, equivalent_points = 128, target_leaf = 160, source_leaf = 32, grid_cells = 0, inner_points = 192;
  double check_ratio = 2.6, equivalent_ratio = 1.05, check_factor = 1.25, inner_ratio = 2.2;
};

Args parse(int argc, char **argv)
{
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(k + " needs a value");
      return argv[++i];
    };
    if (k == "--case") a.kase = next();
    else if (k == "--mesh") a.mesh = next();
    else if (k == "--bc") a.bc = next();
    else if (k == "--nu") a.nu = std::stod(next());
    else if (k == "--band") a.band = std::stod(next());
    else if (k == "--near-ratio") a.near_ratio = std::stod(next());
    else if (k == "--samples") a.samples = std::stoi(next());
    else if (k == "--methods") a.methods = next();
    else if (k == "--csv") a.csv = next();
    else if (k == "--speed") a.speed = std::stoi(next());
    else if (k == "--direct-speed") a.direct_speed = std::stoi(next());
    else if (k == "--mat-type") a.mat_type = next();
    else if (k == "--equivalent-points") a.equivalent_points = std::stoi(next());
    else if (k == "--grid-cells") a.grid_cells = std::stoi(next());
    else if (k == "--target-leaf") a.target_leaf = std::stoi(next());
    else if (k == "--source-leaf") a.source_leaf = std::stoi(next());
    else if (k == "--check-ratio") a.check_ratio = std::stod(next());
    else if (k == "--check-factor") a.check_factor = std::stod(next());
    else if (k == "--equivalent-ratio") a.equivalent_ratio = std::stod(next());
    else if (k == "--inner-points") a.inner_points = std::stoi(next());
    else if (k == "--inner-ratio") a.inner_ratio = std::stod(next());
    else throw std::invalid_argument("unknown argument " + k);
  }
  if (a.mesh.empty()) throw std::invalid_argument("give --mesh");
  return a;
}

/// An exact elastic field: displacement and stress.
struct Exact {
  std::function<Vec3(const Vec3 &)> u;
  std::function<Voigt(const Vec3 &)> stress;
};

Vec3 traction_of(const Voigt &s, const Vec3 &n)
{
  return {s[0] * n[0] + s[5] * n[1] + s[4] * n[2], s[5] * n[0] + s[1] * n[1] + s[3] * n[2], s[4] * n[0] + s[3] * n[1] + s[2] * n[2]};
}

Exact kelvin(const Material &m)
{
  const SomiglianaConstants k(m);
  const Vec3 s{1.2, 0.9, 1.0}, F{1.0, -2.0, 0.5};
  auto field = [k, s, F](const Vec3 &x) {
    std::array<double, 9> out{};
    kelvin_force_point(k, s[0] - x[0], s[1] - x[1], s[2] - x[2], F[0], F[1], F[2], out.data(), 1);
    return out;
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

/// Lamé's hollow sphere, inner radius a, outer b, internal pressure p.
Exact lame(const Material &m, double a, double b, double p)
{
  const double c = p * a * a * a / (b * b * b - a * a * a), b3 = b * b * b;
  const double E = m.E, nu = m.nu;
  return {[=](const Vec3 &x) {
            const double r = norm(x), ur = c / E * ((1 - 2 * nu) * r + (1 + nu) * b3 / (2 * r * r));
            return (ur / r) * x;
          },
          [=](const Vec3 &x) {
            const double r = norm(x), srr = c * (1 - b3 / (r * r * r)), stt = c * (1 + b3 / (2 * r * r * r));
            const Vec3 e = (1.0 / r) * x;
            Voigt s;
            for (int v = 0; v < 6; ++v) {
              const int i = voigt_row[v], j = voigt_col[v];
              s[v] = (srr - stt) * e[i] * e[j] + (i == j ? stt : 0.0);
            }
            return s;
          }};
}

constexpr double lame_pressure = 100.0, lame_inner = 0.5, lame_outer = 1.0, tension_load = 10.0;

Exact tension(const Material &m, double s0)
{
  return {[=](const Vec3 &x) { return Vec3{-m.nu * s0 / m.E * x[0], -m.nu * s0 / m.E * x[1], s0 / m.E * x[2]}; },
          [=](const Vec3 &) { return Voigt{0, 0, s0, 0, 0, 0}; }};
}

BoundaryRule rule(BoundaryRule::Kind kind, Selector where, std::vector<Vec3> rows)
{
  BoundaryRule r;
  r.kind = kind;
  r.where = std::move(where);
  r.rows = std::move(rows);
  return r;
}

Selector all_vertices() { return Selector{}; }
Selector region_sel(const std::string &name)
{
  Selector s;
  s.kind = Selector::Kind::Region;
  s.region_name = name;
  return s;
}
Selector vertex_sel(std::vector<int> v)
{
  Selector s;
  s.kind = Selector::Kind::Vertices;
  s.vertices = std::move(v);
  return s;
}

/// Angle-weighted vertex normals of a closed mesh (the smooth surface's normal to O(h²)).
std::vector<Vec3> vertex_normals(const SurfaceMesh &mesh)
{
  std::vector<Vec3> n(mesh.vertices.size(), Vec3{});
  for (int t = 0; t < mesh.num_triangles(); ++t)
    for (int c = 0; c < 3; ++c) {
      const auto &v = mesh.triangles[t];
      const Vec3 e1 = mesh.vertices[v[(c + 1) % 3]] - mesh.vertices[v[c]], e2 = mesh.vertices[v[(c + 2) % 3]] - mesh.vertices[v[c]];
      n[v[c]] = n[v[c]] + std::atan2(norm(cross(e1, e2)), dot(e1, e2)) * mesh.triangle_normal(t);
    }
  for (Vec3 &v : n) v = normalized(v);
  return n;
}

/// The problem of the case, in code.
ProblemSpec make_spec(const Args &a, const Material &m, const Exact &ex)
{
  ProblemSpec spec;
  spec.file = "bench_stress";
  spec.mesh_path = a.mesh;
  spec.E = m.E;
  spec.nu = m.nu;
  const SurfaceMesh mesh = read_mesh(a.mesh);
  using K = BoundaryRule::Kind;
  if (a.kase == "kelvin") {
    std::vector<Vec3> t, u;
    std::vector<int> upper;
    const std::vector<Vec3> n = vertex_normals(mesh);
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3 &x = mesh.vertices[v];
      t.push_back(traction_of(ex.stress(x), n[v]));
      if (x[2] >= 0) upper.push_back(v), u.push_back(ex.u(x));
    }
    spec.rules = {rule(K::Traction, all_vertices(), t)};
    if (a.bc == "mixed") spec.rules.push_back(rule(K::Displacement, vertex_sel(upper), u));
  } else if (a.kase == "lame") {
    BoundaryRule r;
    r.kind = K::Pressure;
    r.where = region_sel("inner");
    r.pressure = {lame_pressure};
    spec.rules = {r};
  } else if (a.kase == "tension") {
    int origin = -1, xcorner = -1;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (norm(mesh.vertices[v]) < 1e-12) origin = v;
      if (norm(mesh.vertices[v] - Vec3{1, 0, 0}) < 1e-12) xcorner = v;
    }
    const double nan = std::nan("");
    spec.rules = {rule(K::Displacement, region_sel("z0"), {{nan, nan, 0}}), rule(K::Displacement, vertex_sel({origin}), {{0, 0, 0}}),
                  rule(K::Displacement, vertex_sel({xcorner}), {{nan, 0, nan}}), rule(K::Traction, region_sel("z1"), {{0, 0, tension_load}})};
  } else {
    throw std::invalid_argument("unknown case " + a.kase);
  }
  return spec;
}

double voigt_norm(const Voigt &s)
{
  double n = 0;
  for (double v : s) n += v * v;
  return std::sqrt(n);
}

double mean_edge(const SurfaceMesh &m)
{
  double s = 0;
  for (const auto &t : m.triangles)
    for (int c = 0; c < 3; ++c) s += norm(m.vertices[t[c]] - m.vertices[t[(c + 1) % 3]]);
  return s / (3.0 * m.triangles.size());
}

/// Sample points of the surface: random points of random triangles (fixed seed), with the
/// triangle's inward normal.
struct Sample {
  Vec3 x, inward;
};

std::vector<Sample> surface_samples(const SurfaceMesh &m, int n)
{
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> tri(0, m.num_triangles() - 1);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<Sample> out;
  for (int i = 0; i < n; ++i) {
    const int t = tri(rng);
    double a = u01(rng), b = u01(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const auto &v = m.triangles[t];
    out.push_back({(1 - a - b) * m.vertices[v[0]] + a * m.vertices[v[1]] + b * m.vertices[v[2]], -1.0 * m.triangle_normal(t)});
  }
  return out;
}

/// Points of a regular grid over the bounding box, kept where inside (about n of them).
std::vector<Vec3> grid_inside(const SurfaceMesh &mesh, const SurfaceLocator &loc, int n)
{
  Vec3 lo = mesh.vertices[0], hi = lo;
  for (const Vec3 &v : mesh.vertices)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v[c]), hi[c] = std::max(hi[c], v[c]);
  const double vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]), step = std::cbrt(vol / n);
  std::vector<Vec3> pts;
  for (double z = lo[2] + step / 2; z < hi[2]; z += step)
    for (double y = lo[1] + step / 2; y < hi[1]; y += step)
      for (double x = lo[0] + step / 2; x < hi[0]; x += step)
        if (loc.inside({x, y, z})) pts.push_back({x, y, z});
  return pts;
}

/// The fast evaluation against the direct sums at the same points: accuracy and points per second.
void speed(const Args &a, const SomiglianaSources &src, const SurfaceLocator &loc, const SurfaceMesh &mesh, const InteriorEvaluationOptions &eo)
{
  Timer timer;
  const std::vector<Vec3> pts = grid_inside(mesh, loc, a.speed);
  std::printf("speed: %zu points inside (grid), classified in %.2f s\n", pts.size(), timer.seconds());
  timer.restart();
  std::clock_t c0 = std::clock();
  const InteriorEvaluator fast(src, eo);
  const double t_up = timer.seconds(), c_up = double(std::clock() - c0) / CLOCKS_PER_SEC;
  timer.restart();
  c0 = std::clock();
  const std::vector<double> v = fast.evaluate(pts);
  const double t_eval = timer.seconds(), c_eval = double(std::clock() - c0) / CLOCKS_PER_SEC;
  std::printf("cpu seconds: upward %.2f, evaluation %.2f (%.1f us per point)\n", c_up, c_eval, 1e6 * (c_up + c_eval) / pts.size());
  const InteriorEvaluationStats &st = fast.stats();
  std::printf("fast: upward %.2f s, evaluation %.2f s (lists %.2f, downward %.2f, leaves %.2f): %.0f points/s; %lld far pairs, %lld near pairs, %.0f near triangles per point\n",
              t_up, t_eval, st.lists_seconds, st.downward_seconds, st.near_seconds, pts.size() / (t_up + t_eval), st.far_pairs, st.near_pairs,
              double(st.near_triangle_visits) / pts.size());
  const int nd = std::min<int>(a.direct_speed > 0 ? a.direct_speed : 200, static_cast<int>(pts.size()));
  std::vector<Vec3> sub;
  for (int i = 0; i < nd; ++i) sub.push_back(pts[(static_cast<std::size_t>(i) * pts.size()) / nd]);
  InteriorEvaluationOptions direct = eo;
  direct.direct = true;
  timer.restart();
  const std::vector<double> ref = InteriorEvaluator(src, direct).evaluate(sub);
  const double t_direct = timer.seconds();
  double eu = 0, es = 0, nu = 0, ns = 0;
  for (int i = 0; i < nd; ++i) {
    const std::size_t at = (static_cast<std::size_t>(i) * pts.size()) / nd;
    for (int k = 0; k < field_outputs; ++k) {
      const double d = v[at * field_outputs + k] - ref[static_cast<std::size_t>(i) * field_outputs + k], r = ref[static_cast<std::size_t>(i) * field_outputs + k];
      (k < 3 ? eu : es) += d * d;
      (k < 3 ? nu : ns) += r * r;
    }
  }
  std::printf("direct: %d points in %.2f s (%.0f points/s); fast vs direct: displacement %.2e, stress %.2e (relative L2)\n", nd, t_direct, nd / t_direct,
              std::sqrt(eu / nu), std::sqrt(es / ns));
}

/// The reference: the identities of the data minus the linear field of the surface stress at
/// the nearest surface point (exact for that field), every triangle (O(triangles) per point).
FieldValue subtracted(const SomiglianaSources &src, const SurfaceLocator &loc, const Discretization &disc, const std::vector<NodeStress> &nodes,
                      const std::vector<std::array<Vec3, 3>> &corner_u, const Vec3 &x)
{
  const auto n = loc.nearest(x);
  LinearField f;
  Vec3 u0{};
  for (int c = 0; c < 3; ++c) {
    const NodeStress &ns = nodes[disc.element_node(n.triangle, c)];
    for (int m = 0; m < 9; ++m) f.G[m] += n.bary[c] * ns.gradient[m];
    for (int m = 0; m < 6; ++m) f.stress[m] += n.bary[c] * ns.stress[m];
    u0 = u0 + n.bary[c] * corner_u[n.triangle][c];
  }
  for (int r = 0; r < 3; ++r) f.a[r] = u0[r] - (f.G[3 * r] * n.point[0] + f.G[3 * r + 1] * n.point[1] + f.G[3 * r + 2] * n.point[2]);
  FieldValue v{};
  for (int e = 0; e < src.num_triangles(); ++e) src.add_triangle_minus(x, e, f, v.data());
  for (int r = 0; r < 3; ++r) v[r] += f.a[r] + f.G[3 * r] * x[0] + f.G[3 * r + 1] * x[1] + f.G[3 * r + 2] * x[2];
  for (int m = 0; m < 6; ++m) v[3 + m] += f.stress[m];
  return v;
}

/// A point below the surface: `depth` its distance to the surface (in h), `mid` the middle of
/// the chord of the body along the inward normal from its surface point.
struct DepthPoint {
  Vec3 x;
  double depth;
  bool mid;
};

/// Length of the chord of the body from x0 along the unit vector n (marching, then bisection).
double chord(const SurfaceLocator &loc, const Vec3 &x0, const Vec3 &n, double h)
{
  double lo = 0, hi = h / 4;
  while (loc.inside(x0 + hi * n) && hi < 10 * loc.size()) lo = hi, hi += h / 4;
  for (int it = 0; it < 30; ++it) {
    const double m = 0.5 * (lo + hi);
    (loc.inside(x0 + m * n) ? lo : hi) = m;
  }
  return lo;
}

/// The points of every sample at the depths d·h (d in `depths`) short of mid-chord whose nearest
/// surface point is their own (distance ≥ 0.98 d h), and at mid-chord.
std::vector<DepthPoint> depth_points(const SurfaceLocator &loc, const std::vector<Sample> &samples, double h, const std::vector<double> &depths)
{
  std::vector<DepthPoint> out;
  for (const Sample &s : samples) {
    const double L = chord(loc, s.x, s.inward, h);
    const Vec3 mid = s.x + (0.5 * L) * s.inward;
    out.push_back({mid, loc.nearest(mid).distance / h, true});
    for (double d : depths) {
      const Vec3 x = s.x + (d * h) * s.inward;
      if (d * h < 0.5 * L && loc.nearest(x).distance >= 0.98 * d * h) out.push_back({x, d, false});
    }
  }
  return out;
}

double cpu_seconds() { return double(std::clock()) / CLOCKS_PER_SEC; }

/// The driver's interior chain on a grid of (cells + 1)³ points over the bounding box, with the
/// exact Kelvin field as boundary data (no solve: the evaluation's cost does not depend on where
/// the data came from): phase times (wall and CPU), points per second, and the fast evaluation
/// against the direct sums at a few points.
int grid_speed(const Args &a)
{
  std::vector<std::string> notices;
  SurfaceMesh mesh = read_mesh(a.mesh);
  validate_and_orient(mesh, notices);
  const Discretization disc(mesh, 40.0);
  const Material mat = Material::from_young(1000.0, a.nu);
  const Exact ex = kelvin(mat);
  std::vector<Vec3> u(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) u[i] = ex.u(disc.node_position(i));
  std::vector<std::array<Vec3, 3>> t(mesh.triangles.size());
  for (int e = 0; e < mesh.num_triangles(); ++e)
    for (int c = 0; c < 3; ++c) t[e][c] = traction_of(ex.stress(mesh.vertices[mesh.triangles[e][c]]), mesh.triangle_normal(e));
  std::vector<NodeStress> nodes = node_stresses(disc, mat, u, std::vector<Vec3>(disc.num_nodes())); // surface values: not timed here
  Vec3 lo = mesh.vertices[0], hi = lo;
  for (const Vec3 &v : mesh.vertices)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v[c]), hi[c] = std::max(hi[c], v[c]);
  const int n = a.grid_cells;
  InteriorGrid g;
  g.lo = lo, g.hi = hi, g.cells = {n, n, n};
  const std::vector<Vec3> pts = g.points();
  InteriorEvaluationOptions eo;
  eo.equivalent_points = a.equivalent_points, eo.target_leaf = a.target_leaf, eo.source_leaf = a.source_leaf;
  eo.check_ratio = a.check_ratio, eo.check_factor = a.check_factor, eo.equivalent_ratio = a.equivalent_ratio;
  eo.inner_points = a.inner_points, eo.inner_ratio = a.inner_ratio;
  Timer total;
  const double c_start = cpu_seconds();
  Timer timer;
  const SurfaceLocator loc(mesh);
  InteriorPlanOptions po;
  po.band = a.band;
  const std::vector<signed char> side = grid_inside(loc, g.lo, g.spacing(), g.points_per_axis(), InteriorPlan::search_reach(loc, mesh, po));
  const double t_inside = timer.seconds(), c_inside = cpu_seconds() - c_start;
  timer.restart();
  const InteriorPlan plan(loc, mesh, pts, po, &side);
  const double t_plan = timer.seconds(), c_plan = cpu_seconds() - c_start - c_inside;
  timer.restart();
  const SomiglianaSources src(disc, mat, u, t);
  const InteriorEvaluator fast(src, eo);
  const double t_up = timer.seconds(), c_up = cpu_seconds() - c_start - c_inside - c_plan;
  timer.restart();
  const std::vector<double> v = fast.evaluate(plan.evaluation_points());
  const double t_eval = timer.seconds(), c_eval = cpu_seconds() - c_start - c_inside - c_plan - c_up;
  timer.restart();
  const std::vector<FieldValue> f = plan.finish(v, corner_displacements(disc, u), corner_stress(disc, nodes));
  const double t_finish = timer.seconds(), wall = total.seconds(), cpu = cpu_seconds() - c_start;
  long long inside = 0;
  long long marked_deep = 0;
  for (signed char c : side) inside += c >= 1, marked_deep += c == 2;
  const InteriorEvaluationStats &st = fast.stats();
  std::printf("%s: %d triangles (%d unknowns), grid %d^3 = %zu points, %lld inside (%lld deep without a search), %zu integrated; threads %d\n", a.mesh.c_str(), mesh.num_triangles(),
              3 * disc.num_nodes(), n + 1, pts.size(), inside, marked_deep, plan.evaluation_points().size(),
#ifdef _OPENMP
              omp_get_max_threads()
#else
              1
#endif
  );
  std::printf("wall seconds: inside %.2f, plan %.2f, sources + upward %.2f, evaluation %.2f, finish %.2f; total %.2f (%.0f grid points/s, %.0f inside points/s); cpu %.1f s\n",
              t_inside, t_plan, t_up, t_eval, t_finish, wall, pts.size() / wall, inside / wall, cpu);
  std::printf("cpu seconds: inside %.2f, plan %.2f, sources + upward %.2f, evaluation %.2f, finish %.2f; %.0f inside points per cpu second\n", c_inside, c_plan, c_up,
              c_eval, cpu - c_inside - c_plan - c_up - c_eval, inside / cpu);
  std::printf("evaluation: far pairs %lld, fits %lld, per integrated point: far kernels %.0f, fit kernels %.0f, near particles %.0f, inner kernels %.0f, split triangles %.2f\n",
              st.far_pairs, st.local_fits, double(st.kernel_far) / v.size() * field_outputs, double(st.kernel_fit) / v.size() * field_outputs,
              double(st.kernel_near) / v.size() * field_outputs, double(st.kernel_inner) / v.size() * field_outputs,
              double(st.adaptive_triangles) / v.size() * field_outputs);
  const int nd = std::min<int>(a.direct_speed > 0 ? a.direct_speed : 100, static_cast<int>(plan.evaluation_points().size()));
  std::vector<Vec3> sub;
  for (int i = 0; i < nd; ++i) sub.push_back(plan.evaluation_points()[(static_cast<std::size_t>(i) * plan.evaluation_points().size()) / nd]);
  InteriorEvaluationOptions direct = eo;
  direct.direct = true;
  const std::vector<double> ref = InteriorEvaluator(src, direct).evaluate(sub);
  double es = 0, ns = 0;
  for (int i = 0; i < nd; ++i)
    for (int k = 3; k < field_outputs; ++k) {
      const std::size_t at = (static_cast<std::size_t>(i) * plan.evaluation_points().size()) / nd;
      const double d = v[at * field_outputs + k] - ref[static_cast<std::size_t>(i) * field_outputs + k];
      es += d * d, ns += ref[static_cast<std::size_t>(i) * field_outputs + k] * ref[static_cast<std::size_t>(i) * field_outputs + k];
    }
  std::printf("fast vs direct at %d points: stress %.2e (relative L2); peak RSS %.0f MB\n", nd, std::sqrt(es / ns), bench::peak_rss_mb());
  (void)f;
  return 0;
}

int run(const Args &a)
{
  if (a.grid_cells > 0) return grid_speed(a);
  const Material mat = Material::from_young(1000.0, a.nu);
  const Exact ex = a.kase == "kelvin" ? kelvin(mat) : a.kase == "lame" ? lame(mat, lame_inner, lame_outer, lame_pressure) : tension(mat, tension_load);
  ProblemSetup s = setup_problem(make_spec(a, mat, ex), ProblemOverrides{});
  const Discretization &disc = *s.disc;
  const SurfaceMesh &mesh = *s.mesh;
  BemOperator op(disc, s.material);
  Timer timer;
  const std::vector<double> x = solve_problem(PETSC_COMM_WORLD, s, op, a.mat_type == "h2" ? OperatorType::H2 : OperatorType::Dense, true);
  const double t_solve = timer.seconds();
  NodalSolution sol = split_unknowns(s.selection, x);
  if (s.pure_traction) remove_rigid_motion(disc, sol.u);
  // e_u, rigid motion removed
  std::vector<Vec3> diff(disc.num_nodes());
  double den = 0;
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const Vec3 e = ex.u(disc.node_position(i));
    diff[i] = sol.u[i] - e;
    den += dot(e, e);
  }
  std::vector<Vec3> drm = diff;
  remove_rigid_motion(disc, drm);
  double num = 0;
  for (const Vec3 &d : drm) num += dot(d, d);
  const double e_u = std::sqrt(num / den), h = mean_edge(mesh);
  // Rigid motion of the solution relative to the exact field, removed from the data so the
  // interior displacement compares too.
  for (int i = 0; i < disc.num_nodes(); ++i) sol.u[i] = ex.u(disc.node_position(i)) + drm[i];
  timer.restart();
  const std::vector<NodeStress> nodes = node_stresses(disc, s.material, sol.u, sol.t);
  const double t_surface = timer.seconds();
  const std::vector<Voigt> vs = vertex_stress(disc, nodes);
  double scale = 0, se = 0, sn = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Voigt e = ex.stress(mesh.vertices[v]);
    scale = std::max(scale, voigt_norm(e));
    Voigt d;
    for (int c = 0; c < 6; ++c) d[c] = vs[v][c] - e[c];
    se += voigt_norm(d) * voigt_norm(d);
    sn += voigt_norm(e) * voigt_norm(e);
  }
  std::printf("%s on %s (%d triangles, %d unknowns, h %.4f, nu %.2f, bc %s): solve %.2f s, e_u %.3e, b %.3e\n", a.kase.c_str(), a.mesh.c_str(), mesh.num_triangles(),
              3 * disc.num_nodes(), h, a.nu, a.bc.c_str(), t_solve, e_u, std::max(1e-2, 2 * e_u));
  std::printf("surface stress: rel L2 error %.3e (target %.3e), %.4f s (%.3f %% of the solve)\n", std::sqrt(se / sn), std::max(2e-2, 2 * e_u), t_surface,
              100 * t_surface / t_solve);
  // Interior: error against depth.
  InteriorQuadrature iq;
  iq.near_ratio = a.near_ratio;
  const SomiglianaSources src(disc, s.material, sol.u, corner_tractions(disc, s.selection, sol), iq);
  const SurfaceLocator loc(mesh);
  const std::vector<Sample> samples = surface_samples(mesh, a.samples);
  const auto corner_s = corner_stress(disc, nodes);
  const auto corner_u = corner_displacements(disc, sol.u);
  std::ofstream csv;
  if (!a.csv.empty()) csv.open(a.csv), csv << "case,mesh,nu,h,e_u,method,depth_h,points,max_err,rms_err\n";
  const std::vector<double> depths = {4, 2, 1, 0.5, 0.25, 0.1, 0.05};
  const std::vector<DepthPoint> dp = depth_points(loc, samples, h, depths);
  std::vector<Vec3> pts;
  for (const DepthPoint &p : dp) pts.push_back(p.x);
  InteriorEvaluationOptions eo;
  eo.equivalent_points = a.equivalent_points;
  eo.target_leaf = a.target_leaf;
  eo.source_leaf = a.source_leaf;
  eo.check_ratio = a.check_ratio;
  eo.check_factor = a.check_factor;
  eo.equivalent_ratio = a.equivalent_ratio;
  eo.inner_points = a.inner_points;
  eo.inner_ratio = a.inner_ratio;
  const double b = std::max(1e-2, 2 * e_u);
  std::stringstream ms(a.methods);
  std::string method;
  while (std::getline(ms, method, ',')) {
    std::vector<FieldValue> val;
    if (method == "subtract") {
      for (const Vec3 &x : pts) val.push_back(subtracted(src, loc, disc, nodes, corner_u, x));
    } else {
      InteriorPlanOptions po;
      po.band = method == "band" || method == "band-direct" ? a.band : 0.0;
      InteriorEvaluationOptions o = eo;
      o.direct = method == "direct" || method == "band-direct";
      std::vector<PointKind> kinds;
      val = evaluate_interior(src, loc, mesh, corner_u, corner_s, pts, po, o, &kinds);
      std::map<double, int> banded;
      for (std::size_t i = 0; i < pts.size(); ++i) banded[dp[i].mid ? -1.0 : dp[i].depth] += kinds[i] == PointKind::Band;
      std::printf("          interpolated:");
      for (const auto &[d, n] : banded) std::printf(" %.2fh %d", d, n);
      std::printf("\n");
    }
    // per depth, and the three ranges: mid-chord, [1 h, mid), [0.05 h, 1 h)
    std::map<double, std::pair<double, double>> by_depth; // depth -> (max, sum of squares)
    std::map<double, int> count;
    double e_mid = 0, e_far = 0, e_near = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const Voigt e = ex.stress(pts[i]);
      Voigt d;
      for (int c = 0; c < 6; ++c) d[c] = val[i][3 + c] - e[c];
      const double err = voigt_norm(d) / scale;
      if (dp[i].mid) {
        e_mid = std::max(e_mid, err);
        continue;
      }
      (dp[i].depth >= 1 ? e_far : e_near) = std::max(dp[i].depth >= 1 ? e_far : e_near, err);
      auto &bd = by_depth[dp[i].depth];
      bd.first = std::max(bd.first, err), bd.second += err * err, ++count[dp[i].depth];
    }
    std::printf("%-9s mid %.2e (target %.2e)  [1h, mid) %.2e (target %.2e)  [0.05h, 1h) %.2e (target %.2e)\n", method.c_str(), e_mid, b, e_far, 3 * b + 1e-3,
                e_near, std::max(3e-2, 3 * b));
    std::printf("          by depth (max/rms):");
    for (auto it = by_depth.rbegin(); it != by_depth.rend(); ++it) {
      const double rms = std::sqrt(it->second.second / count[it->first]);
      std::printf("  %.2fh %.2e/%.2e", it->first, it->second.first, rms);
      if (csv) csv << a.kase << "," << a.mesh << "," << a.nu << "," << h << "," << e_u << "," << method << "," << it->first << "," << count[it->first] << "," << it->second.first << "," << rms << "\n";
    }
    std::printf("\n");
    if (csv) csv << a.kase << "," << a.mesh << "," << a.nu << "," << h << "," << e_u << "," << method << ",mid," << samples.size() << "," << e_mid << ",\n";
  }
  if (a.speed > 0) speed(a, src, loc, mesh, eo);
  return 0;
}

} // namespace

int main(int argc, char **argv)
{
  int petsc_argc = 1; // the arguments are the benchmark's own
  PetscCall(PetscInitialize(&petsc_argc, &argv, NULL, NULL));
  PetscCall(HssbemInitializePackage());
  int rc = 0;
  try {
    rc = run(parse(argc, argv));
  } catch (const std::exception &e) {
    std::fprintf(stderr, "bench_stress: %s\n", e.what());
    rc = 1;
  }
  PetscCall(PetscFinalize());
  return rc;
}
