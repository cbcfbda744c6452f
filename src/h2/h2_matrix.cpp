// H² matrix: storage, the O(N·r) product and rank/memory figures.
#include "hssbem/h2/h2_matrix.hpp"

#include "hssbem/compress/rank_stats.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"
#include "h2_transfer.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace hssbem {

int H2Stats::max_row_rank() const { return max_level_rank(levels, true); }

int H2Stats::max_col_rank() const { return max_level_rank(levels, false); }

H2Matrix::H2Matrix(ClusterTree tree, int row_block, int col_block)
  : m_tree(std::move(tree)), m_row_block(row_block), m_col_block(col_block), m_col_scale(col_block, 1.0), m_bases(m_tree.num_clusters()),
    m_far(m_tree.num_clusters()), m_near(m_tree.num_clusters())
{
}

const H2Block *H2Matrix::near_block(int a, int b) const
{
  const std::vector<int> &near = m_partition.near[a];
  const auto it = std::lower_bound(near.begin(), near.end(), b);
  return it != near.end() && *it == b ? &m_near[a][it - near.begin()] : nullptr;
}

H2Block *H2Matrix::near_block(int a, int b) { return const_cast<H2Block *>(static_cast<const H2Matrix &>(*this).near_block(a, b)); }

namespace {

using Size = std::size_t;
using transfer::CandidateRows;
using transfer::interp_n;
using transfer::interp_t;

/// Upward pass over stored bases (m_V for the columns, m_U for the rows): moments[c] = B_cᵀ
/// (c's candidate part of X), deepest level first; `block` rows of X per point.
std::vector<DenseMatrix> upward_moments(const ClusterTree &tree, const std::vector<StoredInterpolation> &bases, int block, const double *X, int ldx, int nrhs)
{
  std::vector<DenseMatrix> xh(tree.num_clusters());
  for (int l = tree.levels() - 1; l >= 1; --l)
    for_each_cluster(tree.clusters_at_level(l), [&](int c) {
      const Cluster &cl = tree.cluster(c);
      const StoredInterpolation &B = bases[c];
      xh[c] = DenseMatrix(B.rank(), nrhs);
      if (B.rank() == 0) return;
      CandidateRows<const double> x;
      if (cl.left < 0) x.base = X + static_cast<long>(block) * cl.begin, x.ld = ldx;
      else x.a = &xh[cl.left], x.b = &xh[cl.right];
      std::vector<double> buf;
      interp_t(B, x, nrhs, xh[c].data(), xh[c].ld(), buf);
    });
  return xh;
}

/// Downward transfers over stored bases, top down: each child's potential gains its part of the
/// parent's, pot[child] += B_parent(child's rows) pot[parent].
void downward_transfers(const ClusterTree &tree, const std::vector<StoredInterpolation> &bases, std::vector<DenseMatrix> &pot, int nrhs)
{
  for (int l = 1; l < tree.levels(); ++l)
    for_each_cluster(tree.clusters_at_level(l), [&](int c) {
      const Cluster &cl = tree.cluster(c);
      if (cl.left < 0) return;
      CandidateRows<double> y;
      y.a = &pot[cl.left], y.b = &pot[cl.right];
      std::vector<double> buf;
      interp_n(bases[c], pot[c].data(), pot[c].ld(), nrhs, y, buf);
    });
}

} // namespace

DenseMatrix StoredInterpolation::expand() const
{
  const int k = rank();
  DenseMatrix U(candidates, k);
  for (int t = 0; t < k; ++t) U(skel_pos[t], t) = 1.0;
  for (Size j = 0; j < red_pos.size(); ++j)
    for (int t = 0; t < k; ++t) U(red_pos[j], t) = Tf.empty() ? Td[t + j * k] : Tf[t + j * k];
  return U;
}

StoredInterpolation StoredInterpolation::from(const DenseMatrix &U, const std::vector<int> &cands, const std::vector<int> &skel, bool single)
{
  StoredInterpolation s;
  s.candidates = static_cast<int>(cands.size());
  const int k = static_cast<int>(skel.size());
  if (k == 0) return s; // no basis (the root, or a cluster without far blocks)
  if (U.n != k || U.m != s.candidates) throw std::logic_error("StoredInterpolation: U does not match its candidates and skeleton");
  std::vector<int> at(cands.size(), -1); // candidate position -> skeleton column
  for (int t = 0; t < k; ++t) {
    const int p = static_cast<int>(std::find(cands.begin(), cands.end(), skel[t]) - cands.begin());
    if (p == s.candidates) throw std::logic_error("StoredInterpolation: a skeleton index is no candidate");
    s.skel_pos.push_back(p);
    at[p] = t;
  }
  for (int p = 0; p < s.candidates; ++p)
    if (at[p] < 0) s.red_pos.push_back(p);
  std::vector<double> T(Size(k) * s.red_pos.size());
  for (Size j = 0; j < s.red_pos.size(); ++j)
    for (int t = 0; t < k; ++t) T[t + j * k] = U(s.red_pos[j], t);
  if (single) s.Tf.assign(T.begin(), T.end());
  else s.Td = std::move(T);
  return s;
}

NestedBasis H2Matrix::basis(int c) const
{
  if (!m_bases.empty()) return m_bases[c];
  NestedBasis b;
  b.row_skel = m_row_skel[c];
  b.col_skel = m_col_skel[c];
  b.U = m_U[c].expand();
  b.V = m_V[c].expand();
  b.row_forced = m_row_forced[c];
  b.col_forced = m_col_forced[c];
  return b;
}

void H2Matrix::prepare_stored_bases()
{
  const std::size_t nc = static_cast<std::size_t>(m_tree.num_clusters());
  if (m_basis_stored.size() == nc) return;
  m_U.assign(nc, {});
  m_V.assign(nc, {});
  m_row_forced.assign(nc, 0);
  m_col_forced.assign(nc, 0);
  m_basis_stored.assign(nc, 0);
}

void H2Matrix::store_basis(int c, bool single)
{
  if (m_basis_stored[c] || !holds(c)) return; // another rank's: its skeletons only
  NestedBasis &b = m_bases[c];
  m_U[c] = StoredInterpolation::from(b.U, basis_candidates(m_tree, m_bases, c, m_row_block, true), b.row_skel, single);
  m_V[c] = StoredInterpolation::from(b.V, basis_candidates(m_tree, m_bases, c, m_col_block, false), b.col_skel, single);
  m_row_forced[c] = b.row_forced;
  m_col_forced[c] = b.col_forced;
  b.U = DenseMatrix();
  b.V = DenseMatrix();
  m_basis_stored[c] = 1;
}

void H2Matrix::store_level_bases(int l, bool single)
{
  prepare_stored_bases();
  for_each_cluster(m_tree.clusters_at_level(l), [&](int c) { store_basis(c, single); });
}

void H2Matrix::store_bases(bool single)
{
  prepare_stored_bases();
  const int nc = m_tree.num_clusters();
  std::vector<int> all(nc);
  std::iota(all.begin(), all.end(), 0);
  for_each_cluster(all, [&](int c) { store_basis(c, single); });
  m_row_skel.resize(nc);
  m_col_skel.resize(nc);
  for (int c = 0; c < nc; ++c) {
    m_row_skel[c] = std::move(m_bases[c].row_skel);
    m_col_skel[c] = std::move(m_bases[c].col_skel);
  }
  m_bases.clear();
  m_bases.shrink_to_fit();
  std::vector<char>().swap(m_basis_stored);
}

std::vector<DenseMatrix> H2Matrix::skeleton_far_field(const double *X, int ldx, int nrhs) const
{
  if (!m_bases.empty()) throw std::logic_error("H2Matrix: the bases are not stored yet (store_bases)");
  const int nc = m_tree.num_clusters();
  std::vector<int> all(nc);
  std::iota(all.begin(), all.end(), 0);
  const std::vector<DenseMatrix> xh = upward_moments(m_tree, m_V, m_col_block, X, ldx, nrhs);
  std::vector<DenseMatrix> yh(nc);
  // Far blocks: yh_a = Σ_b K(S_a, C_b) xh_b.
  for_each_cluster(all, [&](int a) {
    yh[a] = DenseMatrix(m_U[a].rank(), nrhs);
    std::vector<double> buf;
    for (const H2Block &B : m_far[a]) B.multiply_add(xh[B.col_cluster].data(), xh[B.col_cluster].ld(), yh[a].data(), yh[a].ld(), nrhs, buf);
  });
  downward_transfers(m_tree, m_U, yh, nrhs);
  return yh;
}

std::vector<DenseMatrix> H2Matrix::skeleton_far_field_transposed(const double *Y, int ldy, int nrhs) const
{
  if (!m_bases.empty()) throw std::logic_error("H2Matrix: the bases are not stored yet (store_bases)");
  const int nc = m_tree.num_clusters();
  const std::vector<DenseMatrix> yh = upward_moments(m_tree, m_U, m_row_block, Y, ldy, nrhs);
  // Far blocks transposed, gathered per column cluster: xh_b = Σ_a K(S_a, C_b)ᵀ yh_a.
  std::vector<std::vector<std::pair<int, int>>> by_col(nc);
  for (int a = 0; a < nc; ++a)
    for (std::size_t i = 0; i < m_far[a].size(); ++i) by_col[m_far[a][i].col_cluster].push_back({a, static_cast<int>(i)});
  std::vector<int> all(nc);
  std::iota(all.begin(), all.end(), 0);
  std::vector<DenseMatrix> xh(nc);
  for_each_cluster(all, [&](int b) {
    xh[b] = DenseMatrix(m_V[b].rank(), nrhs);
    std::vector<double> buf;
    for (const auto &[a, i] : by_col[b]) m_far[a][i].multiply_add_transposed(yh[a].data(), yh[a].ld(), xh[b].data(), xh[b].ld(), nrhs, buf);
  });
  downward_transfers(m_tree, m_V, xh, nrhs);
  return xh;
}

void H2Matrix::apply(const double *X, int ldx, double *Y, int ldy, int nrhs) const
{
  PhaseScope phase(Phase::H2Matvec);
  const std::vector<DenseMatrix> yh = skeleton_far_field(X, ldx, nrhs);
  // Leaves: the far field through their row bases, plus their near blocks.
  for_each_cluster(m_tree.leaves(), [&](int c) {
    const Cluster &cl = m_tree.cluster(c);
    double *y = Y + static_cast<long>(m_row_block) * cl.begin;
    const int m = m_row_block * cl.size();
    for (int k = 0; k < nrhs; ++k) std::fill(y + static_cast<long>(k) * ldy, y + static_cast<long>(k) * ldy + m, 0.0);
    std::vector<double> buf;
    for (const H2Block &B : m_near[c]) B.multiply_add(X + static_cast<long>(m_col_block) * m_tree.cluster(B.col_cluster).begin, ldx, y, ldy, nrhs, buf);
    CandidateRows<double> rows;
    rows.base = y, rows.ld = ldy;
    interp_n(m_U[c], yh[c].data(), yh[c].ld(), nrhs, rows, buf);
  });
}

void H2Matrix::adopt(int c, StoredInterpolation U, StoredInterpolation V, std::vector<H2Block> far, std::vector<H2Block> near)
{
  if (!m_bases.empty()) throw std::logic_error("H2Matrix: the bases are not stored yet (store_bases)");
  m_U[c] = std::move(U);
  m_V[c] = std::move(V);
  m_far[c] = std::move(far);
  m_near[c] = std::move(near);
}

void H2Matrix::update_stats()
{
  const double eta = m_stats.eta;
  m_stats.levels.assign(m_tree.levels(), H2LevelStats{});
  m_stats.eta = eta;
  m_stats.basis_bytes = m_stats.far_bytes = m_stats.near_bytes = 0;
  m_stats.far_blocks = m_stats.near_blocks = 0;
  for (int c = 0; c < m_tree.num_clusters(); ++c) {
    // skeleton sizes, known for every cluster on every rank
    const int kr = static_cast<int>(m_bases.empty() ? m_row_skel[c].size() : m_bases[c].row_skel.size()),
              kc = static_cast<int>(m_bases.empty() ? m_col_skel[c].size() : m_bases[c].col_skel.size());
    if (m_bases.empty())
      m_stats.basis_bytes += m_U[c].bytes() + m_V[c].bytes() + (m_row_skel[c].size() + m_col_skel[c].size()) * sizeof(int);
    else
      m_stats.basis_bytes += m_bases[c].U.bytes() + m_bases[c].V.bytes() + (m_bases[c].row_skel.size() + m_bases[c].col_skel.size()) * sizeof(int);
    for (const H2Block &B : m_far[c]) m_stats.far_bytes += B.bytes() + sizeof(H2Block);
    for (const H2Block &B : m_near[c]) m_stats.near_bytes += B.bytes() + sizeof(H2Block);
    m_stats.far_blocks += static_cast<long>(m_far[c].size());
    m_stats.near_blocks += static_cast<long>(m_near[c].size());
    H2LevelStats &s = m_stats.levels[m_tree.cluster(c).level];
    s.far_blocks += static_cast<long>(m_far[c].size());
    if (m_partition.has_far[c]) add_level_ranks(s, kr, kc); // the root never has far blocks
  }
  finish_level_means(m_stats.levels);
  m_stats.memory_bytes = m_stats.basis_bytes + m_stats.far_bytes + m_stats.near_bytes;
}

} // namespace hssbem
