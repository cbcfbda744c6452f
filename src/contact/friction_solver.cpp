// Coulomb friction (contact_points.hpp): semismooth Newton on Alart–Curnier's function in the
// compliance form, w = w_f + D λ (w: gap and slip in the points' local frames, λ: the contact
// traction on the body). Per point, with r_n = λ_n − ρ g and r_T = λ_T − ρ s:
//   open  (r_n ≤ 0):             λ = 0;
//   stick (|r_T| ≤ μ r_n):       g = 0, s = 0;
//   slip:                        g = 0, λ_T = μ r_n r_T / |r_T|,
// linearised at each step (generalised Jacobian) over the closed points. The Newton systems are
// solved by GMRES preconditioned with the factored Newton matrix of an earlier step (kept from
// step to step and frame to frame, mapped by dof node; factored again in single precision when
// GMRES needs too many products or the closed points moved on).
#include "contact_points.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <unordered_map>
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
  /// D(zone[k], cp) for every k: the column of point cp on the zone's rows (computed here, on
  /// one thread, if prepare() did not).
  const Mat3 *column(int cp)
  {
    std::vector<Mat3> &col = m_column[cp];
    if (col.empty()) fill(cp);
    return col.data();
  }
  /// Computes the missing columns of the points cps in one parallel loop (a loop per column
  /// costs a thread barrier each: on a busy machine a time slice).
  void prepare(const std::vector<int> &cps)
  {
    std::vector<int> missing;
    for (int cp : cps)
      if (m_column[cp].empty()) missing.push_back(cp), m_column[cp].resize(m_zone.size());
    const int nm = static_cast<int>(missing.size());
#pragma omp parallel for schedule(dynamic, 4) if (nm * m_zone.size() > 4096)
    for (int q = 0; q < nm; ++q) fill(missing[q]);
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
  void fill(int cp)
  {
    std::vector<Mat3> &col = m_column[cp];
    col.resize(m_zone.size());
    for (std::size_t k = 0; k < m_zone.size(); ++k) col[k] = m_D.block(m_zone[k], cp);
  }
  const Compliance &m_D;
  std::vector<int> m_zone, m_slot;
  std::vector<std::vector<Mat3>> m_column; ///< per point: its column of blocks on the zone's rows (empty: not computed)
};

struct PointState {
  std::int8_t kind = 0; ///< 0 open, 1 stick, 2 slip
  bool free_slip = false; ///< slipping with λ_T = 0 (frictionless, or no slip direction)
  double rho = 0, rn = 0;
  double rt[2] = {0, 0}, rt_norm = 0;
  Vec3 phi{};           ///< the residual: λ (open); g, s (stick); g, λ_T − μ r_n q (slip)
};

/// The slip rows of a point in the slip state: g = 0 and λ_T = μ r_n q, q = r_T / |r_T| (λ_T = 0
/// without friction or a slip direction).
void slip_rows(const ContactPoint &p, const std::array<bool, 3> &held, const Vec3 &lambda, const Vec3 &w, PointState &s)
{
  for (int a = 0; a < 2; ++a) s.rt[a] = held[a + 1] ? 0.0 : lambda[a + 1] - s.rho * w[a + 1];
  s.rt_norm = std::hypot(s.rt[0], s.rt[1]);
  s.free_slip = !(p.mu > 0 && s.rt_norm > 0);
  const double scale = s.free_slip ? 0.0 : p.mu * s.rn / s.rt_norm;
  s.phi = {w[0], lambda[1] - scale * s.rt[0], lambda[2] - scale * s.rt[1]};
}

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
  s.kind = p.mu > 0 && s.rt_norm <= p.mu * s.rn ? 1 : 2; // frictionless points slide whatever r_T is: λ_T = 0
  if (s.kind == 1) s.phi = w;
  else slip_rows(p, held, lambda, w, s);
  for (int k = 1; k < 3; ++k)
    if (held[k]) s.phi[k] = lambda[k];
  return s;
}

/// A follower is closed with its lead and open with it: closed, its rows are w = 0 (its normal row
/// bound to the partner, its tie rows to the lead's node; tractions of either sign), open λ = 0.
PointState classify_follower(const std::array<bool, 3> &held, const Vec3 &lambda, const Vec3 &w, double rho, std::int8_t lead_kind)
{
  PointState s;
  s.rho = rho;
  s.kind = lead_kind ? 1 : 0;
  s.phi = s.kind ? w : lambda;
  for (int k = 1; k < 3 && s.kind; ++k)
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
  else if (!s.free_slip) {
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
    if (held[k] || (s.kind == 2 && s.free_slip))
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

/// The inverse of a 3×3 block (the identity if it is singular: a preconditioner's block only).
Mat3 inverse(const Mat3 &A)
{
  const Mat3 C{A[4] * A[8] - A[5] * A[7], A[2] * A[7] - A[1] * A[8], A[1] * A[5] - A[2] * A[4], A[5] * A[6] - A[3] * A[8], A[0] * A[8] - A[2] * A[6],
               A[2] * A[3] - A[0] * A[5], A[3] * A[7] - A[4] * A[6], A[1] * A[6] - A[0] * A[7], A[0] * A[4] - A[1] * A[3]};
  const double det = A[0] * C[0] + A[1] * C[3] + A[2] * C[6];
  if (det == 0 || !std::isfinite(det)) return {1, 0, 0, 0, 1, 0, 0, 0, 1};
  Mat3 inv;
  for (int k = 0; k < 9; ++k) inv[k] = C[k] / det;
  return inv;
}

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
  for (std::size_t k = 0; k < zone.size(); ++k) // the leading points first: their followers take their states
    if (D.point(zone[k]).lead < 0) st[zone[k]] = classify(D.point(zone[k]), held_of(D, zone[k]), lambda[zone[k]], w[k], rho[zone[k]]);
  for (std::size_t k = 0; k < zone.size(); ++k)
    if (D.point(zone[k]).lead >= 0) st[zone[k]] = classify_follower(held_of(D, zone[k]), lambda[zone[k]], w[k], rho[zone[k]], st[D.point(zone[k]).lead].kind);
  for (std::size_t k = 0; k < zone.size(); ++k) {
    const int c = zone[k];
    const Vec3 r = scaled_residual(st[c]);
    residual = std::max(residual, max_abs(r));
    merit += dot(r, r);
    if (st[c].kind) closed.push_back(c);
  }
  return residual;
}

/// D on the closed points, packed in single precision (column-major, 3 |closed| square): the
/// Newton matrix's products read it (half the traffic of the cached blocks, one gemv); packed
/// again only when the closed points change.
class ClosedBlocks {
public:
  void pack(BlockCache &blocks, const std::vector<int> &rows)
  {
    if (rows == m_rows && !m_D.empty()) return;
    m_rows = rows;
    const int nr = static_cast<int>(rows.size()), m = 3 * nr;
    m_D.assign(static_cast<std::size_t>(m) * m, 0.0f);
    std::vector<const Mat3 *> col(nr);
    for (int b = 0; b < nr; ++b) col[b] = blocks.column(rows[b]);
    std::vector<int> slot(nr);
    for (int a = 0; a < nr; ++a) slot[a] = blocks.slot(rows[a]);
    for (int b = 0; b < nr; ++b)
      for (int a = 0; a < nr; ++a) {
        const Mat3 &B = col[b][slot[a]];
        for (int l = 0; l < 3; ++l)
          for (int k = 0; k < 3; ++k) m_D[(3 * a + k) + static_cast<std::size_t>(3 * b + l) * m] = static_cast<float>(B[3 * k + l]);
      }
  }
  /// y = D x on the closed points.
  void apply(const double *x, double *y) const
  {
    const int m = 3 * static_cast<int>(m_rows.size());
    std::vector<float> xs(x, x + m), ys(m);
    lapack::gemv('N', m, m, 1.0f, m_D.data(), m, xs.data(), 0.0f, ys.data());
    std::copy(ys.begin(), ys.end(), y);
  }

private:
  std::vector<int> m_rows;
  std::vector<float> m_D;
};

/// The Newton matrix of the closed points at the current states, J(c, c') = R D(c, c') + [c = c'] Δ,
/// as an operator on their 3 |closed| unknowns, rows scaled to traction units (ρ on the gap and
/// stick rows, as in scaled_residual): products through the cached blocks, or assembled.
class NewtonOperator {
public:
  NewtonOperator(const Compliance &D, BlockCache &blocks, const ClosedBlocks &packed, const std::vector<PointState> &st, const std::vector<int> &rows)
      : m_blocks(blocks), m_packed(packed), m_rows(rows)
  {
    m_maps.resize(rows.size()), m_slots.resize(rows.size()), m_scale.resize(rows.size());
    for (std::size_t a = 0; a < rows.size(); ++a) {
      const PointState &s = st[rows[a]];
      m_maps[a] = row_map(D.point(rows[a]), held_of(D, rows[a]), s);
      m_slots[a] = blocks.slot(rows[a]);
      const double t = s.kind == 1 ? s.rho : 1.0;
      m_scale[a] = {s.rho, t, t};
      for (int k = 1; k < 3; ++k) // a held (or frictionless) tangential row is λ_k itself
        if (held_of(D, rows[a])[k] || (s.kind == 2 && s.free_slip)) m_scale[a][k] = 1.0;
    }
  }
  int size() const { return 3 * static_cast<int>(m_rows.size()); }
  const RowMap &map(int a) const { return m_maps[a]; }
  const Vec3 &scale(int a) const { return m_scale[a]; }
  /// y = S J x (x, y: 3 per closed point): D x from the packed blocks, then per point R and Δ.
  void apply(const double *x, double *y) const
  {
    const int nr = static_cast<int>(m_rows.size());
    std::vector<double> w(3 * nr);
    m_packed.apply(x, w.data());
    for (int a = 0; a < nr; ++a) {
      const RowMap &m = m_maps[a];
      const double *v = x + 3 * a, *wa = w.data() + 3 * a;
      for (int k = 0; k < 3; ++k)
        y[3 * a + k] = m_scale[a][k] * (m.R[3 * k] * wa[0] + m.R[3 * k + 1] * wa[1] + m.R[3 * k + 2] * wa[2] + m.diag[3 * k] * v[0] + m.diag[3 * k + 1] * v[1] +
                                        m.diag[3 * k + 2] * v[2]);
    }
  }
  /// S J, dense (column-major, 3 |closed| square), in single precision.
  void assemble(std::vector<float> &out) const
  {
    const int nr = static_cast<int>(m_rows.size()), m = size();
    out.assign(static_cast<std::size_t>(m) * m, 0.0f);
    for (int b = 0; b < nr; ++b) m_blocks.column(m_rows[b]); // computed before the threads read them
#pragma omp parallel for schedule(static) if (nr > 128)
    for (int b = 0; b < nr; ++b) {
      const Mat3 *col = m_blocks.column(m_rows[b]);
      for (int a = 0; a < nr; ++a) {
        const Mat3 Jb = jacobian(m_maps[a], col[m_slots[a]], a == b);
        for (int k = 0; k < 3; ++k)
          for (int l = 0; l < 3; ++l) out[(3 * a + k) + static_cast<std::size_t>(3 * b + l) * m] = static_cast<float>(m_scale[a][k] * Jb[3 * k + l]);
      }
    }
  }
  /// The point's own 3×3 block of S J.
  Mat3 diagonal(int a) const
  {
    Mat3 J = jacobian(m_maps[a], m_blocks.column(m_rows[a])[m_slots[a]], true);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) J[3 * k + l] *= m_scale[a][k];
    return J;
  }

private:
  BlockCache &m_blocks;
  const ClosedBlocks &m_packed;
  const std::vector<int> &m_rows;
  std::vector<RowMap> m_maps;
  std::vector<int> m_slots;
  std::vector<Vec3> m_scale;
};

/// Solves A x = b by GMRES(k) with right preconditioning (the residual it measures is the true
/// one): x starts at 0; stops when |b − A x| ≤ atol or after max_it products. Returns the
/// products made; `converged` says whether it reached atol.
int gmres(int n, const std::function<void(const double *, double *)> &A, const std::function<void(const double *, double *)> &P, const double *b, double *x, double atol,
          int max_it, bool &converged)
{
  std::fill(x, x + n, 0.0);
  std::vector<double> r(b, b + n);
  double beta = std::sqrt(std::inner_product(r.begin(), r.end(), r.begin(), 0.0));
  converged = beta <= atol;
  int it = 0;
  const int k_max = 30;
  std::vector<double> V, Z, H(static_cast<std::size_t>(k_max + 1) * k_max), cs(k_max), sn(k_max), g(k_max + 1), w(n);
  while (!converged && it < max_it) {
    V.assign(static_cast<std::size_t>(n) * (k_max + 1), 0.0), Z.assign(static_cast<std::size_t>(n) * k_max, 0.0);
    std::fill(g.begin(), g.end(), 0.0);
    g[0] = beta;
    for (int i = 0; i < n; ++i) V[i] = r[i] / beta;
    int k = 0;
    for (; k < k_max && it < max_it && !converged; ++k, ++it) {
      P(&V[static_cast<std::size_t>(k) * n], &Z[static_cast<std::size_t>(k) * n]);
      A(&Z[static_cast<std::size_t>(k) * n], w.data());
      for (int i = 0; i <= k; ++i) { // modified Gram–Schmidt
        const double *v = &V[static_cast<std::size_t>(i) * n];
        const double h = std::inner_product(w.begin(), w.end(), v, 0.0);
        H[i + k * (k_max + 1)] = h;
        for (int p = 0; p < n; ++p) w[p] -= h * v[p];
      }
      const double h1 = std::sqrt(std::inner_product(w.begin(), w.end(), w.begin(), 0.0));
      H[k + 1 + k * (k_max + 1)] = h1;
      if (h1 > 0)
        for (int p = 0; p < n; ++p) V[static_cast<std::size_t>(k + 1) * n + p] = w[p] / h1;
      for (int i = 0; i < k; ++i) { // the earlier rotations on the new column
        double &a0 = H[i + k * (k_max + 1)], &a1 = H[i + 1 + k * (k_max + 1)];
        const double t = cs[i] * a0 + sn[i] * a1;
        a1 = -sn[i] * a0 + cs[i] * a1, a0 = t;
      }
      double &a0 = H[k + k * (k_max + 1)], &a1 = H[k + 1 + k * (k_max + 1)];
      const double d = std::hypot(a0, a1);
      cs[k] = d > 0 ? a0 / d : 1.0, sn[k] = d > 0 ? a1 / d : 0.0;
      a0 = d, a1 = 0;
      g[k + 1] = -sn[k] * g[k], g[k] = cs[k] * g[k];
      converged = std::abs(g[k + 1]) <= atol || h1 == 0;
    }
    std::vector<double> y(g.begin(), g.begin() + k); // back substitution, then x += Z y
    for (int i = k - 1; i >= 0; --i) {
      for (int j = i + 1; j < k; ++j) y[i] -= H[i + j * (k_max + 1)] * y[j];
      y[i] = H[i + i * (k_max + 1)] != 0 ? y[i] / H[i + i * (k_max + 1)] : 0.0;
    }
    for (int i = 0; i < k; ++i)
      for (int p = 0; p < n; ++p) x[p] += y[i] * Z[static_cast<std::size_t>(i) * n + p];
    A(x, w.data()); // the true residual for the restart (and the final check)
    for (int p = 0; p < n; ++p) r[p] = b[p] - w[p];
    beta = std::sqrt(std::inner_product(r.begin(), r.end(), r.begin(), 0.0));
    converged = beta <= atol;
  }
  return it;
}

} // namespace

/// The factored Newton matrix of an earlier step, this frame's or an earlier frame's (single
/// precision): it preconditions the Newton systems while the closed set and the states change
/// little, and is factored again when the systems take too many products.
struct FrictionSolver::Preconditioner {
  std::unordered_map<int, int> slot; ///< point key → its position in the factored matrix
  std::vector<float> lu;
  std::vector<int> piv;
  int m = 0;
  bool empty() const { return lu.empty(); }
  void factor(const NewtonOperator &J, const std::vector<int> &rows, const Compliance &D)
  {
    m = J.size();
    J.assemble(lu);
    piv.resize(m);
    slot.clear();
    for (std::size_t a = 0; a < rows.size(); ++a) slot[D.point(rows[a]).key] = static_cast<int>(a);
    if (m > 0 && lapack::getrf(m, lu.data(), m, piv.data()) != 0) throw std::runtime_error("contact: the friction Newton matrix is singular (dependent contact constraints)");
  }
};

namespace {

/// Solves the Newton system S J Δ = rhs by GMRES preconditioned with the kept factorization (the
/// points it does not cover with their own diagonal block); factors J anew when the kept one is
/// missing, covers too few of the points, or GMRES needed more than `k_refactor` products (the
/// next system then starts from a fresh one).
int solve_newton_system(const Compliance &D, const NewtonOperator &J, const std::vector<int> &rows, FrictionSolver::Preconditioner &pre, const std::vector<double> &rhs,
                        std::vector<double> &x, double atol, int &factorizations)
{
  // A factorization costs about m/30 products' time here (m = 3 |closed|); on the 4k organ
  // (m ≈ 300) a refactorization after 10 products gave 3.5 ms per frame, after 20: 3.9, after
  // 40: 3.9, after 4: 4.2 (one thread).
  const int m = J.size(), nr = static_cast<int>(rows.size());
  const int k_refactor = std::clamp(m / 30, 10, 40), k_max = 60;
  x.assign(m, 0.0);
  if (m == 0) return 0;
  // Products and triangular solves of a few MB each: on one thread (threaded BLAS would meet
  // at a barrier per call, a time slice each on a busy machine); the factorization is threaded.
  int products = 0;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int> at(nr, -1);
    int covered = 0;
    if (!pre.empty())
      for (int a = 0; a < nr; ++a) {
        const auto it = pre.slot.find(D.point(rows[a]).key);
        if (it != pre.slot.end()) at[a] = it->second, ++covered;
      }
    if (pre.empty() || covered < 0.8 * nr) {
      pre.factor(J, rows, D), ++factorizations;
      for (int a = 0; a < nr; ++a) at[a] = a;
    }
    std::vector<Mat3> own(nr); // inverses of the diagonal blocks of the points not covered
    for (int a = 0; a < nr; ++a)
      if (at[a] < 0) own[a] = inverse(J.diagonal(a));
    std::vector<float> y(pre.m);
    auto P = [&](const double *v, double *z) {
      std::fill(y.begin(), y.end(), 0.0f);
      for (int a = 0; a < nr; ++a)
        if (at[a] >= 0)
          for (int k = 0; k < 3; ++k) y[3 * at[a] + k] = static_cast<float>(v[3 * a + k]);
      lapack::getrs('N', pre.m, 1, pre.lu.data(), pre.m, pre.piv.data(), y.data(), pre.m);
      for (int a = 0; a < nr; ++a)
        for (int k = 0; k < 3; ++k)
          z[3 * a + k] = at[a] >= 0 ? y[3 * at[a] + k] : own[a][3 * k] * v[3 * a] + own[a][3 * k + 1] * v[3 * a + 1] + own[a][3 * k + 2] * v[3 * a + 2];
    };
    auto A = [&](const double *v, double *z) { J.apply(v, z); };
    bool converged = false;
    std::vector<double> dx(m);
    const SerialBlas serial;
    const int its = gmres(m, A, P, rhs.data(), dx.data(), atol, pass == 0 ? k_max : 2 * k_max, converged);
    products += its;
    if (converged) {
      x = dx;
      if (its > k_refactor) pre.lu.clear(); // the next system factors afresh
      return products;
    }
    pre.lu.clear();
  }
  throw std::runtime_error("contact: the friction Newton system did not converge (GMRES)");
}

/// The Newton step Δ: open points drop their traction (Δ = −λ); the closed ones solve
/// J Δ = −Φ − J_open Δ_open (rows in traction units), to `eta` relative to the right-hand side.
std::vector<Vec3> newton_step(const Compliance &D, BlockCache &blocks, const std::vector<int> &zone, const std::vector<PointState> &st, const std::vector<int> &rows,
                              const std::vector<Vec3> &lambda, ClosedBlocks &packed, FrictionSolver::Preconditioner &pre, double atol, FrictionSolver::Result &r)
{
  const int m = 3 * static_cast<int>(rows.size()), n = D.size();
  std::vector<int> loaded = rows; // the columns this step reads: the closed points', the open ones' that carry a traction
  for (int cp : zone)
    if (!st[cp].kind && max_abs(lambda[cp]) != 0) loaded.push_back(cp);
  blocks.prepare(loaded);
  packed.pack(blocks, rows);
  const NewtonOperator J(D, blocks, packed, st, rows);
  std::vector<double> rhs(m);
  for (int a = 0; a < static_cast<int>(rows.size()); ++a)
    for (int k = 0; k < 3; ++k) rhs[3 * a + k] = -st[rows[a]].phi[k];
  for (int cp : zone) { // Δλ_cp = −λ_cp for the open points that carry a traction
    if (st[cp].kind || max_abs(lambda[cp]) == 0) continue;
    const Mat3 *col = blocks.column(cp);
    for (int a = 0; a < static_cast<int>(rows.size()); ++a) {
      const Mat3 Jb = jacobian(J.map(a), col[blocks.slot(rows[a])], false);
      for (int k = 0; k < 3; ++k) rhs[3 * a + k] += Jb[3 * k] * lambda[cp][0] + Jb[3 * k + 1] * lambda[cp][1] + Jb[3 * k + 2] * lambda[cp][2];
    }
  }
  for (int a = 0; a < static_cast<int>(rows.size()); ++a)
    for (int k = 0; k < 3; ++k) rhs[3 * a + k] *= J.scale(a)[k];
  std::vector<double> x;
  r.products += solve_newton_system(D, J, rows, pre, rhs, x, atol, r.factorizations);
  std::vector<Vec3> step(n, Vec3{0, 0, 0});
  for (int c : zone)
    if (!st[c].kind) step[c] = -1.0 * lambda[c];
  for (int a = 0; a < static_cast<int>(rows.size()); ++a)
    for (int k = 0; k < 3; ++k) step[rows[a]][k] = x[3 * a + k];
  return step;
}

/// Damped semismooth Newton on the points of `zone` (the others keep λ = 0); r counts the steps.
void newton(const Compliance &D, BlockCache &blocks, const std::vector<int> &zone, const std::vector<Vec3> &wf, const std::vector<double> &rho, double tol, int max_it,
            FrictionSolver::Preconditioner &pre, std::vector<Vec3> &lambda, std::vector<PointState> &st, FrictionSolver::Result &r, const std::function<void(int, long long, long long, double)> &monitor)
{
  const int n = D.size();
  const std::size_t nz = zone.size();
  double scale = 0; // the traction scale: the free penetrations' and the warm start's
  for (int c : zone) scale = std::max({scale, max_abs(lambda[c]), rho[c] * std::max(0.0, -wf[c][0])});
  std::vector<Vec3> w(nz), dw(nz), trial_w(nz);
  for (std::size_t k = 0; k < nz; ++k) w[k] = wf[zone[k]];
  blocks.apply(lambda, w); // w = w_f + D λ on the zone
  std::vector<PointState> trial_st(n);
  ClosedBlocks packed;
  std::vector<int> closed, trial_closed;
  std::vector<std::int8_t> last(n, 0);
  double merit = 0, residual = classify_zone(D, zone, rho, lambda, w, st, closed, merit);
  // A trial λ + t Δ: its w is w + t D Δ (D Δ once per step), then its states and Σ |Φ|².
  std::vector<Vec3> trial = lambda;
  auto try_step = [&](const std::vector<Vec3> &step, double t, double &trial_merit) {
    for (int c : zone) trial[c] = lambda[c] + t * step[c];
    for (std::size_t k = 0; k < nz; ++k) trial_w[k] = w[k] + t * dw[k];
    return classify_zone(D, zone, rho, trial, trial_w, trial_st, trial_closed, trial_merit);
  };
  for (;; ++r.iterations) {
    for (int c : zone) scale = std::max(scale, max_abs(lambda[c]));
    long long changed = 0;
    for (int c : zone) changed += st[c].kind != last[c], last[c] = st[c].kind;
    if (monitor) monitor(r.iterations, static_cast<long long>(closed.size()), changed, scale > 0 ? residual / scale : residual);
    if (residual <= tol * scale) { // checked on w = w_f + D λ afresh (the steps update w by products)
      for (std::size_t k = 0; k < nz; ++k) w[k] = wf[zone[k]];
      blocks.apply(lambda, w);
      residual = classify_zone(D, zone, rho, lambda, w, st, closed, merit);
      if (residual <= tol * scale) return;
    }
    if (r.iterations >= max_it) {
      char text[200];
      std::snprintf(text, sizeof text, "friction did not converge in %d Newton iterations (-contact_max_it): residual %.2e of the traction scale (tolerance %.1e)", max_it,
                    scale > 0 ? residual / scale : residual, tol);
      throw std::runtime_error(text);
    }
    // An inexact Newton step, its system solved to η |Φ| with η = min(1e-2, max |Φ| / scale)
    // (the steps stay quadratic; a tenth of the tolerance at least), damped: semismooth Newton
    // alone cycles between stick and slip sets (measured on the sliding instrument), so its
    // step is halved until Σ |Φ|² decreases (Armijo), up to 1/64.
    const double eta = std::min(1e-2, scale > 0 ? residual / scale : 1e-2); // a cap of 0.1 or 0.3: the same time (4k organ)
    const double atol = std::max(eta * std::sqrt(merit), 0.1 * tol * scale);
    const std::vector<Vec3> step = newton_step(D, blocks, zone, st, closed, lambda, packed, pre, atol, r);
    std::fill(dw.begin(), dw.end(), Vec3{0, 0, 0});
    blocks.apply(step, dw);
    for (double t = 1;; t *= 0.5) {
      double trial_merit = 0;
      const double trial_residual = try_step(step, t, trial_merit);
      if (trial_merit <= (1 - 1e-4 * t) * merit || t < 1.0 / 64) {
        lambda.swap(trial), st.swap(trial_st), closed.swap(trial_closed), w.swap(trial_w);
        merit = trial_merit, residual = trial_residual;
        trial = lambda;
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
  for (int c = 0; c < n; ++c) // a follower is watched with its lead
    if (in_zone[D.point(c).lead < 0 ? c : D.point(c).lead]) zone.push_back(c), rho[c] = 1.0 / std::max(D.block(c, c)[0], 1e-300);
    else lambda[c] = {0, 0, 0};
  blocks.set_zone(zone);
  m_factored = false;
  std::vector<PointState> st(n);
  Result r;
  if (!m_pre) m_pre = std::make_shared<Preconditioner>();
  newton(D, blocks, zone, wf, rho, tol, max_it, *m_pre, lambda, st, r, monitor);
  status.assign(n, 0);
  m_state.assign(n, 0);
  m_direction.assign(n, Vec3{0, 0, 0});
  for (int c : zone) {
    if (!st[c].kind) lambda[c] = {0, 0, 0};
    status[c] = m_state[c] = st[c].kind;
    if (st[c].kind == 2 && !st[c].free_slip) m_direction[c] = {0, st[c].rt[0] / st[c].rt_norm, st[c].rt[1] / st[c].rt_norm};
  }
  return r;
}

void FrictionSolver::factor_fixed_states(const Compliance &D)
{
  // The fixed-state system: g = 0 and s = 0 (stick), g = 0 and λ_T = μ λ_n q (slip; λ_T = 0 for a
  // frictionless point), λ_k = 0 along a held tangent.
  m_rows.clear();
  for (int c = 0; c < D.size(); ++c)
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
          if (slip && k > 0) v = (a == b) ? (l == k ? 1.0 : 0.0) - (l == 0 ? D.point(m_rows[a]).mu * m_direction[m_rows[a]][k] : 0.0) : 0.0; // no direction: λ_T = 0
          if (k > 0 && D.held(m_rows[a], k)) v = (a == b && l == k) ? 1.0 : 0.0;
          m_lu[(3 * a + k) + static_cast<std::size_t>(3 * b + l) * m] = v;
        }
    }
  m_piv.resize(m);
  if (m > 0 && lapack::getrf(m, m_lu.data(), m, m_piv.data()) != 0) throw std::runtime_error("the contact's fixed-state system is singular");
  m_factored = true;
}

void FrictionSolver::stick_slipping_points(const Compliance &D)
{
  for (int c = 0; c < D.size(); ++c)
    if (m_state[c] == 2 && D.point(c).mu > 0) m_state[c] = 1;
  factor_fixed_states(D);
}

/// The fixed-state system's right-hand side for wf (closed: the gap and a sticking point's slip;
/// a sliding point's tangential rows and a held tangent's: zero), solved.
std::vector<double> FrictionSolver::fixed_state_answer(const Compliance &D, const std::vector<Vec3> &wf)
{
  if (!m_factored) factor_fixed_states(D);
  const int m = 3 * static_cast<int>(m_rows.size());
  std::vector<double> y(m, 0.0);
  for (int a = 0; a < static_cast<int>(m_rows.size()); ++a) {
    const bool slip = m_state[m_rows[a]] == 2;
    for (int k = 0; k < 3; ++k) y[3 * a + k] = ((slip || D.held(m_rows[a], k)) && k > 0) ? 0.0 : -wf[m_rows[a]][k];
  }
  if (m > 0) lapack::getrs('N', m, 1, m_lu.data(), m, m_piv.data(), y.data(), m);
  return y;
}

void FrictionSolver::fixed_states(const Compliance &D, const std::vector<Vec3> &wf, std::vector<Vec3> &lambda)
{
  const std::vector<double> y = fixed_state_answer(D, wf);
  lambda.assign(D.size(), Vec3{0, 0, 0});
  for (int a = 0; a < static_cast<int>(m_rows.size()); ++a)
    for (int k = 0; k < 3; ++k) lambda[m_rows[a]][k] = y[3 * a + k];
}

void FrictionSolver::haptic(const Compliance &D, const std::vector<Vec3> &wf, double tol_gap, std::vector<Vec3> &lambda)
{
  const std::vector<double> y = fixed_state_answer(D, wf);
  const int m = static_cast<int>(y.size());
  const auto column = [&](const std::vector<int> &rows, double *out) { // one blocked solve
    const int nr = static_cast<int>(rows.size());
    std::fill(out, out + static_cast<std::size_t>(m) * nr, 0.0);
    for (int j = 0; j < nr; ++j) out[rows[j] + static_cast<std::size_t>(j) * m] = 1;
    lapack::getrs('N', m, nr, m_lu.data(), m, m_piv.data(), out, m);
  };
  const std::vector<double> l = open_pulling_points(D, m_rows, 3, y, column, tol_gap);
  lambda.assign(D.size(), Vec3{0, 0, 0});
  for (int a = 0; a < static_cast<int>(m_rows.size()); ++a)
    for (int k = 0; k < 3; ++k) lambda[m_rows[a]][k] = l[3 * a + k];
}

} // namespace hssbem::contact_detail
