// The contact engine of contact_engine.hpp: a frame is detection, the compliance of its contact
// points, the frictionless or frictional solve, and the fields from one product with W's columns.
#include "hssbem/contact/contact_engine.hpp"

#include "contact_points.hpp"

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

double mesh_size(const SurfaceMesh &m)
{
  Vec3 lo = m.vertices.at(0), hi = lo;
  for (const Vec3 &v : m.vertices)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
  return norm(hi - lo);
}

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
  if (!(o.reach >= 0 && std::isfinite(o.reach)) || !(o.depth >= 0 && std::isfinite(o.depth)) || !(o.tol > 0 && o.tol < 1) || o.max_it < 1)
    throw std::invalid_argument("contact: options out of range (reach >= 0, depth >= 0, 0 < tol < 1, max_it >= 1)");
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

std::string join(const std::vector<std::string> &parts)
{
  std::string s;
  for (const std::string &p : parts) s += (s.empty() ? "" : "; ") + p;
  return s;
}

/// x −= Σ_q v[q] col[q] (W's loaded columns, double or single precision), by row blocks on the
/// threads (each streams its rows of the columns); x and the columns in the cache's row order.
template <class T>
void subtract_columns(const std::vector<const T *> &col, const std::vector<double> &v, std::vector<double> &x)
{
  const int n = static_cast<int>(x.size()), block = 4096, nb = (n + block - 1) / block;
  const std::size_t nc = col.size();
#pragma omp parallel for schedule(static) if (static_cast<double>(n) * nc > 1e6)
  for (int b = 0; b < nb; ++b) {
    const int r0 = b * block, r1 = std::min(n, r0 + block);
    std::size_t q = 0;
    for (; q + 2 <= nc; q += 2) { // two columns per pass: half the traffic on x
      const T *w0 = col[q], *w1 = col[q + 1];
      const double c0 = v[q], c1 = v[q + 1];
      for (int r = r0; r < r1; ++r) x[r] -= c0 * w0[r] + c1 * w1[r];
    }
    for (; q < nc; ++q) {
      const T *w = col[q];
      const double c = v[q];
      for (int r = r0; r < r1; ++r) x[r] -= c * w[r];
    }
  }
}

} // namespace

void check_bodies_held(const Discretization &disc, const std::vector<std::array<bool, 3>> &known, const std::vector<Obstacle> &obstacles, const ContactSettings &settings,
                       const ContactOptions &options)
{
  const std::vector<char> pattern = node_pattern(known);
  const Geometry g = make_geometry(disc, pattern, obstacles, settings, options);
  const std::vector<ContactPoint> points = contact_detail::merge_points(contact_detail::obstacle_points(g, std::vector<Vec3>(g.obstacles.size(), Vec3{0, 0, 0}), {}),
                                                                         contact_detail::body_points(g), disc.mesh().num_vertices());
  for (int b = 0; b < g.bodies.count; ++b) {
    std::vector<NodeConstraint> held;
    int lowest = -1;
    for (int i = 0; i < disc.num_nodes(); ++i) {
      if (g.bodies.of_vertex[disc.node(i).vertex] != b) continue;
      if (lowest < 0 || disc.node(i).vertex < lowest) lowest = disc.node(i).vertex;
      for (int c = 0; c < 3; ++c)
        if (known[i][c]) held.push_back({i, Vec3{c == 0 ? 1.0 : 0.0, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0}});
    }
    const ConstraintReport alone = analyse_constraints(disc, held);
    if (alone.rank == 6) continue;
    bool any = false;
    for (const ContactPoint &p : points) {
      const bool mine = p.body == b || p.other == b;
      if (!mine) continue;
      any = true;
      for (int k = 0; k < (p.mu > 0 ? 3 : 1); ++k) held.push_back({p.body == b ? p.node : p.term_node[1], p.frame[k]});
    }
    const ConstraintReport with_contact = analyse_constraints(disc, held);
    const std::string body = "body " + std::to_string(b) + " (the surface of vertex " + std::to_string(lowest) + ")";
    if (!any)
      throw ConstraintError(body + ": its prescribed displacements leave it free to move (" + join(alone.free_modes) + ") and no obstacle or other body is within reach to hold it");
    if (with_contact.rank < 6)
      throw ConstraintError(body + ": held only by frictionless contact, which leaves it free to move (" + join(with_contact.free_modes) +
                            "); prescribe displacements that fix these motions, or give the contact friction");
    throw ConstraintError(body + ": its prescribed displacements leave it free to move (" + join(alone.free_modes) +
                          "); bodies held by contact alone are not supported yet: prescribe displacements that hold it");
  }
}

// --- the engine -----------------------------------------------------------------------------------

struct ContactEngine::State {
  State(const Discretization &d, const ReferenceFactorization &r, Geometry geometry, const ContactOptions &o)
      : disc(&d), ref(&r), opt(o), geo(std::move(geometry)), normal(d.num_nodes())
  {
  }
  const Discretization *disc;
  const ReferenceFactorization *ref;
  ContactOptions opt;
  Geometry geo;
  std::shared_ptr<ReferenceColumns> columns;
  std::vector<int> node_position;      ///< per dof node: where its rows sit in the columns
  std::vector<ContactPoint> body_points, points;
  bool body_points_done = false;
  std::vector<char> forced;            ///< per vertex: penetrated beyond reach once; always a candidate since
  double tol_gap = 0;
  double size = 0;                     ///< the mesh's bounding-box diagonal
  // the free response of the last values
  bool has_free = false;
  SystemSelection free_values;
  std::vector<double> xf;
  SystemSelection solved_values;       ///< the values of the last free response solved (not scaled)
  std::vector<double> solved_xf;       ///< and that response
  bool exact = true;                   ///< the reference's columns are exact (its x_f is never corrected)
  std::vector<Vec3> u_free;
  // the last frame
  std::unique_ptr<Compliance> D;
  std::vector<Vec3> wf, lambda, u_prev, warm_lambda;
  std::vector<double> gap;             ///< per point: the gap after the solve
  std::vector<std::int8_t> point_status;
  std::vector<char> warm_nodes;
  std::vector<char> zone, zone_nodes;  ///< per point: watched by the iterations; per node: joined this frame
  std::vector<Vec3> offsets;
  bool friction = false, solved = false;
  contact_detail::NormalSolver normal;
  contact_detail::FrictionSolver friction_solver;
  ContactFrameReport report;

  void free_response(const SystemSelection &values);
  void set_u_free();
  /// The solve of a frame's points until no vertex went through (rounds of detection).
  void rounds(const std::vector<Vec3> &offsets_, ContactSolution &out, ContactFrameReport &rep);
  void correct(const SystemSelection &values, const std::vector<Vec3> &offsets_, ContactSolution &out, ContactFrameReport &rep);
  void detect(const std::vector<Vec3> &offsets_);
  void solve_points(ContactFrameReport &rep);
  void fields(ContactSolution &out) const;
  void point_gaps(const ContactSolution &out, bool single);
  /// The fields in single precision: frictionless frames on exact columns only (friction
  /// measures the next frame's slip from the fields, and approximate columns are corrected
  /// against the fields to 1e-8, below single precision's 1e-7).
  bool single_fields() const { return opt.single_fields && !friction && ref->exact_columns(); }
  bool zone_violations();
  bool penetrations(const std::vector<Vec3> &offsets_, const ContactSolution &out);
  void outputs(ContactSolution &out) const;
  /// The warm start of the next solve (round or frame): the active set and its tractions.
  void remember();
  Vec3 predicted_traction(int c);
  std::vector<Vec3> warm_offsets;      ///< the obstacles' offsets of the warm start
  TriangleBvh surface;                 ///< the mesh's triangles (the warm start's interpolation)
};

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
  m->forced.assign(disc.mesh().num_vertices(), 0);
  m->u_prev.assign(disc.num_nodes(), Vec3{0, 0, 0});
  m->friction = settings.friction > 0;
  for (const ObstacleGeometry &o : m->geo.obstacles) m->friction = m->friction || o.obstacle().friction > 0;
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
double ContactEngine::reach() const { return m->geo.reach; }
std::size_t ContactEngine::memory_bytes() const { return m->columns->memory_bytes(); }
const std::shared_ptr<ReferenceColumns> &ContactEngine::columns() const { return m->columns; }
std::vector<int> ContactEngine::spatial_order(const Discretization &disc) { return contact_detail::spatial_row_order(disc); }

void ContactEngine::prefetch(const std::vector<std::vector<Vec3>> &placements)
{
  if (!m->friction && !m->ref->exact_columns()) return; // columns that cost solves: only the active points', as the iterations ask
  std::vector<char> need(m->ref->pattern().size(), 0);
  auto mark = [&](const std::vector<ContactPoint> &pts) {
    for (int j : contact_detail::loaded_unknowns(pts, m->ref->pattern(), !m->friction)) need[j] = 1;
  };
  for (const std::vector<Vec3> &offsets : placements) {
    if (offsets.size() != m->geo.obstacles.size()) throw std::invalid_argument("contact: one offset per obstacle expected");
    mark(contact_detail::obstacle_points(m->geo, offsets, m->forced));
  }
  mark(contact_detail::body_points(m->geo));
  std::vector<int> js;
  for (std::size_t j = 0; j < need.size(); ++j)
    if (need[j]) js.push_back(static_cast<int>(j));
  m->columns->require(js);
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
}

/// Approximate columns W̃ (ReferenceFactorization::exact_columns() false): the frame was solved
/// with x = x_f' − W̃ L λ. The true unknowns of its tractions, x_true = A₀⁻¹ b(values + L λ) (one
/// accurate solve), differ by δ; x_f' += δ makes the fields exact at this λ, and the frame is
/// solved again. A fixed point has x = x_true and the contact conditions on it: the exact answer.
/// Each pass shrinks the error by about W̃'s relative error (the factorization's tolerance). The
/// corrected x_f' stays for the next frame of the same values (a warm start of its corrections).
void ContactEngine::State::correct(const SystemSelection &values, const std::vector<Vec3> &offsets_, ContactSolution &out, ContactFrameReport &rep)
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
      throw std::runtime_error("contact: the corrections of the compressed reference did not settle in " + std::to_string(opt.max_it) + " solves (-contact_max_it; last change " +
                               std::to_string(rep.correction) + ")");
    set_u_free();
    rounds(offsets_, out, rep);
  }
}

void ContactEngine::State::detect(const std::vector<Vec3> &offsets_)
{
  const PhaseScope phase(Phase::ContactDetect);
  if (!body_points_done) body_points = contact_detail::body_points(geo), body_points_done = true;
  points = contact_detail::merge_points(contact_detail::obstacle_points(geo, offsets_, forced), body_points, disc->mesh().num_vertices(), node_position);
}

void ContactEngine::State::solve_points(ContactFrameReport &rep)
{
  const PhaseScope phase(Phase::ContactSolve);
  D = std::make_unique<Compliance>(points, ref->pattern(), *columns, !friction);
  wf = D->free_w(u_free, friction ? u_prev : std::vector<Vec3>{});
  const int n = D->size();
  // The zone the iterations watch: what touched before, what starts penetrated, and what went
  // through in an earlier round of this frame; the others' gaps are checked in the fields.
  zone.assign(n, 0);
  for (int c = 0; c < n; ++c) {
    const int node = D->point(c).node;
    zone[c] = wf[c][0] < tol_gap || (!warm_nodes.empty() && warm_nodes[node]) || zone_nodes[node];
  }
  if (!friction) {
    auto monitor = [&](int it, long long active, long long changed) {
      if (opt.monitor) opt.monitor(ContactIteration{it, active, changed, 0.0});
    };
    const auto r = normal.solve(*D, wf, opt.warm_start ? warm_nodes : std::vector<char>{}, zone, tol_gap, opt.max_it, lambda, monitor);
    rep.iterations += r.iterations;
    rep.rebuilt = rep.rebuilt || r.rebuilt;
    point_status.assign(n, 0);
    for (int c = 0; c < n; ++c) point_status[c] = lambda[c][0] > 0 ? 2 : 0;
    return;
  }
  lambda.assign(n, Vec3{0, 0, 0});
  if (opt.warm_start && !warm_lambda.empty())
    for (int c = 0; c < n; ++c) lambda[c] = predicted_traction(c);
  auto monitor = [&](int it, long long active, long long changed, double res) {
    if (opt.monitor) opt.monitor(ContactIteration{it, active, changed, res});
  };
  const auto r = friction_solver.solve(*D, wf, zone, opt.tol, opt.max_it, lambda, point_status, monitor);
  rep.iterations += r.iterations, rep.factorizations += r.factorizations, rep.products += r.products;
}

/// The frame's solve in rounds: the points solved, the fields and every point's gap, then again
/// while a vertex beyond reach penetrated or a point outside the zone went through (8 at most).
void ContactEngine::State::rounds(const std::vector<Vec3> &offsets_, ContactSolution &out, ContactFrameReport &rep)
{
  for (int round = 1;; ++round) {
    ++rep.rounds;
    Timer phase;
    solve_points(rep);
    remember();
    rep.solve_seconds += phase.seconds();
    phase.restart();
    fields(out);
    point_gaps(out, single_fields());
    rep.fields_seconds += phase.seconds();
    phase.restart();
    const bool through = round < 8 && penetrations(offsets_, out); // vertices beyond reach
    const bool joined = round < 8 && zone_violations();            // points outside the zone
    if (through) detect(offsets_);
    rep.detect_seconds += phase.seconds();
    if (!through && !joined) break;
  }
}

/// Every point's gap after the solve, from the fields; where the fields are in single precision
/// (their u carries relative errors of about 1e-7), the gaps of the points near contact (within
/// 1e-4 of the mesh's size) again from the compliance, g = g_f + D_n λ, in double: their sign
/// decides the zone, and the contact's gaps are reported to round-off.
void ContactEngine::State::point_gaps(const ContactSolution &out, bool single)
{
  const PhaseScope phase(Phase::ContactFields);
  const int n = D->size();
  gap.resize(n);
  std::vector<int> near;
  for (int c = 0; c < n; ++c) {
    const ContactPoint &p = D->point(c);
    Vec3 d{};
    for (int i = 0; i < p.terms; ++i) d = d + p.mw[i] * out.u[p.term_node[i]];
    gap[c] = p.g0 + dot(p.frame[0], d);
    if (single && std::abs(gap[c]) <= 1e-4 * size) near.push_back(c), gap[c] = wf[c][0];
  }
  if (near.empty()) return;
  std::vector<int> cols;
  std::vector<Vec3> loaded;
  for (int c = 0; c < n; ++c)
    if (lambda[c][0] != 0 || lambda[c][1] != 0 || lambda[c][2] != 0) cols.push_back(c), loaded.push_back(lambda[c]);
  std::vector<double> g(near.size());
  for (std::size_t r = 0; r < near.size(); ++r) g[r] = wf[near[r]][0];
  D->apply_normal(near, cols, loaded.data(), g.data());
  for (std::size_t r = 0; r < near.size(); ++r) gap[near[r]] = g[r];
}

/// Points outside the zone whose gap went through: they join it.
bool ContactEngine::State::zone_violations()
{
  bool found = false;
  for (int c = 0; c < D->size(); ++c)
    if (!zone[c] && gap[c] < -tol_gap) zone_nodes[D->point(c).node] = 1, found = true;
  return found;
}

void ContactEngine::State::fields(ContactSolution &out) const
{
  const PhaseScope phase(Phase::ContactFields);
  std::vector<int> js;
  std::vector<double> v;
  D->loads(lambda, js, v);
  const std::vector<int> &order = columns->row_order();
  std::vector<double> x(xf.size());
  for (std::size_t p = 0; p < x.size(); ++p) x[p] = xf[order.empty() ? p : order[p]];
  if (single_fields()) { // (point_gaps makes the same choice)
    std::vector<const float *> col;
    for (int j : js) col.push_back(columns->column_single(j));
    subtract_columns(col, v, x);
  } else {
    std::vector<const double *> col;
    for (int j : js) col.push_back(columns->column(j));
    subtract_columns(col, v, x);
  }
  out.x.resize(x.size());
  for (std::size_t p = 0; p < x.size(); ++p) out.x[order.empty() ? p : order[p]] = x[p];
  const std::vector<char> &pattern = ref->pattern();
  const int nn = disc->num_nodes();
  out.u.resize(nn), out.t.resize(nn);
  for (int i = 0; i < nn; ++i)
    for (int c = 0; c < 3; ++c) {
      const int j = 3 * i + c;
      out.u[i][c] = pattern[j] ? free_values.known[i][c] : out.x[j];
      out.t[i][c] = pattern[j] ? out.x[j] : free_values.known[i][c];
    }
  for (std::size_t q = 0; q < js.size(); ++q) out.t[js[q] / 3][js[q] % 3] += v[q];
}

/// Vertices without a contact point that went through an obstacle: they become candidates.
bool ContactEngine::State::penetrations(const std::vector<Vec3> &offsets_, const ContactSolution &out)
{
  const SurfaceMesh &mesh = disc->mesh();
  std::vector<char> has(mesh.num_vertices(), 0);
  for (const ContactPoint &p : points) has[p.vertex] = 1;
  bool found = false;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!geo.candidate[v] || has[v]) continue;
    double reach = 0;
    for (int i = disc->first_node(v); i < disc->first_node(v) + disc->node_count(v); ++i) reach = std::max(reach, norm(out.u[i]));
    for (std::size_t o = 0; o < geo.obstacles.size(); ++o) {
      ObstacleGap h;
      if (!geo.obstacles[o].gap(mesh.vertices[v], offsets_[o], reach, h)) continue;
      if (h.gap + dot(h.normal, out.u[contact_detail::facing_node(*disc, v, h.normal)]) < -tol_gap) forced[v] = 1, found = true;
    }
  }
  return found;
}

void ContactEngine::State::outputs(ContactSolution &out) const
{
  const int nv = disc->mesh().num_vertices();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.pressure.assign(nv, 0.0);
  out.gap.assign(nv, nan);
  out.status.assign(nv, 0);
  out.obstacle_force.assign(geo.obstacles.size(), Vec3{0, 0, 0});
  out.body_force.assign(geo.bodies.count, Vec3{0, 0, 0});
  for (int c = 0; c < D->size(); ++c) {
    const ContactPoint &p = D->point(c);
    if (p.facing) out.gap[p.vertex] = gap[c];
    if (!point_status[c]) continue;
    const Vec3 force = p.area * (lambda[c][0] * p.frame[0] + lambda[c][1] * p.frame[1] + lambda[c][2] * p.frame[2]);
    if (p.facing) out.pressure[p.vertex] = lambda[c][0], out.status[p.vertex] = point_status[c];
    if (p.obstacle >= 0) {
      out.obstacle_force[p.obstacle] = out.obstacle_force[p.obstacle] + force;
      continue;
    }
    out.body_force[p.body] = out.body_force[p.body] + force;
    out.body_force[p.other] = out.body_force[p.other] - force;
    for (int i = 1; i < p.terms; ++i) { // the master side: its share of the pressure
      const int v = disc->node(p.term_node[i]).vertex;
      out.pressure[v] += -p.lw[i] * lambda[c][0];
      out.status[v] = std::max(out.status[v], point_status[c]);
    }
  }
}

/// The warm start of point c: the last solve's traction where the point's obstacle has not
/// moved; where it has, the last solve's tractions carried along with it (interpolated on the
/// surface at the vertex moved back by the obstacle's step), since the contact patch moves
/// with the obstacle.
Vec3 ContactEngine::State::predicted_traction(int c)
{
  const ContactPoint &p = D->point(c);
  if (p.obstacle < 0 || warm_offsets.size() != offsets.size()) return warm_lambda[p.node];
  const Vec3 step = offsets[p.obstacle] - warm_offsets[p.obstacle];
  if (norm(step) == 0) return warm_lambda[p.node];
  if (surface.empty()) surface = TriangleBvh(disc->mesh().vertices, disc->mesh().triangles);
  const TriangleHit hit = surface.closest(disc->mesh().vertices[p.vertex] - step, 4 * norm(step));
  if (hit.triangle < 0) return Vec3{0, 0, 0};
  Vec3 l{0, 0, 0};
  for (int k = 0; k < 3; ++k) l = l + hit.bary[k] * warm_lambda[disc->element_node(hit.triangle, k)];
  return l;
}

void ContactEngine::State::remember()
{
  warm_offsets = offsets;
  warm_nodes.assign(disc->num_nodes(), 0);
  warm_lambda.assign(disc->num_nodes(), Vec3{0, 0, 0});
  for (int c = 0; c < D->size(); ++c)
    if (point_status[c]) warm_nodes[D->point(c).node] = 1, warm_lambda[D->point(c).node] = lambda[c];
}

const ContactFrameReport &ContactEngine::solve(const SystemSelection &values, const std::vector<Vec3> &offsets, ContactSolution &out)
{
  State &s = *m;
  if (offsets.size() != s.geo.obstacles.size()) throw std::invalid_argument("contact: one offset per obstacle expected");
  const Timer timer;
  ContactFrameReport rep;
  s.free_response(values);
  s.offsets = offsets;
  s.zone_nodes.assign(s.disc->num_nodes(), 0);
  const Timer detect;
  s.detect(offsets);
  rep.detect_seconds += detect.seconds();
  rep.rounds = 0;
  s.rounds(offsets, out, rep);
  if (!s.ref->exact_columns()) {
    const Timer correct;
    s.correct(values, offsets, out, rep);
    rep.correct_seconds += correct.seconds();
  }
  s.outputs(out);
  if (s.friction) s.u_prev = out.u; // slip is measured from the previous frame
  s.solved = true;
  rep.candidates = s.D->size();
  for (int c = 0; c < s.D->size(); ++c) { // by vertex: the state of its facing node
    if (!s.D->point(c).facing) continue;
    const std::int8_t st = s.point_status[c];
    rep.active_vertices += st != 0, rep.stick += st == 1, rep.slip += st == 2;
  }
  rep.seconds = timer.seconds();
  s.report = rep;
  return s.report;
}

std::vector<Vec3> ContactEngine::haptic_forces(const std::vector<Vec3> &offsets)
{
  State &s = *m;
  if (!s.solved) throw std::invalid_argument("contact: the haptic call needs a solved frame first");
  if (offsets.size() != s.geo.obstacles.size()) throw std::invalid_argument("contact: one offset per obstacle expected");
  std::vector<Vec3> wf = s.wf, lambda;
  for (int c = 0; c < s.D->size(); ++c) { // the points keep their normals; only the obstacles' gaps move
    const ContactPoint &p = s.D->point(c);
    if (p.obstacle < 0) continue;
    ObstacleGap h;
    if (s.geo.obstacles[p.obstacle].gap(s.disc->mesh().vertices[p.vertex], offsets[p.obstacle], std::numeric_limits<double>::infinity(), h)) wf[c][0] += h.gap - p.g0;
  }
  if (s.friction) s.friction_solver.resolve(*s.D, wf, lambda);
  else s.normal.resolve(*s.D, wf, lambda);
  std::vector<Vec3> force(s.geo.obstacles.size(), Vec3{0, 0, 0});
  for (int c = 0; c < s.D->size(); ++c) {
    const ContactPoint &p = s.D->point(c);
    if (p.obstacle >= 0) force[p.obstacle] = force[p.obstacle] + p.area * (lambda[c][0] * p.frame[0] + lambda[c][1] * p.frame[1] + lambda[c][2] * p.frame[2]);
  }
  return force;
}

} // namespace hssbem
