// Bodies held by contact alone (docs/contact.md, "Bodies held by contact alone"): their free rigid
// motions as unknowns beside the contact tractions, and the balance of the forces and moments on
// each body as their equations, solved by Newton on the motions around the frame's contact solve.
#include "engine_state.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace hssbem {

using contact_detail::ContactPoint;

namespace {

/// The balance is met when the generalized forces are within this of their scale (the loads'
/// and the contact's), relative; or within 100 × -contact_tol, the solvers' own tolerance.
constexpr double k_balance_tol = 1e-9;
/// A motion the contact resists with less than this of its stiffest one counts as unresisted: a
/// faceted ball between frictionless plates resists turning about a horizontal axis only through
/// its facets (singular values ~1e-8 of the largest), and the small rotation of the linearised
/// motion would turn it by radians.
constexpr double k_resisted = 1e-6;
/// With friction, the balance's tolerance: sliding points' directions carry the friction solve's
/// own noise into the moments (measured: 3.5e-8 of the forces on the stack of three cubes).
constexpr double k_balance_tol_friction = 1e-7;
/// Friction: steps in a row with the sliding points held stuck that do not halve the residual
/// before a body that keeps sliding is refused as unbalanced.
constexpr int k_max_stalled = 5;

std::array<double, 6> mode_row(const Vec3 &e, const Vec3 &r, double L)
{
  const Vec3 m = (1.0 / L) * cross(r, e); // e · (θ × r) = θ · (r × e), θ = q_rot / L
  return {e[0], e[1], e[2], m[0], m[1], m[2]};
}

double norm2(const std::vector<double> &v)
{
  double s = 0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

} // namespace

/// The floating bodies are the bodies of the pinned nodes; each one's free motions are the null
/// space of its prescribed components other than the pins (all six when nothing else holds it).
void ContactEngine::State::set_up_floating(const std::vector<int> &pins)
{
  const std::vector<char> &pattern = ref->pattern();
  const SurfaceMesh &mesh = disc->mesh();
  pinned.assign(pattern.size(), 0);
  for (int j : pins) {
    if (j < 0 || j >= static_cast<int>(pattern.size()) || !pattern[j]) throw std::invalid_argument("contact: a pin must be an unknown the reference prescribes");
    pinned[j] = 1;
  }
  node_floating.assign(disc->num_nodes(), -1);
  std::vector<int> index(geo.bodies.count, -1);
  for (int j : pins) {
    const int b = geo.bodies.of_vertex[disc->node(j / 3).vertex];
    if (index[b] >= 0) continue;
    index[b] = static_cast<int>(floating.size());
    floating.push_back(Floating{});
    floating.back().body = b;
  }
  for (Floating &f : floating) {
    Box box;
    int n = 0;
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (geo.bodies.of_vertex[v] == f.body) f.x0 = f.x0 + mesh.vertices[v], ++n, box.add(mesh.vertices[v]), f.lowest = f.lowest < 0 ? v : f.lowest;
    f.x0 = (1.0 / n) * f.x0;
    f.L = std::max(box.diagonal(), 1e-300);
    double gram[36] = {0}, w[6];
    for (int i = 0; i < disc->num_nodes(); ++i) {
      if (geo.bodies.of_vertex[disc->node(i).vertex] != f.body) continue;
      node_floating[i] = index[f.body];
      for (int c = 0; c < 3; ++c) {
        if (!pattern[3 * i + c] || pinned[3 * i + c]) continue;
        const std::array<double, 6> row = mode_row(Vec3{c == 0 ? 1.0 : 0.0, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0}, disc->node_position(i) - f.x0, f.L);
        for (int a = 0; a < 6; ++a)
          for (int b = 0; b < 6; ++b) gram[6 * a + b] += row[a] * row[b];
      }
    }
    lapack::syev(6, gram, w);
    for (int m = 0; m < 6; ++m)
      if (w[m] <= 1e-10 * std::max(w[5], 1e-300) || w[5] <= 0) f.modes.push_back({gram[6 * m], gram[6 * m + 1], gram[6 * m + 2], gram[6 * m + 3], gram[6 * m + 4], gram[6 * m + 5]});
  }
  int first = 0;
  for (Floating &f : floating) f.first = first, first += static_cast<int>(f.modes.size());
  for (int t = 0; t < mesh.num_triangles(); ++t) { // volumes and volume centroids: tetrahedra from the origin
    const int b = geo.bodies.of_triangle[t];
    if (index[b] < 0) continue;
    Floating &f = floating[index[b]];
    const Vec3 &a = mesh.vertices[mesh.triangles[t][0]], &p = mesh.vertices[mesh.triangles[t][1]], &q = mesh.vertices[mesh.triangles[t][2]];
    const double v = dot(a, cross(p, q)) / 6;
    f.volume += v, f.xg = f.xg + (v / 4) * (a + p + q);
  }
  for (Floating &f : floating) f.xg = (1.0 / f.volume) * f.xg;
  alpha.assign(first, 0.0);
}

std::vector<double> ContactEngine::State::weight_correction() const
{
  std::vector<double> r(alpha.size(), 0.0);
  if (t_particular.empty()) return r;
  const std::vector<char> &pattern = ref->pattern();
  for (const Floating &f : floating) {
    const Vec3 W = f.volume * body_force, M = cross(f.xg - f.x0, W);
    for (std::size_t k = 0; k < f.modes.size(); ++k) {
      const std::array<double, 6> &q = f.modes[k];
      r[f.first + k] += dot(W, Vec3{q[0], q[1], q[2]}) + dot(M, Vec3{q[3], q[4], q[5]}) / f.L;
    }
  }
  for (int i = 0; i < disc->num_nodes(); ++i) { // the lumped −t_p the homogeneous loads carry, taken back
    const int f = node_floating[i];
    if (f < 0) continue;
    for (int c = 0; c < 3; ++c)
      if (!pattern[3 * i + c])
        for (std::size_t k = 0; k < floating[f].modes.size(); ++k)
          r[floating[f].first + k] += geo.area[i] * t_particular[i][c] * mode_at(floating[f], static_cast<int>(k), i)[c];
  }
  return r;
}

Vec3 ContactEngine::State::mode_at(const Floating &f, int k, int i) const
{
  const std::array<double, 6> &q = f.modes[k];
  return Vec3{q[0], q[1], q[2]} + (1.0 / f.L) * cross(Vec3{q[3], q[4], q[5]}, disc->node_position(i) - f.x0);
}

Vec3 ContactEngine::State::rigid_at(int i, const std::vector<double> &a) const
{
  if (node_floating.empty() || node_floating[i] < 0) return Vec3{0, 0, 0};
  const Floating &f = floating[node_floating[i]];
  Vec3 u{0, 0, 0};
  for (std::size_t k = 0; k < f.modes.size(); ++k) u = u + a[f.first + k] * mode_at(f, static_cast<int>(k), i);
  return u;
}

std::vector<double> ContactEngine::State::balance(const std::vector<Vec3> &lam, double *gross) const
{
  std::vector<double> r(alpha.size(), 0.0);
  const std::vector<char> &pattern = ref->pattern();
  double sum = 0;
  auto add = [&](int j, double t) { // the force area × t on unknown j's node and component
    const int i = j / 3, f = node_floating[i];
    if (f < 0) return;
    const Floating &fb = floating[f];
    sum += geo.area[i] * std::abs(t);
    for (std::size_t k = 0; k < fb.modes.size(); ++k) r[fb.first + k] += geo.area[i] * t * mode_at(fb, static_cast<int>(k), i)[j % 3];
  };
  for (int i = 0; i < disc->num_nodes(); ++i) // the loads (a prescribed component's reaction does no work on a free motion)
    for (int c = 0; c < 3; ++c)
      if (node_floating[i] >= 0 && !pattern[3 * i + c] && free_values.known[i][c] != 0) add(3 * i + c, free_values.known[i][c]);
  std::vector<int> js;
  std::vector<double> vs;
  D->loads(lam, js, vs);
  for (std::size_t q = 0; q < js.size(); ++q) add(js[q], vs[q]);
  if (gross) *gross = sum;
  const std::vector<double> w = weight_correction();
  for (std::size_t k = 0; k < r.size(); ++k) r[k] += w[k];
  return r;
}

std::vector<Vec3> ContactEngine::State::resolve(const std::vector<Vec3> &w)
{
  std::vector<Vec3> lam;
  if (friction) friction_solver.fixed_states(*D, w, lam);
  else normal.resolve(*D, w, lam);
  return lam;
}

std::vector<Vec3> ContactEngine::State::moved_w(const std::vector<double> &da) const
{
  std::vector<Vec3> u = u_free;
  for (int i = 0; i < disc->num_nodes(); ++i) u[i] = u[i] + rigid_at(i, da);
  return D->free_w(u, friction ? u_prev : std::vector<Vec3>{});
}

/// Columns by differences on the current active set (and stick/slip states): the contact's
/// answer to a motion is linear there (frictionless: exactly; friction: its slip directions held).
std::vector<double> ContactEngine::State::balance_jacobian(const std::vector<double> &r0)
{
  const int K = static_cast<int>(alpha.size());
  const double eps = 1e-6 * size;
  std::vector<double> J(static_cast<std::size_t>(K) * K);
  for (int j = 0; j < K; ++j) {
    std::vector<double> da(K, 0.0);
    da[j] = eps;
    const std::vector<double> r = balance(resolve(moved_w(da)));
    for (int i = 0; i < K; ++i) J[static_cast<std::size_t>(j) * K + i] = (r[i] - r0[i]) / eps; // column-major
  }
  return J;
}

std::string ContactEngine::State::unbalanced_error(const std::vector<double> &unresisted) const
{
  std::size_t worst = 0;
  double top = -1;
  for (std::size_t f = 0; f < floating.size(); ++f) {
    double s = 0;
    for (std::size_t k = 0; k < floating[f].modes.size(); ++k) s += unresisted[floating[f].first + k] * unresisted[floating[f].first + k];
    if (s > top) top = s, worst = f;
  }
  const Floating &f = floating[worst];
  Vec3 F{0, 0, 0}, M{0, 0, 0}; // the generalized force back to a force and a moment about the centroid
  for (std::size_t k = 0; k < f.modes.size(); ++k) {
    const std::array<double, 6> &q = f.modes[k];
    F = F + unresisted[f.first + k] * Vec3{q[0], q[1], q[2]};
    M = M + (unresisted[f.first + k] * f.L) * Vec3{q[3], q[4], q[5]};
  }
  char text[400];
  std::snprintf(text, sizeof text,
                "body %d (the surface of vertex %d) would fly away: nothing it touches balances the force (%.6g, %.6g, %.6g) and the moment (%.6g, %.6g, %.6g) about its centroid on it",
                f.body, f.lowest, F[0], F[1], F[2], M[0], M[1], M[2]);
  return text;
}

/// The motion along the unresisted generalized force (which does positive work with it) that
/// brings the nearest open point of the bodies it moves to a penetration of 2 tol_gap, so that it
/// joins the contact: a body pushed toward what it does not touch yet moves until it touches.
std::vector<double> ContactEngine::State::closing_move(const std::vector<double> &unresisted) const
{
  const double n = norm2(unresisted);
  std::vector<double> dir(unresisted.size());
  for (std::size_t k = 0; k < dir.size(); ++k) dir[k] = unresisted[k] / n;
  const double eps = 1e-6 * size;
  std::vector<double> da(dir.size());
  for (std::size_t k = 0; k < dir.size(); ++k) da[k] = eps * dir[k];
  const std::vector<Vec3> w = moved_w(da);
  double s = std::numeric_limits<double>::infinity();
  for (int c = 0; c < D->size(); ++c) {
    const double rate = (w[c][0] - wf[c][0]) / eps; // the gap's change per unit of motion
    if (D->point(c).lead >= 0 || point_status[c] || rate >= -1e-9) continue;
    s = std::min(s, std::max(gap[c] + 2 * tol_gap, 0.0) / -rate);
  }
  if (!std::isfinite(s)) throw std::runtime_error(unbalanced_error(unresisted));
  for (double &d : dir) d *= s;
  return dir;
}

/// The Newton step −J⁺ r on the current active set (and states) by J's SVD, and r's part in J's
/// null space (left singular vectors of singular values below k_resisted of the largest): unresisted.
/// False when J has such a null space.
bool ContactEngine::State::newton_step(const std::vector<double> &r, std::vector<double> &step, std::vector<double> &unresisted)
{
  bool full = true;
  const int K = static_cast<int>(alpha.size());
  const std::vector<double> r0 = balance(resolve(wf));
  std::vector<double> J = balance_jacobian(r0), s(K), U(static_cast<std::size_t>(K) * K), VT(static_cast<std::size_t>(K) * K);
  if (lapack::gesvd(K, K, J.data(), K, s.data(), U.data(), K, VT.data(), K) != 0) throw std::runtime_error("the floating bodies' Newton matrix: SVD failed");
  step.assign(K, 0.0), unresisted.assign(K, 0.0);
  for (int m = 0; m < K; ++m) {
    double ur = 0;
    for (int i = 0; i < K; ++i) ur += U[static_cast<std::size_t>(m) * K + i] * r[i];
    if (s[m] > k_resisted * s[0] && s[0] > 0)
      for (int k = 0; k < K; ++k) step[k] -= VT[static_cast<std::size_t>(k) * K + m] * ur / s[m];
    else {
      full = false;
      for (int i = 0; i < K; ++i) unresisted[i] += U[static_cast<std::size_t>(m) * K + i] * ur;
    }
  }
  return full;
}

/// Newton on the motions: r(α) = 0, r the generalized forces of balance(), its Jacobian on the
/// current active set. The part of r the contact does not resist (J's null space) either closes
/// an open point by a motion along it, or the body would fly away (an error). Motions nothing
/// resists and nothing drives stay as they are (a frictionless body's slide along a flat table).
void ContactEngine::State::settle(ContactSolution &out, ContactFrameReport &rep)
{
  if (floating.empty()) {
    rounds(out, rep);
    return;
  }
  const int K = static_cast<int>(alpha.size());
  const double tol = std::max(friction ? k_balance_tol_friction : k_balance_tol, 100 * opt.tol);
  int stalled = 0; // friction: steps in a row with sliding points held that did not halve the residual
  double last = std::numeric_limits<double>::infinity();
  for (int it = 1;; ++it) {
    set_u_free();
    rounds(out, rep);
    rep.balances = it;
    double scale = 0; // the forces' size: the sum of their magnitudes, the loads' and the contact's
    const std::vector<double> r = balance(lambda, &scale);
    if (norm2(r) <= tol * scale || scale == 0) return;
    if (it > opt.max_it) {
      char text[200];
      std::snprintf(text, sizeof text, "the floating bodies' forces did not balance in %d solves (-contact_max_it): residual %.2e of the forces", opt.max_it, norm2(r) / scale);
      throw std::runtime_error(text);
    }
    std::vector<double> step, unresisted;
    const bool full_rank = newton_step(r, step, unresisted);
    if (friction && !full_rank) { // sliding points do not resist: as if they stuck
      stalled = norm2(r) > 0.5 * last ? stalled + 1 : 0;
      if (stalled >= k_max_stalled) throw std::runtime_error(unbalanced_error(unresisted)); // it keeps sliding
      friction_solver.stick_slipping_points(*D);
      newton_step(r, step, unresisted);
    }
    if (norm2(unresisted) > tol * scale) {
      const std::vector<double> close = closing_move(unresisted);
      for (int k = 0; k < K; ++k) step[k] += close[k];
    }
    for (int k = 0; k < K; ++k) alpha[k] += step[k];
    last = norm2(r);
  }
}

} // namespace hssbem
