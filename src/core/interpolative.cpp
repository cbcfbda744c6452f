// Interpolative decompositions from column-pivoted QR (dgeqp3); see interpolative.hpp.
#include "hssbem/core/interpolative.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/sampled_qr.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

using Size = std::size_t;

void check_matrix(int m, int n, int lda, const char *what)
{
  if (m < 0 || n < 0) throw std::invalid_argument(std::string(what) + ": negative matrix size");
  if (lda < std::max(1, m)) throw std::invalid_argument(std::string(what) + ": leading dimension below max(1, m)");
}

void check_options(const IdOptions &options)
{
  if (!(options.rel_tol >= 0)) throw std::invalid_argument("interpolative decomposition: rel_tol must be >= 0");
}

/// k: leading diagonal entries of R (p of them, leading dimension ld) above rel_tol·|R_11|,
/// then the cap. Stopping at the first small entry (rather than counting all of them) keeps
/// the error bound of the header true even if rounding breaks the monotonicity of |R_ii|.
int numerical_rank(const double *r, Size ld, int p, const IdOptions &options)
{
  if (p == 0) return 0;
  const double threshold = options.rel_tol * std::abs(r[0]);
  int k = 0;
  while (k < p && std::abs(r[k * (ld + 1)]) > threshold) ++k;
  if (options.max_rank >= 0) k = std::min(k, options.max_rank);
  return k;
}

/// T = R11⁻¹ R12 (k × (n−k), leading dimension k) from the triangular factor in r.
std::vector<double> interpolation_matrix(const double *r, int ld, int k, int n)
{
  if (k == 0 || k == n) return {};
  std::vector<double> T(Size(k) * Size(n - k));
  for (int j = 0; j < n - k; ++j) {
    const double *col = r + Size(k + j) * Size(ld);
    std::copy(col, col + k, T.begin() + Size(j) * Size(k));
  }
  lapack::trsm('L', 'U', 'N', 'N', k, n - k, 1.0, r, ld, T.data(), k);
  return T;
}

/// From this size on (min(m, n)), the pivots come from the sampled blocked QR, which runs at
/// level-3 BLAS speed; below it, dgeqp3.
constexpr int kSampledMin = 128;

/// Column ID of the m×n matrix a (leading dimension ld) from the pivoted Cholesky factorization
/// of aᵀa (see IdOptions::gram).
ColumnId gram_id(const double *a, int m, int n, int ld, const IdOptions &options)
{
  std::vector<double> G(Size(n) * Size(n));
  lapack::syrk_t(n, m, 1.0, a, ld, 0.0, G.data(), n);
  return gram_column_id(G.data(), n, options);
}

/// Column ID of the m×n matrix in `work` (leading dimension ld), which is overwritten.
ColumnId id_in_place(double *work, int m, int n, int ld, const IdOptions &options)
{
  ColumnId id;
  if (m == 0 || n == 0) {
    id.redundant.resize(Size(n));
    std::iota(id.redundant.begin(), id.redundant.end(), 0);
    return id;
  }
  if (options.gram && options.rel_tol >= gram_min_tol) return gram_id(work, m, n, ld, options);
  if (std::min(m, n) >= kSampledMin) {
    const SampledQr qr = sampled_pivoted_qr(work, m, n, ld, options.rel_tol, options.max_rank);
    for (int j = 0; j < n; ++j) (j < qr.rank ? id.skeleton : id.redundant).push_back(qr.perm[Size(j)]);
    id.T = interpolation_matrix(work, ld, qr.rank, n);
    return id;
  }
  if (m > n) {
    // Tall: an unpivoted QR first (level-3 BLAS) leaves a square R with the same column
    // relations, and dgeqp3 (half level-2 BLAS) runs on that.
    std::vector<double> qr_tau(static_cast<Size>(n));
    if (lapack::geqrf(m, n, work, ld, qr_tau.data()) != 0) throw std::runtime_error("interpolative decomposition: dgeqrf failed");
    for (int j = 0; j < n; ++j) std::fill(work + Size(j) * Size(ld) + Size(j) + 1, work + Size(j) * Size(ld) + Size(m), 0.0);
    m = n;
  }
  std::vector<int> jpvt(static_cast<Size>(n));
  std::vector<double> tau(Size(std::min(m, n)));
  const int info = lapack::geqp3(m, n, work, ld, jpvt.data(), tau.data());
  if (info != 0) throw std::runtime_error("interpolative decomposition: dgeqp3 failed, info = " + std::to_string(info));
  const int k = numerical_rank(work, Size(ld), std::min(m, n), options);
  for (int j = 0; j < n; ++j) (j < k ? id.skeleton : id.redundant).push_back(jpvt[Size(j)] - 1);
  id.T = interpolation_matrix(work, ld, k, n);
  return id;
}

void check_id(const ColumnId &id, int n, const char *what)
{
  const Size k = id.skeleton.size(), r = id.redundant.size();
  const auto outside = [n](int i) { return i < 0 || i >= n; };
  const bool bad_index = std::any_of(id.skeleton.begin(), id.skeleton.end(), outside) ||
                         std::any_of(id.redundant.begin(), id.redundant.end(), outside);
  if (k + r != Size(n) || id.T.size() != k * r || bad_index)
    throw std::invalid_argument(std::string(what) + ": ID does not match the matrix");
}

} // namespace

ColumnId gram_column_id(double *G, int n, const IdOptions &options)
{
  double largest = 0;
  for (int j = 0; j < n; ++j) largest = std::max(largest, G[Size(j) * Size(n) + Size(j)]);
  std::vector<int> piv(static_cast<Size>(n));
  int k = largest > 0 ? lapack::pstrf_upper(n, G, n, piv.data(), options.rel_tol * options.rel_tol * largest) : 0;
  if (largest <= 0) std::iota(piv.begin(), piv.end(), 1);
  if (options.max_rank >= 0) k = std::min(k, options.max_rank);
  ColumnId id;
  for (int j = 0; j < n; ++j) (j < k ? id.skeleton : id.redundant).push_back(piv[Size(j)] - 1);
  id.T = interpolation_matrix(G, n, k, n);
  return id;
}

ColumnId column_id(const double *A, int m, int n, int lda, const IdOptions &options)
{
  check_matrix(m, n, lda, "column_id");
  check_options(options);
  if (m == 0 || n == 0) return id_in_place(nullptr, m, n, 1, options);
  if (options.gram && options.rel_tol >= gram_min_tol) return gram_id(A, m, n, lda, options); // reads A only
  std::vector<double> work(Size(m) * Size(n));
  for (int j = 0; j < n; ++j) std::copy(A + Size(j) * Size(lda), A + Size(j) * Size(lda) + m, work.begin() + Size(j) * Size(m));
  return id_in_place(work.data(), m, n, m, options);
}

ColumnId row_id(const double *A, int m, int n, int lda, const IdOptions &options)
{
  check_matrix(m, n, lda, "row_id");
  check_options(options);
  if (m == 0 || n == 0) return id_in_place(nullptr, n, m, 1, options);
  std::vector<double> work(Size(m) * Size(n)); // Aᵀ, n×m with leading dimension n
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < m; ++i) work[Size(i) * Size(n) + Size(j)] = A[Size(j) * Size(lda) + Size(i)];
  return id_in_place(work.data(), n, m, n, options);
}

void column_id_reconstruct(const ColumnId &id, const double *A, int m, int n, int lda, double *out, int ldout)
{
  check_matrix(m, n, lda, "column_id_reconstruct");
  check_matrix(m, n, ldout, "column_id_reconstruct");
  check_id(id, n, "column_id_reconstruct");
  const int k = id.rank(), r = n - k;
  if (m == 0) return;
  std::vector<double> skel(Size(m) * Size(std::max(k, 1))), interp(Size(m) * Size(r), 0.0);
  for (int i = 0; i < k; ++i) {
    const double *col = A + Size(id.skeleton[Size(i)]) * Size(lda);
    std::copy(col, col + m, skel.begin() + Size(i) * Size(m));
    std::copy(col, col + m, out + Size(id.skeleton[Size(i)]) * Size(ldout));
  }
  if (k > 0 && r > 0) lapack::gemm('N', 'N', m, r, k, 1.0, skel.data(), m, id.T.data(), k, 0.0, interp.data(), m);
  for (int j = 0; j < r; ++j) {
    const double *col = interp.data() + Size(j) * Size(m);
    std::copy(col, col + m, out + Size(id.redundant[Size(j)]) * Size(ldout));
  }
}

void row_id_reconstruct(const ColumnId &id, const double *A, int m, int n, int lda, double *out, int ldout)
{
  check_matrix(m, n, lda, "row_id_reconstruct");
  check_matrix(m, n, ldout, "row_id_reconstruct");
  check_id(id, m, "row_id_reconstruct");
  const int k = id.rank(), r = m - k;
  if (n == 0) return;
  std::vector<double> skel(Size(std::max(k, 1)) * Size(n)), interp(Size(r) * Size(n), 0.0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < k; ++i) {
      const double a = A[Size(j) * Size(lda) + Size(id.skeleton[Size(i)])];
      skel[Size(j) * Size(k) + Size(i)] = a;
      out[Size(j) * Size(ldout) + Size(id.skeleton[Size(i)])] = a;
    }
  if (k > 0 && r > 0) lapack::gemm('T', 'N', r, n, k, 1.0, id.T.data(), k, skel.data(), k, 0.0, interp.data(), r);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < r; ++i) out[Size(j) * Size(ldout) + Size(id.redundant[Size(i)])] = interp[Size(j) * Size(r) + Size(i)];
}

} // namespace hssbem
