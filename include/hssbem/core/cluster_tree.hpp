/// \file cluster_tree.hpp
/// Binary cluster tree over the dof nodes, and the one permutation between mesh order and
/// cluster order (docs/distributed.md).
///
/// Points are the collocation points of the dof nodes; a point stands for its node's 3 dofs,
/// which therefore always stay together. The tree reorders the points so that every cluster is a
/// contiguous range [begin, end) of positions in *cluster order*. `perm()` and `iperm()` are the
/// only link between that order and *mesh order* (node index): every input and output of the HSS
/// engine is in mesh order, everything inside it in cluster order, and the conversion goes
/// through `to_cluster_order` / `to_mesh_order` here and nowhere else.
///
/// Construction:
///  - optionally, a top-level partition (one part per MPI rank, e.g. from METIS) is laid out
///    first: parts keep their numbering (part p occupies the p-th block of positions) and each
///    becomes exactly one cluster. With a power-of-two count they form one complete tree level,
///    log2(nparts); otherwise the list of parts is halved recursively, balanced by point count;
///  - below each part (or from the root without a partition), geometric bisection: a cluster is
///    split along the principal axis of its points (largest eigenvector of their covariance) at
///    the median, ties broken by node index, until it has at most `leaf_size` points; by default
///    (`refine_splits`) the axis and the cut are then refined towards more compact halves (see
///    ClusterTreeOptions), so children hold between 1/4 and 3/4 of their parent, else they differ
///    in size by at most one.
///
/// Clusters are numbered breadth first (root 0), so the clusters of one level are consecutive,
/// left to right. Within a leaf, points are in ascending node index. The result depends only on
/// the input: two builds from the same points and options are identical.
#pragma once

#include "hssbem/core/geometry.hpp"
#include "hssbem/core/option_table.hpp"

#include <vector>

namespace hssbem {

/// Parameters of the cluster tree (a plain struct, filled by the PETSc layer).
struct ClusterTreeOptions {
  int leaf_size = option_default::mat_h2_leaf_size; ///< a cluster with at most this many points is a leaf (>= 1; the compressions set theirs)
  /// Refine each split: its axis, starting from the principal axis, moves towards the axis through
  /// the halves' centroids while that lowers their inertia (two-means with equal halves), and its
  /// cut, at the median, moves to a gap within a quarter of the points of it where that lowers the
  /// inertia by 1 % (the two faces of a thin body): more compact clusters, so fewer near pairs;
  /// children hold between 1/4 and 3/4 of their parent. False: median splits on the principal axis.
  bool refine_splits = true;
};

/// One node of the cluster tree: the points at positions [begin, end) of cluster order.
struct Cluster {
  int begin = 0;   ///< first position in cluster order
  int end = 0;     ///< one past the last position
  int parent = -1; ///< -1 for the root
  int left = -1;   ///< first child, -1 for a leaf
  int right = -1;  ///< second child (positions after the first child's), -1 for a leaf
  int level = 0;   ///< depth, 0 for the root
  Vec3 lo{};       ///< bounding box of the points, lower corner
  Vec3 hi{};       ///< bounding box of the points, upper corner
  Vec3 centre{};   ///< centre of the bounding box
  double radius = 0; ///< largest distance from `centre` to one of the points

  int size() const { return end - begin; }
};

/// Binary cluster tree over a point set with the permutation mesh order <-> cluster order.
class ClusterTree {
public:
  /// Tree by geometric bisection from the root. Throws std::invalid_argument for an empty point
  /// set, a non-finite coordinate or leaf_size < 1.
  explicit ClusterTree(const std::vector<Vec3> &points, const ClusterTreeOptions &opts = {});
  /// Tree whose top levels follow the partition `part` (part[i] in [0, nparts) for point i;
  /// every part must be non-empty), with geometric bisection below each part. Throws
  /// std::invalid_argument as above and for a malformed partition.
  ClusterTree(const std::vector<Vec3> &points, const std::vector<int> &part, int nparts,
              const ClusterTreeOptions &opts = {});

  /// Copyable (O(N) integers and boxes): a truncated HSS matrix keeps its own copy.
  ClusterTree(const ClusterTree &) = default;
  ClusterTree &operator=(const ClusterTree &) = default;
  ClusterTree(ClusterTree &&) = default;
  ClusterTree &operator=(ClusterTree &&) = default;

  const ClusterTreeOptions &options() const { return m_opts; }
  int num_points() const { return static_cast<int>(m_perm.size()); }
  int num_clusters() const { return static_cast<int>(m_clusters.size()); }
  const Cluster &cluster(int i) const { return m_clusters[i]; }
  bool is_leaf(int i) const { return m_clusters[i].left < 0; }
  /// Number of levels (1 for a single leaf).
  int levels() const { return static_cast<int>(m_levels.size()); }
  /// Clusters of level l, left to right (consecutive indices).
  const std::vector<int> &clusters_at_level(int l) const { return m_levels[l]; }
  /// All leaves, left to right (ascending `begin`); they may lie on different levels.
  const std::vector<int> &leaves() const { return m_leaves; }
  /// The leaf holding each position of cluster order (num_points() entries).
  std::vector<int> leaf_of_positions() const;

  /// Number of top-level parts (1 when built without a partition).
  int num_parts() const { return static_cast<int>(m_part_cluster.size()); }
  /// The cluster holding exactly the points of part p (the root without a partition).
  int part_cluster(int p) const { return m_part_cluster[p]; }

  /// perm()[k] is the node index (mesh order) of the point at position k (cluster order).
  const std::vector<int> &perm() const { return m_perm; }
  /// iperm()[i] is the position in cluster order of node i; iperm()[perm()[k]] == k.
  const std::vector<int> &iperm() const { return m_iperm; }
  /// out (cluster order) = in (mesh order), with `block` consecutive values per point (3 for the
  /// dofs of a node). Both arrays hold num_points() * block values and must not overlap.
  void to_cluster_order(const double *in, double *out, int block) const;
  /// out (mesh order) = in (cluster order); the inverse of to_cluster_order.
  void to_mesh_order(const double *in, double *out, int block) const;

  /// Whether clusters a and b are well separated, i.e. may be compressed as far field:
  ///   |centre_a - centre_b| > (1 + eta) (radius_a + radius_b),  eta >= 0.
  /// Then every point of b lies strictly outside the sphere of radius (1 + eta) radius_a around
  /// centre_a (by the triangle inequality, at distance > (1 + eta) radius_a + eta radius_b), and
  /// vice versa: with a proxy sphere of radius (1 + eta) r, neither cluster is "near" the other.
  /// The relation is symmetric; it is false for a == b, for an ancestor and its descendant and,
  /// more generally, for any two clusters that share a point or whose spheres intersect (the
  /// strict inequality also covers clusters of coincident points, radius 0). Throws
  /// std::invalid_argument for eta < 0.
  bool admissible(int a, int b, double eta) const;

private:
  void build(const std::vector<Vec3> &points, const std::vector<int> &part, int nparts);
  void add_children(int c, int split);
  void fit_bounds(int c, const Vec3 *x);
  void finish_leaf(int c);
  void index_levels_and_leaves();

  ClusterTreeOptions m_opts;
  std::vector<Cluster> m_clusters;
  std::vector<int> m_perm, m_iperm;
  std::vector<std::vector<int>> m_levels;
  std::vector<int> m_leaves;
  std::vector<int> m_part_cluster;
};

} // namespace hssbem
