// Interpolative decompositions: exact low rank, kernel matrices against the CPQR error bound,
// rank caps, degenerate shapes, and row ID = column ID of the transpose.
#include "hssbem/core/interpolative.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

using hssbem::ColumnId;
using hssbem::IdOptions;

namespace {

/// Column-major m×n matrix.
struct Matrix {
  int m = 0, n = 0;
  std::vector<double> a;
  Matrix(int rows, int cols) : m(rows), n(cols), a(std::size_t(rows) * std::size_t(cols), 0.0) {}
  double &operator()(int i, int j) { return a[std::size_t(j) * std::size_t(m) + std::size_t(i)]; }
  double operator()(int i, int j) const { return a[std::size_t(j) * std::size_t(m) + std::size_t(i)]; }
  int ld() const { return std::max(1, m); }
};

Matrix gaussian(int m, int n, unsigned seed)
{
  std::mt19937 gen(seed);
  std::normal_distribution<double> g;
  Matrix A(m, n);
  for (double &x : A.a) x = g(gen);
  return A;
}

Matrix product(const Matrix &U, const Matrix &V) // U Vᵀ
{
  Matrix A(U.m, V.m);
  for (int j = 0; j < V.m; ++j)
    for (int l = 0; l < U.n; ++l)
      for (int i = 0; i < U.m; ++i) A(i, j) += U(i, l) * V(j, l);
  return A;
}

Matrix transpose(const Matrix &A)
{
  Matrix B(A.n, A.m);
  for (int j = 0; j < A.n; ++j)
    for (int i = 0; i < A.m; ++i) B(j, i) = A(i, j);
  return B;
}

using Cloud = std::vector<std::array<double, 3>>;

/// n points uniform in the unit cube shifted by `shift` along x.
Cloud cloud(int n, double shift, unsigned seed)
{
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c(static_cast<std::size_t>(n));
  for (auto &p : c) p = {shift + u(gen), u(gen), u(gen)};
  return c;
}

/// 1/|x − y| between two clouds whose cubes are 2 apart: smooth, numerically low rank.
Matrix kernel_matrix()
{
  const Cloud x = cloud(200, 0.0, 11), y = cloud(300, 3.0, 12);
  Matrix A(200, 300);
  for (int j = 0; j < A.n; ++j)
    for (int i = 0; i < A.m; ++i) {
      const auto &p = x[std::size_t(i)], &q = y[std::size_t(j)];
      A(i, j) = 1.0 / std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    }
  return A;
}

double frobenius(const std::vector<double> &a)
{
  double s = 0;
  for (double x : a) s += x * x;
  return std::sqrt(s);
}

double relative_error(const Matrix &A, const Matrix &B)
{
  std::vector<double> d(A.a.size());
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = A.a[i] - B.a[i];
  return frobenius(d) / frobenius(A.a);
}

double column_id_error(const Matrix &A, const ColumnId &id)
{
  Matrix B(A.m, A.n);
  hssbem::column_id_reconstruct(id, A.a.data(), A.m, A.n, A.ld(), B.a.data(), B.ld());
  return relative_error(A, B);
}

double row_id_error(const Matrix &A, const ColumnId &id)
{
  Matrix B(A.m, A.n);
  hssbem::row_id_reconstruct(id, A.a.data(), A.m, A.n, A.ld(), B.a.data(), B.ld());
  return relative_error(A, B);
}

double max_abs(const std::vector<double> &a)
{
  double s = 0;
  for (double x : a) s = std::max(s, std::abs(x));
  return s;
}

/// skeleton ∪ redundant is 0..n−1 without repeats, and T has the right size.
void expect_partition(const ColumnId &id, int n)
{
  std::vector<int> all(id.skeleton);
  all.insert(all.end(), id.redundant.begin(), id.redundant.end());
  std::sort(all.begin(), all.end());
  std::vector<int> expected(static_cast<std::size_t>(n));
  std::iota(expected.begin(), expected.end(), 0);
  EXPECT_EQ(all, expected);
  EXPECT_EQ(id.T.size(), id.skeleton.size() * id.redundant.size());
}

ColumnId column_id(const Matrix &A, double tol, int max_rank = -1)
{
  return hssbem::column_id(A.a.data(), A.m, A.n, A.ld(), IdOptions{tol, max_rank});
}

ColumnId row_id(const Matrix &A, double tol, int max_rank = -1)
{
  return hssbem::row_id(A.a.data(), A.m, A.n, A.ld(), IdOptions{tol, max_rank});
}

/// The CPQR bound of interpolative.hpp, ‖A − Â‖_F ≤ tol·sqrt(n−k)·‖A‖_F, with 50% slack for
/// dgeqp3's downdated column norms and a rounding floor.
double error_bound(double tol, int n, int k) { return 1.5 * tol * std::sqrt(double(n - k)) + 1e-13; }

} // namespace

TEST(Interpolative, ExactRankFiveIsRecovered)
{
  const Matrix A = product(gaussian(100, 5, 1), gaussian(80, 5, 2));
  const ColumnId c = column_id(A, 1e-8);
  EXPECT_EQ(c.rank(), 5);
  expect_partition(c, A.n);
  EXPECT_LE(column_id_error(A, c), 1e-12);
  const ColumnId r = row_id(A, 1e-8);
  EXPECT_EQ(r.rank(), 5);
  expect_partition(r, A.m);
  EXPECT_LE(row_id_error(A, r), 1e-12);
}

TEST(Interpolative, KernelMatrixMeetsToleranceAndRankGrows)
{
  const Matrix A = kernel_matrix();
  int previous = 0;
  double max_t = 0;
  for (double tol : {1e-3, 1e-6, 1e-9}) {
    const ColumnId c = column_id(A, tol);
    expect_partition(c, A.n);
    EXPECT_GT(c.rank(), previous) << "tol " << tol;
    EXPECT_LT(c.rank(), A.m) << "tol " << tol;
    EXPECT_LE(column_id_error(A, c), error_bound(tol, A.n, c.rank())) << "tol " << tol;
    previous = c.rank();
    max_t = std::max(max_t, max_abs(c.T));
  }
  EXPECT_LE(max_t, 10.0);
  ::testing::Test::RecordProperty("max_abs_T", std::to_string(max_t));
}

TEST(Interpolative, KernelMatrixRowIdMeetsTolerance)
{
  const Matrix A = kernel_matrix();
  int previous = 0;
  for (double tol : {1e-3, 1e-6, 1e-9}) {
    const ColumnId r = row_id(A, tol);
    expect_partition(r, A.m);
    EXPECT_GT(r.rank(), previous) << "tol " << tol;
    EXPECT_LE(row_id_error(A, r), error_bound(tol, A.m, r.rank())) << "tol " << tol;
    EXPECT_LE(max_abs(r.T), 10.0) << "tol " << tol;
    previous = r.rank();
  }
}

TEST(Interpolative, RowIdIsColumnIdOfTranspose)
{
  const Matrix A = kernel_matrix();
  const ColumnId r = row_id(A, 1e-6);
  const ColumnId c = column_id(transpose(A), 1e-6);
  EXPECT_EQ(r.skeleton, c.skeleton);
  EXPECT_EQ(r.redundant, c.redundant);
  ASSERT_EQ(r.T.size(), c.T.size());
  for (std::size_t i = 0; i < r.T.size(); ++i) EXPECT_NEAR(r.T[i], c.T[i], 1e-12 * (1 + std::abs(c.T[i])));
}

TEST(Interpolative, MaxRankCapsTheRank)
{
  const Matrix A = kernel_matrix();
  const ColumnId full = column_id(A, 1e-12);
  ASSERT_GT(full.rank(), 7);
  const ColumnId capped = column_id(A, 1e-12, 7);
  EXPECT_EQ(capped.rank(), 7);
  expect_partition(capped, A.n);
  // Same pivoted QR, truncated earlier: the skeleton is a prefix of the uncapped one.
  EXPECT_TRUE(std::equal(capped.skeleton.begin(), capped.skeleton.end(), full.skeleton.begin()));
  EXPECT_GT(column_id_error(A, capped), 1e-12);
  EXPECT_LT(column_id_error(A, capped), 1.0);
  EXPECT_EQ(column_id(A, 1e-12, 0).rank(), 0);
  EXPECT_EQ(row_id(A, 1e-12, 7).rank(), 7);
}

TEST(Interpolative, GradedColumnsGiveTheThresholdRank)
{
  // Column c = perm(i) holds d_i = 10^-i in row (7 i) mod 20: orthogonal columns, so pivoted QR
  // has |R_ii| = d_i exactly and k counts the d_i above rel_tol · d_0.
  const int n = 12;
  const std::array<int, n> perm{5, 0, 9, 3, 11, 7, 1, 10, 4, 8, 2, 6};
  Matrix A(20, n);
  for (int i = 0; i < n; ++i) A((7 * i) % 20, perm[std::size_t(i)]) = std::pow(10.0, -i);
  const double tol = std::pow(10.0, -5.5);
  const ColumnId c = column_id(A, tol);
  ASSERT_EQ(c.rank(), 6);
  EXPECT_TRUE(std::equal(c.skeleton.begin(), c.skeleton.end(), perm.begin()));
  EXPECT_EQ(max_abs(c.T), 0.0);
  double head = 0, tail = 0;
  for (int i = 0; i < n; ++i) (i >= 6 ? tail : head) += std::pow(10.0, -2 * i);
  EXPECT_NEAR(column_id_error(A, c), std::sqrt(tail / (head + tail)), 1e-3 * std::sqrt(tail / head));
  EXPECT_EQ(row_id(A, tol).rank(), 6);
}

TEST(Interpolative, ZeroMatrixHasRankZero)
{
  const Matrix Z(30, 20);
  for (const ColumnId &id : {column_id(Z, 1e-8), row_id(Z, 1e-8)}) {
    EXPECT_EQ(id.rank(), 0);
    EXPECT_TRUE(id.T.empty());
  }
  const ColumnId c = column_id(Z, 1e-8);
  expect_partition(c, Z.n);
  Matrix B(Z.m, Z.n);
  std::fill(B.a.begin(), B.a.end(), 1.0);
  hssbem::column_id_reconstruct(c, Z.a.data(), Z.m, Z.n, Z.ld(), B.a.data(), B.ld());
  EXPECT_EQ(max_abs(B.a), 0.0);
}

TEST(Interpolative, ToleranceAboveEverythingGivesRankZero)
{
  const Matrix A = gaussian(20, 15, 3);
  const ColumnId c = column_id(A, 2.0);
  EXPECT_EQ(c.rank(), 0);
  expect_partition(c, A.n);
}

TEST(Interpolative, IdentityHasFullRank)
{
  Matrix I(50, 50);
  for (int i = 0; i < 50; ++i) I(i, i) = 1.0;
  for (const ColumnId &id : {column_id(I, 1e-8), row_id(I, 1e-8)}) {
    EXPECT_EQ(id.rank(), 50);
    EXPECT_TRUE(id.redundant.empty());
    EXPECT_TRUE(id.T.empty());
    expect_partition(id, 50);
  }
  EXPECT_EQ(column_id_error(I, column_id(I, 1e-8)), 0.0);
}

TEST(Interpolative, WideAndTallMatrices)
{
  const Matrix wide = gaussian(10, 30, 4), tall = gaussian(30, 10, 5);
  const ColumnId w = column_id(wide, 1e-10);
  EXPECT_EQ(w.rank(), 10);
  EXPECT_EQ(w.T.size(), 10u * 20u);
  EXPECT_LE(column_id_error(wide, w), 1e-12);
  const ColumnId t = column_id(tall, 1e-10);
  EXPECT_EQ(t.rank(), 10);
  EXPECT_TRUE(t.T.empty());
  const ColumnId rw = row_id(wide, 1e-10), rt = row_id(tall, 1e-10);
  EXPECT_EQ(rw.rank(), 10);
  EXPECT_TRUE(rw.T.empty());
  EXPECT_EQ(rt.rank(), 10);
  EXPECT_LE(row_id_error(tall, rt), 1e-12);
}

TEST(Interpolative, SingleColumnAndEmptyShapes)
{
  const Matrix v = gaussian(12, 1, 6), zero(12, 1);
  EXPECT_EQ(column_id(v, 1e-8).rank(), 1);
  EXPECT_EQ(column_id(zero, 1e-8).rank(), 0);
  EXPECT_EQ(row_id(v, 1e-8).rank(), 1);
  EXPECT_EQ(row_id(v, 1e-8).T.size(), 11u);
  const Matrix no_rows(0, 4), no_cols(4, 0);
  const ColumnId c0 = column_id(no_rows, 1e-8);
  EXPECT_EQ(c0.rank(), 0);
  expect_partition(c0, 4);
  EXPECT_EQ(row_id(no_rows, 1e-8).redundant.size(), 0u);
  EXPECT_EQ(column_id(no_cols, 1e-8).redundant.size(), 0u);
  expect_partition(row_id(no_cols, 1e-8), 4);
}

TEST(Interpolative, LeadingDimensionIsHonoured)
{
  const Matrix A = kernel_matrix();
  const int lda = A.m + 7;
  std::vector<double> padded(std::size_t(lda) * std::size_t(A.n), 1e300);
  for (int j = 0; j < A.n; ++j)
    for (int i = 0; i < A.m; ++i) padded[std::size_t(j) * std::size_t(lda) + std::size_t(i)] = A(i, j);
  const ColumnId a = column_id(A, 1e-6), b = hssbem::column_id(padded.data(), A.m, A.n, lda, IdOptions{1e-6, -1});
  EXPECT_EQ(a.skeleton, b.skeleton);
  EXPECT_EQ(a.T, b.T);
  const ColumnId r = row_id(A, 1e-6), s = hssbem::row_id(padded.data(), A.m, A.n, lda, IdOptions{1e-6, -1});
  EXPECT_EQ(r.skeleton, s.skeleton);
  EXPECT_EQ(r.T, s.T);
}

TEST(Interpolative, BadArgumentsThrow)
{
  const Matrix A = gaussian(5, 4, 7);
  EXPECT_THROW(hssbem::column_id(A.a.data(), 5, 4, 4, {}), std::invalid_argument);
  EXPECT_THROW(hssbem::row_id(A.a.data(), -1, 4, 5, {}), std::invalid_argument);
  EXPECT_THROW(hssbem::column_id(A.a.data(), 5, 4, 5, IdOptions{-1.0, -1}), std::invalid_argument);
  ColumnId wrong = column_id(A, 1e-8);
  wrong.redundant.push_back(0);
  Matrix B(5, 4);
  EXPECT_THROW(hssbem::column_id_reconstruct(wrong, A.a.data(), 5, 4, 5, B.a.data(), 5), std::invalid_argument);
}

TEST(Interpolative, GramPivotsMeetTheSameBoundAsQr)
{
  // Pivoted Cholesky of AᵀA picks the greedy pivots of column-pivoted QR and stops by the same
  // rule; from gram_min_tol up the Gram matrix resolves the residual norms, so the CPQR bound
  // holds and the rank stays within a few of the QR rank. Below it, the QR path is taken.
  const Matrix A = kernel_matrix(), At = transpose(A);
  for (double tol : {1e-3, 1e-5, hssbem::gram_min_tol}) {
    for (const Matrix *M : {&A, &At}) {
      const ColumnId q = hssbem::column_id(M->a.data(), M->m, M->n, M->ld(), IdOptions{tol, -1, false});
      const ColumnId g = hssbem::column_id(M->a.data(), M->m, M->n, M->ld(), IdOptions{tol, -1, true});
      expect_partition(g, M->n);
      EXPECT_LE(column_id_error(*M, g), error_bound(tol, M->n, g.rank())) << "tol " << tol;
      EXPECT_NEAR(g.rank(), q.rank(), 3 + q.rank() / 10) << "tol " << tol;
      EXPECT_LE(max_abs(g.T), 10.0);
    }
  }
  const ColumnId capped = hssbem::column_id(A.a.data(), A.m, A.n, A.ld(), IdOptions{1e-5, 7, true});
  EXPECT_EQ(capped.rank(), 7);
  const ColumnId tight = hssbem::column_id(A.a.data(), A.m, A.n, A.ld(), IdOptions{1e-10, -1, true});
  EXPECT_EQ(tight.rank(), column_id(A, 1e-10).rank()); // the QR path
  Matrix Z(30, 20);
  EXPECT_EQ(hssbem::column_id(Z.a.data(), Z.m, Z.n, Z.ld(), IdOptions{1e-5, -1, true}).rank(), 0);
}
