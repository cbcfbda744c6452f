// The capacitance inverse of capacitance.hpp: rebuilt by LU, updated by Schur complements, in
// double or in single precision with refinement against the explicit C.
#include "hssbem/reference/capacitance.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

std::size_t sq(int n) { return static_cast<std::size_t>(n) * n; }

/// The inverse of the m×m matrix a (column-major, overwritten) into inv: LU, then getri (4/3 m³
/// flops after the LU, against 2 m³ for getrs on the identity; 3 015² in single precision:
/// 0.44 against 0.52 s on two cores).
template <class T>
void invert(int m, std::vector<T> &a, std::vector<T> &inv, const char *what)
{
  std::vector<int> piv(std::max(m, 1));
  if (m == 0) {
    inv.clear();
    return;
  }
  const int info = lapack::getrf(m, a.data(), m, piv.data());
  if (info != 0) throw std::runtime_error(std::string("capacitance matrix: ") + what + " is singular (LU pivot " + std::to_string(info) + " is zero)");
  if (lapack::getri(m, a.data(), m, piv.data()) != 0) throw std::runtime_error(std::string("capacitance matrix: ") + what + ": the inverse failed");
  inv = std::move(a);
}

/// Zero row and column `slot` of the ld-leading matrix M over its first k slots.
template <class T>
void clear_slot(std::vector<T> &M, int ld, int k, int slot)
{
  std::fill_n(&M[static_cast<std::size_t>(slot) * ld], k, T(0));
  for (int q = 0; q < k; ++q) M[slot + static_cast<std::size_t>(q) * ld] = T(0);
}

/// Removes the slots R from the inverse of C (k slots in use, leading dimension ld): with P the
/// other slots, the inverse of C(P, P) is C⁻¹(P, P) − C⁻¹(P, R) C⁻¹(R, R)⁻¹ C⁻¹(R, P). Written
/// over all k slots, the same rank-|R| update also takes rows and columns R to zero, which is
/// then made exact.
template <class T>
void drop_slots(std::vector<T> &inv, int ld, int k, const std::vector<int> &R)
{
  const int m = static_cast<int>(R.size());
  auto at = [&](int i, int j) -> T & { return inv[i + static_cast<std::size_t>(j) * ld]; };
  std::vector<T> B(static_cast<std::size_t>(k) * m), S(sq(m)), Z(static_cast<std::size_t>(m) * k);
  for (int q = 0; q < m; ++q) std::copy_n(&at(0, R[q]), k, &B[static_cast<std::size_t>(q) * k]);
#pragma omp parallel for schedule(static) if (k > 512)
  for (int q = 0; q < k; ++q)
    for (int p = 0; p < m; ++p) Z[p + static_cast<std::size_t>(q) * m] = at(R[p], q);
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < m; ++p) S[p + static_cast<std::size_t>(q) * m] = at(R[p], R[q]);
  std::vector<int> piv(m);
  if (lapack::getrf(m, S.data(), m, piv.data()) != 0) throw std::runtime_error("capacitance matrix: the block of the dropped indices is singular");
  lapack::getrs('N', m, k, S.data(), m, piv.data(), Z.data(), m);
  gemm_over_threads<T>('N', 'N', k, k, m, T(-1), B.data(), k, Z.data(), m, T(1), inv.data(), ld);
  for (int r : R) clear_slot(inv, ld, k, r);
}

/// Puts new indices into the empty slots A of the inverse of C (k slots in use, leading
/// dimension ld; rows and columns A of the inverse are zero). With B = C(:, A), D = C(A, :),
/// E = C(A, A), X = C⁻¹B, Y = D C⁻¹ and S = E − D X, the new inverse is C⁻¹ + X S⁻¹ Y on the old
/// slots, −X S⁻¹ in columns A, −S⁻¹ Y in rows A and S⁻¹ in (A, A). Rows A of X and columns A of
/// Y are zero (so are the rows and columns A of C⁻¹), so every product runs over all k slots.
template <class T>
void add_slots(std::vector<T> &inv, int ld, int k, const std::vector<int> &A, const std::vector<T> &B, const std::vector<T> &D, std::vector<T> S)
{
  const int m = static_cast<int>(A.size());
  auto at = [&](int i, int j) -> T & { return inv[i + static_cast<std::size_t>(j) * ld]; };
  std::vector<T> X(static_cast<std::size_t>(k) * m), Y(static_cast<std::size_t>(m) * k);
  gemm_over_threads<T>('N', 'N', k, m, k, T(1), inv.data(), ld, B.data(), k, T(0), X.data(), k);
  gemm_over_threads<T>('N', 'N', m, k, k, T(1), D.data(), m, inv.data(), ld, T(0), Y.data(), m);
  lapack::gemm('N', 'N', m, m, k, T(-1), D.data(), m, X.data(), k, T(1), S.data(), m);
  std::vector<T> Sinv;
  invert(m, S, Sinv, "the Schur complement of the added indices");
  std::vector<T> Z(static_cast<std::size_t>(m) * k), XS(static_cast<std::size_t>(k) * m); // S⁻¹ Y, X S⁻¹
  gemm_over_threads<T>('N', 'N', m, k, m, T(1), Sinv.data(), m, Y.data(), m, T(0), Z.data(), m);
  lapack::gemm('N', 'N', k, m, m, T(-1), X.data(), k, Sinv.data(), m, T(0), XS.data(), k);
  gemm_over_threads<T>('N', 'N', k, k, m, T(1), X.data(), k, Z.data(), m, T(1), inv.data(), ld); // C⁻¹ + X S⁻¹ Y
  for (int q = 0; q < m; ++q) std::copy_n(&XS[static_cast<std::size_t>(q) * k], k, &at(0, A[q]));
#pragma omp parallel for schedule(static) if (k > 512)
  for (int q = 0; q < k; ++q)
    for (int p = 0; p < m; ++p) at(A[p], q) = -Z[p + static_cast<std::size_t>(q) * m];
  for (int q = 0; q < m; ++q)
    for (int p = 0; p < m; ++p) at(A[p], A[q]) = Sinv[p + static_cast<std::size_t>(q) * m];
}

/// The rows `rows` and columns `cols` of the ld-leading column-major double matrix M as T.
template <class T>
std::vector<T> gather(const std::vector<double> &M, int ld, const std::vector<int> &rows, const std::vector<int> &cols)
{
  const std::size_t nr = rows.size();
  std::vector<T> out(nr * cols.size());
  for (std::size_t q = 0; q < cols.size(); ++q)
    for (std::size_t p = 0; p < nr; ++p) out[p + q * nr] = static_cast<T>(M[rows[p] + static_cast<std::size_t>(cols[q]) * ld]);
  return out;
}

/// The first k×k of an old_ld-leading array in a new_ld × new_ld array of zeros (slots `keep`
/// in that order, or all k when keep is empty).
template <class T>
void relayout(std::vector<T> &M, int old_ld, int new_ld, int k, const std::vector<int> &keep = {})
{
  if (M.empty()) return;
  const int kk = keep.empty() ? k : static_cast<int>(keep.size());
  std::vector<T> out(sq(new_ld), T(0));
#pragma omp parallel for schedule(static) if (kk > 512)
  for (int q = 0; q < kk; ++q) {
    const std::size_t col = static_cast<std::size_t>(keep.empty() ? q : keep[q]) * old_ld;
    for (int p = 0; p < kk; ++p) out[p + static_cast<std::size_t>(q) * new_ld] = M[(keep.empty() ? p : keep[p]) + col];
  }
  M = std::move(out);
}

} // namespace

void StoredColumns::block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, std::size_t ld) const
{
  const int nr = static_cast<int>(rows.size()), nc = static_cast<int>(cols.size());
#pragma omp parallel for schedule(static) if (static_cast<double>(nr) * nc > 262144)
  for (int q = 0; q < nc; ++q) {
    const double *w = m_W + static_cast<std::size_t>(m_column ? (*m_column)[cols[q]] : cols[q]) * m_n;
    for (int p = 0; p < nr; ++p) out[p + q * ld] = w[rows[p]];
  }
}

CapacitanceInverse::CapacitanceInverse(const double *W, int n, int single_from)
    : CapacitanceInverse(std::make_shared<StoredColumns>(W, n), n, single_from)
{
}

CapacitanceInverse::CapacitanceInverse(std::shared_ptr<const MatrixEntries> entries, int n, int single_from)
    : m_W(std::move(entries)), m_n(n), m_single_from(single_from), m_slot_of(n, -1), m_pos(n, -1)
{
}

double CapacitanceInverse::update_flops(double k, double r, double a)
{
  const double kept = std::max(0.0, k - r);
  return 2 * k * k * r + 2 * r * r * r / 3 + 6 * kept * kept * a + 4 * kept * a * a + 8.0 / 3.0 * a * a * a;
}

void CapacitanceInverse::rebuild(const std::vector<int> &J, bool force_double)
{
  const int k = static_cast<int>(J.size());
  std::vector<int> slot_of(m_n, -1);
  for (int p = 0; p < k; ++p) {
    if (J[p] < 0 || J[p] >= m_n || slot_of[J[p]] >= 0) throw std::invalid_argument("CapacitanceInverse::rebuild: index out of range or repeated");
    slot_of[J[p]] = p;
  }
  m_slot_of = std::move(slot_of);
  m_slot_index = J;
  m_empty.clear();
  m_k = k;
  m_ld = k + std::max(32, k / 16); // room for a contact that grows a little
  m_C.assign(sq(m_ld), 0.0);
  m_W->block(J, J, m_C.data(), m_ld);
  m_single = !force_double && k >= m_single_from;
  refresh_view();
  // The inverse of the compact W(J, J), then spread to the leading dimension m_ld.
  if (m_single) {
    std::vector<float> a = gather<float>(m_C, m_ld, slots_upto(k), slots_upto(k));
    invert(k, a, m_invf, "W(J, J)");
    relayout(m_invf, k, m_ld, k);
    std::vector<double>().swap(m_inv);
  } else {
    std::vector<double> a = gather<double>(m_C, m_ld, slots_upto(k), slots_upto(k));
    invert(k, a, m_inv, "W(J, J)");
    relayout(m_inv, k, m_ld, k);
    std::vector<float>().swap(m_invf);
  }
}

void CapacitanceInverse::update(const std::vector<int> &drop, const std::vector<int> &add)
{
  if (!drop.empty()) drop_indices(drop);
  if (!add.empty()) add_indices(add);
  if (static_cast<int>(m_empty.size()) * 8 > m_k) squeeze();
  refresh_view();
}

void CapacitanceInverse::drop_indices(const std::vector<int> &drop)
{
  std::vector<int> R;
  for (int j : drop) {
    if (j < 0 || j >= m_n || m_slot_of[j] < 0 || std::find(R.begin(), R.end(), m_slot_of[j]) != R.end())
      throw std::invalid_argument("CapacitanceInverse::update: dropped index not in the set");
    R.push_back(m_slot_of[j]);
  }
  if (m_single) drop_slots(m_invf, m_ld, m_k, R);
  else drop_slots(m_inv, m_ld, m_k, R);
  for (int r : R) {
    clear_slot(m_C, m_ld, m_k, r);
    m_slot_of[m_slot_index[r]] = -1;
    m_slot_index[r] = -1;
    m_empty.push_back(r);
  }
}

void CapacitanceInverse::add_indices(const std::vector<int> &add)
{
  const int m = static_cast<int>(add.size());
  std::vector<char> seen(m_n, 0);
  for (int j : add) {
    if (j < 0 || j >= m_n || m_slot_of[j] >= 0 || seen[j]) throw std::invalid_argument("CapacitanceInverse::update: added index out of range or already in the set");
    seen[j] = 1;
  }
  // Slots: the empty ones first (highest first, so a later squeeze moves less), then new ones.
  std::sort(m_empty.begin(), m_empty.end());
  const int reuse = std::min<int>(m, static_cast<int>(m_empty.size()));
  std::vector<int> A(m_empty.end() - reuse, m_empty.end());
  const int fresh = m - reuse;
  if (m_k + fresh > m_ld) reserve(m_k + fresh);
  for (int q = 0; q < fresh; ++q) A.push_back(m_k + q);
  const int k = m_k + fresh;
  // C's new rows and columns (the empty slots among them stay zero).
  std::vector<int> idx(k, -1);
  for (int p = 0; p < m_k; ++p) idx[p] = m_slot_index[p];
  for (int q = 0; q < m; ++q) idx[A[q]] = add[q];
  fill_new_entries(idx, A, add);
  const std::vector<int> all = slots_upto(k);
  try {
    if (m_single) add_slots(m_invf, m_ld, k, A, gather<float>(m_C, m_ld, all, A), gather<float>(m_C, m_ld, A, all), gather<float>(m_C, m_ld, A, A));
    else add_slots(m_inv, m_ld, k, A, gather<double>(m_C, m_ld, all, A), gather<double>(m_C, m_ld, A, all), gather<double>(m_C, m_ld, A, A));
  } catch (...) { // the caller rebuilds; leave C as it was
    for (int a : A) clear_slot(m_C, m_ld, k, a);
    throw;
  }
  m_empty.resize(m_empty.size() - static_cast<std::size_t>(reuse));
  m_k = k;
  m_slot_index.resize(k, -1);
  for (int q = 0; q < m; ++q) {
    m_slot_index[A[q]] = add[q];
    m_slot_of[add[q]] = A[q];
  }
}

void CapacitanceInverse::fill_new_entries(const std::vector<int> &idx, const std::vector<int> &A, const std::vector<int> &add)
{
  std::vector<int> used, used_index; // the slots holding an index (old and new), and their indices
  for (std::size_t p = 0; p < idx.size(); ++p)
    if (idx[p] >= 0) used.push_back(static_cast<int>(p)), used_index.push_back(idx[p]);
  const std::size_t nu = used.size(), m = add.size();
  std::vector<double> cols(nu * m), rows(m * nu);
  m_W->block(used_index, add, cols.data(), nu);
  m_W->block(add, used_index, rows.data(), m);
  for (int a : A) clear_slot(m_C, m_ld, static_cast<int>(idx.size()), a);
  for (std::size_t q = 0; q < m; ++q)
    for (std::size_t p = 0; p < nu; ++p) c(used[p], A[q]) = cols[p + q * nu];
  for (std::size_t q = 0; q < nu; ++q)
    for (std::size_t p = 0; p < m; ++p) c(A[p], used[q]) = rows[p + q * m];
}

std::vector<int> CapacitanceInverse::slots_upto(int k)
{
  std::vector<int> s(k);
  std::iota(s.begin(), s.end(), 0);
  return s;
}

void CapacitanceInverse::reserve(int slots)
{
  const int ld = std::max(slots, m_ld + m_ld / 4 + 32);
  relayout(m_C, m_ld, ld, m_k);
  relayout(m_inv, m_ld, ld, m_k);
  relayout(m_invf, m_ld, ld, m_k);
  m_ld = ld;
}

void CapacitanceInverse::squeeze()
{
  std::vector<int> keep;
  for (int p = 0; p < m_k; ++p)
    if (m_slot_index[p] >= 0) keep.push_back(p);
  relayout(m_C, m_ld, m_ld, m_k, keep);
  relayout(m_inv, m_ld, m_ld, m_k, keep);
  relayout(m_invf, m_ld, m_ld, m_k, keep);
  std::vector<int> index(keep.size());
  for (std::size_t p = 0; p < keep.size(); ++p) {
    index[p] = m_slot_index[keep[p]];
    m_slot_of[index[p]] = static_cast<int>(p);
  }
  m_slot_index = std::move(index);
  m_k = static_cast<int>(keep.size());
  m_empty.clear();
}

void CapacitanceInverse::refresh_view()
{
  for (int j : m_J) m_pos[j] = -1;
  m_J.clear();
  m_pos_slot.clear();
  for (int p = 0; p < m_k; ++p)
    if (m_slot_index[p] >= 0) {
      m_pos[m_slot_index[p]] = static_cast<int>(m_J.size());
      m_J.push_back(m_slot_index[p]);
      m_pos_slot.push_back(p);
    }
}

bool CapacitanceInverse::solve(const double *r_in, double *s_out) const
{
  const int n = size(), k = m_k;
  m_last_iterations = 0;
  if (n == 0) return true;
  // By slots: r is zero on the empty ones, whose rows and columns are zero in C and C⁻¹.
  std::vector<double> r(k, 0.0), s(k, 0.0);
  for (int p = 0; p < n; ++p) r[m_pos_slot[p]] = r_in[p];
  const auto out = [&] {
    for (int p = 0; p < n; ++p) s_out[p] = s[m_pos_slot[p]];
  };
  if (!m_single) {
    gemv_over_threads(k, k, m_inv.data(), m_ld, r.data(), s.data());
    out();
    m_last_iterations = 1;
    return true;
  }
  const bool converged = refine(r, s);
  out();
  return converged;
}

/// s ← s + C⁻¹ (r − C s) with the single-precision inverse, the residual in double against C:
/// each step costs a pass over C⁻¹ (float) and one over C (double), until ‖r − C s‖ ≤ 1e-10 ‖r‖
/// (k_refine_tol, capacitance.hpp). The last pass over C is skipped when the contraction
/// measured so far puts the next residual 10x below the tolerance: on the 4k and 10k organs
/// with 20 % switched the first step leaves ~1e-6 and the second ~1e-12, so a solve is two
/// passes over C⁻¹ and one over C (benchmarks/results/2026-11-27-scenes.md).
bool CapacitanceInverse::refine(const std::vector<double> &r, std::vector<double> &s) const
{
  constexpr double tol = k_refine_tol;
  const int k = m_k;
  const auto norm = [k](const std::vector<double> &v) {
    double n = 0;
    for (int i = 0; i < k; ++i) n += v[i] * v[i];
    return std::sqrt(n);
  };
  const double nr = norm(r);
  std::vector<float> rf(k), sf(k);
  std::vector<double> res = r;
  double previous = nr;
  bool predicted = false;
  for (int it = 0; it < 12; ++it) {
    m_last_iterations = it + 1;
    for (int i = 0; i < k; ++i) rf[i] = static_cast<float>(res[i]);
    gemv_over_threads(k, k, m_invf.data(), m_ld, rf.data(), sf.data());
    for (int i = 0; i < k; ++i) s[i] += sf[i];
    if (predicted) return true;
    gemv_over_threads(k, k, m_C.data(), m_ld, s.data(), res.data());
    for (int i = 0; i < k; ++i) res[i] = r[i] - res[i];
    const double nres = norm(res);
    if (nres <= tol * nr || nres == 0) return true;
    if (nres > 0.5 * previous) return false; // no longer contracting
    predicted = nres * (nres / previous) <= 0.1 * tol * nr;
    previous = nres;
  }
  return false;
}

double CapacitanceInverse::inverse_entry(int p, int q) const
{
  const std::size_t i = m_pos_slot[p] + static_cast<std::size_t>(m_pos_slot[q]) * m_ld;
  return m_single ? m_invf[i] : m_inv[i];
}

} // namespace hssbem
