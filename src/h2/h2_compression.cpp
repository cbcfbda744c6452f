// Entries-only H² compression of K = [H, G(, Gn)] (see h2_compression.hpp).
#include "hssbem/h2/h2_compression.hpp"

#include "hssbem/compress/compression.hpp"
#include "hssbem/compress/kernel_blocks.hpp"
#include "hssbem/compress/share_skeletons.hpp"
#include "hssbem/compress/skeletonizer.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/core/tree_ownership.hpp"
#include "hssbem/h2/h2_distributed.hpp"

#include <algorithm>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

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

/// Add the rigid-body terms (docs/discretisation.md, the rigid-body mode) to this rank's near blocks that hold them:
/// D_i = −Σ_j H⁰(i, j), from one product of the compressed H⁰ (slots 0–2, scale 1) with the
/// three translations.
void add_rigid_body_terms(const BemOperator &op, H2Matrix &K, const RankComm &comm)
{
  const ClusterTree &tree = K.tree();
  const int w = K.col_block();
  const H2DistributedProduct product(K, comm);
  const int n = product.num_points(), first = product.first_point();
  std::vector<double> X(static_cast<std::size_t>(w) * n * 3, 0.0), Y(static_cast<std::size_t>(3) * n * 3);
  for (int k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c) X[static_cast<std::size_t>(w) * k + c + static_cast<std::size_t>(c) * w * n] = 1.0;
  product.apply(X.data(), w * n, Y.data(), 3 * n, 3);
  collectively(comm, [&] {
    const std::vector<int> leaf_of = tree.leaf_of_positions();
    for (int k = 0; k < n; ++k) {
      const int pi = first + k, i = tree.perm()[pi], a = leaf_of[pi];
      int cols[3];
      double wts[3];
      const int nc = op.rigid_body_columns(i, cols, wts);
      for (int t = 0; t < nc; ++t) {
        const int pj = tree.iperm()[cols[t]], b = leaf_of[pj];
        H2Block *D = K.near_block(a, b);
        if (!D) throw std::logic_error("H2 compression: a rigid-body term falls outside the near blocks");
        const int r0 = 3 * (pi - tree.cluster(a).begin), c0 = w * (pj - tree.cluster(b).begin);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) D->add(r0 + r, c0 + c, -wts[t] * Y[3 * static_cast<std::size_t>(k) + r + static_cast<std::size_t>(c) * 3 * n]);
      }
    }
  });
}

/// How the tolerance is shared out when the blocks are stored in single precision (low-rank
/// far and near blocks): the product's error comes mostly from the skeletons, so their IDs run
/// tighter than rel_tol and the blocks' own IDs looser than they could. Measured at 80k unknowns
/// against skeletons at rel_tol, far blocks at rel_tol/10 and near blocks at rel_tol/30 (skeletons
/// at 0.7 rel_tol): disk organ memory −3.0 %, sampled K error −28 %; sphere −2.7 %, −27 %. With
/// the two-means splits of the cluster tree (more compact clusters: fewer near pairs, so more of
/// each row is approximated) the sampled error at 300k rose by 22 % (sphere) and 46 % (disk
/// organ) at 0.7; skeletons at 0.55 rel_tol bring it to 7.8e-7 and 9.7e-7 (1.2e-6 and 9.3e-7
/// before both changes) for 1.8–2.0 % more memory than 0.7 on the new tree (benchmarks/results/2026-11-26-h2-compact-clusters.md).
constexpr double k_skeleton_tol_factor = 0.55, k_far_tol_divisor = 5, k_near_tol_divisor = 10;

double skeleton_tolerance(const H2Options &options)
{
  return options.single_precision && (options.low_rank_far || options.low_rank_near) ? k_skeleton_tol_factor * options.rel_tol : options.rel_tol;
}

/// A far block's stored form: low rank at rel_tol / k_far_tol_divisor, or single precision.
void finish_far_block(H2Block &B, const H2Options &options)
{
  if (options.single_precision && options.low_rank_far) B.compress(options.rel_tol / k_far_tol_divisor);
  else if (options.single_precision) B.demote();
}

} // namespace

H2Matrix compress_bem_operator_h2(const BemOperator &op, const H2Options &options)
{
  return compress_bem_operator_h2(op, options, {}, SerialComm());
}

H2Matrix compress_bem_operator_h2(const BemOperator &op, const H2Options &options, const std::vector<int> &node_part, const RankComm &comm)
{
  check_compression_inputs(op, options, "H2");
  if (!(options.eta >= 0)) throw std::invalid_argument("H2: eta must be >= 0");
  const int ranks = comm.size();
  const int nparts = node_part.empty() ? 1 : 1 + *std::max_element(node_part.begin(), node_part.end());
  if (!node_part.empty() && static_cast<int>(node_part.size()) != op.num_nodes()) throw std::invalid_argument("H2: one part per dof node expected");
  if (ranks > 1 && nparts != ranks) throw std::invalid_argument("H2: the node partition has " + std::to_string(nparts) + " parts for " + std::to_string(ranks) + " ranks");
  Timer timer;
  const Progress progress("H2 compression"); // the levels' bases, then the far and the near blocks
  std::optional<PhaseScope> phase(Phase::H2Tree);
  const int w = k_columns_per_node(options.pressure_columns);
  const ClusterTreeOptions topts{options.leaf_size};
  // Until the tree levels are skeletonized, a rank that fails says so at the others' next
  // agreement (the level's skeleton exchange), then throws.
  std::optional<H2Matrix> built;
  std::optional<Skeletonizer> skel;
  std::vector<std::vector<H2Block>> early_far; // per row cluster: far blocks built while skeletonizing
  try {
    const std::vector<Vec3> points = collocation_points(op.discretization());
    built.emplace(nparts > 1 ? ClusterTree(points, node_part, nparts, topts) : ClusterTree(points, topts), 3, w);
    H2Matrix &K = *built;
    const ClusterTree &tree = K.tree();
    K.set_owners(cluster_owners(tree, ranks), comm.rank());
    early_far.resize(tree.num_clusters());
    phase.reset();
    phase.emplace(Phase::H2Compress);
    K.set_col_scales(kernel_column_scales(op, w));
    std::vector<double> scales(w);
    for (int q = 0; q < w; ++q) scales[q] = K.col_scale(q);
    std::vector<NestedBasis *> bases(tree.num_clusters());
    for (int c = 0; c < tree.num_clusters(); ++c) bases[c] = &K.bases()[c];
    const int np = options.proxy_points > 0 ? options.proxy_points : default_proxy_points(options.rel_tol);
    skel.emplace(op, SkeletonizerOptions{skeleton_tolerance(options), options.max_rank, options.proxy_ratio, np, false, true, true}, tree, w, scales, bases);
    const QuadratureReach &reach = skel->reach();
    std::vector<double> radius(tree.num_clusters());
    for (int c = 0; c < tree.num_clusters(); ++c) radius[c] = std::max(reach.row_r[c], reach.src_r[c]);
    K.partition() = strong_block_partition(tree, radius, options.eta);
    const BlockPartition &part = K.partition();
    K.stats().time_tree = timer.seconds();
    K.stats().proxy_points = np;
    K.stats().eta = options.eta;

    // Bases, bottom-up; only clusters with a far block at or above them need one. With several
    // ranks each skeletonizes its own clusters and the skeletons are shared level by level.
    const auto sources = [&](int c, const std::vector<int> &front, std::vector<int> &out) { strong_sources(tree, part, c, front, out); };
    std::vector<char> skip(tree.num_clusters(), 0);
    for (int c = 0; c < tree.num_clusters(); ++c) skip[c] = !K.holds(c);
    Skeletonizer::LevelSync sync;
    if (ranks > 1)
      sync = [&](int l, bool columns) {
        if (comm.any(false)) throw PeerFault();
        share_skeletons(tree.clusters_at_level(l), bases, [&K](int c) { return K.holds(c); }, comm, columns);
      };
    // Far blocks between clusters of one level come out of the row skeletonization, which has
    // sampled their columns inside the row cluster's proxy sphere already.
    skel->build_far_blocks(part.far, [&](int a, int b, DenseMatrix &M) {
      H2Block B;
      B.col_cluster = b;
      B.M = std::move(M);
      finish_far_block(B, options);
      early_far[a].push_back(std::move(B));
    });
    // Each level's interpolation matrices go to their stored form as soon as the level is done,
    // so that the far blocks built meanwhile do not sit beside all the bases in double.
    for (int l = tree.levels() - 1; l >= 1; --l) {
      skel->skeletonize_level(l, sources, &part.has_far, &part.has_far, ranks > 1 ? &skip : nullptr, sync);
      K.store_level_bases(l, options.single_precision);
      progress.report(0.5 * (tree.levels() - l) / tree.levels());
    }
  } catch (const PeerFault &) {
    throw;
  } catch (...) {
    if (ranks > 1) comm.any(true);
    throw;
  }
  H2Matrix &K = *built;
  const ClusterTree &tree = K.tree();
  const BlockPartition &part = K.partition();
  std::vector<int> held, held_leaves;

  // Far blocks between skeletons, for this rank's clusters.
  timer.restart();
  collectively(comm, [&] {
    K.store_bases(options.single_precision);
    for (int c = 0; c < tree.num_clusters(); ++c)
      if (K.holds(c)) held.push_back(c);
    for (int c : tree.leaves())
      if (K.holds(c)) held_leaves.push_back(c);
    for_each_cluster(held, [&](int a) {
      std::vector<H2Block> &early = early_far[a];
      for (int b : part.far[a]) {
        const auto e = std::find_if(early.begin(), early.end(), [b](const H2Block &B) { return B.col_cluster == b; });
        if (e != early.end()) {
          K.far_blocks(a).push_back(std::move(*e));
          continue;
        }
        H2Block B;
        B.col_cluster = b;
        B.M = DenseMatrix(static_cast<int>(K.row_skeleton(a).size()), static_cast<int>(K.col_skeleton(b).size()));
        skel->block(K.row_skeleton(a), K.col_skeleton(b), B.M.data(), 1, B.M.ld());
        finish_far_block(B, options);
        K.far_blocks(a).push_back(std::move(B));
      }
      std::vector<H2Block>().swap(early);
    });
  });
  K.stats().time_far = timer.seconds();
  progress.report(0.6);
  phase.reset();

  // Near blocks (true entries) of this rank's leaves and the rigid-body terms.
  phase.emplace(Phase::H2NearField);
  timer.restart();
  collectively(comm, [&] {
    const std::vector<std::vector<int>> rigid = rigid_term_leaves(op, tree);
    for_each_cluster(held_leaves, [&](int a) {
      const std::vector<int> rows = leaf_indices(tree, a, 3);
      std::vector<H2Block> &near = K.near_blocks(a);
      for (int b : part.near[a]) {
        const std::vector<int> cols = leaf_indices(tree, b, w);
        H2Block B;
        B.col_cluster = b;
        B.M = DenseMatrix(static_cast<int>(rows.size()), static_cast<int>(cols.size()));
        skel->block(rows, cols, B.M.data(), 1, B.M.ld());
        near.push_back(std::move(B));
      }
      // The low-rank near blocks are truncated relative to the leaf's own block (a, a), the
      // largest part of its rows: a weak block between leaves a little apart need not keep
      // digits that the rows' sums do not have.
      const auto self = std::find_if(near.begin(), near.end(), [a](const H2Block &B) { return B.col_cluster == a; });
      const double row_scale = self != near.end() ? dense::largest_row_norm(self->M) : 0.0, col_scale = self != near.end() ? dense::largest_col_norm(self->M) : 0.0;
      for (H2Block &B : near) {
        // Blocks that will receive rigid-body terms stay dense (the diagonal ones, and those of
        // moved collocation points whose triangle reaches into another leaf).
        const bool gets_rigid = std::binary_search(rigid[a].begin(), rigid[a].end(), B.col_cluster);
        if (options.single_precision && options.low_rank_near && !gets_rigid) B.compress(options.rel_tol / k_near_tol_divisor, row_scale, col_scale);
        else if (options.single_precision) B.demote();
      }
    });
  });
  K.stats().time_near = timer.seconds();
  timer.restart();
  add_rigid_body_terms(op, K, comm);
  K.stats().time_rigid = timer.seconds();
  phase.reset();
  K.stats().entries_evaluated = skel->entries();
  K.stats().time_near_field = skel->time_near_field();
  K.stats().time_ids = skel->time_ids();
  K.update_stats();
  return std::move(*built);
}

} // namespace hssbem
