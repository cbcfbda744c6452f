// HSS matrix: generator storage, the O(N·r) product and rank/memory figures.
#include "hssbem/hss/hss_matrix.hpp"

#include "hssbem/compress/rank_stats.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"
#include "hss_product_steps.hpp"

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
  for (int l = m_tree.levels() - 1; l >= 1; --l)
    for_each_cluster(m_tree.clusters_at_level(l), [&](int c) { hss_steps::upward(*this, c, X, ldx, 0, nrhs, xh); });
  for (int l = 0; l < m_tree.levels(); ++l)
    for_each_cluster(m_tree.clusters_at_level(l), [&](int c) {
      if (m_tree.is_leaf(c)) hss_steps::leaf(*this, c, X, ldx, Y, ldy, 0, nrhs, yh);
      else hss_steps::downward_inner(*this, c, nrhs, xh, yh);
    });
}

namespace hss_steps {

void upward(const HssMatrix &K, int c, const double *X, int ldx, int first, int nrhs, std::vector<DenseMatrix> &xh)
{
  const Cluster &cl = K.tree().cluster(c);
  const HssCluster &h = K.cluster(c);
  xh[c] = DenseMatrix(h.V.n, nrhs);
  if (cl.left < 0) {
    lapack::gemm('T', 'N', h.V.n, nrhs, h.V.m, 1.0, h.V.data(), h.V.ld(), X + static_cast<long>(K.col_block()) * (cl.begin - first), ldx, 0.0, xh[c].data(),
                 xh[c].ld());
    return;
  }
  // V_τᵀ [xh_a; xh_b], by the two row blocks of V_τ
  const DenseMatrix &a = xh[cl.left], &b = xh[cl.right];
  lapack::gemm('T', 'N', h.V.n, nrhs, a.m, 1.0, h.V.data(), h.V.ld(), a.data(), a.ld(), 0.0, xh[c].data(), xh[c].ld());
  lapack::gemm('T', 'N', h.V.n, nrhs, b.m, 1.0, h.V.data() + a.m, h.V.ld(), b.data(), b.ld(), 1.0, xh[c].data(), xh[c].ld());
}

void downward_inner(const HssMatrix &K, int c, int nrhs, const std::vector<DenseMatrix> &xh, std::vector<DenseMatrix> &yh)
{
  const Cluster &cl = K.tree().cluster(c);
  const HssCluster &h = K.cluster(c);
  for (int ch : {cl.left, cl.right}) { // a child's rank from its skeleton (its U may be another rank's)
    const int k = static_cast<int>(K.cluster(ch).row_skel.size());
    if (yh[ch].m != k || yh[ch].n != nrhs) yh[ch] = DenseMatrix(k, nrhs);
  }
  DenseMatrix &ya = yh[cl.left], &yb = yh[cl.right];
  const DenseMatrix &xa = xh[cl.left], &xb = xh[cl.right];
  lapack::gemm('N', 'N', h.B12.m, nrhs, h.B12.n, 1.0, h.B12.data(), h.B12.ld(), xb.data(), xb.ld(), 1.0, ya.data(), ya.ld());
  lapack::gemm('N', 'N', h.B21.m, nrhs, h.B21.n, 1.0, h.B21.data(), h.B21.ld(), xa.data(), xa.ld(), 1.0, yb.data(), yb.ld());
  if (c == 0) return;
  // [ya; yb] += U_τ yh_τ, by the two row blocks of U_τ
  lapack::gemm('N', 'N', ya.m, nrhs, h.U.n, 1.0, h.U.data(), h.U.ld(), yh[c].data(), yh[c].ld(), 1.0, ya.data(), ya.ld());
  lapack::gemm('N', 'N', yb.m, nrhs, h.U.n, 1.0, h.U.data() + ya.m, h.U.ld(), yh[c].data(), yh[c].ld(), 1.0, yb.data(), yb.ld());
}

void leaf(const HssMatrix &K, int c, const double *X, int ldx, double *Y, int ldy, int first, int nrhs, const std::vector<DenseMatrix> &yh)
{
  const Cluster &cl = K.tree().cluster(c);
  const HssCluster &h = K.cluster(c);
  double *y = Y + static_cast<long>(K.row_block()) * (cl.begin - first);
  lapack::gemm('N', 'N', h.D.m, nrhs, h.D.n, 1.0, h.D.data(), h.D.ld(), X + static_cast<long>(K.col_block()) * (cl.begin - first), ldx, 0.0, y, ldy);
  if (c != 0) lapack::gemm('N', 'N', h.U.m, nrhs, h.U.n, 1.0, h.U.data(), h.U.ld(), yh[c].data(), yh[c].ld(), 1.0, y, ldy);
}

} // namespace hss_steps

void HssMatrix::update_stats()
{
  m_stats.levels.assign(m_tree.levels(), HssLevelStats{});
  const std::vector<int> part = m_tree.num_parts() > 1 ? cluster_parts(m_tree) : std::vector<int>(m_tree.num_clusters(), 0);
  std::size_t bytes = 0, top = 0;
  m_stats.top_clusters = 0;
  for (int c = 0; c < m_tree.num_clusters(); ++c) {
    const HssCluster &h = m_clusters[c];
    const std::size_t b = h.U.bytes() + h.V.bytes() + h.D.bytes() + h.B12.bytes() + h.B21.bytes() + (h.row_skel.size() + h.col_skel.size()) * sizeof(int);
    m_stats.top_clusters += part[c] < 0;
    if (holds(c)) bytes += b;
    if (holds(c) && part[c] < 0) top += b;
    if (c != 0) add_level_ranks(m_stats.levels[m_tree.cluster(c).level], h);
  }
  finish_level_means(m_stats.levels);
  m_stats.memory_bytes = bytes;
  m_stats.top_bytes = top;
}

} // namespace hssbem
