// The H² factorization's solve for a block of right-hand sides (see h2_factorization.hpp): the
// steps of H2Factorization::solve() with matrix products over the block, so that the factors
// stream once per block instead of once per right-hand side (the single solve is memory-bound).
#include "factors.hpp"

#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"

#include <algorithm>
#include <stdexcept>

namespace hssbem {

namespace {

/// Rows idx of X (ld, nrhs columns) into the packed |idx| × nrhs block B, or back.
void gather(const std::vector<int> &idx, const double *X, std::size_t ld, int nrhs, double *B)
{
  const std::size_t m = idx.size();
  for (int c = 0; c < nrhs; ++c)
    for (std::size_t i = 0; i < m; ++i) B[i + c * m] = X[idx[i] + c * ld];
}

void scatter(const std::vector<int> &idx, const double *B, int nrhs, double *X, std::size_t ld)
{
  const std::size_t m = idx.size();
  for (int c = 0; c < nrhs; ++c)
    for (std::size_t i = 0; i < m; ++i) X[idx[i] + c * ld] = B[i + c * m];
}

/// A panel in double: its own entries, or the single-precision ones widened into buf.
const double *panel(const DenseMatrix &P, const std::vector<float> &Ps, std::vector<double> &buf)
{
  if (Ps.empty()) return P.data();
  buf.assign(Ps.begin(), Ps.end());
  return buf.data();
}

struct BlockWork {
  std::vector<double> s, r, i, panel;
};

void forward_block(const h2f::Step &st, double *X, std::size_t ld, int nrhs, BlockWork &w)
{
  const int k = static_cast<int>(st.S.size()), r = static_cast<int>(st.R.size()), nI = static_cast<int>(st.I.size());
  if (r == 0) return;
  w.s.resize(static_cast<std::size_t>(k) * nrhs), w.r.resize(static_cast<std::size_t>(r) * nrhs), w.i.resize(static_cast<std::size_t>(nI) * nrhs);
  gather(st.R, X, ld, nrhs, w.r.data());
  if (k > 0) {
    gather(st.S, X, ld, nrhs, w.s.data());
    lapack::gemm('T', 'N', r, nrhs, k, -1.0, st.T.data(), st.T.ld(), w.s.data(), k, 1.0, w.r.data(), r);
  }
  lapack::laswp(nrhs, w.r.data(), r, r, st.piv.data());
  lapack::trsm('L', 'L', 'N', 'U', r, nrhs, 1.0, st.LU.data(), st.LU.ld(), w.r.data(), r);
  if (nI > 0) {
    gather(st.I, X, ld, nrhs, w.i.data());
    lapack::gemm('N', 'N', nI, nrhs, r, -1.0, panel(st.Lp, st.Lps, w.panel), nI, w.r.data(), r, 1.0, w.i.data(), nI);
    scatter(st.I, w.i.data(), nrhs, X, ld);
  }
  scatter(st.R, w.r.data(), nrhs, X, ld);
}

void backward_block(const h2f::Step &st, double *X, std::size_t ld, int nrhs, BlockWork &w)
{
  const int k = static_cast<int>(st.S.size()), r = static_cast<int>(st.R.size()), nI = static_cast<int>(st.I.size());
  if (r > 0) {
    w.r.resize(static_cast<std::size_t>(r) * nrhs);
    gather(st.R, X, ld, nrhs, w.r.data());
    if (nI > 0) {
      w.i.resize(static_cast<std::size_t>(nI) * nrhs);
      gather(st.I, X, ld, nrhs, w.i.data());
      lapack::gemm('N', 'N', r, nrhs, nI, -1.0, panel(st.Up, st.Ups, w.panel), r, w.i.data(), nI, 1.0, w.r.data(), r);
    }
    lapack::trsm('L', 'U', 'N', 'N', r, nrhs, 1.0, st.LU.data(), st.LU.ld(), w.r.data(), r);
    scatter(st.R, w.r.data(), nrhs, X, ld);
    if (k > 0) {
      w.s.resize(static_cast<std::size_t>(k) * nrhs);
      gather(st.S, X, ld, nrhs, w.s.data());
      lapack::gemm('N', 'N', k, nrhs, r, -1.0, st.T.data(), st.T.ld(), w.r.data(), r, 1.0, w.s.data(), k);
      scatter(st.S, w.s.data(), nrhs, X, ld);
    }
  }
  const int m = static_cast<int>(st.box.size()); // the unknowns were A_XX x
  if (m == 0) return;
  w.s.resize(static_cast<std::size_t>(m) * nrhs);
  gather(st.box, X, ld, nrhs, w.s.data());
  lapack::getrs('N', m, nrhs, st.D.data(), st.D.ld(), st.dpiv.data(), w.s.data(), m);
  scatter(st.box, w.s.data(), nrhs, X, ld);
}

} // namespace

void H2Factorization::solve_block(double *X, int nrhs, int ld) const
{
  if (m_comm->size() != 1) throw std::logic_error("H2 factorization: a block solve needs the factorization on one rank");
  const std::size_t n = 3 * static_cast<std::size_t>(m_count);
  if (nrhs < 0 || static_cast<std::size_t>(ld) < n) throw std::invalid_argument("H2 factorization: a block solve needs nrhs >= 0 and ld >= the rows");
  PhaseScope phase(Phase::H2Solve);
  const Factors &f = *m_f;
  BlockWork w;
  for (const h2f::Step &s : f.steps) forward_block(s, X, ld, nrhs, w);
  std::vector<double> t(static_cast<std::size_t>(f.top_n));
  for (int c = 0; c < nrhs; ++c) { // the top: its own solve per column (refined in double when mixed)
    double *x = X + static_cast<std::size_t>(c) * ld;
    std::fill(t.begin(), t.end(), 0.0);
    for (std::size_t i = 0; i < f.top_own.size(); ++i) t[f.top_pos[i]] = x[f.top_own[i]];
    if (f.top) f.top->solve(t.data());
    for (std::size_t i = 0; i < f.top_own.size(); ++i) x[f.top_own[i]] = t[f.top_pos[i]];
  }
  for (auto it = f.steps.rbegin(); it != f.steps.rend(); ++it) backward_block(*it, X, ld, nrhs, w);
  for (int c = 0; c < nrhs; ++c) // A-hat = A D: x = D y
    for (std::size_t i = 0; i < n; ++i) X[i + static_cast<std::size_t>(c) * ld] *= m_K.col_scale(f.pattern.slot[i]);
}

} // namespace hssbem
