// One stored block of an H² matrix: dense double, dense single or low-rank single (see H2Block).
#include "hssbem/h2/h2_matrix.hpp"

#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/interpolative.hpp"
#include "hssbem/core/lapack.hpp"
#include "mixed_blas.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace hssbem {

namespace {

using Size = std::size_t;

void widen(const std::vector<float> &f, std::vector<double> &d) { d.assign(f.begin(), f.end()); }

/// The interpolation side P of a low-rank block (other × rank; see H2Block).
struct Interp {
  const std::vector<H2Block::Slot> &slot;
  const float *T; ///< redundant rows, (other − rank) × rank
  int other, rank;
  int red() const { return other - rank; }
};

Interp interp_of(const H2Block &B)
{
  const int other = B.lr_rows ? B.M.m : B.M.n;
  return Interp{B.lr_slot, B.lr_t.data(), other, B.rank};
}

/// t = Pᵀ X (t: rank × nrhs, overwritten; X: other × nrhs).
void interp_t(const Interp &P, const double *X, int ldx, int nrhs, double *t, std::vector<double> &g)
{
  const int r = P.red(), k = P.rank;
  g.resize(Size(r) * nrhs);
  std::fill(t, t + Size(k) * nrhs, 0.0);
  for (int c = 0; c < nrhs; ++c) {
    const double *x = X + Size(c) * ldx;
    for (int p = 0; p < P.other; ++p) {
      const int s = P.slot[Size(p)];
      if (s >= 0) t[s + Size(c) * k] += x[p];
      else g[Size(-1 - s) + Size(c) * r] = x[p];
    }
  }
  if (r == 0) return;
  if (nrhs == 1) return mixed::gemv_t(r, k, P.T, g.data(), t, true);
  std::vector<double> Td(P.T, P.T + Size(r) * k);
  lapack::gemm('T', 'N', k, nrhs, r, 1.0, Td.data(), r, g.data(), r, 1.0, t, k);
}

/// Y += P t (Y: other × nrhs; t: rank × nrhs).
void interp_add(const Interp &P, const double *t, int nrhs, double *Y, int ldy, std::vector<double> &g)
{
  const int r = P.red(), k = P.rank;
  g.assign(Size(r) * nrhs, 0.0);
  if (r > 0) {
    if (nrhs == 1) mixed::gemv(r, k, P.T, t, g.data());
    else {
      std::vector<double> Td(P.T, P.T + Size(r) * k);
      lapack::gemm('N', 'N', r, nrhs, k, 1.0, Td.data(), r, t, k, 0.0, g.data(), r);
    }
  }
  for (int c = 0; c < nrhs; ++c) {
    double *y = Y + Size(c) * ldy;
    for (int p = 0; p < P.other; ++p) {
      const int s = P.slot[Size(p)];
      y[p] += s >= 0 ? t[s + Size(c) * k] : g[Size(-1 - s) + Size(c) * r];
    }
  }
}

/// t = Sᵀ X for the skeleton side S (len × rank, float); t: rank × nrhs, overwritten.
void skel_t(const std::vector<float> &S, int len, int k, const double *X, int ldx, int nrhs, double *t, std::vector<double> &buf)
{
  if (nrhs == 1) return mixed::gemv_t(len, k, S.data(), X, t);
  widen(S, buf);
  lapack::gemm('T', 'N', k, nrhs, len, 1.0, buf.data(), len, X, ldx, 0.0, t, k);
}

/// Y += S t.
void skel_add(const std::vector<float> &S, int len, int k, const double *t, int nrhs, double *Y, int ldy, std::vector<double> &buf)
{
  if (nrhs == 1) return mixed::gemv(len, k, S.data(), t, Y);
  widen(S, buf);
  lapack::gemm('N', 'N', len, nrhs, k, 1.0, buf.data(), len, t, k, 1.0, Y, ldy);
}

} // namespace

void H2Block::demote()
{
  if (M.a.empty()) return;
  single.assign(M.a.begin(), M.a.end());
  M.a.clear();
  M.a.shrink_to_fit();
}

void H2Block::compress(double rel_tol, double row_scale, double col_scale)
{
  const int m = M.m, n = M.n;
  if (M.a.empty() || m == 0 || n == 0) return demote();
  // An ID from the smaller side: columns when n ≤ m (B ≈ B(:, S) Pᵀ), else rows.
  const bool by_cols = n <= m;
  const int len = by_cols ? m : n, other = by_cols ? n : m;
  const double scale = by_cols ? col_scale : row_scale;
  int k = 0;
  ColumnId id;
  const double p1 = by_cols ? dense::largest_col_norm(M) : dense::largest_row_norm(M);
  if (p1 > rel_tol * scale) {
    const double tol = scale > p1 ? rel_tol * scale / p1 : rel_tol;
    id = by_cols ? column_id(M.data(), m, n, M.ld(), IdOptions{tol, -1, true}) : row_id(M.data(), m, n, M.ld(), IdOptions{tol, -1, true});
    k = id.rank();
  }
  if (Size(k) * Size(len + other - k) + Size(other) >= Size(m) * Size(n) || other > std::numeric_limits<Slot>::max()) return demote();
  lr_rows = !by_cols;
  rank = k;
  lr_s.assign(Size(len) * k, 0.0f);
  lr_slot.clear();
  lr_t.clear();
  if (k > 0) {
    const int r = other - k;
    lr_slot.assign(Size(other), 0);
    lr_t.assign(Size(r) * k, 0.0f);
    for (int t = 0; t < k; ++t) {
      const int s = id.skeleton[Size(t)];
      for (int i = 0; i < len; ++i) lr_s[Size(t) * len + i] = static_cast<float>(by_cols ? M(i, s) : M(s, i));
      lr_slot[Size(s)] = static_cast<Slot>(t);
    }
    for (int j = 0; j < r; ++j) {
      lr_slot[Size(id.redundant[Size(j)])] = static_cast<Slot>(-1 - j);
      for (int t = 0; t < k; ++t) lr_t[Size(j) + Size(t) * r] = static_cast<float>(id.T[t + Size(j) * k]);
    }
  }
  M.a.clear();
  M.a.shrink_to_fit();
}

double H2Block::entry(int i, int j) const
{
  if (is_low_rank()) {
    if (rank == 0) return 0.0;
    // the skeleton side's row (len index q) against P's row p
    const int len = lr_rows ? M.n : M.m, p = lr_rows ? i : j, q = lr_rows ? j : i;
    const int s = lr_slot[Size(p)];
    if (s >= 0) return lr_s[Size(q) + Size(s) * len];
    const int r = (lr_rows ? M.m : M.n) - rank, row = -1 - s;
    double sum = 0;
    for (int t = 0; t < rank; ++t) sum += static_cast<double>(lr_s[Size(q) + Size(t) * len]) * lr_t[Size(row) + Size(t) * r];
    return sum;
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
  std::fill(lr_s.begin(), lr_s.end(), 0.0f);
  std::fill(lr_t.begin(), lr_t.end(), 0.0f);
}

const double *H2Block::data(std::vector<double> &buf) const
{
  if (is_low_rank()) {
    buf.assign(Size(M.m) * M.n, 0.0);
    if (rank == 0) return buf.data();
    // P expanded (other × rank) as P I, then B = S Pᵀ (column ID) or P Sᵀ (row ID)
    const Interp P = interp_of(*this);
    std::vector<double> I(Size(rank) * rank, 0.0), Pd(Size(P.other) * rank, 0.0), S, g;
    for (int t = 0; t < rank; ++t) I[Size(t) * rank + t] = 1.0;
    interp_add(P, I.data(), rank, Pd.data(), P.other, g);
    widen(lr_s, S);
    if (lr_rows) lapack::gemm('N', 'T', M.m, M.n, rank, 1.0, Pd.data(), M.m, S.data(), M.n, 0.0, buf.data(), M.m);
    else lapack::gemm('N', 'T', M.m, M.n, rank, 1.0, S.data(), M.m, Pd.data(), M.n, 0.0, buf.data(), M.m);
    return buf.data();
  }
  if (!is_single()) return M.data();
  buf.assign(single.begin(), single.end());
  return buf.data();
}

void H2Block::multiply_add(const double *X, int ldx, double *Y, int ldy, int nrhs, std::vector<double> &buf) const
{
  if (M.m == 0 || M.n == 0 || nrhs == 0) return;
  if (is_low_rank()) { // Y += A (Wᵀ X)
    if (rank == 0) return;
    std::vector<double> t(Size(rank) * nrhs), g;
    if (lr_rows) { // A = P, W = S
      skel_t(lr_s, M.n, rank, X, ldx, nrhs, t.data(), buf);
      return interp_add(interp_of(*this), t.data(), nrhs, Y, ldy, g);
    }
    interp_t(interp_of(*this), X, ldx, nrhs, t.data(), g); // A = S, W = P
    return skel_add(lr_s, M.m, rank, t.data(), nrhs, Y, ldy, buf);
  }
  if (is_single() && nrhs == 1) return mixed::gemv(M.m, M.n, single.data(), X, Y);
  lapack::gemm('N', 'N', M.m, nrhs, M.n, 1.0, data(buf), M.ld(), X, ldx, 1.0, Y, ldy);
}

void H2Block::multiply_add_transposed(const double *Y, int ldy, double *X, int ldx, int nrhs, std::vector<double> &buf) const
{
  if (M.m == 0 || M.n == 0 || nrhs == 0) return;
  if (is_low_rank()) { // Bᵀ Y = W (Aᵀ Y)
    if (rank == 0) return;
    std::vector<double> t(Size(rank) * nrhs), g;
    if (lr_rows) { // A = P, W = S
      interp_t(interp_of(*this), Y, ldy, nrhs, t.data(), g);
      return skel_add(lr_s, M.n, rank, t.data(), nrhs, X, ldx, buf);
    }
    skel_t(lr_s, M.m, rank, Y, ldy, nrhs, t.data(), buf); // A = S, W = P
    return interp_add(interp_of(*this), t.data(), nrhs, X, ldx, g);
  }
  if (is_single() && nrhs == 1) return mixed::gemv_t(M.m, M.n, single.data(), Y, X, true);
  lapack::gemm('T', 'N', M.n, nrhs, M.m, 1.0, data(buf), M.ld(), Y, ldy, 1.0, X, ldx);
}

} // namespace hssbem
