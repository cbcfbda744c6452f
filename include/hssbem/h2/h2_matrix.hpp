/// \file h2_matrix.hpp
/// An H² matrix: nested bases in interpolative form (nested_basis.hpp) on a strong-admissibility
/// block partition (block_partition.hpp).
///
/// Rows and columns follow one ClusterTree, indexed as in HssMatrix (cluster order, `row_block`
/// rows and `col_block` columns per point). With the partition's far blocks (a, b) and near
/// blocks (leaf a, leaf b),
///     K(a, b) ≈ U_a K(S_a, C_b) V_bᵀ   (far; U_a, V_b expanded through the nested bases),
///     K(a, b) = D_ab                    (near, true entries),
/// where S_a (C_b) is a's row (b's column) skeleton. Unlike HSS, a cluster's basis only has to
/// capture its interaction with what is far from it or from one of its ancestors, not with its
/// neighbours, so on a surface its rank stays bounded as the tree grows instead of growing with
/// the cluster's boundary. The product costs O(N·r) with bounded r.
#pragma once

#include "hssbem/compress/nested_basis.hpp"
#include "hssbem/core/cluster_tree.hpp"
#include "hssbem/core/tree_ownership.hpp"
#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/core/packed.hpp"
#include "hssbem/h2/block_partition.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hssbem {

/// One stored block of an H² matrix: far (skeleton × skeleton) or near (leaf × leaf). M holds
/// its dimensions always, and its entries when the block is dense in double precision. To save
/// memory a block may instead be dense in single precision (`single`, column-major with M's
/// dimensions), or of low rank in single precision, kept as its interpolative decomposition
/// (a far block of well-separated clusters has numerical rank well below its dimensions):
///   column ID (lr_rows false):  B ≈ B(:, S) Pᵀ,   row ID (lr_rows true):  B ≈ P B(S, :),
/// where the skeleton side B(:, S) (or B(S, :)ᵀ) is stored in `lr_s` (len × rank, column-major,
/// len = M.m for a column ID, M.n for a row ID) and P (other × rank, other the remaining
/// dimension) has a unit row at each skeleton position, which is not stored: lr_slot[p] = t for
/// the skeleton position p (P(p, :) = e_t), −1 − j for a redundant one (P(p, :) = row j of lr_t,
/// (other − rank) × rank, column-major). Storage rank·(m + n − rank) floats plus `other` slots,
/// below m·n whenever rank < min(m, n). Products always compute in double: stored floats are
/// widened on the fly, so only the storage rounds (relative 6e-8 per stored number).
struct H2Block {
  int col_cluster = -1;
  DenseMatrix M;
  std::vector<float> single;
  int rank = -1;       ///< ≥ 0: low rank, in lr_s, lr_slot, lr_t
  bool lr_rows = false; ///< the ID is of rows (P on the row side)
  std::vector<float> lr_s, lr_t;
  /// Slots fit 16 bits: a block whose `other` side is longer than Slot holds stays in single
  /// precision instead (no skeleton comes near that).
  using Slot = std::int16_t;
  std::vector<Slot> lr_slot;

  bool is_single() const { return !single.empty(); }
  bool is_low_rank() const { return rank >= 0; }
  /// Move the entries to single precision (no-op for an empty block or one not dense in double).
  void demote();
  /// From dense double entries: the low-rank form of the block (an ID from the smaller side:
  /// columns when M.n ≤ M.m, else rows) when it takes less memory than single precision, else
  /// single precision. The ID keeps pivots above rel_tol · max(p₁, scale), p₁ its largest pivot
  /// (the largest column norm for a column ID, row norm for a row ID) and scale = col_scale or
  /// row_scale, a reference norm of the block's columns or rows elsewhere in the matrix (0: the
  /// tolerance is relative to the block alone). A block below rel_tol · scale keeps rank 0.
  void compress(double rel_tol, double row_scale = 0, double col_scale = 0);
  double entry(int i, int j) const;
  /// Add v to entry (i, j) (a dense block only: throws std::logic_error for a low-rank one).
  void add(int i, int j, double v);
  /// Set every stored number to zero (the block then contributes nothing).
  void clear();
  std::size_t bytes() const { return M.bytes() + (single.size() + lr_s.size() + lr_t.size()) * sizeof(float) + lr_slot.size() * sizeof(Slot); }
  /// The entries in double: M's data, or the stored form expanded into buf.
  const double *data(std::vector<double> &buf) const;
  /// Y += B X for nrhs columns (X: M.n × nrhs, Y: M.m × nrhs, column-major). A single-precision
  /// block with one column is widened entry by entry inside the product, so it reads 4 bytes per
  /// stored number instead of widening the block into buf first (the product is memory-bound);
  /// a dense one with more columns goes through data(buf) and one GEMM.
  void multiply_add(const double *X, int ldx, double *Y, int ldy, int nrhs, std::vector<double> &buf) const;
  /// X += Bᵀ Y for nrhs columns (Y: M.m × nrhs, X: M.n × nrhs), in every stored form.
  void multiply_add_transposed(const double *Y, int ldy, double *X, int ldx, int nrhs, std::vector<double> &buf) const;
};

/// One side of a cluster's nested basis as the H² matrix keeps it: U (or V) of NestedBasis in
/// interpolative form without its identity rows. Row skel_pos[t] of U is unit vector t, row
/// red_pos[j] holds the weights T(:, j); T (k × |red_pos|, column-major) is kept in single
/// precision (Tf) or double (Td).
struct StoredInterpolation {
  int candidates = 0;
  std::vector<int> skel_pos, red_pos; ///< positions among the candidates
  std::vector<float> Tf;
  std::vector<double> Td;

  int rank() const { return static_cast<int>(skel_pos.size()); }
  std::size_t bytes() const { return (skel_pos.size() + red_pos.size()) * sizeof(int) + Tf.size() * sizeof(float) + Td.size() * sizeof(double); }
  /// U as NestedBasis holds it (candidates × k, double).
  DenseMatrix expand() const;
  /// From U (candidates × k) whose column t is the unit vector at the candidate skel[t] (global
  /// indices; `cands` lists the candidates' global indices in order).
  static StoredInterpolation from(const DenseMatrix &U, const std::vector<int> &cands, const std::vector<int> &skel, bool single);
};

struct H2LevelStats {
  int clusters = 0; ///< clusters with a basis
  int max_row_rank = 0, max_col_rank = 0;
  double mean_row_rank = 0, mean_col_rank = 0;
  long far_blocks = 0;
};

struct H2Stats {
  std::vector<H2LevelStats> levels; ///< index = tree level (0 = root)
  std::size_t memory_bytes = 0;     ///< all of the below
  std::size_t basis_bytes = 0, far_bytes = 0, near_bytes = 0;
  long far_blocks = 0, near_blocks = 0;
  long long entries_evaluated = 0;
  double time_tree = 0, time_near_field = 0, time_ids = 0, time_far = 0, time_near = 0, time_rigid = 0; ///< seconds (ID samples and IDs in thread-seconds)
  int proxy_points = 0;
  double eta = 0;
  int max_row_rank() const;
  int max_col_rank() const;
};

class H2Matrix {
public:
  H2Matrix(ClusterTree tree, int row_block, int col_block);

  const ClusterTree &tree() const { return m_tree; }
  int row_block() const { return m_row_block; }
  int col_block() const { return m_col_block; }
  int num_rows() const { return m_row_block * m_tree.num_points(); }
  int num_cols() const { return m_col_block * m_tree.num_points(); }

  /// Column scaling by slot, as HssMatrix::col_scale: the matrix held is K S.
  double col_scale(int slot) const { return m_col_scale[slot]; }
  void set_col_scales(std::vector<double> s) { m_col_scale = std::move(s); }

  BlockPartition &partition() { return m_partition; }
  const BlockPartition &partition() const { return m_partition; }
  /// Cluster c's nested basis (skeletons, U and V in double, interpolative form), built from the
  /// stored form: returned by value, so hold the returned object (or a reference bound to it),
  /// not pointers into it. For the skeletons alone, row_skeleton() and col_skeleton() are free.
  NestedBasis basis(int c) const;
  const std::vector<int> &row_skeleton(int c) const { return m_row_skel[c]; }
  const std::vector<int> &col_skeleton(int c) const { return m_col_skel[c]; }
  /// The stored sides of c's basis (U, V without identity rows; see StoredInterpolation).
  const StoredInterpolation &row_interpolation(int c) const { return m_U[c]; }
  const StoredInterpolation &col_interpolation(int c) const { return m_V[c]; }
  /// The bases while the compression builds them; store_bases() moves them into the stored form
  /// (weights in single precision when `single`; of the clusters held here, the skeletons of all)
  /// and empties this.
  std::vector<NestedBasis> &bases() { return m_bases; }
  void store_bases(bool single);
  /// The interpolation matrices of level l's clusters (held here) into the stored form now,
  /// their U and V in bases() freed; the skeletons stay until store_bases().
  void store_level_bases(int l, bool single);
  /// Far blocks of row cluster a: K(S_a, C_b), one per b in partition().far[a], same order.
  std::vector<H2Block> &far_blocks(int a) { return m_far[a]; }
  const std::vector<H2Block> &far_blocks(int a) const { return m_far[a]; }
  /// Near blocks of leaf a: K(rows of a, columns of b), one per b in partition().near[a].
  std::vector<H2Block> &near_blocks(int a) { return m_near[a]; }
  const std::vector<H2Block> &near_blocks(int a) const { return m_near[a]; }
  /// The near block of leaves (a, b), or null when (a, b) is no near block.
  H2Block *near_block(int a, int b);
  const H2Block *near_block(int a, int b) const;

  /// Y = K X for nrhs columns in cluster order, as HssMatrix::apply. O(N·r) per column.
  void apply(const double *X, int ldx, double *Y, int ldy, int nrhs = 1) const;
  /// The far field of X at every row skeleton: out[a] (|S_a| × nrhs) is what the far blocks of a
  /// and of its ancestors contribute to K(S_a, :) X (no near blocks). X: col_block() rows per
  /// point, cluster order. The product's upward, far and downward passes without the leaves.
  std::vector<DenseMatrix> skeleton_far_field(const double *X, int ldx, int nrhs) const;
  /// The same for Kᵀ: out[b] (|C_b| × nrhs) is what the far blocks of b and of its ancestors
  /// contribute to (Kᵀ Y)(C_b, :), for Y with row_block() rows per point.
  std::vector<DenseMatrix> skeleton_far_field_transposed(const double *Y, int ldy, int nrhs) const;

  /// Distributed over ranks (h2_distributed.hpp): owner(c) is the rank holding cluster c's bases
  /// (U, V), its far blocks (its block row) and, for a leaf, its near blocks; every rank knows
  /// every skeleton. Without owners (the default) this rank holds everything.
  void set_owners(std::vector<int> owner, int rank) { m_owners.set(std::move(owner), rank, m_tree.num_clusters()); }
  int owner(int c) const { return m_owners.owner(c); }
  bool holds(int c) const { return m_owners.holds(c); }
  bool holds_all() const { return m_owners.holds_all(); }
  int rank() const { return m_owners.rank(); }
  /// Take over cluster c's stored bases and blocks (gathering a distributed matrix on one rank).
  void adopt(int c, StoredInterpolation U, StoredInterpolation V, std::vector<H2Block> far, std::vector<H2Block> near);

  /// This rank's part in a stored form (persistence: session/h2_file.hpp): its sizes, the column
  /// scales, the block partition, every cluster's skeletons, the bases and blocks of the clusters
  /// held here, and the figures of the compression.
  void pack(PackWriter &w) const;
  /// The matrix pack() stored, on `tree` (the tree it was made on, built again from the points
  /// and the partition), held as `owner` says (empty: everything on this rank) by rank `rank`.
  /// Throws std::invalid_argument ("damaged: ...") for a stored form that does not fit the tree.
  static H2Matrix unpack(ClusterTree tree, std::vector<int> owner, int rank, PackReader &r);

  /// Recompute rank, block and memory figures.
  void update_stats();
  H2Stats &stats() { return m_stats; }
  const H2Stats &stats() const { return m_stats; }

private:
  ClusterTree m_tree;
  int m_row_block, m_col_block;
  std::vector<double> m_col_scale;
  BlockPartition m_partition;
  std::vector<NestedBasis> m_bases; ///< during the compression only
  std::vector<std::vector<int>> m_row_skel, m_col_skel;
  std::vector<int> m_row_forced, m_col_forced;
  std::vector<StoredInterpolation> m_U, m_V;
  std::vector<char> m_basis_stored; ///< while the compression runs: c's U and V are in m_U, m_V
  void store_basis(int c, bool single);
  void prepare_stored_bases();
  std::vector<std::vector<H2Block>> m_far, m_near;
  ClusterOwners m_owners;
  H2Stats m_stats;
};

} // namespace hssbem
