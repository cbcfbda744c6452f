/// \file skeletonizer.hpp
/// Entries-only skeletonization of the BEM operator K = [H, G(, Gn)] with proxy spheres
/// (docs/hss.md), one tree level at a time: the step shared by the HSS compression (weak
/// admissibility, hss/hss_compression.hpp) and the H² compression (strong admissibility,
/// h2/h2_compression.hpp). The formats differ only in which other clusters' indices a cluster
/// must be compressed against (its *sources*).
///
/// For a cluster τ of the level being skeletonized:
///  - the row skeleton comes from an interpolative decomposition (ID) of τ's candidate rows
///    against (a) Kelvin point sources at proxy points on a sphere of radius proxy_ratio·r_τ
///    around τ, standing in for every source outside that sphere, and (b) the true entries of the
///    columns of τ's sources whose quadrature can reach inside that sphere;
///  - the column skeleton likewise, against the fields of τ's columns at the proxy points and
///    the true entries of its sources' rows inside the proxy sphere;
///  - the proxy spheres are large enough that everything outside sees each triangle of τ through
///    the same regular quadrature rule (near_ratio diameters), so the discrete operator, not just
///    the continuous one, is captured to the tolerance.
/// A source on the current *frontier* (the clusters of the level, and leaves above it) offers
/// its candidates; a source below it, already skeletonized, offers its skeleton, which stands for
/// all of its indices against anything outside its own proxy spheres.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/compress/kernel_blocks.hpp"
#include "hssbem/compress/nested_basis.hpp"
#include "hssbem/compress/quadrature_reach.hpp"
#include "hssbem/core/cluster_tree.hpp"

#include <array>
#include <functional>
#include <memory>
#include <vector>

namespace hssbem {

struct SkeletonizerOptions {
  double rel_tol = 1e-6;     ///< relative tolerance of each ID
  int max_rank = -1;         ///< cap on each skeleton; negative: none
  double proxy_ratio = option_default::mat_h2_proxy_ratio; ///< proxy sphere radius / cluster radius (> 1; both formats' default)
  int proxy_points = 64;     ///< points on each proxy sphere
  /// Keep every row (column) whose rigid-body term couples it to a column (row) outside τ in τ's
  /// skeleton, so that the term can be added to a skeleton coupling (HSS). Without it (H²) such
  /// terms must lie in near-field blocks.
  bool force_rigid = true;
  /// Per level, find every column skeleton first, then compress each row skeleton against the
  /// sources' column skeletons rather than their candidates: valid when a source's column basis
  /// covers the cluster (strong admissibility: the cluster is far from it or from an ancestor),
  /// and it halves the explicit row samples (H²).
  bool columns_first = false;
  /// IDs from the Gram matrix of the features (IdOptions::gram), for tolerances ≥ gram_min_tol.
  bool gram_ids = false;
};

class Skeletonizer {
public:
  /// `bases[c]` receives cluster c's skeletons; K's columns are `col_block` per point, scaled
  /// by `col_scale` per slot (see HssMatrix::col_scale, H2Matrix::col_scale).
  Skeletonizer(const BemOperator &op, const SkeletonizerOptions &opt, const ClusterTree &tree, int col_block, std::vector<double> col_scale,
               std::vector<NestedBasis *> bases);
  ~Skeletonizer();

  /// sources(c, front, out): append to `out` the clusters (≠ c) that c is compressed against.
  using Sources = std::function<void(int c, const std::vector<int> &front, std::vector<int> &out)>;
  /// Weak admissibility: every other cluster of the frontier.
  static void all_others(int c, const std::vector<int> &front, std::vector<int> &out);

  /// Skeletons and interpolation matrices of the clusters of level l (their children done).
  /// A cluster with need_rows[c] == 0 (need_cols) gets an empty row (column) skeleton; null
  /// vectors mean every cluster needs both.
  ///
  /// Distributed construction: clusters with skip[c] != 0 are skeletonized on another rank;
  /// sync(l, true) is called once the level's column skeletons are chosen here and must fill in
  /// the skipped clusters' col_skel (and col_forced), sync(l, false) likewise for the rows
  /// (row_skel, row_forced). Their U and V stay with their rank.
  using LevelSync = std::function<void(int l, bool columns)>;
  void skeletonize_level(int l, const Sources &sources, const std::vector<char> *need_rows = nullptr, const std::vector<char> *need_cols = nullptr,
                         const std::vector<char> *skip = nullptr, const LevelSync &sync = {});

  /// Far blocks taken from the row IDs' samples (strong admissibility, columns_first): once the
  /// row skeleton of a cluster a is chosen, every b in far[a] on the frontier whose column
  /// skeleton is final gets its block K(row_skel(a), col_skel(b)) handed to sink(a, b, block) on
  /// the same thread: the columns inside a's proxy sphere are copied from the samples the ID
  /// just used, only the others are evaluated. Pairs not handed over are the caller's to build.
  using FarSink = std::function<void(int a, int b, DenseMatrix &block)>;
  void build_far_blocks(const std::vector<std::vector<int>> &far, FarSink sink)
  {
    m_far = &far;
    m_far_sink = std::move(sink);
  }

  /// out(r, q) = K(rows[r], cols[q]) (scaled, no rigid-body terms) at out[r·rs + q·cs]; counted
  /// in entries(). Thread-safe.
  void block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, long rs, long cs);

  long long entries() const;
  double time_near_field() const; ///< thread-seconds spent on ID samples
  double time_ids() const;        ///< thread-seconds spent on IDs
  int proxy_points() const { return static_cast<int>(m_sphere.size()); }
  const QuadratureReach &reach() const { return m_reach; }

private:
  struct Spheres {
    double r_row, r_col; ///< proxy sphere radii for the row and the column skeleton
    double w_row, w_col; ///< proxy weights (a proxy stands for about one node's area of sources)
  };
  Spheres spheres(int c) const;
  void skeletonize_rows(int c, const std::vector<int> &sources, bool need);
  void skeletonize_cols(int c, const std::vector<int> &sources, bool need);
  /// build_far_blocks for cluster a, its row ID's features X (nfr per candidate, the sources'
  /// columns from first_col on, placed and ranged as skeletonize_rows recorded them).
  void far_blocks_from_samples(int a, const std::vector<double> &X, int nfr, int first_col, const std::vector<int> &skel_local,
                               const std::vector<int> &near_place, const std::vector<std::array<int, 3>> &ranges);
  BemOperator::Workspace &ws();
  bool row_forced(int c, int node) const;
  bool col_forced(int c, int node) const;

  const BemOperator &m_op;
  SkeletonizerOptions m_opt;
  const ClusterTree &m_tree;
  const int m_w;
  KernelBlocks m_eval;
  QuadratureReach m_reach;
  std::vector<NestedBasis *> m_bases;
  std::vector<std::vector<int>> m_cols_of_row, m_rows_of_col; ///< rigid-body coupling pattern (nodes), when forced
  std::vector<Vec3> m_sphere;
  double m_node_area = 1;
  std::vector<std::unique_ptr<BemOperator::Workspace>> m_ws;
  std::vector<long long> m_entries;
  std::vector<double> m_t_near, m_t_id;
  std::vector<char> m_in_front;
  std::vector<char> m_col_done; ///< columns_first: the cluster's column skeleton is final
  std::vector<std::vector<int>> m_active_rows, m_active_cols;
  const std::vector<std::vector<int>> *m_far = nullptr;
  FarSink m_far_sink;
};

} // namespace hssbem
