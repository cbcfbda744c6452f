/// \file h2_factorization.hpp
/// A fast direct factorization of the BEM system A = K E_S on the H² matrix of K (strong
/// admissibility) by strong recursive skeletonization, on the ranks that hold the matrix: each
/// rank eliminates its part's subtree box by box, and the rest, the top, is factored densely. The
/// method (skeletons, sparsification, elimination, parts and cross blocks, the top) is described
/// in docs/h2-factorization.md.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/h2/h2_distributed.hpp"
#include "hssbem/h2/h2_matrix.hpp"
#include "hssbem/h2factor/far_sketch.hpp"
#include "hssbem/h2factor/h2_breakdown.hpp"

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace hssbem {

namespace h2f {
class Frontier;
}

/// Parameters of the factorization; the defaults are the options' (-pc_h2_*, core/option_table.def).
struct H2FactorOptions {
  double rel_tol = option_default::pc_h2_rel_tol;        ///< relative tolerance of each skeleton (joint row/column ID)
  int leaf_size = option_default::pc_h2_leaf_size;       ///< dof nodes per box at the first level factored (≥ the H² leaves); 0: the H² leaves
  int sketch_columns = option_default::pc_h2_sketch_size; ///< random vectors of the far-field sketch; 0: chosen from rel_tol
  int top_size = option_default::pc_h2_top_size;         ///< factor the rest densely once at most this many unknowns remain
  int single_panels = -1;  ///< elimination panels and the working blocks at rest in single precision: 1, 0, or -1 (h2_single_panels(): when rel_tol ≥ 1e-5)
  /// From this many unknowns on, the dense top's LU is in single precision: refined in double by
  /// every solve with double panels, alone with single panels (its accuracy checked by a trial
  /// solve). ≤ 0: always double.
  int single_top_from = option_default::pc_h2_single_top_from;
  /// Stop at a level whose eliminations would cost more flops than factoring everything left
  /// densely (an upper bound of the level's Schur complements against the top's LU); false: go
  /// on while a level has a far field and more than top_size unknowns remain.
  bool top_when_cheaper = option_default::pc_h2_top_when_cheaper;
  /// On one rank, on a tree with parts (ClusterTree's partition constructor): eliminate each
  /// part's subtree separately, as several ranks do with one part each (cross blocks between the
  /// parts), the parts simulated on this rank. Ignored on a tree without parts; always so on
  /// several ranks.
  bool within_parts = false;
  /// On several ranks, a single-precision top (single panels, single_top_from or more unknowns)
  /// is spread over the ranks (ScaLAPACK, blocks of 128 columns); false: factored on rank 0.
  bool spread_top = option_default::pc_h2_spread_top;
};

struct H2FactorLevelStats {
  int level = 0;               ///< tree level (0 = root)
  int boxes = 0;               ///< boxes skeletonized
  double mean_candidates = 0;  ///< unknowns per box before
  int max_candidates = 0;
  double mean_rank = 0;        ///< skeleton size
  int max_rank = 0;
  long long eliminated = 0;    ///< unknowns eliminated at this level
  std::size_t bytes = 0;       ///< factors stored for this level
  double seconds = 0;          ///< skeletons, elimination and merge of this level
  long long cross_blocks = 0;  ///< cross blocks between boxes of different parts at this level (pairs)
  std::size_t cross_bytes = 0; ///< their memory (both copies)
};

struct H2FactorStats {
  std::vector<H2FactorLevelStats> levels; ///< from the finest level factored up
  int top_size = 0;                       ///< unknowns of the dense top block
  bool top_mixed = false;                 ///< the top's LU in single precision, refined in double (H2FactorOptions::single_top_from)
  bool top_single = false;                ///< the top's LU in single precision alone, not refined (single panels and a top of single_top_from or more)
  int top_spread = 0;                     ///< ranks the top is spread over (H2FactorOptions::spread_top; 0: on rank 0 or one rank)
  std::size_t bytes = 0, top_bytes = 0;   ///< all factors; the top's LU (and, mixed, the top block in double)
  /// The largest working store of the factorization (blocks between active boxes, fill-in,
  /// restricted bases), which is freed when it ends.
  std::size_t workspace_bytes = 0;
  double time_sketch = 0;                 ///< far-field sketch (0 when cached)
  double time_init = 0, time_skeleton = 0, time_eliminate = 0, time_merge = 0, time_top = 0;
  double flops_schur = 0;                 ///< of the Schur complement products
  int sketch_columns = 0;
  bool single_panels = false;
  int parts = 1;                          ///< parts eliminated separately (H2FactorOptions::within_parts)
  int top_boxes = 0;                      ///< boxes left for the top (with parts: the parts' roots, or more)
  /// On several ranks the levels, factors, flops and times above are this rank's (its part's
  /// subtree); the top's figures are rank 0's (spread: this rank's share), top_size every rank's.
  double seconds() const { return time_sketch + time_init + time_skeleton + time_eliminate + time_merge + time_top; }
};

/// Per H² matrix, what every factorization of it may reuse (the far-field sketches, by size), and
/// the ranks that hold it. Not thread-safe.
class H2FactorCache {
public:
  /// Of a matrix held whole by this rank alone.
  explicit H2FactorCache(const H2Matrix &K) : m_K(&K) {}
  /// Of a distributed matrix: its sketches are made by the distributed passes (collective),
  /// each rank keeping its clusters' rows.
  explicit H2FactorCache(const H2DistributedProduct &K) : m_K(&K.matrix()), m_dist(&K) {}
  const H2Matrix &matrix() const { return *m_K; }
  /// The ranks that hold the matrix (a matrix held whole: one).
  const RankComm &comm() const { return m_dist ? m_dist->comm() : m_one; }
  /// This rank's points: positions [first_point(), first_point() + num_points()) of cluster order.
  int first_point() const { return m_dist ? m_dist->first_point() : 0; }
  int num_points() const { return m_dist ? m_dist->num_points() : m_K->tree().num_points(); }
  /// The sketch with p columns, made on first use (seconds spent in *made, 0 when cached).
  /// Failure-atomic on the ranks.
  const FarFieldSketch &sketch(int p, double *made = nullptr);
  /// Use `s` as the sketch with s.columns columns (a test compares two factorizations on one
  /// sketch: the distributed one's, gathered).
  void adopt(FarFieldSketch s) { m_sketches.push_back(std::make_unique<FarFieldSketch>(std::move(s))); }

private:
  const H2Matrix *m_K;
  const H2DistributedProduct *m_dist = nullptr;
  SerialComm m_one;
  std::vector<std::unique_ptr<FarFieldSketch>> m_sketches;
};

class H2Factorization {
public:
  /// Factor A-hat = (K E_S + c Φ Φᵀ) D for the pattern `sel` on the H² matrix `cache.matrix()`
  /// (which must outlive this object) on the cache's ranks (collective, failure-atomic); on
  /// several ranks the same steps as one rank with within_parts on the same tree (see
  /// docs/h2-factorization.md). `rigid_modes`: row-major 3N × 6 orthonormal modes (mesh
  /// order) of a pure-traction problem's regularisation, or null. Throws H2Breakdown on every
  /// rank for a singular pivot block on any rank, std::invalid_argument for bad options; another
  /// error on its rank and PeerFault on the others (fault sites H2FSubtree, H2FTop).
  H2Factorization(H2FactorCache &cache, const SystemSelection &sel, const H2FactorOptions &options, const std::vector<double> *rigid_modes = nullptr);
  /// The factorization pack() stored, of the H² matrix `K` (the one it was made of, loaded
  /// too) on the ranks of `comm` (as many as it was made on; this rank's points from `first`,
  /// `count` of them). Collective; throws std::invalid_argument ("damaged: ...") on every rank
  /// for a stored form that does not fit K or this rank's rows.
  H2Factorization(const H2Matrix &K, const RankComm &comm, int first, int count, PackReader &r);
  ~H2Factorization();
  H2Factorization(const H2Factorization &) = delete;
  H2Factorization &operator=(const H2Factorization &) = delete;

  /// x = A⁻¹ b on this rank's rows (collective): 3 values per point of this rank, in cluster
  /// order (one rank: every point; ClusterTree::to_cluster_order converts), x may alias b. Only
  /// the top's unknowns cross ranks.
  void solve(const double *b, double *x) const;
  /// X ← A⁻¹ X for nrhs right-hand sides at once (column-major, leading dimension ld ≥ 3
  /// num_points(), this rank's rows as solve() takes them; collective): solve()'s steps as
  /// matrix products over the block, the factors read once per block.
  void solve_block(double *X, int nrhs, int ld) const;
  const RankComm &comm() const { return *m_comm; }
  const H2Matrix &matrix() const { return m_K; }
  /// This rank's rows: 3 per point from first_point() (cluster order), num_points() points.
  int first_point() const { return m_first; }
  int num_points() const { return m_count; }
  const H2FactorStats &stats() const { return m_stats; }
  /// This rank's factors in a stored form (persistence: session/h2_file.hpp): the options, the
  /// pattern, the steps, the top (this rank's share) and the figures. The solve of a factorization
  /// unpacked from it is this one's, bit for bit.
  void pack(PackWriter &w) const;
  const H2FactorOptions &options() const { return m_options; }
  /// A single-precision top's trial solve error (H2FactorStats::top_single; rank 0's when it is
  /// on rank 0), else 0.
  double top_trial() const;
  /// Steps whose unknowns (the box's, its skeleton's, and those its Schur complement touched)
  /// lie in more than one part of the tree (0 when the parts are eliminated separately).
  int steps_crossing_parts() const;

  struct Factors; ///< the elimination steps and the top (private)

private:
  /// The phases (h2_factorization.cpp, factor_levels.cpp, factor_top.cpp), collective.
  const FarFieldSketch &prepare(H2FactorCache &cache, const SystemSelection &sel, const std::vector<double> *rigid_modes);
  void eliminate_levels(h2f::Frontier &front, int l0, int last);
  void eliminate_level(h2f::Frontier &front, const std::vector<int> &boxes, H2FactorLevelStats &ls);
  void factor_top(std::optional<h2f::Frontier> &front, bool single_store);

  const H2Matrix &m_K;
  const RankComm *m_comm;
  int m_first = 0, m_count = 0; ///< this rank's points (cluster order)
  H2FactorOptions m_options;
  std::unique_ptr<Factors> m_f;
  H2FactorStats m_stats;
};

/// Sketch columns used for a tolerance when H2FactorOptions::sketch_columns is 0 (48 to 320).
int default_sketch_columns(double rel_tol);

/// The most sketch columns H2FactorOptions::sketch_columns may ask for: far beyond what any
/// tolerance needs (the skeletons of a box stay below a few hundred), and each column is a pass
/// over the far field in both directions.
constexpr int kMaxSketchColumns = 4096;

/// x = A⁻¹ b with b and x in mesh order (3 values per node; x may alias b), for a factorization
/// on one rank: F.solve() between ClusterTree::to_cluster_order and to_mesh_order.
void solve_mesh_order(const H2Factorization &F, const double *b, double *x);


/// ‖I − A F⁻¹‖₂ estimated by power iterations from a random vector (the largest of the ratios
/// ‖(I − A F⁻¹) v‖ / ‖v‖ met; collective on F's ranks): how far the factorization is from an
/// exact inverse of A, for apply_a(x, y): y = A x with the operator of the factored pattern, on
/// this rank's rows (as F.solve()).
double estimate_inverse_error(const H2Factorization &F, const std::function<void(const double *, double *)> &apply_a, int iterations = 5, unsigned seed = 1);

} // namespace hssbem
