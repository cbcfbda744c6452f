// Hertz contact (contact/): an elastic hemisphere pressed on a rigid plane, and two equal
// hemispheres pressed together, on meshes refined at the pole (scripts/gen_meshes.py
// --hertz-size). The contact radius and the peak pressure, fitted to p² = p0² (1 − r²/a²),
// against Hertz's for the force the solver reports; no penetration, p ≥ 0, complementarity; the
// plane as a rigid two-triangle mesh; the force against a static solve with the contact area
// prescribed; the forces' balance.
#include "solve_helpers.hpp"

#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/reference/composite_reference.hpp"
#include "hssbem/reference/reference.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

using namespace hssbem;
using namespace hssbem::test;

namespace {

constexpr double E = 1000, nu = 0.3, R = 1;

struct Fit {
  double a = 0, p0 = 0;
  int points = 0;
};

/// Least squares of p² = p0² − (p0²/a²) r² over the touching vertices with r < `within`.
Fit fit_hertz(const SurfaceMesh &m, const std::vector<double> &p, const Vec3 &pole, double within)
{
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  Fit f;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const double r = std::hypot(m.vertices[v][0] - pole[0], m.vertices[v][1] - pole[1]);
    if (p[v] <= 0 || r >= within || std::abs(m.vertices[v][2] - pole[2]) > 0.5 * R) continue;
    const double x = r * r, y = p[v] * p[v];
    sx += x, sy += y, sxx += x * x, sxy += x * y, ++f.points;
  }
  const double slope = (f.points * sxy - sx * sy) / (f.points * sxx - sx * sx), c0 = (sy - slope * sx) / f.points;
  f.p0 = std::sqrt(c0);
  f.a = std::sqrt(-c0 / slope);
  return f;
}

/// The fit on the inner 80 % of the contact radius (the rim's discrete pressures are not Hertz's square root).
Fit fit_contact(const SurfaceMesh &m, const std::vector<double> &p, const Vec3 &pole)
{
  Fit f = fit_hertz(m, p, pole, 1e9);
  return fit_hertz(m, p, pole, 0.8 * f.a);
}

/// The force on the held nodes (every node whose displacement is prescribed, the flat face's rim
/// nodes on the curved side included): the held region's reaction.
Vec3 held_reaction(const Discretization &disc, const NodeConditions &nc, const std::vector<Vec3> &t, int body_sign = 0)
{
  const std::vector<double> area = node_areas(disc);
  Vec3 F{};
  for (int i = 0; i < disc.num_nodes(); ++i) {
    if (body_sign * disc.node_position(i)[2] < 0) continue;
    for (int c = 0; c < 3; ++c)
      if (nc.displacement_prescribed[i][c]) F[c] += area[i] * t[i][c];
  }
  return F;
}

struct Solved {
  ProblemSetup s;
  std::unique_ptr<BemOperator> op;
  NodeConditions base;
  std::unique_ptr<DenseReference> ref;
  ContactSolution sol;
  ContactFrameReport rep;

  /// A contact solve on this reference (obstacles at their base positions).
  void solve(std::vector<Obstacle> obstacles, const ContactSettings &settings)
  {
    ContactOptions opt;
    opt.reach = 0.05 * R;
    ContactEngine engine(*s.disc, *ref, std::move(obstacles), settings, opt);
    rep = engine.solve(selection_of(base), std::vector<Vec3>(engine.num_obstacles(), Vec3{0, 0, 0}), sol);
  }
};

std::unique_ptr<Solved> solve_contact(ProblemSpec spec, std::vector<Obstacle> obstacles, const ContactSettings &settings, const QuadratureOptions &quad = {})
{
  auto r = std::make_unique<Solved>();
  spec.contact.present = true;
  r->s = setup_problem(std::move(spec), ProblemOverrides{});
  r->op = std::make_unique<BemOperator>(*r->s.disc, r->s.material, quad);
  r->base = apply_rules(r->s.spec.rules, *r->s.disc, r->s.spec.file);
  DenseReferenceOptions ro;
  ro.node_body = node_bodies(*r->s.disc);
  r->ref = std::make_unique<DenseReference>(*r->op, r->base.unknown_pattern(), ro);
  r->solve(std::move(obstacles), settings);
  return r;
}

/// The static problem of `nc` with the reference's H and G: dense LU of its system.
NodalSolution static_solve(const DenseReference &ref, const NodeConditions &nc)
{
  const std::vector<char> pattern = nc.unknown_pattern();
  const int N = static_cast<int>(pattern.size());
  std::vector<double> A(static_cast<std::size_t>(N) * N), b;
  ref.system_matrix(pattern, A.data());
  ref.rhs(selection_of(nc), pattern, b);
  std::vector<int> piv(N);
  EXPECT_EQ(lapack::getrf(N, A.data(), N, piv.data()), 0);
  lapack::getrs('N', N, 1, A.data(), N, piv.data(), b.data(), N);
  return split_unknowns(selection_of(nc), b);
}

/// Hertz's radius and peak pressure for the force F, effective radius Rs and modulus Es.
Fit hertz(double F, double Rs, double Es)
{
  Fit h;
  h.a = std::cbrt(3 * F * Rs / (4 * Es));
  h.p0 = 3 * F / (2 * M_PI * h.a * h.a);
  return h;
}

} // namespace

TEST(ContactHertz, SphereOnAPlane)
{
  const double delta = 0.05;
  ProblemSpec spec = spec_for("hertz_hemisphere.msh", E, nu);
  spec.rules = {rule(BoundaryRule::Kind::Displacement, region("flat"), {{0, 0, -delta}})};
  const auto plane = solve_contact(spec, {Obstacle::plane("table", {0, 0, 0}, {0, 0, 1})}, {});
  const SurfaceMesh &m = *plane->s.mesh;
  const double F = plane->sol.obstacle_force[0][2];
  const Fit got = fit_contact(m, plane->sol.pressure, {0, 0, 0}), want = hertz(F, R, E / (1 - nu * nu));
  double worst_gap = 0, worst_comp = 0, pmin = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (std::isnan(plane->sol.gap[v])) continue;
    worst_gap = std::min(worst_gap, plane->sol.gap[v]);
    worst_comp = std::max(worst_comp, std::abs(plane->sol.pressure[v] * plane->sol.gap[v]));
    pmin = std::min(pmin, plane->sol.pressure[v]);
  }
  const Vec3 R_flat = held_reaction(*plane->s.disc, plane->base, plane->sol.t);
  std::printf("Hertz sphere on a plane: F = %.4f; a = %.4f (Hertz %.4f, %+.2f %%), p0 = %.3f (Hertz %.3f, %+.2f %%) from %d points; %lld touching, %lld iterations; "
              "min gap %.1e R, max |p g| %.1e, reaction of the held face %.4f\n",
              F, got.a, want.a, 100 * (got.a / want.a - 1), got.p0, want.p0, 100 * (got.p0 / want.p0 - 1), got.points, plane->rep.active_vertices, plane->rep.iterations, worst_gap / R,
              worst_comp / (want.p0 * R), R_flat[2]);
  EXPECT_NEAR(got.a / want.a, 1, 0.05);
  EXPECT_NEAR(got.p0 / want.p0, 1, 0.05);
  EXPECT_GE(got.points, 20);
  EXPECT_GE(worst_gap, -1e-8 * R);
  EXPECT_GE(pmin, 0.0);
  EXPECT_LE(worst_comp, 1e-8 * want.p0 * R);
  EXPECT_NEAR(R_flat[2] + F, 0, 1e-2 * F); // the contact force balances the held face's reaction

  // The same plane as a rigid mesh of two triangles: the same answer.
  SurfaceMesh square;
  square.vertices = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  const std::vector<Vec3> u_plane = plane->sol.u;
  plane->solve({Obstacle::mesh("table", square)}, {});
  double du = 0;
  for (std::size_t i = 0; i < u_plane.size(); ++i) du = std::max(du, norm(plane->sol.u[i] - u_plane[i]));
  EXPECT_LE(du, 1e-6 * delta);
  EXPECT_NEAR(plane->sol.obstacle_force[0][2], F, 1e-6 * F);

  // An independent static solve: the contact area prescribed (u_z = -g0 at its nodes, rollers).
  NodeConditions nc = plane->base;
  for (int v = 0; v < m.num_vertices(); ++v)
    if (plane->sol.status[v]) {
      const int i = plane->s.disc->first_node(v);
      nc.displacement_prescribed[i][2] = true;
      nc.value[i][2] = -m.vertices[v][2];
    }
  const NodalSolution st = static_solve(*plane->ref, nc);
  double ds = 0, us = 0;
  for (std::size_t i = 0; i < u_plane.size(); ++i) ds = std::max(ds, norm(st.u[i] - u_plane[i])), us = std::max(us, norm(u_plane[i]));
  std::printf("Hertz sphere on a plane: the static solve with the contact area prescribed differs by %.1e (relative)\n", ds / us);
  EXPECT_LE(ds, 7e-8 * us); // measured 6.8e-9: the default single-precision fields' rounding (7e-15 in double), 10x; the target is 1e-6
}

TEST(ContactHertz, TwoSpheres)
{
  // Two equal hemispheres, poles 0.002 R apart, their flat faces pushed toward each other.
  const double delta = 0.05, gap = 0.002;
  ProblemSpec spec = spec_for("hertz_pair.msh", E, nu);
  spec.rules = {rule(BoundaryRule::Kind::Displacement, region("flat_a"), {{0, 0, -0.5 * delta}}),
                rule(BoundaryRule::Kind::Displacement, region("flat_b"), {{0, 0, 0.5 * delta}})};
  ContactSettings bodies;
  bodies.bodies = true;
  const auto r = solve_contact(spec, {}, bodies);
  const SurfaceMesh &m = *r->s.mesh;
  const double F = r->sol.body_force[0][2];
  const Fit want = hertz(std::abs(F), R / 2, E / (2 * (1 - nu * nu)));
  std::vector<double> upper(m.num_vertices(), 0.0), lower(m.num_vertices(), 0.0);
  for (int v = 0; v < m.num_vertices(); ++v) (m.vertices[v][2] > -0.5 * gap ? upper : lower)[v] = r->sol.pressure[v];
  const Fit a = fit_contact(m, upper, {0, 0, 0}), b = fit_contact(m, lower, {0, 0, -gap});
  std::printf("Hertz two spheres: F = %.4f (%.4f on the other); a = %.4f / %.4f (Hertz %.4f), p0 = %.3f / %.3f (Hertz %.3f) from %d / %d points; %lld touching, %lld iterations\n",
              F, r->sol.body_force[1][2], a.a, b.a, want.a, a.p0, b.p0, want.p0, a.points, b.points, r->rep.active_vertices, r->rep.iterations);
  for (const Fit &f : {a, b}) {
    EXPECT_NEAR(f.a / want.a, 1, 0.05);
    EXPECT_NEAR(f.p0 / want.p0, 1, 0.05);
    EXPECT_GE(f.points, 20);
  }
  EXPECT_NEAR(r->sol.body_force[0][2] + r->sol.body_force[1][2], 0, 1e-3 * std::abs(F));
  const Vec3 Ra = held_reaction(*r->s.disc, r->base, r->sol.t, +1);
  std::printf("Hertz two spheres: the upper sphere's held face %.4f against the contact force %.4f\n", Ra[2], F);
  EXPECT_NEAR(Ra[2] + F, 0, 1e-2 * std::abs(F));

  // The same on the composite reference (each hemisphere on its own surface and operator: the
  // driver's path), against the whole mesh's dense reference with the bodies separated.
  const BodyReferenceFactory dense = [](const BemOperator &op, std::vector<char> pattern, std::vector<char>, int) {
    DenseReferenceOptions o;
    o.reference_columns_only = true;
    return std::make_unique<DenseReference>(op, std::move(pattern), o);
  };
  const CompositeReference composite(*r->op, node_bodies(*r->s.disc), r->base.unknown_pattern(), {}, dense);
  ContactOptions opt;
  opt.reach = 0.05 * R;
  ContactEngine engine(*r->s.disc, composite, {}, bodies, opt);
  ContactSolution sol;
  const ContactFrameReport rep = engine.solve(selection_of(r->base), std::vector<Pose>{}, sol);
  double dp = 0, pm = 0, du = 0, um = 0;
  for (int v = 0; v < m.num_vertices(); ++v) dp = std::max(dp, std::abs(sol.pressure[v] - r->sol.pressure[v])), pm = std::max(pm, r->sol.pressure[v]);
  for (std::size_t i = 0; i < sol.u.size(); ++i) du = std::max(du, norm(sol.u[i] - r->sol.u[i])), um = std::max(um, norm(r->sol.u[i]));
  std::printf("Hertz two spheres, composite reference against node_body: pressure %.1e, u %.1e; %lld touching (%lld); memory %.0f MB (%.0f MB)\n", dp / pm, du / um,
              rep.active_vertices, r->rep.active_vertices, composite.memory_bytes() / 1e6, r->ref->memory_bytes() / 1e6);
  EXPECT_EQ(rep.active_vertices, r->rep.active_vertices);
  EXPECT_LE(dp, 5e-13 * pm); // measured 5.2e-14 (node_body's other-body integrals cancel to round-off; 10x)
  EXPECT_LE(du, 4e-11 * um); // measured 3.8e-12
}
