// Sampled blocked pivoted QR: its stopping bound holds exactly (every remaining column norm below
// the threshold), its rank stays close to dgeqp3's, exact ranks at and around block boundaries are
// found, and the cap and degenerate inputs behave.
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/sampled_qr.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <utility>
#include <cmath>
#include <random>
#include <vector>

namespace {

using Size = std::size_t;

struct Matrix {
  int m, n;
  std::vector<double> a;
  Matrix(int rows, int cols) : m(rows), n(cols), a(Size(rows) * Size(cols), 0.0) {}
  double &operator()(int i, int j) { return a[Size(j) * Size(m) + Size(i)]; }
  double operator()(int i, int j) const { return a[Size(j) * Size(m) + Size(i)]; }
};

/// Rank-r product of Gaussian factors.
Matrix low_rank(int m, int n, int r, unsigned seed)
{
  std::mt19937 gen(seed);
  std::normal_distribution<double> g;
  Matrix U(m, r), V(n, r), A(m, n);
  for (double &x : U.a) x = g(gen);
  for (double &x : V.a) x = g(gen);
  hssbem::lapack::gemm('N', 'T', m, n, r, 1.0, U.a.data(), m, V.a.data(), n, 0.0, A.a.data(), m);
  return A;
}

/// 1/|x − y| between points on two touching unit squares, one tilted: the kind of matrix the HSS
/// compression sees (near entries make it high rank, the far part decays).
Matrix touching_patches(int m, int n)
{
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Matrix A(m, n);
  std::vector<std::array<double, 3>> x(static_cast<Size>(m)), y(static_cast<Size>(n));
  for (auto &p : x) p = {u(gen), u(gen), 0.0};
  for (auto &q : y) {
    const double s = u(gen);
    q = {1.0 + 0.02 + s * 0.8, u(gen), s * 0.6};
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < m; ++i) {
      const auto &p = x[Size(i)], &q = y[Size(j)];
      A(i, j) = 1.0 / std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    }
  return A;
}

double column_norm(const Matrix &A, int j, int from = 0)
{
  double s = 0;
  for (int i = from; i < A.m; ++i) s += A(i, j) * A(i, j);
  return std::sqrt(s);
}

/// Largest column norm of A(:, perm[k:]) − A(:, perm[:k]) R11⁻¹ R12, the ID residual of the result.
double id_residual(const Matrix &A, const Matrix &F, const hssbem::SampledQr &qr)
{
  const int k = qr.rank, r = A.n - k;
  if (r == 0) return 0.0;
  std::vector<double> T(Size(std::max(k, 1)) * Size(r));
  for (int j = 0; j < r; ++j)
    for (int i = 0; i < k; ++i) T[Size(j) * Size(k) + Size(i)] = F(i, k + j);
  if (k > 0) hssbem::lapack::trsm('L', 'U', 'N', 'N', k, r, 1.0, F.a.data(), F.m, T.data(), k);
  double worst = 0;
  for (int j = 0; j < r; ++j) {
    double s = 0;
    for (int i = 0; i < A.m; ++i) {
      double v = A(i, qr.perm[Size(k + j)]);
      for (int t = 0; t < k; ++t) v -= A(i, qr.perm[Size(t)]) * T[Size(j) * Size(k) + Size(t)];
      s += v * v;
    }
    worst = std::max(worst, std::sqrt(s));
  }
  return worst;
}

/// dgeqp3's rank at the same threshold: pivots with |R_ii| > threshold.
int reference_rank(Matrix A, double threshold)
{
  std::vector<int> jpvt(Size(A.n), 0);
  std::vector<double> tau(Size(std::min(A.m, A.n)));
  EXPECT_EQ(hssbem::lapack::geqp3(A.m, A.n, A.a.data(), A.m, jpvt.data(), tau.data()), 0);
  int k = 0;
  while (k < std::min(A.m, A.n) && std::abs(A(k, k)) > threshold) ++k;
  return k;
}

double max_column_norm(const Matrix &A)
{
  double s = 0;
  for (int j = 0; j < A.n; ++j) s = std::max(s, column_norm(A, j));
  return s;
}

hssbem::SampledQr factor(const Matrix &A, Matrix &F, double rel_tol, int max_rank = -1, int block = 64)
{
  F = A;
  return hssbem::sampled_pivoted_qr(F.a.data(), F.m, F.n, std::max(1, F.m), rel_tol, max_rank, block);
}

} // namespace

TEST(SampledQr, ThresholdBoundHoldsAndRankStaysNearDgeqp3)
{
  for (const auto &[m, n] : {std::pair{700, 500}, std::pair{400, 900}}) {
    const Matrix A = touching_patches(m, n);
    const double scale = max_column_norm(A);
    for (double tol : {1e-3, 1e-6, 1e-10}) {
      Matrix F(0, 0);
      const auto qr = factor(A, F, tol);
      const int ref = reference_rank(A, tol * scale);
      std::vector<int> sorted = qr.perm;
      std::sort(sorted.begin(), sorted.end());
      for (int j = 0; j < n; ++j) ASSERT_EQ(sorted[Size(j)], j);
      EXPECT_LE(id_residual(A, F, qr), tol * scale * (1 + 1e-6) + 1e-12 * scale) << m << "x" << n << " tol " << tol;
      EXPECT_GE(qr.rank, ref * 0.9) << "tol " << tol;          // it cannot beat the optimum by much
      EXPECT_LE(qr.rank, ref * 1.1 + 4) << "tol " << tol;      // and compresses about as well as dgeqp3
      EXPECT_LT(qr.rank, std::min(m, n)) << "tol " << tol;     // the matrix is numerically rank deficient
      std::printf("%dx%d tol %.0e: rank %d (dgeqp3 %d)\n", m, n, tol, qr.rank, ref);
    }
  }
}

TEST(SampledQr, ExactRanksAroundBlockBoundaries)
{
  for (int r : {1, 31, 32, 33, 64, 65, 130}) {
    const Matrix A = low_rank(300, 260, r, 7 + r);
    Matrix F(0, 0);
    const auto qr = factor(A, F, 1e-10, -1, 32);
    EXPECT_EQ(qr.rank, r);
    EXPECT_LE(id_residual(A, F, qr), 1e-9 * max_column_norm(A)) << "rank " << r;
  }
}

TEST(SampledQr, FullRankCapAndDegenerateInputs)
{
  std::mt19937 gen(3);
  std::normal_distribution<double> g;
  Matrix G(150, 150);
  for (double &x : G.a) x = g(gen);
  Matrix F(0, 0);
  EXPECT_EQ(factor(G, F, 1e-12).rank, 150);
  const auto capped = factor(G, F, 1e-12, 70, 32);
  EXPECT_EQ(capped.rank, 70);
  EXPECT_EQ(capped.perm.size(), 150u);
  EXPECT_EQ(factor(Matrix(40, 30), F, 0.0).rank, 0); // zero matrix
  EXPECT_EQ(factor(G, F, 1e3).rank, 0);
  EXPECT_EQ(factor(Matrix(0, 5), F, 1.0).rank, 0);
  EXPECT_EQ(factor(Matrix(5, 0), F, 1.0).perm.size(), 0u);
  const Matrix wide = low_rank(20, 200, 20, 9);
  EXPECT_EQ(factor(wide, F, 1e-12).rank, 20);
}
