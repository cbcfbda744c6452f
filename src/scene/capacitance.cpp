// The capacitance inverse of capacitance.hpp: rebuilt by LU, updated by Schur complements, in
// double or in single precision with refinement against the explicit C.
#include "hssbem/scene/capacitance.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

std::size_t sq(int n) { return static_cast<std::size_t>(n) * n; }

/// The inverse of the m×m matrix a (column-major, overwritten by its LU factors) into inv.
template <class T>
void invert(int m, std::vector<T> &a, std::vector<T> &inv, const char *what)
{
  std::vector<int> piv(std::max(m, 1));
  inv.assign(sq(m), T(0));
  if (m == 0) return;
  for (int i = 0; i < m; ++i) inv[i + static_cast<std::size_t>(i) * m] = T(1);
  const int info = lapack::getrf(m, a.data(), m, piv.data());
  if (info != 0) throw std::runtime_error(std::string("capacitance matrix: ") + what + " is singular (LU pivot " + std::to_string(info) + " is zero)");
  lapack::getrs('N', m, m, a.data(), m, piv.data(), inv.data(), m);
}

/// The k×k matrix M restricted to the positions `keep` (in that order).
template <class T>
std::vector<T> restrict_to(const std::vector<T> &M, int k, const std::vector<int> &keep)
{
  const int kp = static_cast<int>(keep.size());
  std::vector<T> out(sq(kp));
#pragma omp parallel for schedule(static) if (kp > 512)
  for (int q = 0; q < kp; ++q)
    for (int p = 0; p < kp; ++p) out[p + static_cast<std::size_t>(q) * kp] = M[keep[p] + static_cast<std::size_t>(keep[q]) * k];
  return out;
}

/// With P the kept positions and R the dropped ones, the inverse of C(P, P) is
/// C⁻¹(P, P) − C⁻¹(P, R) C⁻¹(R, R)⁻¹ C⁻¹(R, P).
template <class T>
void drop_from_inverse(std::vector<T> &inv, int k, const std::vector<int> &P, const std::vector<int> &R)
{
  const int kp = static_cast<int>(P.size()), m = static_cast<int>(R.size());
  auto at = [&](int i, int j) { return inv[i + static_cast<std::size_t>(j) * k]; };
  std::vector<T> A = restrict_to(inv, k, P), B(static_cast<std::size_t>(kp) * m), S(sq(m)), Tm(static_cast<std::size_t>(m) * kp);
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < kp; ++p) B[p + static_cast<std::size_t>(q) * kp] = at(P[p], R[q]);
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < m; ++p) S[p + static_cast<std::size_t>(q) * m] = at(R[p], R[q]);
  for (int q = 0; q < kp; ++q)
    for (int p = 0; p < m; ++p) Tm[p + static_cast<std::size_t>(q) * m] = at(R[p], P[q]);
  if (kp > 0) {
    std::vector<int> piv(m);
    if (lapack::getrf(m, S.data(), m, piv.data()) != 0) throw std::runtime_error("capacitance matrix: the block of the dropped indices is singular");
    lapack::getrs('N', m, kp, S.data(), m, piv.data(), Tm.data(), m);
    gemm_over_threads<T>('N', 'N', kp, kp, m, T(-1), B.data(), kp, Tm.data(), m, T(1), A.data(), kp);
  }
  inv = std::move(A);
}

/// C' = [C B; D E]: with X = C⁻¹B, Y = D C⁻¹ and S = E − D X,
/// C'⁻¹ = [C⁻¹ + X S⁻¹ Y, −X S⁻¹; −S⁻¹ Y, S⁻¹].
template <class T>
void add_to_inverse(std::vector<T> &inv, int k, int m, const std::vector<T> &B, const std::vector<T> &D, std::vector<T> S)
{
  const int kn = k + m, lk = std::max(k, 1);
  std::vector<T> X(static_cast<std::size_t>(k) * m), Y(static_cast<std::size_t>(m) * k);
  gemm_over_threads<T>('N', 'N', k, m, k, T(1), inv.data(), lk, B.data(), lk, T(0), X.data(), lk);
  gemm_over_threads<T>('N', 'N', m, k, k, T(1), D.data(), m, inv.data(), lk, T(0), Y.data(), m);
  lapack::gemm('N', 'N', m, m, k, T(-1), D.data(), m, X.data(), lk, T(1), S.data(), m);
  std::vector<T> Sinv;
  invert(m, S, Sinv, "the Schur complement of the added indices");
  std::vector<T> Z(static_cast<std::size_t>(m) * k); // S⁻¹ Y
  lapack::gemm('N', 'N', m, k, m, T(1), Sinv.data(), m, Y.data(), m, T(0), Z.data(), m);
  std::vector<T> out(sq(kn));
#pragma omp parallel for schedule(static) if (k > 512)
  for (int q = 0; q < k; ++q)
    std::copy_n(&inv[static_cast<std::size_t>(q) * k], k, &out[static_cast<std::size_t>(q) * kn]);
  gemm_over_threads<T>('N', 'N', k, k, m, T(1), X.data(), lk, Z.data(), m, T(1), out.data(), kn); // C⁻¹ + X S⁻¹ Y
  lapack::gemm('N', 'N', k, m, m, T(-1), X.data(), lk, Sinv.data(), m, T(0), &out[static_cast<std::size_t>(k) * kn], kn);
  for (int q = 0; q < k; ++q)
    for (int p = 0; p < m; ++p) out[k + p + static_cast<std::size_t>(q) * kn] = -Z[p + static_cast<std::size_t>(q) * m];
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < m; ++p) out[k + p + static_cast<std::size_t>(k + q) * kn] = Sinv[p + static_cast<std::size_t>(q) * m];
  inv = std::move(out);
}

/// The block (rows r0.., cols c0..) of the ld-leading column-major double matrix M as T.
template <class T>
std::vector<T> block_of(const std::vector<double> &M, int ld, int r0, int nr, int c0, int nc)
{
  std::vector<T> out(static_cast<std::size_t>(nr) * nc);
  for (int q = 0; q < nc; ++q)
    for (int p = 0; p < nr; ++p) out[p + static_cast<std::size_t>(q) * nr] = static_cast<T>(M[r0 + p + static_cast<std::size_t>(c0 + q) * ld]);
  return out;
}

} // namespace

CapacitanceInverse::CapacitanceInverse(const double *W, int n, int single_from) : m_W(W), m_n(n), m_single_from(single_from), m_pos(n, -1) {}

double CapacitanceInverse::update_flops(double k, double r, double a)
{
  const double kept = std::max(0.0, k - r);
  return 2 * k * k * r + 2 * r * r * r / 3 + 6 * kept * kept * a + 4 * kept * a * a + 8.0 / 3.0 * a * a * a;
}

void CapacitanceInverse::rebuild(const std::vector<int> &J, bool force_double)
{
  for (int j : m_J) m_pos[j] = -1;
  m_J.clear();
  const int k = static_cast<int>(J.size());
  for (int p = 0; p < k; ++p) {
    if (J[p] < 0 || J[p] >= m_n || m_pos[J[p]] >= 0) {
      for (int q = 0; q < p; ++q) m_pos[J[q]] = -1;
      throw std::invalid_argument("CapacitanceInverse::rebuild: index out of range or repeated");
    }
    m_pos[J[p]] = p;
  }
  m_J = J;
  m_C.resize(sq(k));
#pragma omp parallel for schedule(static) if (k > 512)
  for (int q = 0; q < k; ++q)
    for (int p = 0; p < k; ++p) m_C[p + static_cast<std::size_t>(q) * k] = w(m_J[p], m_J[q]);
  m_single = !force_double && k >= m_single_from;
  if (m_single) {
    std::vector<float> a = block_of<float>(m_C, k, 0, k, 0, k);
    invert(k, a, m_invf, "W(J, J)");
    std::vector<double>().swap(m_inv);
  } else {
    std::vector<double> a = m_C;
    invert(k, a, m_inv, "W(J, J)");
    std::vector<float>().swap(m_invf);
  }
}

void CapacitanceInverse::update(const std::vector<int> &drop, const std::vector<int> &add)
{
  if (!drop.empty()) drop_indices(drop);
  if (!add.empty()) add_indices(add);
}

void CapacitanceInverse::drop_indices(const std::vector<int> &drop)
{
  const int k = size();
  std::vector<char> dropped(k, 0);
  for (int j : drop) {
    if (j < 0 || j >= m_n || m_pos[j] < 0 || dropped[m_pos[j]]) throw std::invalid_argument("CapacitanceInverse::update: dropped index not in the set");
    dropped[m_pos[j]] = 1;
  }
  std::vector<int> P, R;
  for (int p = 0; p < k; ++p) (dropped[p] ? R : P).push_back(p);
  if (m_single) drop_from_inverse(m_invf, k, P, R);
  else drop_from_inverse(m_inv, k, P, R);
  m_C = restrict_to(m_C, k, P);
  std::vector<int> J(P.size());
  for (std::size_t p = 0; p < P.size(); ++p) J[p] = m_J[P[p]];
  for (int j : m_J) m_pos[j] = -1;
  m_J = std::move(J);
  for (int p = 0; p < size(); ++p) m_pos[m_J[p]] = p;
}

void CapacitanceInverse::add_indices(const std::vector<int> &add)
{
  const int k = size(), m = static_cast<int>(add.size()), kn = k + m;
  for (std::size_t p = 0; p < add.size(); ++p) {
    const int j = add[p];
    if (j < 0 || j >= m_n || m_pos[j] >= 0) {
      for (std::size_t q = 0; q < p; ++q) m_pos[add[q]] = -1;
      throw std::invalid_argument("CapacitanceInverse::update: added index out of range or already in the set");
    }
    m_pos[j] = k + static_cast<int>(p); // also catches a repeat within `add`
  }
  // C' = [C, W(J, a); W(a, J), W(a, a)]
  std::vector<double> C(sq(kn));
#pragma omp parallel for schedule(static) if (k > 512)
  for (int q = 0; q < kn; ++q) {
    double *c = &C[static_cast<std::size_t>(q) * kn];
    if (q < k) std::copy_n(&m_C[static_cast<std::size_t>(q) * k], k, c);
    else
      for (int p = 0; p < k; ++p) c[p] = w(m_J[p], add[q - k]);
    const int jq = q < k ? m_J[q] : add[q - k];
    for (int p = 0; p < m; ++p) c[k + p] = w(add[p], jq);
  }
  try {
    if (m_single) add_to_inverse(m_invf, k, m, block_of<float>(C, kn, 0, k, k, m), block_of<float>(C, kn, k, m, 0, k), block_of<float>(C, kn, k, m, k, m));
    else add_to_inverse(m_inv, k, m, block_of<double>(C, kn, 0, k, k, m), block_of<double>(C, kn, k, m, 0, k), block_of<double>(C, kn, k, m, k, m));
  } catch (...) {
    for (int j : add) m_pos[j] = -1;
    throw;
  }
  m_C = std::move(C);
  m_J.insert(m_J.end(), add.begin(), add.end());
}

bool CapacitanceInverse::solve(const double *r, double *s) const
{
  const int k = size();
  if (k == 0) return true;
  if (!m_single) {
    gemv_over_threads(k, k, m_inv.data(), k, r, s);
    return true;
  }
  double nr = 0;
  for (int i = 0; i < k; ++i) nr += r[i] * r[i];
  nr = std::sqrt(nr);
  std::vector<float> rf(k), sf(k);
  std::vector<double> res(r, r + k);
  std::fill(s, s + k, 0.0);
  double previous = nr;
  for (int it = 0; it < 12; ++it) { // s ← s + C⁻¹ (r − C s), the correction in single precision
    for (int i = 0; i < k; ++i) rf[i] = static_cast<float>(res[i]);
    gemv_over_threads(k, k, m_invf.data(), k, rf.data(), sf.data());
    for (int i = 0; i < k; ++i) s[i] += sf[i];
    gemv_over_threads(k, k, m_C.data(), k, s, res.data());
    for (int i = 0; i < k; ++i) res[i] = r[i] - res[i];
    double nres = 0;
    for (int i = 0; i < k; ++i) nres += res[i] * res[i];
    nres = std::sqrt(nres);
    if (nres <= 1e-13 * nr || nres == 0) return true;
    if (nres > 0.5 * previous) return false; // no longer contracting
    previous = nres;
  }
  return false;
}

double CapacitanceInverse::inverse_entry(int p, int q) const
{
  const std::size_t i = p + static_cast<std::size_t>(q) * size();
  return m_single ? m_invf[i] : m_inv[i];
}

} // namespace hssbem
