// Entries-only HSS compression of K = [H, G(, Gn)] with proxy spheres (see hss_compression.hpp).
#include "hssbem/hss/hss_compression.hpp"

#include "hssbem/compress/compression.hpp"
#include "hssbem/compress/kernel_blocks.hpp"
#include "hssbem/compress/share_skeletons.hpp"
#include "hssbem/compress/skeletonizer.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/core/tree_ownership.hpp"
#include "hssbem/hss/hss_distributed.hpp"

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
/// couplings and the leaves' diagonal blocks; on several ranks each its own clusters'.
class Compressor {
public:
  Compressor(const BemOperator &op, const HssOptions &opt, HssMatrix &K)
    : m_K(K), m_tree(K.tree()), m_bases(basis_pointers(K)),
      m_skel(op, SkeletonizerOptions{opt.rel_tol, opt.max_rank, opt.proxy_ratio, opt.proxy_points > 0 ? opt.proxy_points : default_proxy_points(opt.rel_tol), true},
             K.tree(), K.col_block(), col_scales(K), m_bases)
  {
    m_K.stats().proxy_points = m_skel.proxy_points();
  }

  /// Skeletons, level by level from the leaves up. With several ranks each skeletonizes the
  /// clusters it holds and the skeletons are shared level by level; a rank that fails says so at
  /// the others' next agreement (the level's skeleton exchange).
  void skeletonize(const RankComm &comm)
  {
    std::vector<char> skip(m_tree.num_clusters(), 0);
    for (int c = 0; c < m_tree.num_clusters(); ++c) skip[c] = !m_K.holds(c);
    Skeletonizer::LevelSync sync;
    if (comm.size() > 1)
      sync = [&](int l, bool columns) {
        if (comm.any(false)) throw PeerFault();
        share_skeletons(m_tree.clusters_at_level(l), m_bases, [this](int c) { return m_K.holds(c); }, comm, columns);
      };
    for (int l = m_tree.levels() - 1; l >= 1; --l) {
      fault_point("HssSkeletons");
      m_skel.skeletonize_level(l, Skeletonizer::all_others, nullptr, nullptr, comm.size() > 1 ? &skip : nullptr, sync);
    }
  }

  /// The sibling couplings of the inner clusters held here (true entries between skeletons).
  void couple()
  {
    const Timer timer;
    for (int l = m_tree.levels() - 2; l >= 0; --l)
      for_each_cluster(m_tree.clusters_at_level(l), [this](int c) {
        if (m_K.holds(c)) couple_children(c);
      });
    m_K.stats().time_couplings += timer.seconds();
  }

  /// The diagonal blocks of the leaves held here (true entries), then the totals of the counters.
  void fill_leaves()
  {
    const Timer timer;
    for_each_cluster(m_tree.leaves(), [this](int c) {
      if (m_K.holds(c)) fill_leaf(c);
    });
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
  std::vector<NestedBasis *> m_bases;
  Skeletonizer m_skel;
};

/// Where a rigid-body term of row r (global, cluster order) and column q lands: a leaf's diagonal
/// block, or the sibling coupling of the two clusters that separate them.
struct TermPlace {
  int cluster;   ///< the leaf, or the parent holding the coupling
  int block;     ///< 0: D, 1: B12, 2: B21
  int row, col;  ///< within that block
};

TermPlace term_place(const HssMatrix &K, const std::vector<int> &leaf_of, int pi, int pj, int r, int c)
{
  const ClusterTree &tree = K.tree();
  const int w = K.col_block();
  auto position = [](const std::vector<int> &list, int value) {
    const auto it = std::find(list.begin(), list.end(), value);
    if (it == list.end()) throw std::logic_error("HSS compression: a rigid-body coupling is missing from a skeleton");
    return static_cast<int>(it - list.begin());
  };
  int ci = leaf_of[pi];
  if (leaf_of[pj] == ci) {
    const Cluster &cl = tree.cluster(ci);
    return {ci, 0, 3 * (pi - cl.begin) + r, w * (pj - cl.begin) + c};
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
  return {parent, left ? 1 : 2, position(K.cluster(ci).row_skel, 3 * pi + r), position(K.cluster(cj).col_skel, w * pj + c)};
}

/// Adds weight · d at t (written as one expression, as the compressor always has: the compiler
/// may fuse it into one multiply-add).
void add_term(HssMatrix &K, const TermPlace &t, double weight, double d)
{
  HssCluster &h = K.cluster(t.cluster);
  DenseMatrix &M = t.block == 0 ? h.D : t.block == 1 ? h.B12 : h.B21;
  M(t.row, t.col) += weight * d;
}

/// Rigid-body terms by a fast product (D_i = −Σ_j H⁰(i, j)), then added where they belong: a
/// leaf's diagonal block, or the skeleton coupling of the two clusters that separate row and
/// column. A term whose coupling another rank holds (rank 0, above the parts) is sent there.
void add_rigid_body_terms(const BemOperator &op, HssMatrix &K, const RankComm &comm)
{
  const ClusterTree &tree = K.tree();
  const int w = K.col_block(), P = comm.size();
  const HssDistributedProduct product(K, comm);
  const int n = product.num_points(), first = product.first_point();
  std::vector<double> X(static_cast<std::size_t>(w) * n * 3, 0.0), Y(static_cast<std::size_t>(3) * n * 3);
  for (int k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c) X[static_cast<std::size_t>(w) * k + c + static_cast<std::size_t>(c) * w * n] = 1.0;
  product.apply(X.data(), w * n, Y.data(), 3 * n, 3);
  std::vector<std::vector<int>> where(P);
  std::vector<std::vector<double>> values(P);
  collectively(comm, [&] {
    const std::vector<int> leaf_of = tree.leaf_of_positions();
    for (int k = 0; k < n; ++k) {
      const int pi = first + k, i = tree.perm()[pi];
      int cols[3];
      double wts[3];
      const int nc = op.rigid_body_columns(i, cols, wts);
      for (int a = 0; a < nc; ++a)
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) {
            const TermPlace t = term_place(K, leaf_of, pi, tree.iperm()[cols[a]], r, c);
            const double d = -Y[3 * static_cast<std::size_t>(k) + r + static_cast<std::size_t>(c) * 3 * n];
            if (K.holds(t.cluster)) {
              add_term(K, t, wts[a], d);
              continue;
            }
            const int q = K.owner(t.cluster);
            where[q].insert(where[q].end(), {t.cluster, t.block, t.row, t.col});
            values[q].insert(values[q].end(), {wts[a], d});
          }
    }
  });
  const std::vector<std::vector<int>> places = comm.exchange(where);
  std::vector<std::vector<double>> received(P);
  for (int q = 0; q < P; ++q) received[q].resize(places[q].size() / 2); // a weight and a value per place
  comm.exchange(values, received);
  collectively(comm, [&] {
    for (int q = 0; q < P; ++q)
      for (std::size_t e = 0; e < places[q].size() / 4; ++e) {
        const int *t = &places[q][4 * e];
        add_term(K, TermPlace{t[0], t[1], t[2], t[3]}, received[q][2 * e], received[q][2 * e + 1]);
      }
  });
}

} // namespace

HssMatrix compress_bem_operator_hss(const BemOperator &op, const HssOptions &options) { return compress_bem_operator_hss(op, options, {}, SerialComm()); }

HssMatrix compress_bem_operator_hss(const BemOperator &op, const HssOptions &options, const std::vector<int> &node_part, const RankComm &comm)
{
  check_compression_inputs(op, options, "HSS");
  const int ranks = comm.size();
  const int nparts = node_part.empty() ? 1 : 1 + *std::max_element(node_part.begin(), node_part.end());
  if (!node_part.empty() && static_cast<int>(node_part.size()) != op.num_nodes()) throw std::invalid_argument("HSS: one part per dof node expected");
  if (ranks > 1 && nparts != ranks) throw std::invalid_argument("HSS: the node partition has " + std::to_string(nparts) + " parts for " + std::to_string(ranks) + " ranks");
  Timer timer;
  std::optional<PhaseScope> phase(Phase::Tree);
  std::optional<HssMatrix> built;
  std::optional<Compressor> compressor;
  try {
    const std::vector<Vec3> points = collocation_points(op.discretization());
    const ClusterTreeOptions topts{options.leaf_size};
    built.emplace(nparts > 1 ? ClusterTree(points, node_part, nparts, topts) : ClusterTree(points, topts), 3, k_columns_per_node(options.pressure_columns));
    built->set_owners(ranks > 1 ? cluster_owners(built->tree(), ranks) : std::vector<int>{}, comm.rank());
    phase.reset();
    phase.emplace(Phase::Compression);
    built->set_col_scales(kernel_column_scales(op, built->col_block()));
    built->stats().time_tree = timer.seconds();
    compressor.emplace(op, options, *built);
    compressor->skeletonize(comm);
  } catch (const PeerFault &) {
    throw;
  } catch (...) {
    if (ranks > 1) comm.any(true); // the others' next agreement: a skeleton exchange, or the couplings below
    throw;
  }
  HssMatrix &K = *built;
  collectively(comm, [&] {
    fault_point("HssCouplings");
    compressor->couple();
  });
  phase.reset();
  phase.emplace(Phase::NearField);
  collectively(comm, [&] { compressor->fill_leaves(); });
  timer.restart();
  add_rigid_body_terms(op, K, comm);
  K.stats().time_rigid = timer.seconds();
  phase.reset();
  K.update_stats();
  return std::move(*built);
}

} // namespace hssbem
