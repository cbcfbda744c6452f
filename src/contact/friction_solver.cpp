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

/// D's 3×3 blocks, column by column (a point's column computed the first time it is asked
/// for), on the rows of a zone of points only: the others are not read until the zone changes.
class BlockCache {
public:
  explicit BlockCache(const Compliance &D) : m_D(D), m_slot(D.size(), -1), m_column(D.size()) {}
  /// The rows the columns cover from now on (the columns computed so far are dropped).
  void set_zone(const std::vector<int> &zone)
  {
    m_zone = zone;
    std::fill(m_slot.begin(), m_slot.end(), -1);
    for (std::size_t k = 0; k < zone.size(); ++k) m_slot[zone[k]] = static_cast<int>(k);
    for (std::vector<Mat3> &c : m_column) c.clear();
  }
  /// D(zone[k], cp) for every k: the column of point cp on the zone's rows.
  const Mat3 *column(int cp)
  {
    std::vector<Mat3> &col = m_column[cp];
    if (col.empty()) {
      const int nz = static_cast<int>(m_zone.size());
      col.resize(nz);
#pragma omp parallel for schedule(static) if (nz > 64)
      for (int k = 0; k < nz; ++k) col[k] = m_D.block(m_zone[k], cp);
    }
    return col.data();
  }
  /// D(c, cp) for c in the zone.
  const Mat3 &at(int c, int cp) { return column(cp)[m_slot[c]]; }
  int slot(int c) const { return m_slot[c]; }
  /// dw[k] += Σ_cp D(zone[k], cp) x[cp] over the points with x ≠ 0, column by column.
  void apply(const std::vector<Vec3> &x, std::vector<Vec3> &dw)
  {
    for (std::size_t q = 0; q < m_zone.size(); ++q) {
      const int cp = m_zone[q];
      const Vec3 &v = x[cp];
      if (v[0] == 0 && v[1] == 0 && v[2] == 0) continue;
      const Mat3 *col = column(cp);
      for (std::size_t k = 0; k < m_zone.size(); ++k) {
        const Mat3 &B = col[k];
        Vec3 &w = dw[k];
        w[0] += B[0] * v[0] + B[1] * v[1] + B[2] * v[2];
        w[1] += B[3] * v[0] + B[4] * v[1] + B[5] * v[2];
        w[2] += B[6] * v[0] + B[7] * v[1] + B[8] * v[2];
      }
    }
  }

private:
  const Compliance &m_D;
  std::vector<int> m_zone, m_slot;
  std::vector<std::vector<Mat3>> m_column; ///< per point: its column of blocks on the zone's rows (empty: not computed)
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

/// Φ in traction units: ρ times the gap and slip rows, the rows of λ as they are.
Vec3 scaled_residual(const PointState &s)
{
  if (s.kind == 0) return s.phi;
  const double t = s.kind == 1 ? s.rho : 1.0;
  return {s.rho * s.phi[0], t * s.phi[1], t * s.phi[2]};
}

/// The rows of the Newton matrix of a closed point, J(c, c') = R D(c, c') + [c = c'] Δ: the
/// normal row is D's (∂g/∂λ); a stick point's tangential rows are D's (∂s/∂λ); a slip point's are
/// the derivative of λ_T − μ r_n q, q = r_T/|r_T|, with ∂r_n = e_n δ − ρ D_n and
/// ∂r_T = E_T δ − ρ D_T, so R = μρ (q_a e_n + r_n Σ_b P_ab e_{b+1}), P = (I − q qᵀ)/|r_T|; a held
/// (or frictionless slipping) tangential row is λ_k itself.
struct RowMap {
  Mat3 R{}, diag{};
};

RowMap row_map(const ContactPoint &p, const std::array<bool, 3> &held, const PointState &s)
{
  RowMap m;
  m.R[0] = 1;
  if (s.kind == 1) m.R[4] = m.R[8] = 1;
  else if (p.mu > 0) {
    const double q[2] = {s.rt[0] / s.rt_norm, s.rt[1] / s.rt_norm};
    const double P[2][2] = {{(1 - q[0] * q[0]) / s.rt_norm, -q[0] * q[1] / s.rt_norm}, {-q[1] * q[0] / s.rt_norm, (1 - q[1] * q[1]) / s.rt_norm}};
    for (int a = 0; a < 2; ++a) {
      m.R[3 * (a + 1)] = p.mu * s.rho * q[a];
      m.diag[3 * (a + 1)] = -p.mu * q[a];
      m.diag[3 * (a + 1) + a + 1] = 1;
      for (int b = 0; b < 2; ++b) {
        m.R[3 * (a + 1) + b + 1] = p.mu * s.rho * s.rn * P[a][b];
        m.diag[3 * (a + 1) + b + 1] -= p.mu * s.rn * P[a][b];
      }
    }
  } else m.diag[4] = m.diag[8] = 1; // frictionless: λ_T = 0
  for (int k = 1; k < 3; ++k)
    if (held[k] || (s.kind == 2 && p.mu == 0))
      for (int l = 0; l < 3; ++l) m.R[3 * k + l] = 0, m.diag[3 * k + l] = (l == k ? 1.0 : 0.0);
  return m;
}

/// R B (+ Δ for the point's own block).
Mat3 jacobian(const RowMap &m, const Mat3 &B, bool same)
{
  Mat3 J{};
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) J[3 * k + l] = m.R[3 * k] * B[l] + m.R[3 * k + 1] * B[3 + l] + m.R[3 * k + 2] * B[6 + l] + (same ? m.diag[3 * k + l] : 0.0);
  return J;
}

double max_abs(const Vec3 &v) { return std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])}); }

std::array<bool, 3> held_of(const Compliance &D, int c) { return {D.held(c, 0), D.held(c, 1), D.held(c, 2)}; }

} // namespace

namespace {

/// The states of the zone's points for tractions λ and relative displacements w (by zone
/// position): fills the closed points, returns max |Φ| and sets `merit` to Σ |Φ|² (traction units).
double classify_zone(const Compliance &D, const std::vector<int> &zone, const std::vector<double> &rho, const std::vector<Vec3> &lambda, const std::vector<Vec3> &w,
                     std::vector<PointState> &st, std::vector<int> &closed, double &merit)
{
  double residual = 0;
  merit = 0;
  closed.clear();
  for (std::size_t k = 0; k < zone.size(); ++k) {
    const int c = zone[k];
    st[c] = classify(D.point(c), held_of(D, c), lambda[c], w[k], rho[c]);
    const Vec3 r = scaled_residual(st[c]);
    residual = std::max(residual, max_abs(r));
    merit += dot(r, r);
    if (st[c].kind) closed.push_back(c);
  }
  return residual;
}

/// The Newton matrix of the closed points, factored: kept while the states stay, so that later
/// steps solve with it (chord steps) instead of factoring again.
struct NewtonMatrix {
  std::vector<int> rows;
  std::vector<std::int8_t> kinds;
  std::vector<double> lu;
  std::vector<int> piv;
  bool fits(const std::vector<int> &closed, const std::vector<PointState> &st) const
  {
    if (closed != rows) return false;
    for (std::size_t a = 0; a < rows.size(); ++a)
      if (st[rows[a]].kind != kinds[a]) return false;
    return !lu.empty() || rows.empty();
  }
};

/// The Newton step Δ: open points drop their traction (Δ = −λ); the closed ones solve
/// J Δ = −Φ − J_open Δ_open, with J factored now, or the matrix kept from an earlier step
/// (`chord`: it fits the states).
std::vector<Vec3> newton_step(const Compliance &D, BlockCache &blocks, const std::vector<int> &zone, const std::vector<PointState> &st, const std::vector<int> &rows,
                              const std::vector<Vec3> &lambda, NewtonMatrix &J, bool chord)
{
  const int m = 3 * static_cast<int>(rows.size()), n = D.size();
  std::vector<double> rhs(m);
  if (!chord) {
    J.rows = rows, J.kinds.resize(rows.size()), J.lu.assign(static_cast<std::size_t>(m) * m, 0.0), J.piv.resize(m);
    for (std::size_t a = 0; a < rows.size(); ++a) J.kinds[a] = st[rows[a]].kind;
  }
  for (int a = 0; a < static_cast<int>(rows.size()); ++a)
    for (int k = 0; k < 3; ++k) rhs[3 * a + k] = -st[rows[a]].phi[k];
  std::vector<RowMap> maps(rows.size());
  for (std::size_t a = 0; a < rows.size(); ++a) maps[a] = row_map(D.point(rows[a]), held_of(D, rows[a]), st[rows[a]]);
  for (int b = 0; b < static_cast<int>(rows.size()) && !chord; ++b) { // column by column: each a contiguous column of blocks
    const Mat3 *col = blocks.column(rows[b]);
    for (int a = 0; a < static_cast<int>(rows.size()); ++a) {
      const int c = rows[a];
      const Mat3 Jb = jacobian(maps[a], col[blocks.slot(c)], c == rows[b]);
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) J.lu[(3 * a + k) + static_cast<std::size_t>(3 * b + l) * m] = Jb[3 * k + l];
    }
  }
  for (int cp : zone) { // Δλ_cp = −λ_cp for the open points that carry a traction
    if (st[cp].kind || max_abs(lambda[cp]) == 0) continue;
    const Mat3 *col = blocks.column(cp);
    for (int a = 0; a < static_cast<int>(rows.size()); ++a) {
      const Mat3 Jb = jacobian(maps[a], col[blocks.slot(rows[a])], false);
      for (int k = 0; k < 3; ++k) rhs[3 * a + k] += Jb[3 * k] * lambda[cp][0] + Jb[3 * k + 1] * lambda[cp][1] + Jb[3 * k + 2] * lambda[cp][2];
    }
  }
  if (m > 0) {
    if (!chord && lapack::getrf(m, J.lu.data(), m, J.piv.data()) != 0)
      throw std::runtime_error("contact: the friction Newton matrix is singular (dependent contact constraints)");
    lapack::getrs('N', m, 1, J.lu.data(), m, J.piv.data(), rhs.data(), m);
  }
  std::vector<Vec3> step(n, Vec3{0, 0, 0});
  for (int c : zone)
    if (!st[c].kind) step[c] = -1.0 * lambda[c];
  for (int a = 0; a < static_cast<int>(rows.size()); ++a)
    for (int k = 0; k < 3; ++k) step[rows[a]][k] = rhs[3 * a + k];
  return step;
}

/// Damped semismooth Newton on the points of `zone` (the others keep λ = 0); r counts the steps.
void newton(const Compliance &D, BlockCache &blocks, const std::vector<int> &zone, const std::vector<Vec3> &wf, const std::vector<double> &rho, double tol, int max_it,
            std::vector<Vec3> &lambda, std::vector<PointState> &st, FrictionSolver::Result &r, const std::function<void(int, long long, long long, double)> &monitor)
{
  const int n = D.size();
  const std::size_t nz = zone.size();
  double scale = 0; // the traction scale: the free penetrations' and the warm start's
  for (int c : zone) scale = std::max({scale, max_abs(lambda[c]), rho[c] * std::max(0.0, -wf[c][0])});
  std::vector<Vec3> w(nz), dw(nz), trial_w(nz);
  for (std::size_t k = 0; k < nz; ++k) w[k] = wf[zone[k]];
  blocks.apply(lambda, w); // w = w_f + D λ on the zone
  std::vector<PointState> trial_st(n);
  std::vector<int> closed, trial_closed;
  std::vector<std::int8_t> last(n, 0);
  NewtonMatrix J;
  double merit = 0, residual = classify_zone(D, zone, rho, lambda, w, st, closed, merit);
  // A trial λ + t Δ: its w is w + t D Δ (D Δ once per step), then its states and Σ |Φ|².
  std::vector<Vec3> trial = lambda;
  auto try_step = [&](const std::vector<Vec3> &step, double t, double &trial_merit) {
    for (int c : zone) trial[c] = lambda[c] + t * step[c];
    for (std::size_t k = 0; k < nz; ++k) trial_w[k] = w[k] + t * dw[k];
    return classify_zone(D, zone, rho, trial, trial_w, trial_st, trial_closed, trial_merit);
  };
  auto accept = [&](double trial_merit, double trial_residual) {
    lambda.swap(trial), st.swap(trial_st), closed.swap(trial_closed), w.swap(trial_w);
    merit = trial_merit, residual = trial_residual;
    trial = lambda;
  };
  for (;; ++r.iterations) {
    for (int c : zone) scale = std::max(scale, max_abs(lambda[c]));
    long long changed = 0;
    for (int c : zone) changed += st[c].kind != last[c], last[c] = st[c].kind;
    if (monitor) monitor(r.iterations, static_cast<long long>(closed.size()), changed, scale > 0 ? residual / scale : residual);
    if (residual <= tol * scale) return;
    if (r.iterations >= max_it) throw std::runtime_error("contact: friction did not converge in " + std::to_string(max_it) + " Newton iterations (-contact_max_it)");
    // While the states stay, the factored matrix of the last step serves (a chord step) as long
    // as it quarters Σ |Φ|²; otherwise a Newton step, damped: semismooth Newton alone cycles
    // between stick and slip sets (measured on the sliding instrument), so its step is halved
    // until Σ |Φ|² decreases (Armijo), up to 1/64.
    double trial_merit = 0;
    if (J.fits(closed, st)) {
      const std::vector<Vec3> step = newton_step(D, blocks, zone, st, closed, lambda, J, true);
      std::fill(dw.begin(), dw.end(), Vec3{0, 0, 0});
      blocks.apply(step, dw);
      const double trial_residual = try_step(step, 1.0, trial_merit);
      if (trial_merit <= 0.25 * merit) {
        accept(trial_merit, trial_residual);
        continue;
      }
    }
    const std::vector<Vec3> step = newton_step(D, blocks, zone, st, closed, lambda, J, false);
    std::fill(dw.begin(), dw.end(), Vec3{0, 0, 0});
    blocks.apply(step, dw);
    for (double t = 1;; t *= 0.5) {
      const double trial_residual = try_step(step, t, trial_merit);
      if (trial_merit <= (1 - 1e-4 * t) * merit || t < 1.0 / 64) {
        accept(trial_merit, trial_residual);
        break;
      }
    }
  }
}

} // namespace

FrictionSolver::Result FrictionSolver::solve(const Compliance &D, const std::vector<Vec3> &wf, const std::vector<char> &in_zone, double tol, int max_it,
                                             std::vector<Vec3> &lambda, std::vector<std::int8_t> &status,
                                             const std::function<void(int, long long, long long, double)> &monitor)
{
  const int n = D.size();
  BlockCache blocks(D);
  lambda.resize(n, Vec3{0, 0, 0});
  std::vector<int> zone;
  std::vector<double> rho(n, 0.0);
  for (int c = 0; c < n; ++c)
    if (in_zone[c]) zone.push_back(c), rho[c] = 1.0 / std::max(D.block(c, c)[0], 1e-300);
    else lambda[c] = {0, 0, 0};
  blocks.set_zone(zone);
  m_factored = false;
  std::vector<PointState> st(n);
  Result r;
  newton(D, blocks, zone, wf, rho, tol, max_it, lambda, st, r, monitor);
  status.assign(n, 0);
  m_state.assign(n, 0);
  m_direction.assign(n, Vec3{0, 0, 0});
  for (int c : zone) {
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
