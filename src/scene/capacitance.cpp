// The capacitance inverse of capacitance.hpp: rebuilt by LU, updated by Schur complements.
#include "hssbem/scene/capacitance.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

/// The inverse of the m×m matrix a (column-major, overwritten by its LU factors) into inv.
void invert(int m, std::vector<double> &a, std::vector<double> &inv, const char *what)
{
  std::vector<int> piv(std::max(m, 1));
  inv.assign(static_cast<std::size_t>(m) * m, 0.0);
  if (m == 0) return;
  for (int i = 0; i < m; ++i) inv[i + static_cast<std::size_t>(i) * m] = 1.0;
  const int info = lapack::getrf(m, a.data(), m, piv.data());
  if (info != 0) throw std::runtime_error(std::string("capacitance matrix: ") + what + " is singular (LU pivot " + std::to_string(info) + " is zero)");
  lapack::getrs('N', m, m, a.data(), m, piv.data(), inv.data(), m);
}

} // namespace

CapacitanceInverse::CapacitanceInverse(const double *W, int n) : m_W(W), m_n(n), m_pos(n, -1) {}

double CapacitanceInverse::update_flops(double k, double r, double a)
{
  const double kept = std::max(0.0, k - r);
  return 2 * k * k * r + 2 * r * r * r / 3 + 6 * kept * kept * a + 4 * kept * a * a + 8.0 / 3.0 * a * a * a;
}

void CapacitanceInverse::rebuild(const std::vector<int> &J)
{
  for (int j : m_J) m_pos[j] = -1;
  m_J = J;
  const int k = size();
  for (int p = 0; p < k; ++p) {
    if (m_J[p] < 0 || m_J[p] >= m_n || m_pos[m_J[p]] >= 0) throw std::invalid_argument("CapacitanceInverse::rebuild: index out of range or repeated");
    m_pos[m_J[p]] = p;
  }
  std::vector<double> C(static_cast<std::size_t>(k) * k);
  for (int q = 0; q < k; ++q)
    for (int p = 0; p < k; ++p) C[p + static_cast<std::size_t>(q) * k] = w(m_J[p], m_J[q]);
  invert(k, C, m_inv, "W(J, J)");
}

void CapacitanceInverse::update(const std::vector<int> &drop, const std::vector<int> &add)
{
  if (!drop.empty()) drop_indices(drop);
  if (!add.empty()) add_indices(add);
}

void CapacitanceInverse::apply(const double *r, double *s) const
{
  const int k = size();
  if (k == 0) return;
  gemv_over_threads(k, k, m_inv.data(), k, r, s);
}

/// With P the kept positions and R the dropped ones, the inverse of C(P, P) is
/// C⁻¹(P, P) − C⁻¹(P, R) C⁻¹(R, R)⁻¹ C⁻¹(R, P).
void CapacitanceInverse::drop_indices(const std::vector<int> &drop)
{
  const int k = size(), m = static_cast<int>(drop.size()), kp = k - m;
  std::vector<char> dropped(k, 0);
  for (int j : drop) {
    if (j < 0 || j >= m_n || m_pos[j] < 0 || dropped[m_pos[j]]) throw std::invalid_argument("CapacitanceInverse::update: dropped index not in the set");
    dropped[m_pos[j]] = 1;
  }
  std::vector<int> P, R;
  for (int p = 0; p < k; ++p) (dropped[p] ? R : P).push_back(p);
  auto inv = [&](int i, int j) { return m_inv[i + static_cast<std::size_t>(j) * k]; };
  std::vector<double> A(static_cast<std::size_t>(kp) * kp), B(static_cast<std::size_t>(kp) * m), S(static_cast<std::size_t>(m) * m),
      T(static_cast<std::size_t>(m) * kp);
#pragma omp parallel for schedule(static) if (kp > 512)
  for (int q = 0; q < kp; ++q)
    for (int p = 0; p < kp; ++p) A[p + static_cast<std::size_t>(q) * kp] = inv(P[p], P[q]);
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < kp; ++p) B[p + static_cast<std::size_t>(q) * kp] = inv(P[p], R[q]);
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < m; ++p) S[p + static_cast<std::size_t>(q) * m] = inv(R[p], R[q]);
  for (int q = 0; q < kp; ++q)
    for (int p = 0; p < m; ++p) T[p + static_cast<std::size_t>(q) * m] = inv(R[p], P[q]);
  if (kp > 0) {
    std::vector<int> piv(m);
    const int info = lapack::getrf(m, S.data(), m, piv.data());
    if (info != 0) throw std::runtime_error("capacitance matrix: the block of the dropped indices is singular");
    lapack::getrs('N', m, kp, S.data(), m, piv.data(), T.data(), m);
    gemm_over_threads('N', 'N', kp, kp, m, -1.0, B.data(), kp, T.data(), m, 1.0, A.data(), kp);
  }
  std::vector<int> J(kp);
  for (int p = 0; p < kp; ++p) J[p] = m_J[P[p]];
  for (int j : m_J) m_pos[j] = -1;
  m_J = std::move(J);
  for (int p = 0; p < kp; ++p) m_pos[m_J[p]] = p;
  m_inv = std::move(A);
}

/// C' = [C B; D E] with B = W(J, a), D = W(a, J), E = W(a, a); with X = C⁻¹B, Y = D C⁻¹ and
/// S = E − D X: C'⁻¹ = [C⁻¹ + X S⁻¹ Y, −X S⁻¹; −S⁻¹ Y, S⁻¹].
void CapacitanceInverse::add_indices(const std::vector<int> &add)
{
  const int k = size(), m = static_cast<int>(add.size()), kn = k + m;
  for (std::size_t p = 0; p < add.size(); ++p) {
    const int j = add[p];
    if (j < 0 || j >= m_n || m_pos[j] >= 0) throw std::invalid_argument("CapacitanceInverse::update: added index out of range or already in the set");
    m_pos[j] = k + static_cast<int>(p); // also catches a repeat within `add`
  }
  std::vector<double> B(static_cast<std::size_t>(k) * m), D(static_cast<std::size_t>(m) * k), S(static_cast<std::size_t>(m) * m);
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < k; ++p) B[p + static_cast<std::size_t>(q) * k] = w(m_J[p], add[q]);
  for (int q = 0; q < k; ++q)
    for (int p = 0; p < m; ++p) D[p + static_cast<std::size_t>(q) * m] = w(add[p], m_J[q]);
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < m; ++p) S[p + static_cast<std::size_t>(q) * m] = w(add[p], add[q]);
  std::vector<double> X(static_cast<std::size_t>(k) * m), Y(static_cast<std::size_t>(m) * k);
  gemm_over_threads('N', 'N', k, m, k, 1.0, m_inv.data(), std::max(k, 1), B.data(), std::max(k, 1), 0.0, X.data(), std::max(k, 1));
  gemm_over_threads('N', 'N', m, k, k, 1.0, D.data(), m, m_inv.data(), std::max(k, 1), 0.0, Y.data(), m);
  lapack::gemm('N', 'N', m, m, k, -1.0, D.data(), m, X.data(), std::max(k, 1), 1.0, S.data(), m);
  std::vector<double> Sinv;
  try {
    invert(m, S, Sinv, "the Schur complement of the added indices");
  } catch (...) {
    for (int j : add) m_pos[j] = -1;
    throw;
  }
  std::vector<double> Z(static_cast<std::size_t>(m) * k); // S⁻¹ Y
  lapack::gemm('N', 'N', m, k, m, 1.0, Sinv.data(), m, Y.data(), m, 0.0, Z.data(), m);
  std::vector<double> inv(static_cast<std::size_t>(kn) * kn);
#pragma omp parallel for schedule(static) if (k > 512)
  for (int q = 0; q < k; ++q)
    std::copy_n(&m_inv[static_cast<std::size_t>(q) * k], k, &inv[static_cast<std::size_t>(q) * kn]);
  gemm_over_threads('N', 'N', k, k, m, 1.0, X.data(), std::max(k, 1), Z.data(), m, 1.0, inv.data(), kn); // C⁻¹ + X S⁻¹ Y
  lapack::gemm('N', 'N', k, m, m, -1.0, X.data(), std::max(k, 1), Sinv.data(), m, 0.0, &inv[static_cast<std::size_t>(k) * kn], kn);
  for (int q = 0; q < k; ++q)
    for (int p = 0; p < m; ++p) inv[k + p + static_cast<std::size_t>(q) * kn] = -Z[p + static_cast<std::size_t>(q) * m];
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < m; ++p) inv[k + p + static_cast<std::size_t>(k + q) * kn] = Sinv[p + static_cast<std::size_t>(q) * m];
  m_J.insert(m_J.end(), add.begin(), add.end());
  m_inv = std::move(inv);
}

} // namespace hssbem
