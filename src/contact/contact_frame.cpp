// A contact frame's phases (contact_engine.hpp, engine_state.hpp): detection and the slip's rigid
// motions, the frictionless or frictional solve of the points, the fields from one product with
// W's columns, the checks that end the rounds (vertices that went through, the gaps' residual),
// the outputs and the warm start of the next frame.
#include "engine_state.hpp"

#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace hssbem {

using contact_detail::Compliance;
using contact_detail::ContactPoint;

namespace {

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

bool same_pose(const Pose &a, const Pose &b) { return a.rotation == b.rotation && a.about == b.about && a.translate == b.translate; }

/// The frictionless gaps' residual after which the kept inverse is rebuilt (and, again, an error).
constexpr double k_gap_residual = 1e-8;
/// Rounds of detection per frame (vertices that went through from beyond reach join).
constexpr int k_max_rounds = 8;

} // namespace

std::string ContactEngine::State::frame_error(const std::string &what) const
{
  const std::string rest = what.rfind("contact: ", 0) == 0 ? what.substr(9) : what;
  return "contact: frame " + std::to_string(frame) + ": " + rest;
}

Vec3 ContactEngine::State::step_motion(const ContactPoint &p, const Pose &to, const Pose &from) const
{
  if (to.is_translation() && from.is_translation()) return to.translate - from.translate; // every point moves alike
  ObstacleGap h;
  if (!geo.obstacles[p.obstacle].gap(disc->mesh().vertices[p.vertex], from, std::numeric_limits<double>::infinity(), h)) return to.translate - from.translate;
  return to.apply(h.base_point) - from.apply(h.base_point);
}

void ContactEngine::State::set_motions()
{
  for (ContactPoint &p : points)
    if (p.obstacle >= 0 && p.lead < 0) p.motion = step_motion(p, poses[p.obstacle], step_from[p.obstacle]);
}

double ContactEngine::State::relative_motion(const std::vector<Vec3> &u) const
{
  // Per body the mean change since the pairing (its translation) and the largest change beside it.
  const int nn = disc->num_nodes(), nb = geo.bodies.count;
  std::vector<Vec3> mean(nb, Vec3{0, 0, 0});
  std::vector<int> count(nb, 0);
  for (int i = 0; i < nn; ++i) {
    const int b = geo.bodies.of_vertex[disc->node(i).vertex];
    mean[b] = mean[b] + (u[i] - u_paired[i]), ++count[b];
  }
  for (int b = 0; b < nb; ++b) mean[b] = (1.0 / std::max(1, count[b])) * mean[b];
  double apart = 0, own = 0;
  for (int a = 0; a < nb; ++a)
    for (int b = a + 1; b < nb; ++b) apart = std::max(apart, norm(mean[a] - mean[b]));
  for (int i = 0; i < nn; ++i) own = std::max(own, norm(u[i] - u_paired[i] - mean[geo.bodies.of_vertex[disc->node(i).vertex]]));
  return apart + 2 * own;
}

bool ContactEngine::State::pair_bodies()
{
  if (!geo.bodies_touch) return false;
  const int nn = disc->num_nodes();
  if (!body_points_done) {
    body_points = contact_detail::body_points(geo, {}, &slave_of), body_points_done = true;
    u_paired.assign(nn, Vec3{0, 0, 0});
    loadable.assign(nn, 0); // what contact_loaded_unknowns keeps: the candidates' nodes and the undeformed pairs' masters
    for (int i = 0; i < nn; ++i) loadable[i] = geo.candidate[disc->node(i).vertex];
    for (const ContactPoint &p : body_points)
      for (int k = 0; k < p.terms; ++k) loadable[p.term_node[k]] = 1;
  }
  if (!responded) return false; // no frame solved yet: the free response alone may carry bodies through each other
  std::vector<Vec3> u(nn);
  for (int i = 0; i < nn; ++i) u[i] = u_free[i] + u_response[i];
  if (opt.pair_again > 0 && relative_motion(u) <= opt.pair_again * geo.reach) return false;
  body_points = contact_detail::body_points(geo, contact_detail::BodyPlacement(geo, u, loadable), &slave_of);
  u_paired = std::move(u);
  return true;
}

void ContactEngine::State::detect()
{
  const PhaseScope phase(Phase::ContactDetect);
  points = contact_detail::merge_points(geo, contact_detail::obstacle_points(geo, poses, forced), body_points, node_position);
  if (friction) set_motions();
}

void ContactEngine::State::solve_points(ContactFrameReport &rep)
{
  const PhaseScope phase(Phase::ContactSolve);
  D = std::make_unique<Compliance>(points, ref->pattern(), *columns, !friction);
  wf = D->free_w(u_free, friction ? u_prev : std::vector<Vec3>{});
  const int n = D->size();
  // The zone the iterations watch: what touched before, what starts penetrated, and what went
  // through in an earlier round of this frame; the others' gaps are checked in the fields. A
  // follower is watched with its lead.
  zone.assign(n, 0);
  for (int c = 0; c < n; ++c) {
    const int key = D->point(c).key;
    zone[c] = wf[c][0] < tol_gap || (!warm_keys.empty() && warm_keys[key]) || zone_keys[key];
  }
  for (int c = 0; c < n; ++c)
    if (D->point(c).lead >= 0) zone[c] = zone[D->point(c).lead];
  if (!friction) {
    auto monitor = [&](int it, long long active, long long changed) {
      if (opt.monitor) opt.monitor(ContactIteration{it, active, changed, 0.0});
    };
    const auto r = normal.solve(*D, wf, opt.warm_start ? warm_keys : std::vector<char>{}, zone, tol_gap, size, opt.max_it, lambda, monitor);
    rep.iterations += r.iterations;
    rep.rebuilt = rep.rebuilt || r.rebuilt;
    point_status.assign(n, 0);
    for (int c = 0; c < n; ++c)
      if (D->point(c).lead < 0) point_status[c] = lambda[c][0] > 0 ? 2 : 0;
    for (int c = 0; c < n; ++c) // a follower is closed with its lead (its traction of either sign)
      if (D->point(c).lead >= 0) point_status[c] = point_status[D->point(c).lead];
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

double ContactEngine::State::gap_residual() const
{
  double worst = 0, scale = tol_gap;
  for (int c = 0; c < D->size(); ++c)
    if (point_status[c]) worst = std::max(worst, std::abs(gap[c])), scale = std::max(scale, std::abs(wf[c][0]));
  return worst / scale;
}

/// The frame's solve in rounds: the points solved, the fields and every point's gap, then again
/// while a vertex beyond reach penetrated or a point outside the zone went through. A frame that
/// still has one after k_max_rounds rounds is an error, as is a frictionless solve whose touching
/// points keep a gap (the kept inverse is rebuilt once first).
void ContactEngine::State::rounds(ContactSolution &out, ContactFrameReport &rep)
{
  bool rebuilt_for_residual = false;
  for (int round = 1;; ++round) {
    ++rep.rounds;
    Timer phase;
    solve_points(rep);
    rep.solve_seconds += phase.seconds();
    phase.restart();
    fields(out);
    point_gaps(out, single_fields());
    rep.fields_seconds += phase.seconds();
    if (!friction) {
      const double residual = gap_residual();
      if (residual > k_gap_residual) {
        if (rebuilt_for_residual) {
          char text[200];
          std::snprintf(text, sizeof text, "the touching points' gaps after the solve are %.2e of the gaps closed (at most %.0e): the active block's solve is inaccurate",
                        residual, k_gap_residual);
          throw std::runtime_error(text);
        }
        rebuilt_for_residual = true, normal.reset(), --round;
        continue;
      }
    }
    remember();
    phase.restart();
    worst_penetration = 0;
    const bool through = penetrations(out); // vertices beyond reach
    const bool joined = zone_violations();  // points outside the zone
    rep.detect_seconds += phase.seconds();
    if (!through && !joined) return;
    if (round >= k_max_rounds) {
      char text[200];
      std::snprintf(text, sizeof text, "vertices still go through the obstacles after %d rounds of detection: residual %.2e (the largest penetration, of the mesh's size)", k_max_rounds,
                    worst_penetration);
      throw std::runtime_error(text);
    }
    if (through) detect();
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
    for (int i = 0; i < p.terms; ++i) d = d + p.mw[i][0] * out.u[p.term_node[i]];
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

/// Leading points outside the zone whose gap went through: they join it.
bool ContactEngine::State::zone_violations()
{
  bool found = false;
  for (int c = 0; c < D->size(); ++c)
    if (!zone[c] && D->point(c).lead < 0 && gap[c] < -tol_gap) zone_keys[D->point(c).key] = 1, found = true, worst_penetration = std::max(worst_penetration, -gap[c] / size);
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
  if (!floating.empty())
    for (int i = 0; i < nn; ++i) out.u[i] = out.u[i] + rigid_at(i, alpha); // the floating bodies' motions
  if (!u_particular.empty())
    for (int i = 0; i < nn; ++i) out.u[i] = out.u[i] + u_particular[i]; // the whole displacement
}

/// Vertices without a point of an obstacle that went through it: they get one (forced).
bool ContactEngine::State::penetrations(const ContactSolution &out)
{
  const SurfaceMesh &mesh = disc->mesh();
  const std::size_t no = geo.obstacles.size();
  std::vector<char> has(mesh.num_vertices() * no, 0);
  for (const ContactPoint &p : points)
    if (p.obstacle >= 0) has[p.vertex * no + p.obstacle] = 1;
  bool found = false;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!geo.candidate[v]) continue;
    double reach = 0;
    for (int i = disc->first_node(v); i < disc->first_node(v) + disc->node_count(v); ++i) reach = std::max(reach, norm(out.u[i]));
    for (std::size_t o = 0; o < no; ++o) {
      ObstacleGap h;
      if (has[v * no + o] || !geo.obstacles[o].gap(mesh.vertices[v], poses[o], reach, h)) continue;
      const double g = h.gap + dot(h.normal, out.u[contact_detail::facing_node(*disc, v, h.normal)]);
      if (g < -tol_gap) forced[v * no + o] = 1, found = true, worst_penetration = std::max(worst_penetration, -g / size);
    }
  }
  return found;
}

/// The rigid part of body b's displacement u: the least-squares fit t + θ × (x − x_c) over its
/// dof nodes weighted by their areas (x_c their area centroid): t the mean displacement, θ from
/// (Σ A (|r|² I − r rᵀ)) θ = Σ A r × u. Independent of where the pins sit (the motion α is not:
/// it is the rigid motion of the pins' frame).
void ContactEngine::State::rigid_part(int b, const std::vector<Vec3> &u, Vec3 &t, Vec3 &theta) const
{
  double A = 0;
  Vec3 xc{0, 0, 0};
  t = Vec3{0, 0, 0};
  for (int i = 0; i < disc->num_nodes(); ++i)
    if (geo.bodies.of_vertex[disc->node(i).vertex] == b) A += geo.area[i], xc = xc + geo.area[i] * disc->node_position(i), t = t + geo.area[i] * u[i];
  xc = (1.0 / A) * xc, t = (1.0 / A) * t;
  double M[9] = {0}, rhs[3] = {0};
  for (int i = 0; i < disc->num_nodes(); ++i) {
    if (geo.bodies.of_vertex[disc->node(i).vertex] != b) continue;
    const Vec3 r = disc->node_position(i) - xc, m = cross(r, u[i]);
    for (int a = 0; a < 3; ++a) {
      rhs[a] += geo.area[i] * m[a];
      for (int c = 0; c < 3; ++c) M[3 * a + c] += geo.area[i] * ((a == c ? dot(r, r) : 0.0) - r[a] * r[c]);
    }
  }
  if (lapack::gesv(3, 1, M, rhs) != 0) rhs[0] = rhs[1] = rhs[2] = 0; // a body on a line: no rotation to read
  theta = Vec3{rhs[0], rhs[1], rhs[2]};
}

/// Per vertex, of its leading points: the largest pressure and its state, the smallest gap; the
/// forces of every point (a follower's normal traction only: its tie rows' are internal).
void ContactEngine::State::outputs(ContactSolution &out) const
{
  const int nv = disc->mesh().num_vertices();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.pressure.assign(nv, 0.0);
  out.gap.assign(nv, nan);
  out.status.assign(nv, 0);
  out.contact_traction.assign(nv, Vec3{0, 0, 0});
  out.obstacle_force.assign(geo.obstacles.size(), Vec3{0, 0, 0});
  out.body_force.assign(geo.bodies.count, Vec3{0, 0, 0});
  out.body_translation.assign(geo.bodies.count, Vec3{0, 0, 0});
  out.body_rotation.assign(geo.bodies.count, Vec3{0, 0, 0});
  for (const Floating &f : floating) rigid_part(f.body, out.u, out.body_translation[f.body], out.body_rotation[f.body]);
  for (int c = 0; c < D->size(); ++c) {
    const ContactPoint &p = D->point(c);
    if (p.lead < 0 && !(gap[c] >= out.gap[p.vertex])) out.gap[p.vertex] = gap[c];
    // a follower's normal traction comes from its partner, its tie rows' are internal to the body
    const Vec3 force = p.area * (lambda[c][0] * p.frame[0] + (p.lead >= 0 ? Vec3{0, 0, 0} : lambda[c][1] * p.frame[1] + lambda[c][2] * p.frame[2]));
    const bool shown = p.lead < 0 && point_status[c] && (out.status[p.vertex] == 0 || lambda[c][0] > out.pressure[p.vertex]);
    if (shown) out.pressure[p.vertex] = lambda[c][0], out.status[p.vertex] = point_status[c], out.contact_traction[p.vertex] = (1.0 / p.area) * force;
    if (p.obstacle >= 0) {
      out.obstacle_force[p.obstacle] = out.obstacle_force[p.obstacle] + force;
      continue;
    }
    out.body_force[p.body] = out.body_force[p.body] + force;
    out.body_force[p.other] = out.body_force[p.other] - force;
    if (p.lead >= 0 || !point_status[c]) continue;
    for (int i = 1; i < p.terms; ++i) { // the master side: its share of the pressure
      const int v = disc->node(p.term_node[i]).vertex;
      out.pressure[v] += -p.lw[i][0] * lambda[c][0];
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
  if (p.obstacle < 0 || warm_poses.size() != poses.size() || same_pose(poses[p.obstacle], warm_poses[p.obstacle])) return warm_lambda[p.key];
  const Vec3 &x = disc->mesh().vertices[p.vertex];
  const Vec3 back = warm_poses[p.obstacle].apply(poses[p.obstacle].apply_inverse(x));
  if (surface.empty()) surface = TriangleBvh(disc->mesh().vertices, disc->mesh().triangles);
  const TriangleHit hit = surface.closest(back, 4 * norm(x - back));
  if (hit.triangle < 0) return Vec3{0, 0, 0};
  Vec3 l{0, 0, 0};
  for (int k = 0; k < 3; ++k) l = l + hit.bary[k] * warm_lambda[static_cast<std::size_t>(disc->element_node(hit.triangle, k)) * geo.partners + p.partner];
  return l;
}

void ContactEngine::State::remember()
{
  warm_poses = poses;
  const std::size_t keys = disc->num_nodes() * static_cast<std::size_t>(geo.partners);
  warm_keys.assign(keys, 0);
  warm_lambda.assign(keys, Vec3{0, 0, 0});
  for (int c = 0; c < D->size(); ++c)
    if (point_status[c]) warm_keys[D->point(c).key] = 1, warm_lambda[D->point(c).key] = lambda[c];
}

} // namespace hssbem
