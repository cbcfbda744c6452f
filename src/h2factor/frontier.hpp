// Private to the H² factorization: the active boxes of one level and their explicit blocks (the
// block store of strong recursive skeletonization). Its member functions live by responsibility:
// frontier.cpp (the boxes, their bases and far parts), frontier_merge.cpp (a level into its
// parents), box_elimination.cpp (one box's step), frontier_ranks.cpp (what crosses ranks) and
// top_assembly.cpp (the dense top); the steps it produces are elimination_step.hpp's.
#pragma once

#include "elimination_step.hpp"
#include "stored_block.hpp"

#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/h2/h2_matrix.hpp"
#include "hssbem/h2factor/far_sketch.hpp"

#include <algorithm>
#include <map>
#include <vector>

namespace hssbem::h2f {

class TopSink;

/// One side of cluster c's nested basis in double (rows: U, else V), candidates × rank.
inline DenseMatrix basis_side(const H2Matrix &K, int c, bool rows) { return rows ? K.row_interpolation(c).expand() : K.col_interpolation(c).expand(); }

/// A fill-in block that an elimination created between two boxes that are not close; kept aside
/// while other boxes of the same colour class are eliminated, then added with add_fill().
struct NewFill {
  int row, col;
  DenseMatrix B;
};

/// A box's skeleton: local indices into its active unknowns.
struct BoxSkeleton {
  std::vector<int> S, R;
  DenseMatrix T; ///< |S| × |R|
};

/// What a box's step did to the cross blocks it shares with boxes of other parts, as the other
/// side applies it after the level: it keeps rows `kept` of a block in its rows (local indices,
/// in the order of its new active unknowns), and a block B in its columns becomes B C with
/// C = A_XX⁻¹(:, kept) (|D_X| × |kept|).
struct CrossSide {
  bool recorded = false;
  std::vector<int> kept;
  DenseMatrix C;
};

class Frontier {
public:
  /// The leaves of K, with their near blocks in A-hat form; `single`: blocks rest in single
  /// precision (StoredBlock). `part` (per cluster: its part, −1 above the parts; empty: one part)
  /// splits the boxes into parts that are never close to each other: their couplings stay as
  /// cross blocks in two copies, one for each side (docs/h2-factorization.md, "Parts and
  /// ranks"). On several ranks (`part` then required, part p on rank p) this rank holds its
  /// boxes' unknowns, bases and blocks, its rows of the cross blocks and the copies of those in
  /// its boxes' columns; K is this rank's part of a distributed H² matrix and the sketch its rows.
  Frontier(const H2Matrix &K, const FarFieldSketch &sketch, const Pattern &pattern, bool single, std::vector<int> part, const RankComm &comm);
  /// Whether this rank holds box c (always on one rank).
  bool mine(int c) const { return m_owner.empty() || m_owner[c] == m_rank; }

  const std::vector<int> &boxes() const { return m_front; }
  const std::vector<int> &active(int X) const { return m_D[X]; }
  std::size_t active_total() const;
  /// Whether some box of level l has a far field or fill-in to skeletonize against.
  bool level_has_far_field(int l) const;
  /// The close boxes of the frontier other than X (of X's part).
  std::vector<int> neighbours(int X) const;
  /// Whether X and Y lie in one part (always without parts).
  bool same_part(int X, int Y) const { return m_box_part.empty() || m_box_part[X] == m_box_part[Y]; }
  /// Whether level l's box X takes a step (in the frontier, below or at its part's root).
  bool steps_at(int X) const { return m_in_front[X] && (m_box_part.empty() || m_box_part[X] >= 0); }
  /// Cross blocks now (pairs, each counted once) and the bytes of both copies.
  long long cross_pairs() const;
  std::size_t cross_bytes() const;
  /// After a level whose boxes went through their steps: each cross block gets the other
  /// side's part of the steps (the boxes' CrossSide, recorded by eliminate()), as if the two
  /// copies lived on two ranks and exchanged the sides at the level's end.
  void finish_level();

  /// Before X's steps 0–3, with no step of another box adding fill-in meanwhile (add_fill()
  /// inserts into the maps of the store): the fill-in blocks in X's columns, located once, so
  /// that the steps never search a map that a concurrent add_fill() may change.
  void claim(int X);
  /// Step 0: the unknowns of X become A_XX x_X (a block-Jacobi change of variables); the LU of
  /// A_XX goes to st (box, D, dpiv). Throws H2Breakdown when A_XX is singular to working precision.
  void precondition(int X, Step *st);
  /// Step 1: the joint row/column skeleton of X at relative tolerance tol.
  BoxSkeleton skeleton(int X, double tol) const;
  /// Steps 2–3: sparsify with the skeleton, eliminate the redundant unknowns, add the Schur
  /// complement to the blocks of X's skeleton and neighbours; X keeps its skeleton. The rest of
  /// the step goes to st; adds the Schur complement's flops to *flops. Fill-in on pairs that had
  /// none goes to *fresh, for add_fill(). Throws H2Breakdown for a singular pivot block. Boxes
  /// with disjoint closed neighbourhoods may go through steps 0–3 concurrently (add_fill() for
  /// one of them, serialised with claim(), inserts only into the rows of its neighbourhood).
  void eliminate(int X, const BoxSkeleton &sk, Step *st, double *flops, std::vector<NewFill> *fresh);
  /// eliminate()'s parts: rows R −= Tᵀ rows S and columns R −= columns S T in every block of X
  /// (the redundant unknowns then couple to X and its neighbours only); the LU of the redundant
  /// block and the panels L_p = A(I, R) U⁻¹, U_p = L⁻¹ P A(R, I) into st (I: X's skeleton and
  /// its neighbours `targets`, rows off[t] .. off[t + 1] − 1 of I); and A(I, I) −= L_p U_p into
  /// the blocks, fill-in that is new into *fresh.
  void sparsify(int X, const BoxSkeleton &sk);
  void panels(int X, int k, const std::vector<int> &targets, const std::vector<int> &off, Step &st) const;
  void schur_complement(int X, const std::vector<int> &targets, const std::vector<int> &off, const Step &st, std::vector<NewFill> *fresh);
  /// Park the blocks that precondition() and eliminate() opened for X (single precision only).
  void rest(int X);
  /// Store fill-in blocks that eliminate() created.
  void add_fill(std::vector<NewFill> &&fresh);
  /// Bytes of the block store, fill-in and restricted bases now.
  std::size_t store_bytes() const;
  /// The largest store_bytes() seen at the checkpoints (construction, note_bytes(), and a merge,
  /// which holds both levels' blocks for a moment).
  std::size_t peak_bytes() const { return m_peak; }
  void note_bytes() { m_peak = std::max(m_peak, store_bytes()); }
  /// The frontier of level l − 1 from that of level l (boxes never merge above their part's
  /// root: a part's root stays in the frontier as it is).
  void merge(int l);
  /// The top (collective): every rank takes the remaining unknowns' rows of its boxes into its
  /// sink, whose messages carry them on (top_assembly.hpp); the blocks move out of the store (the
  /// frontier is spent). *own gets this rank's top unknowns, *pos their positions in the top
  /// (boxes in frontier order); returns the top's size.
  int take_top(TopSink &sink, std::vector<int> *own, std::vector<int> *pos);

private:
  /// Box row s of the top (position s of the frontier) into the sink; its blocks move out.
  void take_row(int s, TopSink &sink);
  /// Once the top's rows are out: every block, basis and copy goes (the unknowns stay).
  void release_stores();
  /// Several ranks, before the top: every box's unknowns to every rank, and the column data
  /// (Ψ, bases) that the other ranks' rows of the top need from this rank's boxes.
  void share_top_columns();
  /// The top's row offsets: box s of the frontier holds rows off[s] .. off[s + 1] − 1.
  std::vector<int> top_offsets() const;
  /// The positions of this rank's boxes in the frontier.
  std::vector<int> my_positions() const;
  DenseMatrix leaf_col_basis(int c) const;
  DenseMatrix leaf_near(int a, int b) const;
  /// The m × n block at out (leading dimension ld) += c Φ_P Ψ_Qᵀ, the regularisation between P and Q.
  void add_regularisation(int m, int n, double *out, int ld, int P, int Q) const;
  DenseMatrix restricted_basis(int P, int a, bool rows) const;
  /// out (|P| × |Q|, leading dimension ld) += the current block between boxes P and Q that are
  /// not close: the H² far block above them through their bases, the regularisation, the fill-in.
  void add_far_part(int P, int Q, double *out, int ld) const;
  DenseMatrix far_part(int P, int Q) const;
  /// The fill-in between the new boxes that are not close (the children's blocks move out).
  std::vector<std::map<int, StoredBlock>> merged_fill(int l);
  /// b opened for box X's step (logged for rest(X)).
  DenseMatrix &open(int X, StoredBlock &b);
  void settle(StoredBlock &b) const
  {
    if (m_single) b.park();
  }
  std::vector<int> parts_of(int P, int l) const;
  /// Several ranks: for pairs (b another rank's, c mine), c's column data that b's rows need
  /// (unknowns, Ψ, and, where b and c are not close, c's column basis carried to the far block).
  void send_column_data(const std::vector<std::pair<int, int>> &pairs);
  /// Several ranks: the far parts of pairs (b mine, c another rank's) for the copies in c's
  /// columns, with b's unknowns.
  void send_far_parts(const std::vector<std::pair<int, int>> &pairs);
  /// What those two and exchange_leaf_copies() send: other ranks' boxes' unknowns, Ψ, column
  /// bases, far parts and cross blocks.
  void read_records(const std::vector<std::vector<double>> &recv);
  /// The leaves' unknowns, restricted bases, Φ, Ψ and blocks (this rank's).
  void init_leaves();
  /// Several ranks: the leaves' cross blocks, copied to the ranks of their columns.
  void exchange_leaf_copies();
  /// finish_level()'s work on this rank's copies.
  void apply_other_sides();
  /// Several ranks: the sides of this level's steps to the ranks of the partners' copies.
  void exchange_sides();
  /// merge(): the new boxes' unknowns, Φ, Ψ and restricted bases (this rank's parents), then
  /// their blocks (and the frontier becomes `front`).
  void merge_bases(const std::vector<int> &parents);
  void merge_blocks(int l, std::vector<int> &front, std::vector<char> &in_front);
  /// Several ranks: the data the new level's cross blocks need, before merge() assembles them.
  void prepare_cross_merge(int l, const std::vector<int> &front, const std::vector<char> &in_front);
  /// The far ancestors (a, b) of boxes P and Q (a = P or above, b = Q or above).
  std::pair<int, int> far_pair(int P, int Q) const;
  /// Q's column basis carried to b: its own, or the one another rank sent.
  DenseMatrix col_basis_to(int Q, int b) const;
  /// Whether (P, Q) of the current frontier hold a cross block.
  bool cross_close(int P, int Q) const { return m_in_front[P] && m_in_front[Q] && !same_part(P, Q) && m_part.is_close(P, Q); }
  /// The block between new boxes P and Q of level l − 1 in `which` (m_M between close boxes; a
  /// cross block's copy, m_X or m_G), from the children's blocks there, which move out of the
  /// store (each serves exactly one such pair), and the far parts between the children.
  DenseMatrix assemble(int P, int Q, int l, std::vector<std::map<int, StoredBlock>> &which);

  const H2Matrix &m_K;
  const ClusterTree &m_tree;
  const BlockPartition &m_part;
  const FarFieldSketch &m_sketch;
  const Pattern &m_pat;
  int m_w;
  std::vector<int> m_front;
  std::vector<char> m_in_front;
  std::vector<std::vector<int>> m_D;          ///< active unknowns of each frontier box
  std::vector<StoredBlock> m_Eu, m_Ew;        ///< H² row and column bases restricted to m_D (expanded; at rest like the blocks)
  std::vector<DenseMatrix> m_Phi, m_Psi;      ///< regularisation c Φ Ψᵀ: Φ and Ψ restricted to m_D (|m_D| × 6)
  bool m_single;
  std::vector<std::map<int, StoredBlock>> m_M; ///< blocks between close frontier boxes (current values)
  std::vector<std::map<int, StoredBlock>> m_F; ///< fill-in between boxes that are not close (updates only)
  std::vector<int> m_box_part;                 ///< per cluster: its part (-1 above them); empty: one part
  /// Cross blocks between boxes of different parts that the H² partition calls close (full
  /// values): m_X[X][Y] is the copy in X's rows (X's side applied by X's steps, Y's by
  /// finish_level), m_G[X][Y] the copy in Y's columns (the reverse); m_cross[X] the partners.
  std::vector<std::map<int, StoredBlock>> m_X, m_G;
  std::vector<std::vector<int>> m_cross;
  std::vector<CrossSide> m_side; ///< per box: its side of the current level's step
  const RankComm *m_comm;        ///< the ranks (a SerialComm on one)
  std::vector<int> m_owner;      ///< per cluster: the rank holding it (empty on one rank)
  int m_rank = 0;
  std::map<std::pair<int, int>, DenseMatrix> m_remote_w; ///< (c, b): another rank's box c's column basis carried to b
  std::map<std::pair<int, int>, DenseMatrix> m_pair_far; ///< (b, c): the far part of boxes of two ranks, from b's rank
  std::vector<std::vector<StoredBlock *>> m_opened; ///< per box: blocks its step has opened
  std::size_t m_peak = 0;
  std::vector<std::vector<int>> m_fill_cols;   ///< m_fill_cols[X]: boxes Z with a block m_F[Z][X]
  std::vector<std::vector<StoredBlock *>> m_fill_col_blocks; ///< those blocks, as claim(X) found them
};

} // namespace hssbem::h2f
