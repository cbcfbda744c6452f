// The contact engine of contact_engine.hpp: a frame is detection, the compliance of its contact
// points, the frictionless or frictional solve, and the fields from one product with W's columns.
#include "hssbem/contact/contact_engine.hpp"

#include "engine_state.hpp"

#include "hssbem/bem/discretization.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hssbem {

using contact_detail::Compliance;
using contact_detail::ContactPoint;
using contact_detail::Geometry;

namespace {

double mesh_size(const SurfaceMesh &m) { return Box::of(m.vertices).diagonal(); }

/// The candidates: vertices the settings allow, used by a triangle, not held in all three
/// components at every dof node.
std::vector<char> candidates(const Discretization &disc, const std::vector<char> &pattern, const ContactSettings &s)
{
  const int nv = disc.mesh().num_vertices();
  if (!s.candidate.empty() && static_cast<int>(s.candidate.size()) != nv) throw std::invalid_argument("contact: the candidate list needs one entry per vertex");
  std::vector<char> c(nv, 0);
  for (int v = 0; v < nv; ++v) {
    if ((!s.candidate.empty() && !s.candidate[v]) || disc.node_count(v) == 0) continue;
    for (int i = disc.first_node(v); i < disc.first_node(v) + disc.node_count(v); ++i)
      if (!pattern[3 * i] || !pattern[3 * i + 1] || !pattern[3 * i + 2]) c[v] = 1;
  }
  return c;
}

/// `pattern` must outlive the geometry (detection reads it).
Geometry make_geometry(const Discretization &disc, const std::vector<char> &pattern, std::vector<Obstacle> obstacles, const ContactSettings &s, const ContactOptions &o)
{
  if (!(s.friction >= 0 && std::isfinite(s.friction))) throw std::invalid_argument("contact: the friction coefficient must be finite and >= 0");
  if (!(o.reach >= 0 && std::isfinite(o.reach)) || !(o.depth >= 0 && std::isfinite(o.depth)) || !(o.tol > 0 && o.tol < 1) || o.max_it < 1 || !(o.pair_again >= 0))
    throw std::invalid_argument("contact: options out of range (reach >= 0, depth >= 0, 0 < tol < 1, max_it >= 1, pair_again >= 0)");
  Geometry g;
  g.reach = o.reach > 0 ? o.reach : 0.05 * mesh_size(disc.mesh());
  g.disc = &disc;
  g.pattern = &pattern;
  g.bodies = find_bodies(disc.mesh());
  g.area = node_areas(disc);
  g.candidate = candidates(disc, pattern, s);
  for (std::size_t i = 0; i < obstacles.size(); ++i) {
    for (std::size_t k = 0; k < i; ++k)
      if (obstacles[k].name == obstacles[i].name) throw std::invalid_argument("contact: two obstacles are named '" + obstacles[i].name + "'");
    g.obstacles.emplace_back(std::move(obstacles[i]), o.depth > 0 ? o.depth : g.reach);
  }
  g.partners = static_cast<int>(g.obstacles.size()) + g.bodies.count;
  g.friction = s.friction;
  g.bodies_touch = s.bodies;
  if (s.bodies)
    for (int b = 0; b < g.bodies.count; ++b) {
      std::vector<int> tris;
      for (int t = 0; t < disc.mesh().num_triangles(); ++t)
        if (g.bodies.of_triangle[t] == b) tris.push_back(t);
      g.body_bvh.emplace_back(disc.mesh().vertices, disc.mesh().triangles, tris);
    }
  return g;
}

std::vector<char> node_pattern(const std::vector<std::array<bool, 3>> &known)
{
  std::vector<char> p(3 * known.size());
  for (std::size_t i = 0; i < known.size(); ++i)
    for (int c = 0; c < 3; ++c) p[3 * i + c] = known[i][c];
  return p;
}

/// s when `values` are `base`'s known values times s (the same pattern, no pressure loads, each
/// value within round-off of s times base's), else NaN: the free response of a load that ramps
/// up is the last solved one scaled, no solve.
double known_ratio(const SystemSelection &values, const SystemSelection &base)
{
  const auto no_pressure = [](const SystemSelection &v) { return std::all_of(v.pressure.begin(), v.pressure.end(), [](double p) { return std::isnan(p); }); };
  if (values.displacement_known != base.displacement_known || values.known.size() != base.known.size() || !no_pressure(values) || !no_pressure(base)) return std::nan("");
  double s = std::nan("");
  for (std::size_t i = 0; i < base.known.size() && std::isnan(s); ++i)
    for (int c = 0; c < 3 && std::isnan(s); ++c)
      if (base.known[i][c] != 0) s = values.known[i][c] / base.known[i][c];
  if (!std::isfinite(s)) return std::nan("");
  for (std::size_t i = 0; i < base.known.size(); ++i)
    for (int c = 0; c < 3; ++c)
      if (std::abs(values.known[i][c] - s * base.known[i][c]) > 4e-16 * std::abs(values.known[i][c])) return std::nan("");
  return s;
}

} // namespace

namespace {

/// The prescribed components of body b's dof nodes as constraints on its rigid motions.
std::vector<NodeConstraint> body_constraints(const Discretization &disc, const std::vector<std::array<bool, 3>> &known, const Bodies &bodies, int b)
{
  std::vector<NodeConstraint> held;
  for (int i = 0; i < disc.num_nodes(); ++i)
    if (bodies.of_vertex[disc.node(i).vertex] == b)
      for (int c = 0; c < 3; ++c)
        if (known[i][c]) held.push_back({i, Vec3{c == 0 ? 1.0 : 0.0, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0}});
  return held;
}

/// How far vertex v of body b lies from what may touch it at the base positions: the obstacles'
/// gaps and, with "bodies", the other bodies' surfaces (infinite for a vertex that never touches).
double partner_distance(const Geometry &g, int v, int b)
{
  const Vec3 &x = g.disc->mesh().vertices[v];
  double d = std::numeric_limits<double>::infinity();
  if (!g.candidate[v]) return d;
  for (const ObstacleGeometry &o : g.obstacles) {
    ObstacleGap h;
    if (o.gap(x, Pose{}, std::numeric_limits<double>::infinity(), h)) d = std::min(d, std::abs(h.gap));
  }
  for (int other = 0; g.bodies_touch && other < g.bodies.count; ++other) {
    if (other == b) continue;
    const TriangleHit hit = g.body_bvh[other].closest(x);
    if (hit.triangle >= 0) d = std::min(d, norm(hit.point - x));
  }
  return d;
}

/// Body b's pin vertices: the farthest from its partners (A), then among those at least half as
/// far, the farthest from A (B) and from the line AB (C); then the rest by distance (a fallback).
std::vector<int> pin_vertices(const Geometry &g, int b, const std::vector<char> &loaded)
{
  const std::vector<Vec3> &xs = g.disc->mesh().vertices;
  std::vector<int> vs;
  std::vector<double> dist(xs.size(), 0);
  for (int v = 0; v < static_cast<int>(xs.size()); ++v)
    if (g.bodies.of_vertex[v] == b && g.disc->node_count(v) > 0) vs.push_back(v), dist[v] = !loaded.empty() && loaded[v] ? 0.0 : std::min(partner_distance(g, v, b), 1e300);
  std::stable_sort(vs.begin(), vs.end(), [&](int p, int q) { return dist[p] > dist[q]; });
  if (vs.empty()) return vs;
  const int A = vs[0];
  auto pick = [&](auto score) {
    int best = A;
    double top = -1;
    for (int v : vs)
      if (dist[v] >= 0.5 * dist[A] && score(v) > top) top = score(v), best = v;
    return best;
  };
  const int B = pick([&](int v) { return norm(xs[v] - xs[A]); });
  const Vec3 ab = xs[B] - xs[A];
  const int C = pick([&](int v) { return norm(cross(ab, xs[v] - xs[A])); });
  std::vector<int> order{A, B, C};
  order.insert(order.end(), vs.begin(), vs.end());
  return order;
}

} // namespace

std::vector<int> floating_pins(const Discretization &disc, const std::vector<std::array<bool, 3>> &known, const std::vector<Obstacle> &obstacles, const ContactSettings &settings,
                               const ContactOptions &options, const std::vector<char> &loaded)
{
  const std::vector<char> pattern = node_pattern(known);
  ContactSettings s = settings;
  s.bodies = true; // the other bodies' surfaces count as partners for the pins' distance
  const Geometry g = make_geometry(disc, pattern, obstacles, s, options);
  std::vector<int> pins;
  for (int b = 0; b < g.bodies.count; ++b) {
    std::vector<NodeConstraint> held = body_constraints(disc, known, g.bodies, b);
    int rank = analyse_constraints(disc, held).rank;
    for (int v : rank == 6 ? std::vector<int>{} : pin_vertices(g, b, loaded))
      for (int c = 0; c < 3 && rank < 6; ++c) {
        const Vec3 e{c == 0 ? 1.0 : 0.0, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0};
        std::vector<NodeConstraint> more = held;
        for (int i = disc.first_node(v); i < disc.first_node(v) + disc.node_count(v); ++i) more.push_back({i, e});
        const int r = analyse_constraints(disc, more).rank;
        if (r <= rank) continue;
        rank = r, held = std::move(more);
        for (int i = disc.first_node(v); i < disc.first_node(v) + disc.node_count(v); ++i) pins.push_back(3 * i + c);
      }
  }
  std::sort(pins.begin(), pins.end());
  return pins;
}

// --- the engine -----------------------------------------------------------------------------------

ContactEngine::ContactEngine(const Discretization &disc, const ReferenceFactorization &reference, std::vector<Obstacle> obstacles, const ContactSettings &settings,
                             const ContactOptions &options, std::shared_ptr<ReferenceColumns> columns)
{
  if (reference.num_unknowns() != 3 * disc.num_nodes()) throw std::invalid_argument("contact: the reference does not match the discretization");
  if (columns && &columns->reference() != &reference) throw std::invalid_argument("contact: the shared columns belong to another reference");
  m = std::make_unique<State>(disc, reference, make_geometry(disc, reference.pattern(), std::move(obstacles), settings, options), options);
  m->exact = reference.exact_columns();
  m->columns = columns ? std::move(columns) : std::make_shared<ReferenceColumns>(reference, spatial_order(disc));
  m->node_position.resize(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) m->node_position[i] = m->columns->position(3 * i) / 3;
  m->size = mesh_size(disc.mesh());
  m->tol_gap = options.tol * m->size;
  m->forced.assign(static_cast<std::size_t>(disc.mesh().num_vertices()) * m->geo.obstacles.size(), 0);
  m->u_prev.assign(disc.num_nodes(), Vec3{0, 0, 0});
  m->u_response.assign(disc.num_nodes(), Vec3{0, 0, 0});
  m->friction = settings.friction > 0;
  for (const ObstacleGeometry &o : m->geo.obstacles) m->friction = m->friction || o.obstacle().friction > 0;
  m->set_up_floating(settings.pins);
}

ContactEngine::~ContactEngine() = default;

int ContactEngine::num_obstacles() const { return static_cast<int>(m->geo.obstacles.size()); }
const std::string &ContactEngine::obstacle_name(int o) const { return m->geo.obstacles.at(o).name(); }
std::vector<char> contact_loaded_unknowns(const Discretization &disc, const std::vector<char> &pattern, const std::vector<Obstacle> &obstacles, const ContactSettings &settings,
                                          const ContactOptions &options)
{
  const Geometry g = make_geometry(disc, pattern, obstacles, settings, options);
  std::vector<char> need(pattern.size(), 0);
  for (int i = 0; i < disc.num_nodes(); ++i)
    if (g.candidate[disc.node(i).vertex])
      for (int c = 0; c < 3; ++c) need[3 * i + c] = 1;
  for (const ContactPoint &p : contact_detail::body_points(g)) // the master nodes a pair loads
    for (int k = 0; k < p.terms; ++k)
      for (int c = 0; c < 3; ++c) need[3 * p.term_node[k] + c] = 1;
  return need;
}

const Bodies &ContactEngine::bodies() const { return m->geo.bodies; }
std::vector<int> ContactEngine::floating_bodies() const
{
  std::vector<int> b;
  for (const State::Floating &f : m->floating) b.push_back(f.body);
  std::sort(b.begin(), b.end());
  return b;
}
double ContactEngine::reach() const { return m->geo.reach; }
std::size_t ContactEngine::memory_bytes() const { return m->columns->memory_bytes(); }
const std::shared_ptr<ReferenceColumns> &ContactEngine::columns() const { return m->columns; }
std::vector<int> ContactEngine::spatial_order(const Discretization &disc) { return contact_detail::spatial_row_order(disc); }

void ContactEngine::prefetch(const std::vector<std::vector<Pose>> &placements)
{
  if (!m->friction && !m->ref->exact_columns()) return; // columns that cost solves: only the active points', as the iterations ask
  std::vector<char> need(m->ref->pattern().size(), 0);
  auto mark = [&](const std::vector<ContactPoint> &pts) {
    for (int j : contact_detail::loaded_unknowns(pts, m->ref->pattern(), !m->friction)) need[j] = 1;
  };
  const std::vector<ContactPoint> pairs = contact_detail::body_points(m->geo);
  for (const std::vector<Pose> &poses : placements) { // the followers at sharp vertices load columns too
    if (poses.size() != m->geo.obstacles.size()) throw std::invalid_argument("contact: one pose per obstacle expected");
    mark(contact_detail::merge_points(m->geo, contact_detail::obstacle_points(m->geo, poses, m->forced), pairs));
  }
  if (placements.empty()) mark(contact_detail::merge_points(m->geo, {}, pairs));
  std::vector<int> js;
  for (std::size_t j = 0; j < need.size(); ++j)
    if (need[j]) js.push_back(static_cast<int>(j));
  m->columns->require(js);
}

namespace {

std::vector<Pose> poses_of(const std::vector<Vec3> &offsets)
{
  std::vector<Pose> poses;
  for (const Vec3 &t : offsets) poses.push_back(Pose::translation(t));
  return poses;
}

} // namespace

void ContactEngine::prefetch(const std::vector<std::vector<Vec3>> &placements)
{
  std::vector<std::vector<Pose>> poses;
  for (const std::vector<Vec3> &offsets : placements) poses.push_back(poses_of(offsets));
  prefetch(poses);
}

void ContactEngine::State::free_response(const SystemSelection &values)
{
  const bool same = has_free && values.displacement_known == free_values.displacement_known && values.known == free_values.known &&
                    values.pressure.size() == free_values.pressure.size() &&
                    std::equal(values.pressure.begin(), values.pressure.end(), free_values.pressure.begin(), [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); });
  if (same) return;
  free_values = values;
  has_free = true;
  const double s = exact ? known_ratio(values, solved_values) : std::nan("");
  if (std::isfinite(s)) { // the same loads scaled (a push that ramps up): the response scales
    xf.resize(solved_xf.size());
    for (std::size_t p = 0; p < xf.size(); ++p) xf[p] = s * solved_xf[p];
  } else {
    ref->free_response(values, xf);
    solved_values = values, solved_xf = xf;
  }
  set_u_free();
}

void ContactEngine::State::set_u_free()
{
  const std::vector<char> &pattern = ref->pattern();
  u_free.resize(disc->num_nodes());
  for (int i = 0; i < disc->num_nodes(); ++i)
    for (int c = 0; c < 3; ++c) u_free[i][c] = pattern[3 * i + c] ? free_values.known[i][c] : xf[3 * i + c];
  if (!floating.empty())
    for (int i = 0; i < disc->num_nodes(); ++i) u_free[i] = u_free[i] + rigid_at(i, alpha); // the floating bodies' motions
  if (!u_particular.empty())
    for (int i = 0; i < disc->num_nodes(); ++i) u_free[i] = u_free[i] + u_particular[i]; // the body force's particular solution
}

void ContactEngine::set_body_force(const Vec3 &b, std::vector<Vec3> u_p, std::vector<Vec3> t_p)
{
  const std::size_t n = m->disc->num_nodes();
  if ((!u_p.empty() && u_p.size() != n) || t_p.size() != u_p.size()) throw std::invalid_argument("contact: the particular traces need one entry per dof node");
  m->body_force = b;
  m->t_particular = std::move(t_p);
  if (u_p == m->u_particular) return;
  m->u_particular = std::move(u_p);
  m->has_free = false; // the free displacement changes
}

/// Approximate columns W̃ (ReferenceFactorization::exact_columns() false): the frame was solved
/// with x = x_f' − W̃ L λ. The true unknowns of its tractions, x_true = A₀⁻¹ b(values + L λ) (one
/// accurate solve), differ by δ; x_f' += δ makes the fields exact at this λ, and the frame is
/// solved again. A fixed point has x = x_true and the contact conditions on it: the exact answer.
/// Each pass shrinks the error by about W̃'s relative error (the factorization's tolerance). The
/// corrected x_f' stays for the next frame of the same values (a warm start of its corrections).
void ContactEngine::State::correct(const SystemSelection &values, ContactSolution &out, ContactFrameReport &rep)
{
  const PhaseScope phase(Phase::ContactCorrect);
  for (;;) {
    SystemSelection loaded = values;
    std::vector<int> js;
    std::vector<double> v, x;
    D->loads(lambda, js, v);
    for (std::size_t q = 0; q < js.size(); ++q) loaded.known[js[q] / 3][js[q] % 3] += v[q];
    ref->free_response(loaded, x);
    double dn = 0, xn = 0;
    for (std::size_t p = 0; p < x.size(); ++p) {
      const double d = x[p] - out.x[p];
      dn += d * d, xn += x[p] * x[p], xf[p] += d;
    }
    ++rep.corrections;
    rep.correction = std::sqrt(dn / std::max(xn, 1e-300));
    if (rep.correction <= opt.correction_tol) return;
    if (rep.corrections >= opt.max_it)
      throw std::runtime_error("the corrections of the compressed reference did not settle in " + std::to_string(opt.max_it) + " solves (-contact_max_it; last change " +
                               std::to_string(rep.correction) + ")");
    set_u_free(); // xf changed
    settle(out, rep);
  }
}

const ContactFrameReport &ContactEngine::solve(const SystemSelection &values, const std::vector<Pose> &poses, ContactSolution &out)
{
  State &s = *m;
  if (poses.size() != s.geo.obstacles.size()) throw std::invalid_argument("contact: one pose per obstacle expected");
  s.solved = false; // until this frame is solved: the haptic call refuses a failed frame
  ++s.frame;
  const Timer timer;
  ContactFrameReport rep;
  try {
    s.free_response(values);
    s.poses = poses;
    s.step_from = s.last_poses.empty() ? poses : s.last_poses;
    s.zone_keys.assign(s.disc->num_nodes() * static_cast<std::size_t>(s.geo.partners), 0);
    const Timer detect;
    rep.paired = s.pair_bodies();
    rep.pair_seconds = detect.seconds();
    s.detect();
    rep.detect_seconds += detect.seconds();
    rep.rounds = 0;
    s.settle(out, rep);
    if (!s.ref->exact_columns()) {
      const Timer correct;
      s.correct(values, out, rep);
      rep.correct_seconds += correct.seconds();
    }
  } catch (const std::runtime_error &e) {
    throw std::runtime_error(s.frame_error(e.what()));
  }
  s.outputs(out);
  if (s.friction) s.u_prev = out.u; // slip is measured from the previous frame
  if (s.geo.bodies_touch) // the contact's share of the displacement: the next frame's pairing adds its free response
    for (std::size_t i = 0; i < out.u.size(); ++i) s.u_response[i] = out.u[i] - s.u_free[i], s.responded = true;
  s.last_poses = poses;
  s.solved = true;
  rep.candidates = s.D->size();
  for (std::int8_t st : out.status) rep.active_vertices += st != 0, rep.stick += st == 1, rep.slip += st == 2;
  rep.seconds = timer.seconds();
  s.report = rep;
  return s.report;
}

const ContactFrameReport &ContactEngine::solve(const SystemSelection &values, const std::vector<Vec3> &offsets, ContactSolution &out)
{
  return solve(values, poses_of(offsets), out);
}

std::vector<Vec3> ContactEngine::haptic_forces(const std::vector<Pose> &poses)
{
  State &s = *m;
  if (!s.solved) throw std::runtime_error(s.frame < 0 ? "contact: the haptic call needs a solved frame first" : "contact: the haptic call refuses to run: the last frame (" + std::to_string(s.frame) + ") was not solved");
  if (poses.size() != s.geo.obstacles.size()) throw std::invalid_argument("contact: one pose per obstacle expected");
  std::vector<Vec3> wf = s.wf, lambda;
  for (int c = 0; c < s.D->size(); ++c) { // the points keep their normals; the obstacles' gaps and their surface points' motions move
    const ContactPoint &p = s.D->point(c);
    if (p.obstacle < 0) continue;
    ObstacleGap h;
    if (s.geo.obstacles[p.obstacle].gap(s.disc->mesh().vertices[p.vertex], poses[p.obstacle], std::numeric_limits<double>::infinity(), h)) wf[c][0] += h.gap - p.g0;
    if (!s.friction || p.lead >= 0) continue; // a follower's tangential rows are ties to its vertex's anchor
    const Vec3 moved = s.step_motion(p, poses[p.obstacle], s.step_from[p.obstacle]) - p.motion;
    for (int k = 1; k < 3; ++k) wf[c][k] -= dot(p.frame[k], moved);
  }
  try {
    if (s.friction) s.friction_solver.haptic(*s.D, wf, s.tol_gap, lambda);
    else s.normal.haptic(*s.D, wf, s.tol_gap, lambda);
  } catch (const std::runtime_error &e) {
    throw std::runtime_error(s.frame_error(e.what()));
  }
  std::vector<Vec3> force(s.geo.obstacles.size(), Vec3{0, 0, 0});
  for (int c = 0; c < s.D->size(); ++c) {
    const ContactPoint &p = s.D->point(c);
    if (p.obstacle >= 0) force[p.obstacle] = force[p.obstacle] + p.area * (lambda[c][0] * p.frame[0] + (p.lead >= 0 ? Vec3{0, 0, 0} : lambda[c][1] * p.frame[1] + lambda[c][2] * p.frame[2]));
  }
  return force;
}

std::vector<Vec3> ContactEngine::haptic_forces(const std::vector<Vec3> &offsets) { return haptic_forces(poses_of(offsets)); }

} // namespace hssbem
