// One stored block of an H² matrix: dense double, dense single or low-rank single (see H2Block).
#include "hssbem/h2/h2_matrix.hpp"

#include "hssbem/core/interpolative.hpp"
#include "hssbem/core/lapack.hpp"
#include "mixed_blas.hpp"

#include <algorithm>
#include <stdexcept>

namespace hssbem {

namespace {

using Size = std::size_t;

void widen(const std::vector<float> &f, std::vector<double> &d) { d.assign(f.begin(), f.end()); }

} // namespace

void H2Block::demote()
{
  if (M.a.empty()) return;
  single.assign(M.a.begin(), M.a.end());
  M.a.clear();
  M.a.shrink_to_fit();
}

void H2Block::compress(double rel_tol)
{
  const int m = M.m, n = M.n;
  if (M.a.empty() || m == 0 || n == 0) return demote();
  // An ID from the smaller side: columns when n ≤ m (B ≈ B(:, S) [I T] Pᵀ), else rows.
  const bool by_cols = n <= m;
  const ColumnId id = by_cols ? column_id(M.data(), m, n, M.ld(), IdOptions{rel_tol, -1, true}) : row_id(M.data(), m, n, M.ld(), IdOptions{rel_tol, -1, true});
  const int k = id.rank();
  if (Size(k) * Size(m + n) >= Size(m) * Size(n)) return demote();
  // The skeleton side keeps true entries; the other gets [I T] scattered back to its order.
  std::vector<float> skel(Size(by_cols ? m : n) * k), interp(Size(by_cols ? n : m) * k, 0.0f);
  const int len = by_cols ? m : n, other = by_cols ? n : m;
  for (int t = 0; t < k; ++t) {
    const int s = id.skeleton[Size(t)];
    for (int i = 0; i < len; ++i) skel[Size(t) * len + i] = static_cast<float>(by_cols ? M(i, s) : M(s, i));
    interp[Size(t) * other + s] = 1.0f;
    for (Size j = 0; j < id.redundant.size(); ++j) interp[Size(t) * other + id.redundant[j]] = static_cast<float>(id.T[t + j * Size(k)]);
  }
  lr_a = by_cols ? std::move(skel) : std::move(interp);
  lr_w = by_cols ? std::move(interp) : std::move(skel);
  rank = k;
  M.a.clear();
  M.a.shrink_to_fit();
}

double H2Block::entry(int i, int j) const
{
  if (is_low_rank()) {
    double s = 0;
    for (int l = 0; l < rank; ++l) s += static_cast<double>(lr_a[i + Size(l) * M.m]) * lr_w[j + Size(l) * M.n];
    return s;
  }
  return is_single() ? single[i + Size(j) * M.m] : M(i, j);
}

void H2Block::add(int i, int j, double v)
{
  if (is_low_rank()) throw std::logic_error("H2Block::add: the block is stored in low-rank form");
  if (is_single()) single[i + Size(j) * M.m] += static_cast<float>(v);
  else M(i, j) += v;
}

void H2Block::clear()
{
  std::fill(M.a.begin(), M.a.end(), 0.0);
  std::fill(single.begin(), single.end(), 0.0f);
  std::fill(lr_a.begin(), lr_a.end(), 0.0f);
}

const double *H2Block::data(std::vector<double> &buf) const
{
  if (is_low_rank()) {
    std::vector<double> a, w;
    widen(lr_a, a);
    widen(lr_w, w);
    buf.assign(Size(M.m) * M.n, 0.0);
    if (rank > 0) lapack::gemm('N', 'T', M.m, M.n, rank, 1.0, a.data(), M.m, w.data(), M.n, 0.0, buf.data(), std::max(1, M.m));
    return buf.data();
  }
  if (!is_single()) return M.data();
  buf.assign(single.begin(), single.end());
  return buf.data();
}

void H2Block::multiply_add(const double *X, int ldx, double *Y, int ldy, int nrhs, std::vector<double> &buf) const
{
  if (M.m == 0 || M.n == 0 || nrhs == 0) return;
  if (is_low_rank()) {
    if (rank == 0) return;
    std::vector<double> t(Size(rank) * nrhs);
    if (nrhs == 1) {
      mixed::gemv_t(M.n, rank, lr_w.data(), X, t.data());
      return mixed::gemv(M.m, rank, lr_a.data(), t.data(), Y);
    }
    std::vector<double> w;
    widen(lr_w, w);
    lapack::gemm('T', 'N', rank, nrhs, M.n, 1.0, w.data(), M.n, X, ldx, 0.0, t.data(), rank);
    widen(lr_a, buf);
    return lapack::gemm('N', 'N', M.m, nrhs, rank, 1.0, buf.data(), M.m, t.data(), rank, 1.0, Y, ldy);
  }
  if (is_single() && nrhs == 1) return mixed::gemv(M.m, M.n, single.data(), X, Y);
  lapack::gemm('N', 'N', M.m, nrhs, M.n, 1.0, data(buf), M.ld(), X, ldx, 1.0, Y, ldy);
}

void H2Block::multiply_add_transposed(const double *Y, int ldy, double *X, int ldx, int nrhs, std::vector<double> &buf) const
{
  if (M.m == 0 || M.n == 0 || nrhs == 0) return;
  if (is_low_rank()) { // Bᵀ Y = W (Aᵀ Y)
    if (rank == 0) return;
    std::vector<double> t(Size(rank) * nrhs);
    if (nrhs == 1) {
      mixed::gemv_t(M.m, rank, lr_a.data(), Y, t.data());
      return mixed::gemv(M.n, rank, lr_w.data(), t.data(), X);
    }
    std::vector<double> a;
    widen(lr_a, a);
    lapack::gemm('T', 'N', rank, nrhs, M.m, 1.0, a.data(), M.m, Y, ldy, 0.0, t.data(), rank);
    widen(lr_w, buf);
    return lapack::gemm('N', 'N', M.n, nrhs, rank, 1.0, buf.data(), M.n, t.data(), rank, 1.0, X, ldx);
  }
  if (is_single() && nrhs == 1) return mixed::gemv_t(M.m, M.n, single.data(), Y, X, true);
  lapack::gemm('T', 'N', M.n, nrhs, M.m, 1.0, data(buf), M.ld(), Y, ldy, 1.0, X, ldx);
}

} // namespace hssbem
