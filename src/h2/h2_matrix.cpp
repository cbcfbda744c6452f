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

void H2Block::demote()
{
  if (M.a.empty()) return;
  single.assign(M.a.begin(), M.a.end());
  M.a.clear();
  M.a.shrink_to_fit();
}

const double *H2Block::data(std::vector<double> &buf) const
{
  if (!is_single()) return M.data();
  buf.assign(single.begin(), single.end());
  return buf.data();
}

namespace {

/// y += A x for a column-major float matrix A (m × n) and double x, y: four columns at a time,
/// widening each entry as it is used.
void mixed_gemv(int m, int n, const float *A, const double *x, double *y)
{
  int j = 0;
  for (; j + 4 <= n; j += 4) {
    const float *a0 = A + static_cast<std::size_t>(j) * m, *a1 = a0 + m, *a2 = a1 + m, *a3 = a2 + m;
    const double x0 = x[j], x1 = x[j + 1], x2 = x[j + 2], x3 = x[j + 3];
    for (int i = 0; i < m; ++i)
      y[i] += (static_cast<double>(a0[i]) * x0 + static_cast<double>(a1[i]) * x1) + (static_cast<double>(a2[i]) * x2 + static_cast<double>(a3[i]) * x3);
  }
  for (; j < n; ++j) {
    const float *a = A + static_cast<std::size_t>(j) * m;
    const double xj = x[j];
    for (int i = 0; i < m; ++i) y[i] += static_cast<double>(a[i]) * xj;
  }
}

} // namespace

void H2Block::multiply_add(const double *X, int ldx, double *Y, int ldy, int nrhs, std::vector<double> &buf) const
{
  if (M.m == 0 || M.n == 0 || nrhs == 0) return;
  if (is_single() && nrhs == 1) return mixed_gemv(M.m, M.n, single.data(), X, Y);
  lapack::gemm('N', 'N', M.m, nrhs, M.n, 1.0, data(buf), M.ld(), X, ldx, 1.0, Y, ldy);
}

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

/// Upward pass over the row (rows = true) or column bases: moments[c] = B_cᵀ (c's candidate
/// part of X), deepest level first; `block` rows of X per point.
std::vector<DenseMatrix> upward_moments(const ClusterTree &tree, const std::vector<NestedBasis> &bases, bool rows, int block, const double *X, int ldx, int nrhs)
{
  std::vector<DenseMatrix> xh(tree.num_clusters());
  for (int l = tree.levels() - 1; l >= 1; --l)
    for_each_cluster(tree.clusters_at_level(l), [&](int c) {
      const Cluster &cl = tree.cluster(c);
      const DenseMatrix &B = rows ? bases[c].U : bases[c].V;
      xh[c] = DenseMatrix(B.n, nrhs);
      if (B.n == 0) return;
      if (cl.left < 0) {
        lapack::gemm('T', 'N', B.n, nrhs, B.m, 1.0, B.data(), B.ld(), X + static_cast<long>(block) * cl.begin, ldx, 0.0, xh[c].data(), xh[c].ld());
      } else {
        const DenseMatrix &a = xh[cl.left], &b = xh[cl.right];
        lapack::gemm('T', 'N', B.n, nrhs, a.m, 1.0, B.data(), B.ld(), a.data(), a.ld(), 0.0, xh[c].data(), xh[c].ld());
        lapack::gemm('T', 'N', B.n, nrhs, b.m, 1.0, B.data() + a.m, B.ld(), b.data(), b.ld(), 1.0, xh[c].data(), xh[c].ld());
      }
    });
  return xh;
}

/// Downward transfers over the row (rows = true) or column bases, top down: each child's
/// potential gains its part of the parent's, pot[child] += B_parent(child's rows) pot[parent].
void downward_transfers(const ClusterTree &tree, const std::vector<NestedBasis> &bases, bool rows, std::vector<DenseMatrix> &pot, int nrhs)
{
  for (int l = 1; l < tree.levels(); ++l)
    for_each_cluster(tree.clusters_at_level(l), [&](int c) {
      const Cluster &cl = tree.cluster(c);
      const DenseMatrix &B = rows ? bases[c].U : bases[c].V;
      if (cl.left < 0 || B.n == 0) return;
      DenseMatrix &ya = pot[cl.left], &yb = pot[cl.right];
      lapack::gemm('N', 'N', ya.m, nrhs, B.n, 1.0, B.data(), B.ld(), pot[c].data(), pot[c].ld(), 1.0, ya.data(), ya.ld());
      lapack::gemm('N', 'N', yb.m, nrhs, B.n, 1.0, B.data() + ya.m, B.ld(), pot[c].data(), pot[c].ld(), 1.0, yb.data(), yb.ld());
    });
}

} // namespace

std::vector<DenseMatrix> H2Matrix::skeleton_far_field(const double *X, int ldx, int nrhs) const
{
  const int nc = m_tree.num_clusters();
  std::vector<int> all(nc);
  std::iota(all.begin(), all.end(), 0);
  const std::vector<DenseMatrix> xh = upward_moments(m_tree, m_bases, false, m_col_block, X, ldx, nrhs);
  std::vector<DenseMatrix> yh(nc);
  // Far blocks: yh_a = Σ_b K(S_a, C_b) xh_b.
  for_each_cluster(all, [&](int a) {
    yh[a] = DenseMatrix(m_bases[a].U.n, nrhs);
    std::vector<double> buf;
    for (const H2Block &B : m_far[a]) B.multiply_add(xh[B.col_cluster].data(), xh[B.col_cluster].ld(), yh[a].data(), yh[a].ld(), nrhs, buf);
  });
  downward_transfers(m_tree, m_bases, true, yh, nrhs);
  return yh;
}

std::vector<DenseMatrix> H2Matrix::skeleton_far_field_transposed(const double *Y, int ldy, int nrhs) const
{
  const int nc = m_tree.num_clusters();
  const std::vector<DenseMatrix> yh = upward_moments(m_tree, m_bases, true, m_row_block, Y, ldy, nrhs);
  // Far blocks transposed, gathered per column cluster: xh_b = Σ_a K(S_a, C_b)ᵀ yh_a.
  std::vector<std::vector<std::pair<int, int>>> by_col(nc);
  for (int a = 0; a < nc; ++a)
    for (std::size_t i = 0; i < m_far[a].size(); ++i) by_col[m_far[a][i].col_cluster].push_back({a, static_cast<int>(i)});
  std::vector<int> all(nc);
  std::iota(all.begin(), all.end(), 0);
  std::vector<DenseMatrix> xh(nc);
  for_each_cluster(all, [&](int b) {
    xh[b] = DenseMatrix(m_bases[b].V.n, nrhs);
    std::vector<double> buf;
    for (const auto &[a, i] : by_col[b]) {
      const H2Block &B = m_far[a][i];
      if (B.M.m > 0 && B.M.n > 0)
        lapack::gemm('T', 'N', B.M.n, nrhs, B.M.m, 1.0, B.data(buf), B.M.ld(), yh[a].data(), yh[a].ld(), 1.0, xh[b].data(), xh[b].ld());
    }
  });
  downward_transfers(m_tree, m_bases, false, xh, nrhs);
  return xh;
}

void H2Matrix::apply(const double *X, int ldx, double *Y, int ldy, int nrhs) const
{
  PhaseScope phase(Phase::Matvec);
  const std::vector<DenseMatrix> yh = skeleton_far_field(X, ldx, nrhs);
  // Leaves: the far field through their row bases, plus their near blocks.
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
