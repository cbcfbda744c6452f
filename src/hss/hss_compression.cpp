// Entries-only HSS compression of K = [H, G(, Gn)] with proxy spheres (see hss_compression.hpp).
#include "hssbem/hss/hss_compression.hpp"

#include "hssbem/compress/compression.hpp"
#include "hssbem/compress/kernel_blocks.hpp"
#include "hssbem/compress/rigid_body_blocks.hpp"
#include "hssbem/compress/skeletonizer.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

std::vector<double> col_scales(const HssMatrix &K)
{
  std::vector<double> s(K.col_block());
  for (int q = 0; q < K.col_block(); ++q) s[q] = K.col_scale(q);
  return s;
}

std::vector<NestedBasis *> basis_pointers(HssMatrix &K)
{
  std::vector<NestedBasis *> p(K.tree().num_clusters());
  for (int c = 0; c < K.tree().num_clusters(); ++c) p[c] = &K.cluster(c);
  return p;
}

/// Skeletons by weak admissibility (every cluster against everything outside it), the sibling
/// couplings and the leaves' diagonal blocks.
class Compressor {
public:
  Compressor(const BemOperator &op, const HssOptions &opt, HssMatrix &K)
    : m_K(K), m_tree(K.tree()),
      m_skel(op, SkeletonizerOptions{opt.rel_tol, opt.max_rank, opt.proxy_ratio, opt.proxy_points > 0 ? opt.proxy_points : default_proxy_points(opt.rel_tol), true},
             K.tree(), K.col_block(), col_scales(K), basis_pointers(K))
  {
    m_K.stats().proxy_points = m_skel.proxy_points();
  }

  /// Skeletons and couplings, level by level from the leaves up.
  void skeletonize()
  {
    for (int l = m_tree.levels() - 1; l >= 1; --l) {
      m_skel.skeletonize_level(l, Skeletonizer::all_others);
      const Timer timer;
      for_each_cluster(m_tree.clusters_at_level(l - 1), [this](int c) { couple_children(c); });
      m_K.stats().time_couplings += timer.seconds();
    }
  }

  /// The leaves' diagonal blocks (true entries), then the totals of the counters.
  void fill_leaves()
  {
    const Timer timer;
    for_each_cluster(m_tree.leaves(), [this](int c) { fill_leaf(c); });
    m_K.stats().time_leaves = timer.seconds();
    m_K.stats().entries_evaluated += m_skel.entries();
    m_K.stats().time_near_field += m_skel.time_near_field();
    m_K.stats().time_ids += m_skel.time_ids();
  }

private:
  void couple_children(int c)
  {
    const Cluster &cl = m_tree.cluster(c);
    if (cl.left < 0) return;
    HssCluster &h = m_K.cluster(c);
    const HssCluster &a = m_K.cluster(cl.left), &b = m_K.cluster(cl.right);
    h.B12 = DenseMatrix(static_cast<int>(a.row_skel.size()), static_cast<int>(b.col_skel.size()));
    h.B21 = DenseMatrix(static_cast<int>(b.row_skel.size()), static_cast<int>(a.col_skel.size()));
    m_skel.block(a.row_skel, b.col_skel, h.B12.data(), 1, h.B12.ld());
    m_skel.block(b.row_skel, a.col_skel, h.B21.data(), 1, h.B21.ld());
  }

  void fill_leaf(int c)
  {
    HssCluster &h = m_K.cluster(c);
    const std::vector<int> rows = m_K.candidate_rows(c), cols = m_K.candidate_cols(c);
    h.D = DenseMatrix(static_cast<int>(rows.size()), static_cast<int>(cols.size()));
    m_skel.block(rows, cols, h.D.data(), 1, h.D.ld());
  }

  HssMatrix &m_K;
  const ClusterTree &m_tree;
  Skeletonizer m_skel;
};

/// Rigid-body terms by a fast matvec (D_i = −Σ_j H⁰(i, j)), then added where they belong: a
/// leaf's diagonal block, or the skeleton coupling of the two clusters that separate row and column.
void add_rigid_body_terms(const BemOperator &op, HssMatrix &K)
{
  const ClusterTree &tree = K.tree();
  const int w = K.col_block();
  const std::vector<double> rigid = rigid_body_blocks(K);
  const std::vector<int> leaf_of = tree.leaf_of_positions();
  auto position = [](const std::vector<int> &list, int value) {
    const auto it = std::find(list.begin(), list.end(), value);
    if (it == list.end()) throw std::logic_error("HSS compression: a rigid-body coupling is missing from a skeleton");
    return static_cast<int>(it - list.begin());
  };
  for (int i = 0; i < op.num_nodes(); ++i) {
    const int pi = tree.iperm()[i];
    const double *Dm = &rigid[9 * static_cast<std::size_t>(pi)];
    int cols[3];
    double wts[3];
    const int nc = op.rigid_body_columns(i, cols, wts);
    for (int a = 0; a < nc; ++a) {
      const int pj = tree.iperm()[cols[a]];
      int ci = leaf_of[pi];
      if (leaf_of[pj] == ci) {
        const Cluster &cl = tree.cluster(ci);
        DenseMatrix &D = K.cluster(ci).D;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) D(3 * (pi - cl.begin) + r, w * (pj - cl.begin) + c) += wts[a] * Dm[3 * r + c];
        continue;
      }
      // Climb to the child of the lowest common ancestor that holds the row.
      while (true) {
        const int p = tree.cluster(ci).parent;
        if (pj >= tree.cluster(p).begin && pj < tree.cluster(p).end) break;
        ci = p;
      }
      const int parent = tree.cluster(ci).parent;
      const bool left = tree.cluster(parent).left == ci;
      const int cj = left ? tree.cluster(parent).right : tree.cluster(parent).left;
      DenseMatrix &B = left ? K.cluster(parent).B12 : K.cluster(parent).B21;
      for (int r = 0; r < 3; ++r) {
        const int row = position(K.cluster(ci).row_skel, 3 * pi + r);
        for (int c = 0; c < 3; ++c) B(row, position(K.cluster(cj).col_skel, w * pj + c)) += wts[a] * Dm[3 * r + c];
      }
    }
  }
}

} // namespace

HssMatrix compress_bem_operator_hss(const BemOperator &op, const HssOptions &options)
{
  check_compression_inputs(op, options, "HSS");
  Timer timer;
  std::optional<PhaseScope> phase(Phase::Tree);
  HssMatrix K(ClusterTree(collocation_points(op.discretization()), ClusterTreeOptions{options.leaf_size}), 3, k_columns_per_node(options.pressure_columns));
  phase.reset();
  phase.emplace(Phase::Compression);
  K.set_col_scales(kernel_column_scales(op, K.col_block()));
  K.stats().time_tree = timer.seconds();
  Compressor compressor(op, options, K);
  compressor.skeletonize();
  phase.reset();
  phase.emplace(Phase::NearField);
  compressor.fill_leaves();
  timer.restart();
  add_rigid_body_terms(op, K);
  K.stats().time_rigid = timer.seconds();
  phase.reset();
  K.update_stats();
  return K;
}

} // namespace hssbem
