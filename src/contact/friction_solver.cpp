// Coulomb friction (contact_points.hpp): semismooth Newton on Alart–Curnier's function in the
// compliance form, w = w_f + D λ (w: gap and slip in the points' local frames, λ: the contact
// traction on the body). Per point, with r_n = λ_n − ρ g and r_T = λ_T − ρ s:
//   open  (r_n ≤ 0):             λ = 0;
//   stick (|r_T| ≤ μ r_n):       g = 0, s = 0;
//   slip:                        g = 0, λ_T = μ r_n r_T / |r_T|,
// linearised at each step (generalised Jacobian) and solved with a dense LU over the closed points.
#include "contact_points.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hssbem::contact_detail {

namespace {

/// D's 3×3 blocks, column by column (a point's column computed the first time it is asked for).
class BlockCache {
public:
  explicit BlockCache(const Compliance &D) : m_D(D), m_n(D.size()), m_done(D.size(), 0), m_blocks(static_cast<std::size_t>(D.size()) * D.size()) {}
  const Mat3 &at(int c, int cp)
  {
    if (!m_done[cp]) {
#pragma omp parallel for schedule(static) if (m_n > 64)
      for (int c2 = 0; c2 < m_n; ++c2) m_blocks[c2 + static_cast<std::size_t>(cp) * m_n] = m_D.block(c2, cp);
      m_done[cp] = 1;
    }
    return m_blocks[c + static_cast<std::size_t>(cp) * m_n];
  }

private:
  const Compliance &m_D;
  int m_n;
  std::vector<char> m_done;
  std::vector<Mat3> m_blocks;
};

struct PointState {
  std::int8_t kind = 0; ///< 0 open, 1 stick, 2 slip
  double rho = 0, rn = 0;
  double rt[2] = {0, 0}, rt_norm = 0;
  Vec3 phi{};           ///< the residual: λ (open); g, s (stick); g, λ_T − μ r_n q (slip)
};

/// Held tangential components (prescribed displacement along them) keep λ = 0 and take no part
/// in the slip.
PointState classify(const ContactPoint &p, const std::array<bool, 3> &held, const Vec3 &lambda, const Vec3 &w, double rho)
{
  PointState s;
  s.rho = rho;
  s.rn = lambda[0] - rho * w[0];
  if (s.rn <= 0) {
    s.phi = lambda;
    return s;
  }
  for (int a = 0; a < 2; ++a) s.rt[a] = held[a + 1] ? 0.0 : lambda[a + 1] - rho * w[a + 1];
  s.rt_norm = std::hypot(s.rt[0], s.rt[1]);
  if (p.mu > 0 && s.rt_norm <= p.mu * s.rn) {
    s.kind = 1;
    s.phi = w;
  } else {
    s.kind = 2; // frictionless points slide whatever r_T is: λ_T = 0
    const double scale = p.mu > 0 ? p.mu * s.rn / s.rt_norm : 0.0;
    s.phi = {w[0], lambda[1] - scale * s.rt[0], lambda[2] - scale * s.rt[1]};
  }
  for (int k = 1; k < 3; ++k)
    if (held[k]) s.phi[k] = lambda[k];
  return s;
}

/// |Φ| in traction units: ρ times the gap and slip rows, the slip rows of λ as they are.
double residual_of(const PointState &s)
{
  if (s.kind == 0) return std::max({std::abs(s.phi[0]), std::abs(s.phi[1]), std::abs(s.phi[2])});
  const double t = s.kind == 1 ? s.rho * std::max(std::abs(s.phi[1]), std::abs(s.phi[2])) : std::max(std::abs(s.phi[1]), std::abs(s.phi[2]));
  return std::max(s.rho * std::abs(s.phi[0]), t);
}

Mat3 jacobian_free(const ContactPoint &p, const PointState &s, const Mat3 &Dblk, bool same);

/// Rows of the Newton matrix for closed point c against point cp (3×3, row-major): ∂Φ_c/∂λ_cp.
Mat3 jacobian(const ContactPoint &p, const std::array<bool, 3> &held, const PointState &s, const Mat3 &Dblk, bool same)
{
  Mat3 J = jacobian_free(p, s, Dblk, same);
  for (int k = 1; k < 3; ++k)
    if (held[k])
      for (int l = 0; l < 3; ++l) J[3 * k + l] = same && l == k ? 1.0 : 0.0;
  return J;
}

/// jacobian() with every component free.
Mat3 jacobian_free(const ContactPoint &p, const PointState &s, const Mat3 &Dblk, bool same)
{
  Mat3 J{};
  for (int l = 0; l < 3; ++l) J[l] = Dblk[l]; // the normal row: ∂g/∂λ
  if (s.kind == 1) {
    for (int k = 1; k < 3; ++k)
      for (int l = 0; l < 3; ++l) J[3 * k + l] = Dblk[3 * k + l];
    return J;
  }
  if (p.mu == 0) { // λ_T = 0
    if (same) J[4] = J[8] = 1;
    return J;
  }
  // slip: ∂/∂λ of λ_T − μ r_n q, q = r_T/|r_T|; ∂r_n = e_n δ − ρ D_n, ∂r_T = E_T δ − ρ D_T
  const double q[2] = {s.rt[0] / s.rt_norm, s.rt[1] / s.rt_norm};
  const double P[2][2] = {{(1 - q[0] * q[0]) / s.rt_norm, -q[0] * q[1] / s.rt_norm}, {-q[1] * q[0] / s.rt_norm, (1 - q[1] * q[1]) / s.rt_norm}};
  for (int a = 0; a < 2; ++a)
    for (int l = 0; l < 3; ++l) {
      const double drn = (same && l == 0 ? 1.0 : 0.0) - s.rho * Dblk[l];
      double v = (same && l == a + 1 ? 1.0 : 0.0) - p.mu * q[a] * drn;
      for (int b = 0; b < 2; ++b) v -= p.mu * s.rn * P[a][b] * ((same && l == b + 1 ? 1.0 : 0.0) - s.rho * Dblk[3 * (b + 1) + l]);
      J[3 * (a + 1) + l] = v;
    }
  return J;
}

double max_abs(const Vec3 &v) { return std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])}); }

std::array<bool, 3> held_of(const Compliance &D, int c) { return {D.held(c, 0), D.held(c, 1), D.held(c, 2)}; }

} // namespace

namespace {

/// The states of every point at λ (w = w_f + D λ); returns max |Φ| and fills the closed points.
double evaluate(const Compliance &D, BlockCache &blocks, const std::vector<Vec3> &wf, const std::vector<double> &rho, const std::vector<Vec3> &lambda,
                std::vector<PointState> &st, std::vector<int> &closed)
{
  const int n = D.size();
  std::vector<int> loaded;
  for (int c = 0; c < n; ++c)
    if (max_abs(lambda[c]) > 0) loaded.push_back(c);
  double residual = 0;
  closed.clear();
  for (int c = 0; c < n; ++c) {
    Vec3 w = wf[c];
    for (int cp : loaded) {
      const Mat3 &B = blocks.at(c, cp);
      for (int k = 0; k < 3; ++k) w[k] += B[3 * k] * lambda[cp][0] + B[3 * k + 1] * lambda[cp][1] + B[3 * k + 2] * lambda[cp][2];
    }
    st[c] = classify(D.point(c), held_of(D, c), lambda[c], w, rho[c]);
    residual = std::max(residual, residual_of(st[c]));
    if (st[c].kind) closed.push_back(c);
  }
  return residual;
}

/// One Newton step: open points drop their traction; the closed ones solve J Δ = −Φ − J_open Δ_open.
void newton_step(const Compliance &D, BlockCache &blocks, const std::vector<PointState> &st, const std::vector<int> &rows, std::vector<Vec3> &lambda)
{
  const int m = 3 * static_cast<int>(rows.size()), n = D.size();
  std::vector<double> J(static_cast<std::size_t>(m) * m), rhs(m);
  for (int a = 0; a < static_cast<int>(rows.size()); ++a) {
    const int c = rows[a];
    for (int k = 0; k < 3; ++k) rhs[3 * a + k] = -st[c].phi[k];
    for (int b = 0; b < static_cast<int>(rows.size()); ++b) {
      const Mat3 Jb = jacobian(D.point(c), held_of(D, c), st[c], blocks.at(c, rows[b]), c == rows[b]);
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) J[(3 * a + k) + static_cast<std::size_t>(3 * b + l) * m] = Jb[3 * k + l];
    }
    for (int cp = 0; cp < n; ++cp) {
      if (st[cp].kind || max_abs(lambda[cp]) == 0) continue;
      const Mat3 Jb = jacobian(D.point(c), held_of(D, c), st[c], blocks.at(c, cp), false); // Δλ_cp = −λ_cp
      for (int k = 0; k < 3; ++k) rhs[3 * a + k] += Jb[3 * k] * lambda[cp][0] + Jb[3 * k + 1] * lambda[cp][1] + Jb[3 * k + 2] * lambda[cp][2];
    }
  }
  if (m > 0) {
    std::vector<int> piv(m);
    if (lapack::getrf(m, J.data(), m, piv.data()) != 0) throw std::runtime_error("contact: the friction Newton matrix is singular (dependent contact constraints)");
    lapack::getrs('N', m, 1, J.data(), m, piv.data(), rhs.data(), m);
  }
  for (int c = 0; c < n; ++c)
    if (!st[c].kind) lambda[c] = {0, 0, 0};
  for (int a = 0; a < static_cast<int>(rows.size()); ++a)
    for (int k = 0; k < 3; ++k) lambda[rows[a]][k] += rhs[3 * a + k];
}

} // namespace

FrictionSolver::Result FrictionSolver::solve(const Compliance &D, const std::vector<Vec3> &wf, double tol, int max_it, std::vector<Vec3> &lambda,
                                             std::vector<std::int8_t> &status, const std::function<void(int, long long, long long, double)> &monitor)
{
  const int n = D.size();
  BlockCache blocks(D);
  lambda.resize(n, Vec3{0, 0, 0});
  std::vector<double> rho(n);
  double scale = 0; // the traction scale: the free penetrations' and the warm start's
  for (int c = 0; c < n; ++c) {
    rho[c] = 1.0 / std::max(blocks.at(c, c)[0], 1e-300);
    scale = std::max({scale, max_abs(lambda[c]), rho[c] * std::max(0.0, -wf[c][0])});
  }
  m_factored = false;
  std::vector<PointState> st(n);
  std::vector<int> closed;
  std::vector<std::int8_t> last(n, 0);
  Result r;
  for (;; ++r.iterations) {
    const double residual = evaluate(D, blocks, wf, rho, lambda, st, closed);
    for (const Vec3 &l : lambda) scale = std::max(scale, max_abs(l));
    long long changed = 0;
    for (int c = 0; c < n; ++c) changed += st[c].kind != last[c], last[c] = st[c].kind;
    if (monitor) monitor(r.iterations, static_cast<long long>(closed.size()), changed, scale > 0 ? residual / scale : residual);
    if (residual <= tol * scale) break;
    if (r.iterations >= max_it) throw std::runtime_error("contact: friction did not converge in " + std::to_string(max_it) + " Newton iterations (-contact_max_it)");
    newton_step(D, blocks, st, closed, lambda);
  }
  status.assign(n, 0);
  m_state.assign(n, 0);
  m_direction.assign(n, Vec3{0, 0, 0});
  for (int c = 0; c < n; ++c) {
    if (!st[c].kind) lambda[c] = {0, 0, 0};
    status[c] = m_state[c] = st[c].kind;
    if (st[c].kind == 2 && st[c].rt_norm > 0) m_direction[c] = {0, st[c].rt[0] / st[c].rt_norm, st[c].rt[1] / st[c].rt_norm};
  }
  return r;
}

void FrictionSolver::resolve(const Compliance &D, const std::vector<Vec3> &wf, std::vector<Vec3> &lambda)
{
  const int n = D.size();
  if (!m_factored) { // the fixed-state system: g = 0 and s = 0 (stick), g = 0 and λ_T = μ λ_n q (slip)
    m_rows.clear();
    for (int c = 0; c < n; ++c)
      if (m_state[c]) m_rows.push_back(c);
    const int m = 3 * static_cast<int>(m_rows.size());
    m_lu.assign(static_cast<std::size_t>(m) * m, 0.0);
    for (int a = 0; a < static_cast<int>(m_rows.size()); ++a)
      for (int b = 0; b < static_cast<int>(m_rows.size()); ++b) {
        const Mat3 B = D.block(m_rows[a], m_rows[b]);
        const bool slip = m_state[m_rows[a]] == 2;
        for (int k = 0; k < 3; ++k)
          for (int l = 0; l < 3; ++l) {
            double v = B[3 * k + l];
            if (slip && k > 0) v = (a == b) ? (l == k ? 1.0 : 0.0) - (l == 0 ? D.point(m_rows[a]).mu * m_direction[m_rows[a]][k] : 0.0) : 0.0;
            if (k > 0 && D.held(m_rows[a], k)) v = (a == b && l == k) ? 1.0 : 0.0;
            m_lu[(3 * a + k) + static_cast<std::size_t>(3 * b + l) * m] = v;
          }
      }
    m_piv.resize(m);
    if (m > 0 && lapack::getrf(m, m_lu.data(), m, m_piv.data()) != 0) throw std::runtime_error("contact: the contact's fixed-state system is singular");
    m_factored = true;
  }
  const int m = 3 * static_cast<int>(m_rows.size());
  std::vector<double> rhs(m, 0.0);
  for (int a = 0; a < static_cast<int>(m_rows.size()); ++a) {
    const bool slip = m_state[m_rows[a]] == 2;
    for (int k = 0; k < 3; ++k) rhs[3 * a + k] = ((slip || D.held(m_rows[a], k)) && k > 0) ? 0.0 : -wf[m_rows[a]][k];
  }
  if (m > 0) lapack::getrs('N', m, 1, m_lu.data(), m, m_piv.data(), rhs.data(), m);
  lambda.assign(n, Vec3{0, 0, 0});
  for (int a = 0; a < static_cast<int>(m_rows.size()); ++a)
    for (int k = 0; k < 3; ++k) lambda[m_rows[a]][k] = rhs[3 * a + k];
}

} // namespace hssbem::contact_detail
