// Randomized blocked column-pivoted QR stopped at a tolerance (see sampled_qr.hpp).
#include "hssbem/core/sampled_qr.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

using Size = std::size_t;

constexpr int kOversampling = 8;

void check(int info, const char *routine)
{
  if (info != 0) throw std::runtime_error(std::string("sampled pivoted QR: ") + routine + " failed, info = " + std::to_string(info));
}

/// Squared norm of rows [from, m) of column c.
double tail_norm2(const double *a, int lda, int c, int from, int m)
{
  const double *col = a + Size(c) * Size(lda);
  double s = 0;
  for (int i = from; i < m; ++i) s += col[i] * col[i];
  return s;
}

} // namespace

SampledQr sampled_pivoted_qr(double *a, int m, int n, int lda, double rel_tol, int max_rank, int block, std::uint64_t seed)
{
  if (m < 0 || n < 0 || lda < std::max(1, m)) throw std::invalid_argument("sampled pivoted QR: bad matrix size or leading dimension");
  SampledQr out;
  out.perm.resize(Size(n));
  std::iota(out.perm.begin(), out.perm.end(), 0);
  const int kmax = std::min(m, n);
  const int cap = max_rank >= 0 ? std::min(kmax, max_rank) : kmax;
  if (cap == 0) return out;
  // norm2[c]: squared norm of the part of column c below the rows already factorized.
  std::vector<double> norm2(static_cast<Size>(n));
  for (int c = 0; c < n; ++c) norm2[Size(c)] = tail_norm2(a, lda, c, 0, m);
  const double largest2 = *std::max_element(norm2.begin(), norm2.end());
  const double t2 = rel_tol * rel_tol * largest2; // the threshold, squared
  if (largest2 <= t2) return out;

  // Sketch Y = Ω A with Ω uniform in [−1, 1] (ell × m): its columns have the Gram matrix of A's
  // up to a random distortion, which is all the pivot choice needs.
  const int b = std::max(1, block), ell = std::min(b + kOversampling, m);
  std::vector<double> omega(Size(ell) * Size(m)), Y(Size(ell) * Size(n));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (double &w : omega) w = uniform(rng);
  lapack::gemm('N', 'N', ell, n, m, 1.0, omega.data(), ell, a, lda, 0.0, Y.data(), ell);

  auto A = [a, lda](int i, int j) -> double & { return a[Size(j) * Size(lda) + Size(i)]; };
  auto swap_columns = [&](int p, int q) {
    if (p == q) return;
    std::swap_ranges(&A(0, p), &A(0, p) + m, &A(0, q));
    std::swap_ranges(&Y[Size(p) * Size(ell)], &Y[Size(p) * Size(ell)] + ell, &Y[Size(q) * Size(ell)]);
    std::swap(norm2[Size(p)], norm2[Size(q)]);
    std::swap(out.perm[Size(p)], out.perm[Size(q)]);
  };

  std::vector<double> sketch, ytau, Z, tfac(static_cast<Size>(b) * static_cast<Size>(b)), panel_res(static_cast<Size>(b)), rest(static_cast<Size>(n));
  std::vector<int> jpvt, position, at;
  for (int j = 0; j < cap;) {
    const int bb = std::min(b, cap - j), rows = m - j, cols = n - j, trailing = cols - bb;

    // 1. Pivots: column-pivoted QR of the remaining columns' sketch; its first bb pivots move to
    //    positions j .. j+bb−1.
    sketch.assign(Y.begin() + std::ptrdiff_t(Size(j) * Size(ell)), Y.end());
    jpvt.assign(Size(cols), 0);
    ytau.resize(Size(std::min(ell, cols)));
    check(lapack::geqp3(ell, cols, sketch.data(), ell, jpvt.data(), ytau.data()), "dgeqp3");
    position.resize(Size(cols));
    at.resize(Size(cols));
    std::iota(position.begin(), position.end(), 0); // position[c]: where local column c is now
    std::iota(at.begin(), at.end(), 0);             // at[p]: the local column now at p
    for (int t = 0; t < bb; ++t) {
      const int want = jpvt[Size(t)] - 1, p = position[Size(want)];
      swap_columns(j + t, j + p);
      const int moved = at[Size(t)];
      std::swap(at[Size(t)], at[Size(p)]);
      position[Size(want)] = t;
      position[Size(moved)] = p;
    }

    // 2. Householder QR of the panel (recursive, so level-3 BLAS too), then the update of the
    //    remaining columns.
    check(lapack::geqrt3(rows, bb, &A(j, j), lda, tfac.data(), bb), "dgeqrt3");
    if (trailing > 0) lapack::larfb_left('T', rows, trailing, bb, &A(j, j), lda, tfac.data(), bb, &A(j, j + bb), lda);

    // 3. Exact remainder norms for every k in [j, j+bb]: remainder(k) is the largest column norm
    //    of rows k.. of the columns k.. (panel columns count their R entries only).
    for (int c = j + bb; c < n; ++c) norm2[Size(c)] = tail_norm2(a, lda, c, j + bb, m);
    for (int c = j + bb; c < n; ++c) rest[Size(c)] = norm2[Size(c)];
    double worst_trailing = 0;
    for (int c = j + bb; c < n; ++c) worst_trailing = std::max(worst_trailing, rest[Size(c)]);
    int stop = worst_trailing <= t2 ? j + bb : -1;
    std::fill(panel_res.begin(), panel_res.end(), 0.0);
    for (int k = j + bb - 1; k >= j; --k) {
      worst_trailing = 0;
      for (int c = j + bb; c < n; ++c) {
        rest[Size(c)] += A(k, c) * A(k, c);
        worst_trailing = std::max(worst_trailing, rest[Size(c)]);
      }
      double worst = worst_trailing;
      for (int c = k; c < j + bb; ++c) {
        panel_res[Size(c - j)] += A(k, c) * A(k, c);
        worst = std::max(worst, panel_res[Size(c - j)]);
      }
      if (worst > t2) break;
      stop = k;
    }
    if (stop >= 0) {
      out.rank = stop;
      return out;
    }

    // 4. Downdate the sketch of the remaining columns: Y2 ← Y2 − Y1 R11⁻¹ R12. An exactly
    //    singular R11 (a pivot with no residual left) cannot be inverted; then the sketch is taken
    //    afresh from the remaining rows, which span the same residual geometry.
    bool singular = false;
    for (int t = 0; t < bb; ++t) singular = singular || A(j + t, j + t) == 0.0;
    if (trailing > 0 && singular) {
      const int rest_rows = rows - bb, ell_rest = std::min(ell, rest_rows);
      std::fill(Y.begin() + std::ptrdiff_t(Size(j + bb) * Size(ell)), Y.end(), 0.0);
      if (ell_rest > 0)
        lapack::gemm('N', 'N', ell_rest, trailing, rest_rows, 1.0, omega.data(), ell, &A(j + bb, j + bb), lda, 0.0, &Y[Size(j + bb) * Size(ell)], ell);
    } else if (trailing > 0) {
      Z.resize(Size(bb) * Size(trailing));
      for (int c = 0; c < trailing; ++c) std::copy(&A(j, j + bb + c), &A(j, j + bb + c) + bb, &Z[Size(c) * Size(bb)]);
      lapack::trsm('L', 'U', 'N', 'N', bb, trailing, 1.0, &A(j, j), lda, Z.data(), bb);
      lapack::gemm('N', 'N', ell, trailing, bb, -1.0, &Y[Size(j) * Size(ell)], ell, Z.data(), bb, 1.0, &Y[Size(j + bb) * Size(ell)], ell);
    }
    j += bb;
    out.rank = j;
  }
  return out;
}

} // namespace hssbem
