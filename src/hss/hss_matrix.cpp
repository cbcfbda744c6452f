// HSS matrix: generator storage, the O(N·r) product and rank/memory figures.
#include "hssbem/hss/hss_matrix.hpp"

#include "hssbem/compress/rank_stats.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"

#include <algorithm>
#include <numeric>

namespace hssbem {

int HssStats::max_row_rank() const { return max_level_rank(levels, true); }

int HssStats::max_col_rank() const { return max_level_rank(levels, false); }

HssMatrix::HssMatrix(ClusterTree tree, int row_block, int col_block)
  : m_tree(std::move(tree)), m_row_block(row_block), m_col_block(col_block), m_col_scale(col_block, 1.0), m_clusters(m_tree.num_clusters())
{
}

std::vector<int> HssMatrix::candidate_rows(int c) const { return basis_candidates(m_tree, m_clusters, c, m_row_block, true); }

std::vector<int> HssMatrix::candidate_cols(int c) const { return basis_candidates(m_tree, m_clusters, c, m_col_block, false); }

void HssMatrix::apply(const double *X, int ldx, double *Y, int ldy, int nrhs) const
{
  PhaseScope phase(Phase::Matvec);
  const int nc = m_tree.num_clusters();
  std::vector<DenseMatrix> xh(nc), yh(nc);
  // Upward pass: xh_τ = V_τᵀ (candidate part of x), deepest level first.
  for (int l = m_tree.levels() - 1; l >= 1; --l)
    for_each_cluster(m_tree.clusters_at_level(l), [&](int c) {
      const Cluster &cl = m_tree.cluster(c);
      const HssCluster &h = m_clusters[c];
      xh[c] = DenseMatrix(h.V.n, nrhs);
      if (cl.left < 0) {
        lapack::gemm('T', 'N', h.V.n, nrhs, h.V.m, 1.0, h.V.data(), h.V.ld(), X + static_cast<long>(m_col_block) * cl.begin, ldx, 0.0,
                     xh[c].data(), xh[c].ld());
      } else { // V_τᵀ [xh_a; xh_b], by the two row blocks of V_τ
        const DenseMatrix &a = xh[cl.left], &b = xh[cl.right];
        lapack::gemm('T', 'N', h.V.n, nrhs, a.m, 1.0, h.V.data(), h.V.ld(), a.data(), a.ld(), 0.0, xh[c].data(), xh[c].ld());
        lapack::gemm('T', 'N', h.V.n, nrhs, b.m, 1.0, h.V.data() + a.m, h.V.ld(), b.data(), b.ld(), 1.0, xh[c].data(), xh[c].ld());
      }
    });
  // Sibling couplings, then the downward pass: yh_children += U_τ yh_τ; leaves add D x.
  for (int c = 0; c < nc; ++c) {
    const Cluster &cl = m_tree.cluster(c);
    if (cl.left < 0) continue;
    yh[cl.left] = DenseMatrix(m_clusters[cl.left].U.n, nrhs);
    yh[cl.right] = DenseMatrix(m_clusters[cl.right].U.n, nrhs);
  }
  for (int l = 0; l < m_tree.levels(); ++l)
    for_each_cluster(m_tree.clusters_at_level(l), [&](int c) {
      const Cluster &cl = m_tree.cluster(c);
      const HssCluster &h = m_clusters[c];
      if (cl.left >= 0) {
        DenseMatrix &ya = yh[cl.left], &yb = yh[cl.right];
        const DenseMatrix &xa = xh[cl.left], &xb = xh[cl.right];
        lapack::gemm('N', 'N', h.B12.m, nrhs, h.B12.n, 1.0, h.B12.data(), h.B12.ld(), xb.data(), xb.ld(), 1.0, ya.data(), ya.ld());
        lapack::gemm('N', 'N', h.B21.m, nrhs, h.B21.n, 1.0, h.B21.data(), h.B21.ld(), xa.data(), xa.ld(), 1.0, yb.data(), yb.ld());
        if (c != 0) { // [ya; yb] += U_τ yh_τ, by the two row blocks of U_τ
          lapack::gemm('N', 'N', ya.m, nrhs, h.U.n, 1.0, h.U.data(), h.U.ld(), yh[c].data(), yh[c].ld(), 1.0, ya.data(), ya.ld());
          lapack::gemm('N', 'N', yb.m, nrhs, h.U.n, 1.0, h.U.data() + ya.m, h.U.ld(), yh[c].data(), yh[c].ld(), 1.0, yb.data(), yb.ld());
        }
      } else {
        double *y = Y + static_cast<long>(m_row_block) * cl.begin;
        lapack::gemm('N', 'N', h.D.m, nrhs, h.D.n, 1.0, h.D.data(), h.D.ld(), X + static_cast<long>(m_col_block) * cl.begin, ldx, 0.0, y, ldy);
        if (c != 0) lapack::gemm('N', 'N', h.U.m, nrhs, h.U.n, 1.0, h.U.data(), h.U.ld(), yh[c].data(), yh[c].ld(), 1.0, y, ldy);
      }
    });
}

void HssMatrix::update_stats()
{
  m_stats.levels.assign(m_tree.levels(), HssLevelStats{});
  std::size_t bytes = 0;
  for (int c = 0; c < m_tree.num_clusters(); ++c) {
    const HssCluster &h = m_clusters[c];
    bytes += h.U.bytes() + h.V.bytes() + h.D.bytes() + h.B12.bytes() + h.B21.bytes();
    bytes += (h.row_skel.size() + h.col_skel.size()) * sizeof(int);
    if (c != 0) add_level_ranks(m_stats.levels[m_tree.cluster(c).level], h);
  }
  finish_level_means(m_stats.levels);
  m_stats.memory_bytes = bytes;
}

} // namespace hssbem
