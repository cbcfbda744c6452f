// Private to h2/: the transfers of nested bases in interpolative form (StoredInterpolation),
// shared by the H² product (h2_matrix.cpp) and its distributed form (h2_distributed.cpp).
#pragma once

#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/h2/h2_matrix.hpp"
#include "mixed_blas.hpp"

#include <cstddef>
#include <vector>

namespace hssbem {
namespace transfer {

using Size = std::size_t;

/// Rows of the candidates of a cluster: a leaf's rows of X (or Y), else its children's
/// skeleton coefficients (left, then right). Row p is at ptr(p) with column stride ld(p).
template <class T>
struct CandidateRows {
  T *base = nullptr; ///< a leaf's first row, stride `ld`
  long ld = 0;
  DenseMatrix *a = nullptr, *b = nullptr; ///< an inner cluster's children
  T *ptr(int p) const
  {
    if (base) return base + p;
    return p < a->m ? a->data() + p : b->data() + (p - a->m);
  }
  long stride(int p) const { return base ? ld : p < a->m ? a->ld() : b->ld(); }
};

/// out (k × nrhs, leading dimension ldo) = Uᵀ x, x the candidates' rows.
template <class Elem>
void interp_t(const StoredInterpolation &U, const CandidateRows<Elem> &x, int nrhs, double *out, int ldo, std::vector<double> &buf)
{
  const int k = U.rank(), nred = static_cast<int>(U.red_pos.size());
  for (int r = 0; r < nrhs; ++r)
    for (int t = 0; t < k; ++t) out[t + Size(r) * ldo] = x.ptr(U.skel_pos[t])[r * x.stride(U.skel_pos[t])];
  if (k == 0 || nred == 0) return;
  buf.resize(Size(nred) * nrhs);
  for (int r = 0; r < nrhs; ++r)
    for (int j = 0; j < nred; ++j) buf[j + Size(r) * nred] = x.ptr(U.red_pos[j])[r * x.stride(U.red_pos[j])];
  if (!U.Tf.empty() && nrhs == 1) return mixed::gemv(k, nred, U.Tf.data(), buf.data(), out);
  std::vector<double> wide;
  const double *T = U.Td.data();
  if (!U.Tf.empty()) wide.assign(U.Tf.begin(), U.Tf.end()), T = wide.data();
  lapack::gemm('N', 'N', k, nrhs, nred, 1.0, T, k, buf.data(), nred, 1.0, out, ldo);
}

/// y += U yh (yh: k × nrhs, leading dimension ldh), y the candidates' rows.
inline void interp_n(const StoredInterpolation &U, const double *yh, int ldh, int nrhs, const CandidateRows<double> &y, std::vector<double> &buf)
{
  const int k = U.rank(), nred = static_cast<int>(U.red_pos.size());
  if (k == 0) return;
  for (int r = 0; r < nrhs; ++r)
    for (int t = 0; t < k; ++t) y.ptr(U.skel_pos[t])[r * y.stride(U.skel_pos[t])] += yh[t + Size(r) * ldh];
  if (nred == 0) return;
  buf.resize(Size(nred) * nrhs);
  if (!U.Tf.empty() && nrhs == 1) {
    mixed::gemv_t(k, nred, U.Tf.data(), yh, buf.data());
  } else {
    std::vector<double> wide;
    const double *T = U.Td.data();
    if (!U.Tf.empty()) wide.assign(U.Tf.begin(), U.Tf.end()), T = wide.data();
    lapack::gemm('T', 'N', nred, nrhs, k, 1.0, T, k, yh, ldh, 0.0, buf.data(), nred);
  }
  for (int r = 0; r < nrhs; ++r)
    for (int j = 0; j < nred; ++j) y.ptr(U.red_pos[j])[r * y.stride(U.red_pos[j])] += buf[j + Size(r) * nred];
}

} // namespace transfer
} // namespace hssbem
