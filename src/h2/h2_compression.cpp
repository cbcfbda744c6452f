// Entries-only H² compression of K = [H, G(, Gn)] (see h2_compression.hpp).
#include "hssbem/h2/h2_compression.hpp"

#include "hssbem/compress/compression.hpp"
#include "hssbem/compress/kernel_blocks.hpp"
#include "hssbem/compress/rigid_body_blocks.hpp"
#include "hssbem/compress/skeletonizer.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <numeric>
#include <optional>
#include <stdexcept>

namespace hssbem {

namespace {

/// The clusters that c must be compressed against while its level is skeletonized: every
/// frontier cluster that is not close to c (far from c or from an ancestor), and, when c is a
/// leaf, the clusters below a close frontier cluster that are far from c.
void strong_sources(const ClusterTree &tree, const BlockPartition &p, int c, const std::vector<int> &front, std::vector<int> &out)
{
  std::vector<int> stack;
  for (int f : front) {
    if (f == c) continue;
    if (!p.is_close(c, f)) {
      out.push_back(f);
      continue;
    }
    if (tree.cluster(c).left >= 0) continue; // resolved by c's children
    stack.assign({f});
    while (!stack.empty()) {
      const int g = stack.back();
      stack.pop_back();
      const Cluster &cg = tree.cluster(g);
      if (cg.left < 0) continue;
      for (int h : {cg.left, cg.right}) {
        if (p.is_far(c, h))
          out.push_back(h);
        else if (p.is_close(c, h))
          stack.push_back(h);
      }
    }
  }
}

/// The `block` indices per point of leaf c (its rows or columns).
std::vector<int> leaf_indices(const ClusterTree &tree, int c, int block)
{
  std::vector<int> out(static_cast<std::size_t>(block) * tree.cluster(c).size());
  std::iota(out.begin(), out.end(), block * tree.cluster(c).begin);
  return out;
}

/// Per leaf a: the leaves (ascending) whose columns a's rows couple to through rigid-body terms.
std::vector<std::vector<int>> rigid_term_leaves(const BemOperator &op, const ClusterTree &tree)
{
  std::vector<std::vector<int>> out(tree.num_clusters());
  const std::vector<int> leaf_of = tree.leaf_of_positions();
  for (int i = 0; i < op.num_nodes(); ++i) {
    int cols[3];
    double wts[3];
    const int a = leaf_of[tree.iperm()[i]], nc = op.rigid_body_columns(i, cols, wts);
    for (int t = 0; t < nc; ++t) out[a].push_back(leaf_of[tree.iperm()[cols[t]]]);
  }
  for (std::vector<int> &v : out) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  }
  return out;
}

/// Add the rigid-body terms (rigid_body_blocks.hpp) to the near blocks that hold them.
void add_rigid_body_terms(const BemOperator &op, H2Matrix &K)
{
  const ClusterTree &tree = K.tree();
  const int w = K.col_block();
  const std::vector<double> rigid = rigid_body_blocks(K);
  const std::vector<int> leaf_of = tree.leaf_of_positions();
  for (int i = 0; i < op.num_nodes(); ++i) {
    const int pi = tree.iperm()[i], a = leaf_of[pi];
    int cols[3];
    double wts[3];
    const int nc = op.rigid_body_columns(i, cols, wts);
    for (int t = 0; t < nc; ++t) {
      const int pj = tree.iperm()[cols[t]], b = leaf_of[pj];
      H2Block *D = K.near_block(a, b);
      if (!D) throw std::logic_error("H2 compression: a rigid-body term falls outside the near blocks");
      const int r0 = 3 * (pi - tree.cluster(a).begin), c0 = w * (pj - tree.cluster(b).begin);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) D->add(r0 + r, c0 + c, wts[t] * rigid[9 * static_cast<std::size_t>(pi) + 3 * r + c]);
    }
  }
}

} // namespace

H2Matrix compress_bem_operator_h2(const BemOperator &op, const H2Options &options)
{
  check_compression_inputs(op, options, "H2");
  if (!(options.eta >= 0)) throw std::invalid_argument("H2: eta must be >= 0");
  Timer timer;
  std::optional<PhaseScope> phase(Phase::Tree);
  const int w = k_columns_per_node(options.pressure_columns);
  H2Matrix K(ClusterTree(collocation_points(op.discretization()), ClusterTreeOptions{options.leaf_size}), 3, w);
  const ClusterTree &tree = K.tree();
  phase.reset();
  phase.emplace(Phase::Compression);
  K.set_col_scales(kernel_column_scales(op, w));
  std::vector<double> scales(w);
  for (int q = 0; q < w; ++q) scales[q] = K.col_scale(q);
  std::vector<NestedBasis *> bases(tree.num_clusters());
  for (int c = 0; c < tree.num_clusters(); ++c) bases[c] = &K.bases()[c];
  const int np = options.proxy_points > 0 ? options.proxy_points : default_proxy_points(options.rel_tol);
  Skeletonizer skel(op, SkeletonizerOptions{options.rel_tol, options.max_rank, options.proxy_ratio, np, false, true, true}, tree, w, scales, bases);
  const QuadratureReach &reach = skel.reach();
  std::vector<double> radius(tree.num_clusters());
  for (int c = 0; c < tree.num_clusters(); ++c) radius[c] = std::max(reach.row_r[c], reach.src_r[c]);
  K.partition() = strong_block_partition(tree, radius, options.eta);
  const BlockPartition &part = K.partition();
  K.stats().time_tree = timer.seconds();
  K.stats().proxy_points = np;
  K.stats().eta = options.eta;

  // Bases, bottom-up; only clusters with a far block at or above them need one.
  const auto sources = [&](int c, const std::vector<int> &front, std::vector<int> &out) { strong_sources(tree, part, c, front, out); };
  for (int l = tree.levels() - 1; l >= 1; --l) skel.skeletonize_level(l, sources, &part.has_far, &part.has_far);
  K.store_bases(options.single_precision);

  // Far blocks between skeletons.
  std::vector<int> all(tree.num_clusters());
  std::iota(all.begin(), all.end(), 0);
  timer.restart();
  for_each_cluster(all, [&](int a) {
    for (int b : part.far[a]) {
      H2Block B;
      B.col_cluster = b;
      B.M = DenseMatrix(static_cast<int>(K.row_skeleton(a).size()), static_cast<int>(K.col_skeleton(b).size()));
      skel.block(K.row_skeleton(a), K.col_skeleton(b), B.M.data(), 1, B.M.ld());
      if (options.single_precision && options.low_rank_far) B.compress(options.rel_tol / 10);
      else if (options.single_precision) B.demote();
      K.far_blocks(a).push_back(std::move(B));
    }
  });
  K.stats().time_far = timer.seconds();
  phase.reset();

  // Near blocks (true entries) and the rigid-body terms.
  phase.emplace(Phase::NearField);
  timer.restart();
  const std::vector<std::vector<int>> rigid = rigid_term_leaves(op, tree);
  for_each_cluster(tree.leaves(), [&](int a) {
    const std::vector<int> rows = leaf_indices(tree, a, 3);
    for (int b : part.near[a]) {
      const std::vector<int> cols = leaf_indices(tree, b, w);
      H2Block B;
      B.col_cluster = b;
      B.M = DenseMatrix(static_cast<int>(rows.size()), static_cast<int>(cols.size()));
      skel.block(rows, cols, B.M.data(), 1, B.M.ld());
      // Blocks that will receive rigid-body terms stay dense (the diagonal ones, and those of
      // moved collocation points whose triangle reaches into another leaf).
      const bool gets_rigid = std::binary_search(rigid[a].begin(), rigid[a].end(), b);
      if (options.single_precision && options.low_rank_near && !gets_rigid) B.compress(options.rel_tol / 30);
      else if (options.single_precision) B.demote();
      K.near_blocks(a).push_back(std::move(B));
    }
  });
  K.stats().time_near = timer.seconds();
  timer.restart();
  add_rigid_body_terms(op, K);
  K.stats().time_rigid = timer.seconds();
  phase.reset();
  K.stats().entries_evaluated = skel.entries();
  K.stats().time_near_field = skel.time_near_field();
  K.stats().time_ids = skel.time_ids();
  K.update_stats();
  return K;
}

} // namespace hssbem
