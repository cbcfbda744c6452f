// Several bodies on a composite reference (reference/composite_reference.hpp): each body on its own
// surface, operator and reference. Against the dense reference of the whole mesh with the other
// bodies' blocks zeroed (DenseReferenceOptions::node_body), which holds the same equations: W's
// columns, the free response and the contact solution of two stacked cubes agree to round-off;
// and with the H² reference per body (the H² path's several bodies) the contact agrees with the
// dense one to the H² operator's tolerance. Junctions: an edge on a table and against another
// body keeps both contacts; three bodies side by side carry the uniaxial force.
#include "hand_problem.hpp"
#include "solve_helpers.hpp"

#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/reference/composite_reference.hpp"
#include "hssbem/petsc/krylov.h"
#include "hssbem/reference/h2_reference.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

using namespace hssbem;
using namespace hssbem::test;

namespace {

constexpr double E = 1000, nu = 0.3, delta = 0.01;

/// Two unit cubes, one on the other with a gap g, rollers on x0 and y0, the bottom's u_z = 0 and
/// the top pushed down by δ (tests/verification/test_contact.cpp, TwoStackedCubesShareTheLoad).
struct StackedCubes {
  SurfaceMesh mesh;
  std::unique_ptr<Discretization> disc;
  std::unique_ptr<BemOperator> op;
  SystemSelection sel;
  std::vector<char> pattern;
  ContactSettings settings;

  explicit StackedCubes(double g)
  {
    mesh = stacked_cubes(g);
    disc = std::make_unique<Discretization>(mesh, 40.0);
    op = std::make_unique<BemOperator>(*disc, Material{E, nu});
    const int nn = disc->num_nodes();
    sel = SystemSelection{std::vector<std::array<bool, 3>>(nn, {false, false, false}), std::vector<Vec3>(nn, Vec3{0, 0, 0}), {}};
    for (int i = 0; i < nn; ++i) {
      const Vec3 x = disc->node_position(i), n = disc->node(i).normal;
      if (x[2] < 1e-12 && n[2] < -0.9) sel.displacement_known[i] = {false, false, true};
      if (x[2] > 2 && n[2] > 0.9) sel.displacement_known[i] = {false, false, true}, sel.known[i][2] = -delta;
      if (x[0] < 1e-12) sel.displacement_known[i][0] = true;
      if (x[1] < 1e-12) sel.displacement_known[i][1] = true;
    }
    pattern.resize(3 * nn);
    for (int i = 0; i < nn; ++i)
      for (int c = 0; c < 3; ++c) pattern[3 * i + c] = sel.displacement_known[i][c];
    settings.bodies = true;
  }

  ContactSolution contact(const ReferenceFactorization &ref, ContactFrameReport *rep = nullptr) const
  {
    ContactEngine engine(*disc, ref, {}, settings);
    ContactSolution sol;
    const ContactFrameReport r = engine.solve(sel, std::vector<Pose>{}, sol);
    if (rep) *rep = r;
    return sol;
  }
};

std::unique_ptr<ReferenceFactorization> dense_body(const BemOperator &op, std::vector<char> pattern, std::vector<char> kept, int)
{
  DenseReferenceOptions o;
  o.reference_columns_only = true;
  o.kept_columns = std::move(kept);
  return std::make_unique<DenseReference>(op, std::move(pattern), o);
}

double max_abs(const std::vector<double> &a)
{
  double m = 0;
  for (double x : a) m = std::max(m, std::abs(x));
  return m;
}

double max_diff(const std::vector<double> &a, const std::vector<double> &b)
{
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

double max_diff(const std::vector<Vec3> &a, const std::vector<Vec3> &b, double &scale)
{
  double m = 0;
  scale = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, norm(a[i] - b[i])), scale = std::max(scale, norm(b[i]));
  return m;
}

} // namespace

TEST(ContactBodies, CompositeReferenceEqualsTheSeparatedDenseOne)
{
  const StackedCubes c(0.1 * delta);
  DenseReferenceOptions ro;
  ro.node_body = node_bodies(*c.disc);
  const DenseReference whole(*c.op, c.pattern, ro);
  const CompositeReference composite(*c.op, node_bodies(*c.disc), c.pattern, {}, dense_body);
  ASSERT_EQ(composite.num_bodies(), 2);
  const int N = composite.num_unknowns();

  // W's columns: a few of each body's traction-known unknowns.
  std::vector<int> js;
  for (int j = 0; j < N && js.size() < 40; j += 7)
    if (!c.pattern[j]) js.push_back(j);
  std::vector<double> Ww(static_cast<std::size_t>(N) * js.size()), Wc(Ww.size());
  whole.columns(js, Ww.data());
  composite.columns(js, Wc.data());
  const double dW = max_diff(Ww, Wc) / max_abs(Ww);
  // The free response of the push, and the contact.
  std::vector<double> yw, yc;
  whole.free_response(c.sel, yw);
  composite.free_response(c.sel, yc);
  const double dy = max_diff(yw, yc) / max_abs(yw);
  ContactFrameReport rw, rc;
  const ContactSolution sw = c.contact(whole, &rw), sc = c.contact(composite, &rc);
  double us = 0;
  const double du = max_diff(sc.u, sw.u, us) / us, dp = max_diff(sc.pressure, sw.pressure) / max_abs(sw.pressure);
  std::printf("composite against node_body: W %.1e, free response %.1e, u %.1e, pressure %.1e; %lld / %lld touching; memory %.1f / %.1f MB\n", dW, dy, du, dp, rc.active_vertices,
              rw.active_vertices, composite.memory_bytes() / 1e6, whole.memory_bytes() / 1e6);
  EXPECT_EQ(rc.active_vertices, rw.active_vertices);
  EXPECT_GE(rc.active_vertices, 20); // the cubes' facing faces (25 vertices)
  // Round-off: the same integrals, but node_body sums the other body's nearly singular integrals
  // (0.004 h away) into the rigid-body term and takes them out again. Measured: W 2.3e-15, the
  // free response 2.1e-11 (of its largest entry, a traction), u 4.9e-15, pressure 2.4e-14 (2.5e-15,
  // 3.9e-15, 3.5e-14 before the junction rule's followers); the bounds about 10x, for other
  // machines, BLAS kernels and thread counts.
  EXPECT_LE(dW, 3e-14);
  EXPECT_LE(dy, 2e-10);
  EXPECT_LE(du, 4e-14);
  EXPECT_LE(dp, 4e-13);
  EXPECT_LT(composite.memory_bytes(), whole.memory_bytes() / 2);
}

TEST(ContactBodies, KeptColumnsOnly)
{
  // A dense reference that keeps K₀′'s columns of a mask answers as the full one on them and
  // refuses the others.
  const StackedCubes c(0.1 * delta);
  std::vector<char> kept(c.pattern.size(), 0);
  for (std::size_t j = 0; j < kept.size(); ++j) kept[j] = c.pattern[j] || (j / 3) % 2 == 0; // the known values' columns and every other node's
  const CompositeReference all(*c.op, node_bodies(*c.disc), c.pattern, {}, dense_body), some(*c.op, node_bodies(*c.disc), c.pattern, kept, dense_body);
  std::vector<int> js;
  for (std::size_t j = 0; j < kept.size(); ++j)
    if (kept[j] && !c.pattern[j]) js.push_back(static_cast<int>(j));
  const std::size_t N = kept.size();
  std::vector<double> Wa(N * js.size()), Ws(Wa.size()), ya, ys;
  all.columns(js, Wa.data());
  some.columns(js, Ws.data());
  all.free_response(c.sel, ya);
  some.free_response(c.sel, ys);
  EXPECT_EQ(max_diff(Wa, Ws), 0.0);
  EXPECT_EQ(max_diff(ya, ys), 0.0);
  EXPECT_LT(some.memory_bytes(), all.memory_bytes());
  int missing = 1;
  while (kept[missing]) ++missing;
  std::vector<double> col(N);
  EXPECT_THROW(some.columns({missing}, col.data()), std::invalid_argument);
}

TEST(ContactBodies, H2ReferencePerBodyAgreesWithDense)
{
  const StackedCubes c(0.1 * delta);
  const CompositeReference dense(*c.op, node_bodies(*c.disc), c.pattern, {}, dense_body);
  H2ReferenceOptions ho;
  ho.compression.rel_tol = 1e-5, ho.compression.single_precision = true, ho.compression.leaf_size = 32; // several levels on a small body
  const CompositeReference h2(*c.op, node_bodies(*c.disc), c.pattern, {}, [&](const BemOperator &op, std::vector<char> p, std::vector<char>, int) {
    return std::make_unique<H2Reference>(op, std::move(p), ho, HssbemH2ReferenceKrylovCreate());
  });
  EXPECT_FALSE(h2.exact_columns());
  ContactFrameReport rd, rh;
  const ContactSolution sd = c.contact(dense, &rd), sh = c.contact(h2, &rh);
  double us = 0;
  const double du = max_diff(sh.u, sd.u, us) / us, dp = max_diff(sh.pressure, sd.pressure) / max_abs(sd.pressure);
  const double F = sd.body_force[1][2], dF = std::abs(sh.body_force[1][2] - F) / F;
  std::printf("H2 per body against dense per body: u %.1e, pressure %.1e, force %.1e; %d corrections (last %.1e); %lld / %lld touching\n", du, dp, dF, rh.corrections,
              rh.correction, rh.active_vertices, rd.active_vertices);
  EXPECT_EQ(rh.active_vertices, rd.active_vertices);
  EXPECT_GE(rh.corrections, 1);
  EXPECT_LE(rh.correction, 1e-8);
  // Measured: u 3.8e-7, pressure 1.1e-6, force 7.2e-9 (the H² operator at 1e-5 against the
  // dense one; one correction, ending at 1.7e-14).
  EXPECT_LE(du, 1.2e-6);
  EXPECT_LE(dp, 4e-6);
  EXPECT_LE(dF, 4e-8);
  EXPECT_NEAR(sh.body_force[0][2] + sh.body_force[1][2], 0.0, 1e-9 * F);
}

namespace {

/// Copies of the shipped unit cube, the k-th moved by offsets[k] (bodies in that order).
SurfaceMesh cubes_at(const std::vector<Vec3> &offsets)
{
  const SurfaceMesh one = read_mesh(mesh_file("cube_l0.msh"));
  SurfaceMesh all;
  for (const Vec3 &o : offsets) {
    const int base = all.num_vertices();
    for (const Vec3 &v : one.vertices) all.vertices.push_back(v + o);
    for (const auto &t : one.triangles) all.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    all.triangle_region.insert(all.triangle_region.end(), one.triangle_region.begin(), one.triangle_region.end());
  }
  std::vector<std::string> notices;
  validate_and_orient(all, notices);
  return all;
}

/// A hand-set problem on a mesh of several bodies, on the composite reference (a dense one per
/// body), frictionless.
struct Bodies3 : HandProblem {
  explicit Bodies3(SurfaceMesh m) : HandProblem(std::move(m), Material{E, nu}) {}
  ContactSolution solve(const std::vector<Obstacle> &obstacles, ContactFrameReport &rep)
  {
    ContactSettings s;
    s.bodies = true;
    EXPECT_TRUE(floating_pins(*disc, sel.displacement_known, obstacles, s).empty());
    reference = std::make_unique<CompositeReference>(*op, node_bodies(*disc), pattern(), std::vector<char>{}, dense_body);
    ContactEngine engine(*disc, *reference, obstacles, s);
    ContactSolution sol;
    rep = engine.solve(sel, std::vector<Vec3>(obstacles.size(), Vec3{0, 0, 0}), sol);
    return sol;
  }
  std::unique_ptr<CompositeReference> reference;
};

bool near(double a, double b) { return std::abs(a - b) < 1e-9; }

} // namespace

TEST(ContactBodies, AnEdgeOnATableAndAgainstAnotherBodyKeepsBothContacts)
{
  // Two unit cubes side by side along x, a gap g apart, their tops clamped and moved toward each
  // other (and down) by delta, on a frictionless table at z = 0: the vertices of the facing
  // bottom edges touch the table and the other cube at once. Each keeps both contacts: after the
  // solve none goes through the table (u_z ≥ 0) nor through the other cube (the x gap to its
  // facing vertex ≥ 0) — with one contact point per vertex the edge kept only the table and went
  // into the other cube. The forces balance: the table's against the clamped tops' reactions, the
  // cubes' on each other.
  const double g = 0.1 * delta;
  Bodies3 c(cubes_at({{0, 0, 0}, {1 + g, 0, 0}}));
  const auto top_a = [&](const Vec3 &x) { return near(x[2], 1) && x[0] < 1 + 0.5 * g; };
  const auto top_b = [&](const Vec3 &x) { return near(x[2], 1) && x[0] > 1 + 0.5 * g; };
  for (int k = 0; k < 3; ++k) c.hold_at(top_a, k, k == 0 ? delta : k == 2 ? -delta : 0.0), c.hold_at(top_b, k, k == 0 ? -delta : k == 2 ? -delta : 0.0);
  ContactFrameReport rep;
  const ContactSolution sol = c.solve({Obstacle::plane("table", {0, 0, 0}, {0, 0, 1})}, rep);
  const auto node_of = [&](int v, const Vec3 &normal) { // the dof node of v on the face of this normal
    int best = c.disc->first_node(v);
    for (int i = best; i < c.disc->first_node(v) + c.disc->node_count(v); ++i)
      if (dot(c.disc->node(i).normal, normal) > dot(c.disc->node(best).normal, normal)) best = i;
    return best;
  };
  double table_gap = 0, body_gap = 0;
  int edge = 0;
  for (int v = 0; v < c.mesh.num_vertices(); ++v) {
    const Vec3 &x = c.mesh.vertices[v];
    if (!near(x[2], 0) || !near(x[0], 1)) continue; // cube A's facing bottom edge
    for (int w = 0; w < c.mesh.num_vertices(); ++w)
      if (near(c.mesh.vertices[w][0], 1 + g) && near(c.mesh.vertices[w][1], x[1]) && near(c.mesh.vertices[w][2], 0)) {
        body_gap = std::min(body_gap, g + sol.u[node_of(w, {-1, 0, 0})][0] - sol.u[node_of(v, {1, 0, 0})][0]); // the facing faces' nodes
        for (int k : {v, w})
          for (int i = c.disc->first_node(k); i < c.disc->first_node(k) + c.disc->node_count(k); ++i) table_gap = std::min(table_gap, sol.u[i][2]);
        ++edge;
      }
  }
  const auto R = [&](bool b) { // the clamped top's reaction of cube a (b false) or b
    Vec3 F{};
    const std::vector<double> area = node_areas(*c.disc);
    for (int i = 0; i < c.disc->num_nodes(); ++i) {
      const Vec3 &x = c.mesh.vertices[c.disc->node(i).vertex];
      if (b ? top_b(x) : top_a(x)) F = F + area[i] * sol.t[i];
    }
    return F;
  };
  const Vec3 table = sol.obstacle_force[0], held = R(false) + R(true);
  const double balance = norm(table + held) / norm(table), pair = norm(sol.body_force[0] + sol.body_force[1]) / norm(sol.body_force[0]);
  std::printf("an edge on a table and against a cube: %d edge vertex pairs; smallest gap to the table %.2e, to the other cube %.2e (delta %.0e); table (%.4f, %.4f, %.4f), "
              "cube 0 from cube 1 (%.4f, %.4f, %.4f); table + held reactions %.1e, the cubes' forces %.1e (relative)\n",
              edge, table_gap, body_gap, delta, table[0], table[1], table[2], sol.body_force[0][0], sol.body_force[0][1], sol.body_force[0][2], balance, pair);
  EXPECT_EQ(edge, 5);
  // A free point joins once it penetrates by 1e-10 of the mesh's size (2.45 here): 10x that.
  EXPECT_GE(table_gap, -2.5e-9);
  EXPECT_GE(body_gap, -2.5e-9);
  EXPECT_GT(table[2], 0.5 * E * delta);            // both cubes pressed on the table
  EXPECT_LT(sol.body_force[0][0], -0.2 * E * delta); // and against each other
  EXPECT_LE(balance, 1e-3);
  EXPECT_LE(pair, 1e-3);
}

TEST(ContactBodies, ThreeBodiesSideBySideCarryTheUniaxialForce)
{
  // Three unit cubes along x, g apart: the outer faces pushed in by delta each, rollers on the
  // y = 0 and z = 0 faces (symmetry planes), the middle cube held along x at the middle of its
  // base (x = 0.5), every other face free, frictionless interfaces. The exact field is uniaxial
  // in every cube, ε = (2 delta − 2 g) / 3, so each interface carries E ε times its area (1).
  const double g = 0.1 * delta, eps = (2 * delta - 2 * g) / 3;
  Bodies3 c(cubes_at({{-1 - g, 0, 0}, {0, 0, 0}, {1 + g, 0, 0}}));
  c.hold_at([](const Vec3 &x) { return near(x[1], 0); }, 1, 0.0);
  c.hold_at([](const Vec3 &x) { return near(x[2], 0); }, 2, 0.0);
  c.hold_at([&](const Vec3 &x) { return near(x[0], -1 - g); }, 0, delta);
  c.hold_at([&](const Vec3 &x) { return near(x[0], 2 + g); }, 0, -delta);
  c.hold_at([](const Vec3 &x) { return near(x[0], 0.5) && near(x[2], 0); }, 0, 0.0);
  ContactFrameReport rep;
  const ContactSolution sol = c.solve({}, rep);
  const double F = E * eps;
  double perr = 0;
  int touching = 0;
  for (int v = 0; v < c.mesh.num_vertices(); ++v) {
    const double x = c.mesh.vertices[v][0];
    if (near(x, -g) || near(x, 0) || near(x, 1) || near(x, 1 + g)) perr = std::max(perr, std::abs(sol.pressure[v] - F) / F), touching += sol.status[v] != 0;
  }
  std::printf("three cubes side by side: forces on the outer cubes %.6f, %.6f, on the middle %.1e (E eps = %.6f); pressure %.1e; %d of 100 interface vertices touching\n",
              sol.body_force[0][0], sol.body_force[2][0], norm(sol.body_force[1]), F, perr, touching);
  EXPECT_EQ(touching, 100);
  EXPECT_NEAR(-sol.body_force[0][0], F, 1e-3 * F);
  EXPECT_NEAR(sol.body_force[2][0], F, 1e-3 * F);
  EXPECT_LE(norm(sol.body_force[1]), 1e-3 * F);
  EXPECT_LE(perr, 1e-3);
}

TEST(ContactBodies, FrictionBetweenBodiesIsRelative)
{
  // Two stacked cubes with friction 0.5 between them, pressed together (the lower's bottom and
  // the upper's top held, the top pushed down); in the next frame both held faces move by the
  // same (0.05, 0.02, 0): the pair moves rigidly, nothing slips relative to anything, and the frame
  // is the first one translated (slip measured on one body alone would be the whole move).
  const double g = 0.1 * delta;
  Bodies3 c(cubes_at({{0, 0, 0}, {0, 0, 1 + g}}));
  const auto bottom = [](const Vec3 &x) { return near(x[2], 0); };
  const auto top = [&](const Vec3 &x) { return near(x[2], 2 + g); };
  for (int k = 0; k < 3; ++k) c.hold_at(bottom, k, 0.0), c.hold_at(top, k, k == 2 ? -delta : 0.0);
  ContactSettings s;
  s.bodies = true, s.friction = 0.5;
  const CompositeReference ref(*c.op, node_bodies(*c.disc), c.pattern(), {}, dense_body);
  ContactEngine engine(*c.disc, ref, {}, s);
  ContactSolution first, moved;
  engine.solve(c.sel, std::vector<Pose>{}, first);
  const Vec3 shift{0.05, 0.02, 0};
  SystemSelection sel = c.sel;
  for (std::size_t i = 0; i < sel.known.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (sel.displacement_known[i][k]) sel.known[i][k] += shift[k];
  const ContactFrameReport rep = engine.solve(sel, std::vector<Pose>{}, moved);
  double du = 0, dt = 0, us = 0, ts = 0;
  for (std::size_t i = 0; i < first.u.size(); ++i)
    du = std::max(du, norm(moved.u[i] - first.u[i] - shift)), dt = std::max(dt, norm(moved.t[i] - first.t[i])), us = std::max(us, norm(first.u[i])), ts = std::max(ts, norm(first.t[i]));
  std::printf("two rough cubes moved rigidly: u against the first frame moved %.2e, t %.2e (relative); %lld stick, %lld slip\n", du / us, dt / ts, rep.stick, rep.slip);
  EXPECT_GT(rep.active_vertices, 20);
  EXPECT_LE(du, 1e-9 * us); // measured 2.0e-14 (t: 2.8e-13); the Newton tolerance x10 is the bound
  EXPECT_LE(dt, 1e-9 * ts);
}
