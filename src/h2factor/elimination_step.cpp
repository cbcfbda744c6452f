// The elimination steps of the H² factorization as the solve replays them (see elimination_step.hpp).
#include "elimination_step.hpp"

#include "hssbem/core/lapack.hpp"

namespace hssbem::h2f {

namespace {

/// y += alpha A x for a column-major float matrix A (m × n).
void gemv_single(int m, int n, double alpha, const float *A, const double *x, double *y)
{
  for (int j = 0; j < n; ++j) {
    const float *a = A + static_cast<std::size_t>(j) * m;
    const double xj = alpha * x[j];
    for (int i = 0; i < m; ++i) y[i] += static_cast<double>(a[i]) * xj;
  }
}

} // namespace

std::size_t Step::bytes() const
{
  const std::size_t panels = Lps.empty() ? Lp.bytes() + Up.bytes() : (Lps.size() + Ups.size()) * sizeof(float);
  return panels + T.bytes() + LU.bytes() + D.bytes() + (box.size() + dpiv.size() + S.size() + R.size() + I.size() + piv.size()) * sizeof(int);
}

void Step::demote()
{
  Lps.assign(Lp.a.begin(), Lp.a.end());
  Ups.assign(Up.a.begin(), Up.a.end());
  Lp.a.clear();
  Lp.a.shrink_to_fit();
  Up.a.clear();
  Up.a.shrink_to_fit();
}

void Step::forward(double *b, std::vector<double> &work) const
{
  const int k = static_cast<int>(S.size()), r = static_cast<int>(R.size()), nI = static_cast<int>(I.size());
  if (r == 0) return;
  work.resize(static_cast<std::size_t>(k) + r + nI);
  double *bs = work.data(), *br = bs + k, *bi = br + r;
  for (int i = 0; i < k; ++i) bs[i] = b[S[i]];
  for (int i = 0; i < r; ++i) br[i] = b[R[i]];
  if (k > 0) lapack::gemv('T', k, r, -1.0, T.data(), T.ld(), bs, 1.0, br);
  lapack::laswp(1, br, r, r, piv.data());
  lapack::trsv('L', 'U', r, LU.data(), LU.ld(), br);
  for (int i = 0; i < nI; ++i) bi[i] = b[I[i]];
  if (nI > 0) {
    if (Lps.empty()) lapack::gemv('N', nI, r, -1.0, Lp.data(), Lp.ld(), br, 1.0, bi);
    else gemv_single(nI, r, -1.0, Lps.data(), br, bi);
  }
  for (int i = 0; i < nI; ++i) b[I[i]] = bi[i];
  for (int i = 0; i < r; ++i) b[R[i]] = br[i];
}

void Step::backward(double *b, std::vector<double> &work) const
{
  const int k = static_cast<int>(S.size()), r = static_cast<int>(R.size()), nI = static_cast<int>(I.size());
  if (r > 0) {
    work.resize(static_cast<std::size_t>(k) + r + nI);
    double *xs = work.data(), *xr = xs + k, *xi = xr + r;
    for (int i = 0; i < r; ++i) xr[i] = b[R[i]];
    for (int i = 0; i < nI; ++i) xi[i] = b[I[i]];
    if (nI > 0) {
      if (Ups.empty()) lapack::gemv('N', r, nI, -1.0, Up.data(), Up.ld(), xi, 1.0, xr);
      else gemv_single(r, nI, -1.0, Ups.data(), xi, xr);
    }
    lapack::trsv('U', 'N', r, LU.data(), LU.ld(), xr);
    for (int i = 0; i < r; ++i) b[R[i]] = xr[i];
    if (k > 0) {
      for (int i = 0; i < k; ++i) xs[i] = b[S[i]];
      lapack::gemv('N', k, r, -1.0, T.data(), T.ld(), xr, 1.0, xs);
      for (int i = 0; i < k; ++i) b[S[i]] = xs[i];
    }
  }
  // The unknowns were A_XX x: x = A_XX⁻¹ (that).
  const int m = static_cast<int>(box.size());
  if (m == 0) return;
  work.resize(m);
  for (int i = 0; i < m; ++i) work[i] = b[box[i]];
  lapack::getrs('N', m, 1, D.data(), D.ld(), dpiv.data(), work.data(), m);
  for (int i = 0; i < m; ++i) b[box[i]] = work[i];
}

} // namespace hssbem::h2f
