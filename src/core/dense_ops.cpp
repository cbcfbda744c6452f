#include "hssbem/core/dense_ops.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>

namespace hssbem::dense {

DenseMatrix sub(const DenseMatrix &M, int r0, int nr, int c0, int nc)
{
  DenseMatrix S(nr, nc);
  for (int j = 0; j < nc; ++j)
    for (int i = 0; i < nr; ++i) S(i, j) = M(r0 + i, c0 + j);
  return S;
}

DenseMatrix rows_at(const DenseMatrix &M, const std::vector<int> &idx)
{
  DenseMatrix out(static_cast<int>(idx.size()), M.n);
  for (int j = 0; j < M.n; ++j)
    for (int i = 0; i < out.m; ++i) out(i, j) = M(idx[i], j);
  return out;
}

void put(DenseMatrix &M, int r0, int c0, const DenseMatrix &S)
{
  for (int j = 0; j < S.n; ++j)
    for (int i = 0; i < S.m; ++i) M(r0 + i, c0 + j) = S(i, j);
}

DenseMatrix hcat(const DenseMatrix &A, const DenseMatrix &B)
{
  DenseMatrix C(A.m, A.n + B.n);
  std::copy(A.a.begin(), A.a.end(), C.a.begin());
  std::copy(B.a.begin(), B.a.end(), C.a.begin() + static_cast<long>(A.a.size()));
  return C;
}

DenseMatrix vcat(const DenseMatrix &A, const DenseMatrix &B)
{
  DenseMatrix C(A.m + B.m, A.n);
  put(C, 0, 0, A);
  put(C, A.m, 0, B);
  return C;
}

DenseMatrix product(const DenseMatrix &A, char ta, const DenseMatrix &B, char tb)
{
  const int m = ta == 'N' ? A.m : A.n, k = ta == 'N' ? A.n : A.m, n = tb == 'N' ? B.n : B.m;
  DenseMatrix C(m, n);
  lapack::gemm(ta, tb, m, n, k, 1.0, A.data(), A.ld(), B.data(), B.ld(), 0.0, C.data(), C.ld());
  return C;
}

bool lu_regular(DenseMatrix &A, std::vector<int> &piv)
{
  const double amax = max_abs(A);
  piv.resize(A.m);
  if (A.m == 0) return true;
  if (lapack::getrf(A.m, A.data(), A.ld(), piv.data()) != 0) return false;
  double umin = HUGE_VAL;
  for (int i = 0; i < A.m; ++i) umin = std::min(umin, std::abs(A(i, i)));
  return umin > 1e-14 * amax; // the HSS factorization's test (ulv.cpp)
}

double max_abs(const DenseMatrix &M)
{
  double v = 0;
  for (double x : M.a) v = std::max(v, std::abs(x));
  return v;
}

double largest_col_norm(const DenseMatrix &M)
{
  double big = 0;
  for (int j = 0; j < M.n; ++j) {
    double s = 0;
    for (int i = 0; i < M.m; ++i) s += M(i, j) * M(i, j);
    big = std::max(big, s);
  }
  return std::sqrt(big);
}

double largest_row_norm(const DenseMatrix &M)
{
  std::vector<double> r(static_cast<std::size_t>(M.m), 0.0);
  for (int j = 0; j < M.n; ++j)
    for (int i = 0; i < M.m; ++i) r[static_cast<std::size_t>(i)] += M(i, j) * M(i, j);
  double big = 0;
  for (const double v : r) big = std::max(big, v);
  return std::sqrt(big);
}

} // namespace hssbem::dense
