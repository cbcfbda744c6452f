// H² matrix: storage, the O(N·r) product and rank/memory figures.
#include "hssbem/h2/h2_matrix.hpp"

#include "hssbem/compress/rank_stats.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"

#include <algorithm>
#include <numeric>

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

void H2Matrix::apply(const double *X, int ldx, double *Y, int ldy, int nrhs) const
{
  PhaseScope phase(Phase::Matvec);
  const int nc = m_tree.num_clusters();
  std::vector<int> all(nc);
  std::iota(all.begin(), all.end(), 0);
  std::vector<DenseMatrix> xh(nc), yh(nc);
  // Upward pass: xh_τ = V_τᵀ (candidate part of x), deepest level first.
  for (int l = m_tree.levels() - 1; l >= 1; --l)
    for_each_cluster(m_tree.clusters_at_level(l), [&](int c) {
      const Cluster &cl = m_tree.cluster(c);
      const DenseMatrix &V = m_bases[c].V;
      xh[c] = DenseMatrix(V.n, nrhs);
      if (V.n == 0) return;
      if (cl.left < 0) {
        lapack::gemm('T', 'N', V.n, nrhs, V.m, 1.0, V.data(), V.ld(), X + static_cast<long>(m_col_block) * cl.begin, ldx, 0.0, xh[c].data(), xh[c].ld());
      } else {
        const DenseMatrix &a = xh[cl.left], &b = xh[cl.right];
        lapack::gemm('T', 'N', V.n, nrhs, a.m, 1.0, V.data(), V.ld(), a.data(), a.ld(), 0.0, xh[c].data(), xh[c].ld());
        lapack::gemm('T', 'N', V.n, nrhs, b.m, 1.0, V.data() + a.m, V.ld(), b.data(), b.ld(), 1.0, xh[c].data(), xh[c].ld());
      }
    });
  // Far blocks: yh_a = Σ_b K(S_a, C_b) xh_b.
  for_each_cluster(all, [&](int a) {
    yh[a] = DenseMatrix(m_bases[a].U.n, nrhs);
    std::vector<double> buf;
    for (const H2Block &B : m_far[a]) B.multiply_add(xh[B.col_cluster].data(), xh[B.col_cluster].ld(), yh[a].data(), yh[a].ld(), nrhs, buf);
  });
  // Downward pass: children's yh += U_τ yh_τ; leaves add U yh and their near blocks.
  for (int l = 1; l < m_tree.levels(); ++l)
    for_each_cluster(m_tree.clusters_at_level(l), [&](int c) {
      const Cluster &cl = m_tree.cluster(c);
      const DenseMatrix &U = m_bases[c].U;
      if (cl.left >= 0) {
        if (U.n == 0) return;
        DenseMatrix &ya = yh[cl.left], &yb = yh[cl.right];
        lapack::gemm('N', 'N', ya.m, nrhs, U.n, 1.0, U.data(), U.ld(), yh[c].data(), yh[c].ld(), 1.0, ya.data(), ya.ld());
        lapack::gemm('N', 'N', yb.m, nrhs, U.n, 1.0, U.data() + ya.m, U.ld(), yh[c].data(), yh[c].ld(), 1.0, yb.data(), yb.ld());
      }
    });
  for_each_cluster(m_tree.leaves(), [&](int c) {
    const Cluster &cl = m_tree.cluster(c);
    double *y = Y + static_cast<long>(m_row_block) * cl.begin;
    const int m = m_row_block * cl.size();
    for (int k = 0; k < nrhs; ++k) std::fill(y + static_cast<long>(k) * ldy, y + static_cast<long>(k) * ldy + m, 0.0);
    std::vector<double> buf;
    for (const H2Block &B : m_near[c]) B.multiply_add(X + static_cast<long>(m_col_block) * m_tree.cluster(B.col_cluster).begin, ldx, y, ldy, nrhs, buf);
    const DenseMatrix &U = m_bases[c].U;
    if (U.n > 0) lapack::gemm('N', 'N', U.m, nrhs, U.n, 1.0, U.data(), U.ld(), yh[c].data(), yh[c].ld(), 1.0, y, ldy);
  });
}

void H2Matrix::update_stats()
{
  const double eta = m_stats.eta;
  m_stats.levels.assign(m_tree.levels(), H2LevelStats{});
  m_stats.eta = eta;
  m_stats.basis_bytes = m_stats.far_bytes = m_stats.near_bytes = 0;
  m_stats.far_blocks = m_stats.near_blocks = 0;
  for (int c = 0; c < m_tree.num_clusters(); ++c) {
    const NestedBasis &b = m_bases[c];
    m_stats.basis_bytes += b.U.bytes() + b.V.bytes() + (b.row_skel.size() + b.col_skel.size()) * sizeof(int);
    for (const H2Block &B : m_far[c]) m_stats.far_bytes += B.bytes() + sizeof(H2Block);
    for (const H2Block &B : m_near[c]) m_stats.near_bytes += B.bytes() + sizeof(H2Block);
    m_stats.far_blocks += static_cast<long>(m_far[c].size());
    m_stats.near_blocks += static_cast<long>(m_near[c].size());
    H2LevelStats &s = m_stats.levels[m_tree.cluster(c).level];
    s.far_blocks += static_cast<long>(m_far[c].size());
    if (m_partition.has_far[c]) add_level_ranks(s, b); // the root never has far blocks
  }
  finish_level_means(m_stats.levels);
  m_stats.memory_bytes = m_stats.basis_bytes + m_stats.far_bytes + m_stats.near_bytes;
}

} // namespace hssbem
