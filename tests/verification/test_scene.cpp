// Scenes (scene/dense_scene.hpp): every strategy against a from-scratch dense solve of the same
// boundary conditions, on the paper's cardioid with a contact patch moving over it; the
// capacitance inverse's updates against its rebuild.
#include "hssbem/core/lapack.hpp"
#include "hssbem/petsc/scene_krylov.h"
#include "hssbem/problem/problem.hpp"
#include "hssbem/problem/setup.hpp"
#include "hssbem/reference/capacitance.hpp"
#include "hssbem/scene/dense_scene.hpp"
#include "hssbem/scene/scene.hpp"
#include "hssbem/post/post.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <string>

namespace hssbem {
namespace {

// ---------------------------------------------------------------- capacitance inverse

std::vector<double> random_matrix(int n, unsigned seed)
{
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> W(static_cast<std::size_t>(n) * n);
  for (double &w : W) w = u(gen) / n;
  for (int i = 0; i < n; ++i) W[i + static_cast<std::size_t>(i) * n] += 1.0 + 0.5 * u(gen);
  return W;
}

/// The index set after an update: `set` without `drop`, then `add`.
std::vector<int> after_update(const std::vector<int> &set, const std::vector<int> &drop, const std::vector<int> &add)
{
  std::vector<int> next;
  for (int j : set)
    if (std::find(drop.begin(), drop.end(), j) == drop.end()) next.push_back(j);
  next.insert(next.end(), add.begin(), add.end());
  return next;
}

double max_diff(const CapacitanceInverse &a, const CapacitanceInverse &b)
{
  // same index set, possibly another order: compare entry (J_p, J_q)
  double d = 0;
  const int k = a.size();
  for (int p = 0; p < k; ++p)
    for (int q = 0; q < k; ++q) {
      const int i = b.position(a.indices()[p]), j = b.position(a.indices()[q]);
      d = std::max(d, std::abs(a.inverse_entry(p, q) - b.inverse_entry(i, j)));
    }
  return d;
}

TEST(Capacitance, UpdatesMatchTheRebuildAndInvertTheSubmatrix)
{
  const int n = 80;
  const std::vector<double> W = random_matrix(n, 7);
  CapacitanceInverse inc(W.data(), n), full(W.data(), n);
  inc.rebuild({3, 10, 11, 40, 41, 42});
  std::vector<int> set = {3, 10, 11, 40, 41, 42};
  std::mt19937 gen(3);
  for (int step = 0; step < 30; ++step) { // a window that moves: drop a few, add a few
    std::vector<int> drop, add;
    for (int j : set)
      if (gen() % 4 == 0) drop.push_back(j);
    for (int j = 0; j < n; ++j)
      if (std::find(set.begin(), set.end(), j) == set.end() && gen() % 12 == 0) add.push_back(j);
    inc.update(drop, add);
    set = after_update(set, drop, add);
    full.rebuild(set);
    ASSERT_EQ(inc.size(), static_cast<int>(set.size()));
    EXPECT_LT(max_diff(inc, full), 1e-11) << "step " << step;
  }
  // C⁻¹ C = I for the final set (and the set is not trivial)
  const int k = inc.size();
  ASSERT_GE(k, 5);
  double err = 0;
  for (int p = 0; p < k; ++p)
    for (int q = 0; q < k; ++q) {
      double s = 0;
      for (int r = 0; r < k; ++r) s += inc.inverse_entry(p, r) * W[inc.indices()[r] + static_cast<std::size_t>(inc.indices()[q]) * n];
      err = std::max(err, std::abs(s - (p == q)));
    }
  EXPECT_LT(err, 1e-12);
}

TEST(Capacitance, SinglePrecisionInverseRefinesToDoubleAccuracy)
{
  const int n = 300;
  const std::vector<double> W = random_matrix(n, 11);
  CapacitanceInverse single(W.data(), n, 0), exact(W.data(), n);
  std::vector<int> set;
  for (int j = 0; j < 120; ++j) set.push_back(2 * j);
  single.rebuild(set);
  ASSERT_TRUE(single.single());
  std::mt19937 gen(5);
  for (int step = 0; step < 20; ++step) {
    std::vector<int> drop, add;
    for (int j : set)
      if (gen() % 10 == 0) drop.push_back(j);
    for (int j = 1; j < n; j += 2)
      if (std::find(set.begin(), set.end(), j) == set.end() && gen() % 30 == 0) add.push_back(j);
    single.update(drop, add);
    set = after_update(set, drop, add);
  }
  exact.rebuild(single.indices());
  ASSERT_FALSE(exact.single());
  const int k = single.size();
  std::vector<double> r(k), s1(k), s2(k);
  for (int i = 0; i < k; ++i) r[i] = std::sin(0.3 * i) + 0.1;
  ASSERT_TRUE(single.solve(r.data(), s1.data()));
  exact.solve(r.data(), s2.data());
  double d = 0, nrm = 0;
  for (int i = 0; i < k; ++i) d += (s1[i] - s2[i]) * (s1[i] - s2[i]), nrm += s2[i] * s2[i];
  EXPECT_LT(std::sqrt(d / nrm), 1e-12);
  // single-precision entries really are single: they differ from the double inverse's
  double e = 0;
  for (int p = 0; p < k; ++p) e = std::max(e, std::abs(single.inverse_entry(p, p) - exact.inverse_entry(p, p)));
  EXPECT_GT(e, 1e-12);
}

TEST(Capacitance, InPlaceSlotsSurviveShrinkingGrowingAndSqueezing)
{
  // Updates work in place on slots: a dropped index leaves an empty slot, an added one fills
  // one or appends. Drive every case — drops without adds (empty slots, then a squeeze), adds
  // beyond the capacity (growth), swaps of equal size (slots reused) — in double and in single
  // precision, and compare each state with a rebuild and with C⁻¹ C = I.
  const int n = 400;
  const std::vector<double> W = random_matrix(n, 21);
  for (const int single_from : {INT_MAX, 0}) {
    CapacitanceInverse inc(W.data(), n, single_from), full(W.data(), n);
    std::vector<int> set;
    for (int j = 0; j < 60; ++j) set.push_back(3 * j);
    inc.rebuild(set);
    const int cap0 = inc.capacity();
    ASSERT_GT(cap0, 60);
    auto apply = [&](const std::vector<int> &drop, const std::vector<int> &add) {
      inc.update(drop, add);
      set = after_update(set, drop, add);
      full.rebuild(set);
      ASSERT_EQ(inc.size(), static_cast<int>(set.size()));
      const double tol = single_from == 0 ? 1e-5 : 1e-11; // single: the inverse itself is float
      EXPECT_LT(max_diff(inc, full), tol);
      // the same right-hand side by index (the two keep their indices in different orders)
      std::vector<double> r(set.size()), rf(set.size()), s(set.size()), e(set.size());
      for (std::size_t i = 0; i < r.size(); ++i) {
        r[i] = std::cos(0.7 * inc.indices()[i]) + 0.2;
        rf[full.position(inc.indices()[i])] = r[i];
      }
      ASSERT_TRUE(inc.solve(r.data(), s.data()));
      full.solve(rf.data(), e.data());
      double d = 0, nrm = 0;
      for (std::size_t i = 0; i < r.size(); ++i) {
        const double ei = e[full.position(inc.indices()[i])];
        d += (s[i] - ei) * (s[i] - ei), nrm += ei * ei;
      }
      EXPECT_LT(std::sqrt(d / nrm), 1e-11);
    };
    // Drop 5: five empty slots, not yet squeezed (5·8 ≤ 60).
    apply({0, 9, 30, 90, 177}, {});
    EXPECT_EQ(inc.slots(), 60);
    // Swap 4 for 4: the empty slots are reused, none appended.
    apply({3, 6}, {1, 4, 7, 10});
    EXPECT_EQ(inc.slots(), 60);
    // Add more than the capacity holds: the arrays grow.
    std::vector<int> add;
    for (int j = 0; static_cast<int>(add.size()) < cap0; ++j)
      if (std::find(set.begin(), set.end(), j) == set.end()) add.push_back(j);
    apply({12}, add);
    EXPECT_GT(inc.capacity(), cap0);
    // Drop a third: the empty slots exceed 1/8 and are squeezed out.
    std::vector<int> drop(set.begin(), set.begin() + static_cast<std::ptrdiff_t>(set.size() / 3));
    apply(drop, {});
    EXPECT_EQ(inc.slots(), inc.size());
  }
}

TEST(Capacitance, IllConditionedSinglePrecisionAsksForARebuild)
{
  const int n = 60;
  std::vector<double> W(static_cast<std::size_t>(n) * n, 0.0);
  std::mt19937 gen(9);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < n; ++i) // lower triangular with a huge spread on the diagonal: cond ~ 1e10
    for (int j = 0; j <= i; ++j) W[i + static_cast<std::size_t>(j) * n] = i == j ? std::pow(10.0, -10.0 * i / (n - 1)) : 0.5 * u(gen);
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  CapacitanceInverse c(W.data(), n, 0);
  c.rebuild(all);
  std::vector<double> r(n, 1.0), s(n);
  EXPECT_FALSE(c.solve(r.data(), s.data()));
  c.rebuild(all, true);
  EXPECT_FALSE(c.single());
  EXPECT_TRUE(c.solve(r.data(), s.data()));
}

TEST(Capacitance, RejectsIndicesNotInOrAlreadyInTheSet)
{
  const int n = 10;
  const std::vector<double> W = random_matrix(n, 1);
  CapacitanceInverse c(W.data(), n);
  c.rebuild({1, 2});
  EXPECT_THROW(c.update({5}, {}), std::invalid_argument);
  EXPECT_THROW(c.update({}, {2}), std::invalid_argument);
  EXPECT_THROW(c.rebuild({1, 1}), std::invalid_argument);
  std::vector<double> Z(n * n, 0.0);
  CapacitanceInverse s(Z.data(), n);
  EXPECT_THROW(s.rebuild({0, 1}), std::runtime_error);
}

// ---------------------------------------------------------------- scenes on the cardioid

struct Cardioid {
  SurfaceMesh mesh;
  std::unique_ptr<Discretization> disc;
  std::unique_ptr<BemOperator> op;
  std::vector<BoundaryRule> base;

  Cardioid()
  {
    mesh = read_mesh(std::string(HSSBEM_MESHES) + "/cardioid_832.msh");
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
    disc = std::make_unique<Discretization>(mesh, 40.0);
    op = std::make_unique<BemOperator>(*disc, Material::from_lame(1000.0, 500.0));
    BoundaryRule clamp;
    clamp.kind = BoundaryRule::Kind::Displacement;
    clamp.where.kind = Selector::Kind::Region;
    clamp.where.region_name = "base";
    clamp.rows = {{0, 0, 0}};
    base = {clamp};
  }

  /// Base rules plus a contact patch around angle phi at mid height pushed in by depth (all
  /// three components prescribed when full, else only the radial ones, the rest traction-free),
  /// and optionally a pressure load on the tip.
  SystemSelection frame(double phi, double depth, bool full = false, double tip_pressure = 0) const
  {
    std::vector<BoundaryRule> rules = base;
    BoundaryRule patch;
    patch.kind = BoundaryRule::Kind::Displacement;
    patch.where.kind = Selector::Kind::Sphere;
    patch.where.center = {0.45 * std::cos(phi), 0.45 * std::sin(phi), 0.5};
    patch.where.radius = 0.3;
    const double nan = std::nan("");
    patch.rows = {full ? Vec3{-depth * std::cos(phi), -depth * std::sin(phi), 0.0} : Vec3{-depth * std::cos(phi), nan, nan}};
    rules.push_back(patch);
    if (tip_pressure != 0) {
      BoundaryRule p;
      p.kind = BoundaryRule::Kind::Pressure;
      p.where.kind = Selector::Kind::Sphere;
      p.where.center = {0, 0, 1};
      p.where.radius = 0.2;
      p.pressure = {tip_pressure};
      rules.push_back(p);
    }
    return selection_of(apply_rules(rules, *disc, "test"));
  }

  SystemSelection reference() const
  {
    return selection_of(apply_rules(base, *disc, "test"));
  }

  /// From-scratch dense solve of the same boundary conditions.
  std::vector<double> dense(const SystemSelection &sel) const
  {
    const int nn = disc->num_nodes(), N = 3 * nn;
    std::vector<int> all(nn);
    std::iota(all.begin(), all.end(), 0);
    std::vector<double> A(static_cast<std::size_t>(N) * N), b(N);
    fill_system_block(*op, sel, all, all, A.data(), N, b.data());
    std::vector<int> piv(N);
    EXPECT_EQ(lapack::getrf(N, A.data(), N, piv.data()), 0);
    lapack::getrs('T', N, 1, A.data(), N, piv.data(), b.data(), N); // A is row-major: solve with its transpose
    return b;
  }
};

const Cardioid &cardioid()
{
  static const Cardioid c;
  return c;
}

double rel_diff(const std::vector<double> &a, const std::vector<double> &b)
{
  double num = 0, den = 0;
  for (std::size_t i = 0; i < a.size(); ++i) num += (a[i] - b[i]) * (a[i] - b[i]), den += b[i] * b[i];
  return std::sqrt(num / den);
}

TEST(DenseScene, EveryStrategyMatchesADenseSolveOfTheFrame)
{
  const Cardioid &c = cardioid();
  DenseScene scene(*c.op, c.reference(), SceneOptions{}, HssbemSceneKrylovCreate());
  std::vector<double> x, first;
  const SceneStrategy order[] = {SceneStrategy::Update, SceneStrategy::Update, SceneStrategy::Refactor, SceneStrategy::Krylov, SceneStrategy::Update,
                                 SceneStrategy::Krylov, SceneStrategy::Auto};
  for (int f = 0; f < 7; ++f) {
    const SystemSelection sel = c.frame(0.25 * f, 0.04 + 0.002 * f, f % 3 == 2);
    const SceneFrameReport &rep = scene.solve(sel, x, order[f]);
    const std::vector<double> ref = c.dense(sel);
    // Round-off margins (10x): measured up to 4.7e-10 (the krylov frames: GMRES to a true residual
    // of 1e-10), and a residual of 8.4e-11, below the tolerance by construction but for rounding.
    EXPECT_LT(rel_diff(x, ref), 5e-9) << "frame " << f << " (" << scene_strategy_name(rep.strategy) << ")";
    EXPECT_LT(scene.residual(sel, x), 1e-9) << "frame " << f;
    EXPECT_GE(rep.switched, 10) << "frame " << f; // the patch switches unknowns: not the reference
    EXPECT_GT(rep.changed, 0) << "frame " << f;
    if (order[f] != SceneStrategy::Auto) EXPECT_EQ(rep.strategy, order[f]);
    if (rep.strategy == SceneStrategy::Krylov) {
      EXPECT_GE(rep.iterations, 1);
      EXPECT_LE(rep.iterations, rep.changed + 2); // the previous factorization differs by rank `changed`
    }
    if (f == 0) first = x;
  }
  EXPECT_GT(rel_diff(x, first), 1e-2); // the patch moved: the answer changed
}

TEST(DenseScene, ValuesOnlyFramesSolveAndTheHapticLoopGivesTheSwitchedUnknowns)
{
  const Cardioid &c = cardioid();
  DenseScene scene(*c.op, c.reference());
  std::vector<double> x, sw;
  const SystemSelection sel = c.frame(1.0, 0.03);
  EXPECT_EQ(scene.solve(sel, x).strategy, SceneStrategy::Update);
  for (double depth : {0.01, 0.05}) {
    const SystemSelection deeper = c.frame(1.0, depth);
    const SceneFrameReport &rep = scene.solve(deeper, x);
    EXPECT_EQ(rep.strategy, SceneStrategy::Solve); // auto: the pattern did not change
    EXPECT_EQ(rep.changed, 0);
    EXPECT_LT(rel_diff(x, c.dense(deeper)), 1e-9);
    scene.solve_switched(deeper, sw);
    ASSERT_EQ(sw.size(), scene.switched().size());
    ASSERT_GE(sw.size(), 10u);
    double d = 0, n = 0;
    for (std::size_t p = 0; p < sw.size(); ++p) d = std::max(d, std::abs(sw[p] - x[scene.switched()[p]])), n = std::max(n, std::abs(x[scene.switched()[p]]));
    EXPECT_LT(d, 1e-10 * n);
    EXPECT_GT(n, 0.0);
  }
  EXPECT_THROW(scene.solve(c.frame(2.0, 0.03), x, SceneStrategy::Solve), std::invalid_argument);
  EXPECT_THROW(scene.solve_switched(c.frame(2.0, 0.03), sw), std::invalid_argument);
}

TEST(DenseScene, PressureLoadsAndLongMovesKeepTheAccuracy)
{
  const Cardioid &c = cardioid();
  SceneOptions opt;
  opt.with_pressure = true;
  opt.refresh_every = 1000; // incremental updates only: their error must not build up
  DenseScene scene(*c.op, c.reference(), opt);
  std::vector<double> x;
  int incremental = 0;
  for (int f = 0; f < 40; ++f) {
    const SystemSelection sel = c.frame(0.05 * f, 0.03, false, f % 5 == 0 ? 50.0 : 0.0);
    const SceneFrameReport &rep = scene.solve(sel, x, SceneStrategy::Update);
    incremental += !rep.rebuilt && rep.changed > 0;
    if (f % 13 == 0 || f == 39) EXPECT_LT(rel_diff(x, c.dense(sel)), 1e-9) << "frame " << f;
  }
  EXPECT_GT(incremental, 10); // the small moves were incremental updates
  SceneOptions no_pressure;
  DenseScene plain(*c.op, c.reference(), no_pressure);
  EXPECT_THROW(plain.solve(c.frame(0, 0.03, false, 50.0), x), std::invalid_argument);
}

TEST(DenseScene, SinglePrecisionCapacitanceMatchesTheDenseSolves)
{
  const Cardioid &c = cardioid();
  SceneOptions opt;
  opt.single_from = 0; // every switched set in single precision, refined in double
  DenseScene scene(*c.op, c.reference(), opt);
  std::vector<double> x, sw;
  for (int f = 0; f < 12; ++f) {
    const SystemSelection sel = c.frame(0.08 * f, 0.04, f % 2 == 0);
    const SceneFrameReport &rep = scene.solve(sel, x, SceneStrategy::Update);
    if (f % 4 == 3) EXPECT_LT(rel_diff(x, c.dense(sel)), 1e-9) << "frame " << f << (rep.rebuilt ? " (rebuilt)" : "");
  }
  scene.solve_switched(c.frame(0.88, 0.05, false), sw); // the last pattern (f = 11), new values
  const SystemSelection last = c.frame(0.88, 0.05, false);
  scene.solve(last, x);
  ASSERT_EQ(sw.size(), scene.switched().size());
  for (std::size_t p = 0; p < sw.size(); ++p) EXPECT_NEAR(sw[p], x[scene.switched()[p]], 1e-9 * (1 + std::abs(x[scene.switched()[p]])));
}

TEST(DenseScene, SinglePrecisionFieldsKeepTheSwitchedUnknownsInDouble)
{
  const Cardioid &c = cardioid();
  SceneOptions opt, exact;
  opt.single_from = opt.single_fields_from = 0; // W(:, J) for the fields in single precision
  exact.single_from = 0;                          // the same capacitance, fields in double
  DenseScene scene(*c.op, c.reference(), opt), twin(*c.op, c.reference(), exact);
  std::vector<double> x, y;
  double worst = 0, least = 1;
  for (int f = 0; f < 10; ++f) { // moves (updates), values only, and a move back (slots reused)
    const SystemSelection sel = c.frame(f < 8 ? 0.08 * (f / 2) : 0.0, f % 2 ? 0.05 : 0.03, true);
    const SceneFrameReport &rep = scene.solve(sel, x);
    twin.solve(sel, y);
    EXPECT_GE(rep.refinements, 1) << "frame " << f;
    const std::vector<double> ref = c.dense(sel);
    const double err = rel_diff(x, ref);
    worst = std::max(worst, err), least = std::min(least, rel_diff(x, y));
    EXPECT_LT(err, 5e-8) << "frame " << f; // measured up to 5.0e-9 (W's single-precision rounding; 10x for other machines)
    double d = 0, n = 0; // the switched unknowns (the contact's tractions) stay double-accurate
    for (int j : scene.switched()) d = std::max(d, std::abs(x[j] - ref[j])), n = std::max(n, std::abs(ref[j]));
    EXPECT_LT(d, 1e-9 * n) << "frame " << f;
  }
  EXPECT_GT(least, 1e-12); // the fields really came from single precision: measured 4.3e-9 apart at least (double: ~1e-14)
  EXPECT_GT(worst, 0.0);
}

TEST(DenseScene, CandidateColumnsOnlyGiveTheSameFramesAndRefuseOthers)
{
  const Cardioid &c = cardioid();
  std::vector<SystemSelection> frames;
  for (int f = 0; f < 4; ++f) frames.push_back(c.frame(0.08 * f, f % 2 ? 0.05 : 0.03, f % 2 == 0));
  SceneOptions opt;
  for (const SystemSelection &f : frames) mark_scene_candidates(c.reference(), f, opt.candidates);
  const long long count = std::count(opt.candidates.begin(), opt.candidates.end(), 1);
  DenseScene scene(*c.op, c.reference(), opt), twin(*c.op, c.reference());
  const double N = scene.num_unknowns();
  ASSERT_GT(count, 0);
  ASSERT_LT(count, N / 2); // the patches' unknowns only
  EXPECT_LE(scene.memory_bytes(), twin.memory_bytes() - 8.0 * N * (N - count)); // W's other columns are not kept
  std::vector<double> x, y;
  for (int round = 0; round < 2; ++round)
    for (const SystemSelection &f : frames) { // updates, then the same patterns again
      scene.solve(f, x);
      twin.solve(f, y);
      EXPECT_LT(rel_diff(x, y), 1e-12); // measured 0: the same columns, the same arithmetic
    }
  try { // a patch on the other side switches unknowns that are no candidates
    scene.solve(c.frame(3.0, 0.05, true), x);
    ADD_FAILURE() << "a frame outside the candidates was solved";
  } catch (const std::invalid_argument &e) {
    EXPECT_NE(std::string(e.what()).find("not among the scene's candidates"), std::string::npos) << e.what();
  }
  scene.solve(frames[1], x); // and the scene goes on
  twin.solve(frames[1], y);
  EXPECT_LT(rel_diff(x, y), 1e-12);
  SceneOptions none; // no candidates at all: W is empty, the cost model keeps finite rates
  none.candidates.assign(static_cast<std::size_t>(N), 0);
  const DenseScene bare(*c.op, c.reference(), none);
  EXPECT_GT(bare.bandwidth(), 0.0);
  EXPECT_TRUE(std::isfinite(bare.bandwidth()));
}

/// The Scene API's reference pattern on the cardioid: its base (z < 0.044) clamped.
Scene::Pattern clamped_base(const Cardioid &c)
{
  Scene::Pattern reference(c.mesh.num_vertices(), {false, false, false});
  for (int v = 0; v < c.mesh.num_vertices(); ++v)
    if (c.mesh.vertices[v][2] < 0.044) reference[v] = {true, true, true};
  return reference;
}

TEST(Scene, PerVertexFramesMatchTheEngineAndTheHapticForcesMatchTheTractions)
{
  const Cardioid &c = cardioid();
  const int nv = c.mesh.num_vertices();
  const Scene::Pattern reference = clamped_base(c);
  Scene scene(c.mesh, Material::from_lame(1000.0, 500.0), reference);
  for (int f = 0; f < 3; ++f) {
    Scene::Pattern pattern = reference;
    std::vector<Vec3> values(nv, Vec3{0, 0, 0});
    const Vec3 centre{0.45 * std::cos(0.3 * f), 0.45 * std::sin(0.3 * f), 0.5};
    int contact = 0;
    for (int v = 0; v < nv; ++v)
      if (!reference[v][0] && norm(c.mesh.vertices[v] - centre) < 0.3) pattern[v] = {true, true, true}, values[v] = {0, 0, -0.02}, ++contact;
    ASSERT_GT(contact, 10);
    scene.set_pattern(pattern);
    scene.set_values(values);
    const SceneFrameReport &rep = scene.solve();
    EXPECT_EQ(rep.switched, 3 * contact);
    // the same frame through the node-level selection and a dense solve
    SystemSelection sel;
    for (int n = 0; n < scene.discretization().num_nodes(); ++n) {
      const int v = scene.discretization().node(n).vertex;
      sel.displacement_known.push_back(pattern[v]);
      sel.known.push_back(values[v]);
    }
    const NodalSolution ref = split_unknowns(sel, c.dense(sel));
    const std::vector<Vec3> u = vertex_average(scene.discretization(), ref.u), t = vertex_average(scene.discretization(), ref.t);
    double du = 0, nu = 0;
    for (int v = 0; v < nv; ++v) du += dot(scene.displacement()[v] - u[v], scene.displacement()[v] - u[v]), nu += dot(u[v], u[v]);
    EXPECT_LT(std::sqrt(du / nu), 1e-9);
    // haptic: force = traction x lumped area on the contact vertices
    const std::vector<double> area = node_areas(scene.discretization());
    const std::vector<Scene::VertexForce> forces = scene.contact_forces();
    EXPECT_EQ(static_cast<int>(forces.size()), contact);
    double df = 0, nf = 0;
    for (const auto &vf : forces) {
      const int n = scene.discretization().first_node(vf.vertex);
      ASSERT_EQ(scene.discretization().node_count(vf.vertex), 1);
      const Vec3 expect = area[n] * ref.t[n];
      df = std::max(df, norm(vf.force - expect)), nf = std::max(nf, norm(expect));
    }
    EXPECT_GT(nf, 0.0);
    EXPECT_LT(df, 1e-9 * nf);
  }
  EXPECT_THROW(scene.set_pattern(Scene::Pattern(3)), std::invalid_argument);
  EXPECT_THROW(scene.set_values(std::vector<Vec3>(3)), std::invalid_argument);
}

TEST(Scene, CandidateVerticesGiveTheSameFrames)
{
  const Cardioid &c = cardioid();
  const int nv = c.mesh.num_vertices();
  const Scene::Pattern reference = clamped_base(c);
  const auto patch = [&](double phi) {
    const Vec3 centre{0.45 * std::cos(phi), 0.45 * std::sin(phi), 0.5};
    std::vector<char> in(nv, 0);
    for (int v = 0; v < nv; ++v) in[v] = !reference[v][0] && norm(c.mesh.vertices[v] - centre) < 0.3;
    return in;
  };
  std::vector<char> candidates(nv, 0);
  for (int f = 0; f < 3; ++f)
    for (int v = 0; v < nv; ++v) candidates[v] |= patch(0.3 * f)[v];
  Scene lean(c.mesh, Material::from_lame(1000.0, 500.0), reference, {}, nullptr, 40.0, candidates), full(c.mesh, Material::from_lame(1000.0, 500.0), reference);
  EXPECT_LT(lean.engine().memory_bytes(), full.engine().memory_bytes()); // W's other columns are not computed
  for (int f = 0; f < 3; ++f) {
    Scene::Pattern pattern = reference;
    std::vector<Vec3> values(nv, Vec3{0, 0, 0});
    const std::vector<char> in = patch(0.3 * f);
    for (int v = 0; v < nv; ++v)
      if (in[v]) pattern[v] = {true, true, true}, values[v] = {0, 0, -0.02};
    for (Scene *s : {&lean, &full}) s->set_pattern(pattern), s->set_values(values), s->solve();
    double d = 0, n = 0;
    for (int v = 0; v < nv; ++v) d = std::max(d, norm(lean.displacement()[v] - full.displacement()[v])), n = std::max(n, norm(full.displacement()[v]));
    EXPECT_GT(n, 0.0);
    EXPECT_LE(d, 1e-12 * n); // measured 0: the same columns
  }
  Scene::Pattern away = reference; // a vertex on the far side is no candidate
  const std::vector<char> far = patch(3.0);
  for (int v = 0; v < nv; ++v)
    if (far[v] && !candidates[v]) away[v] = {true, true, true};
  lean.set_pattern(away);
  EXPECT_THROW(lean.solve(), std::invalid_argument);
  SceneOptions per_unknown;
  per_unknown.candidates.assign(3, 1);
  EXPECT_THROW(Scene(c.mesh, Material::from_lame(1000.0, 500.0), reference, per_unknown), std::invalid_argument);
}

TEST(SceneStrategy, NamesRoundTrip)
{
  for (const char *s : {"auto", "solve", "update", "refactor", "krylov"}) EXPECT_STREQ(scene_strategy_name(*parse_scene_strategy(s)), s);
  EXPECT_FALSE(parse_scene_strategy("woodbury"));
}

} // namespace
} // namespace hssbem
