// Private to the H² factorization: the dense block left at the top of the elimination, and its
// solve.
#pragma once

#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/core/rank_comm.hpp"

#include <cstddef>
#include <memory>
#include <vector>

namespace hssbem::h2f {

/// The top block as the frontier leaves it: a grid of its boxes' blocks (box s's unknowns are
/// rows off[s] .. off[s + 1] − 1), block (s, t) at blocks[s · boxes + t].
struct BlockGrid {
  std::vector<int> off{0};
  std::vector<DenseMatrix> blocks;
  int boxes() const { return static_cast<int>(off.size()) - 1; }
  int size() const { return off.back(); }
  const DenseMatrix &block(int s, int t) const { return blocks[static_cast<std::size_t>(s) * boxes() + t]; }
  std::size_t bytes() const;
  /// The whole block in double (n × n), or in single precision into `out` (n × n, column-major)
  /// with ‖A‖_∞ in *inf_norm.
  DenseMatrix dense() const;
  void dense_single(float *out, double *inf_norm) const;
  /// y ← y + alpha A x.
  void gemv(double alpha, const double *x, double *y) const;
};

/// Where the frontier's top goes, box block by box block: begin() once with the boxes' row
/// offsets (box s holds rows off[s] .. off[s + 1] − 1), then put() for every block (s, t);
/// concurrent put() calls have different s.
class TopSink {
public:
  virtual ~TopSink() = default;
  virtual void begin(const std::vector<int> &off) = 0;
  virtual void put(int s, int t, DenseMatrix B) = 0;
  /// Whether the sink rounds to single precision (so another rank may send it rounded blocks).
  virtual bool single() const { return false; }
};

/// Into a BlockGrid (the double and the mixed LU, which keeps the blocks for its refinement).
class GridSink : public TopSink {
public:
  explicit GridSink(BlockGrid &G) : m_G(G) {}
  void begin(const std::vector<int> &off) override;
  void put(int s, int t, DenseMatrix B) override;

private:
  BlockGrid &m_G;
};

/// The top as one dense matrix in single precision, n × n column-major, and in double the sums
/// of its rows (A·1, the right-hand side of a trial solve).
struct SingleTop {
  int n = 0;
  std::unique_ptr<float[]> a;
  std::vector<double> row_sums;
};

/// Into a SingleTop: each block is rounded as it comes, and no copy of the top in double is
/// ever whole.
class SingleSink : public TopSink {
public:
  explicit SingleSink(SingleTop &A) : m_A(A) {}
  void begin(const std::vector<int> &off) override;
  void put(int s, int t, DenseMatrix B) override;
  bool single() const override { return true; }

private:
  SingleTop &m_A;
  std::vector<int> m_off;
};

/// The top block A (n × n) factored once and solved many times. Below `mixed_from` unknowns (or
/// with mixed_from ≤ 0) it is an LU in double. From there on the LU runs in single precision,
/// twice the speed of dgetrf, and each solve refines its result in double against A itself
/// (LAPACK's dsgesv scheme: x += LU⁻¹ (b − A x) until the residual is at rounding level), so the
/// result is as accurate as the double LU's. A is kept in double for the residuals as the
/// frontier's own blocks (the grid), never copied into one dense matrix (1.5× the memory of the
/// double LU). A factor that the refinement does not contract on a trial solve is redone in
/// double.
class TopBlock {
public:
  /// Factor A. False when A is singular to working precision (the double LU's test).
  bool factor(BlockGrid A, int mixed_from);
  /// Factor A in single precision alone, for a factorization whose panels are in single
  /// precision too (a preconditioner): no copy of A is kept and solves are not refined, so the
  /// top takes n² floats where the mixed LU takes three times that. False when A is singular to
  /// single precision: a zero pivot, or a trial solve (A x = A·1) off by more than `trial_tol`.
  bool factor_single(SingleTop A, double trial_tol);
  /// x ← A⁻¹ x (n entries).
  void solve(double *x) const;
  int size() const { return m_n; }
  bool mixed() const { return m_mixed; }
  bool single() const { return m_single; }
  /// The trial solve's error (factor_single), ‖x − 1‖∞.
  double trial_error() const { return m_trial; }
  std::size_t bytes() const { return m_A.bytes() + m_grid.bytes() + (m_lu ? static_cast<std::size_t>(m_n) * m_n * sizeof(float) : 0) + m_piv.size() * sizeof(int); }
  /// Refinement steps of the last solve (0 with the double LU).
  int last_steps() const { return m_steps; }

private:
  /// The refined solve; false when it stopped before the residual reached rounding level.
  bool refine(const double *b, double *x) const;

  int m_n = 0;
  DenseMatrix m_A;  ///< the double LU's factors
  BlockGrid m_grid; ///< (mixed) the block itself
  std::unique_ptr<float[]> m_lu; ///< (mixed) n × n single-precision LU factors
  std::vector<int> m_piv;
  double m_norm = 0; ///< ‖A‖_∞ (mixed)
  bool m_mixed = false;
  bool m_single = false;
  double m_trial = 0;
  mutable int m_steps = 0;
};

/// The top of a distributed factorization spread over its ranks, in single precision (panels in
/// single precision, a top of mixed_top_from or more): rank r holds the columns of the blocks
/// j ≡ r (mod P), kBlock wide, of the LU (RankComm::spread_getrf, ScaLAPACK), so that the ranks
/// share the top's flops and memory instead of rank 0 holding and factoring it alone. The solves
/// run in double arithmetic on the rounded factors, block column by block column: the owner of a
/// block solves its diagonal block once the others' updates to its rows are summed (one sum of
/// kBlock values over the ranks per block and triangle).
class SpreadTop {
public:
  static constexpr int kBlock = 128;
  /// Factor (collective, failure-atomic). `local`: this rank's columns (n × spread_columns(n,
  /// kBlock, rank, P)), `row_sums`: A·1 on this rank's rows of A, zero elsewhere (n entries).
  /// Throws H2Breakdown on every rank when the LU meets a zero pivot or its trial solve
  /// (A x = A·1) is off by more than trial_tol on any rank (fault site SpreadTopBreakdown: as if
  /// on this rank), std::length_error beyond ScaLAPACK's 32-bit local indexing.
  void factor(const RankComm &comm, int n, std::vector<float> local, std::vector<double> row_sums, double trial_tol);
  /// x ← A⁻¹ x, all n entries on every rank, in and out (collective).
  void solve(double *x) const;
  int size() const { return m_n; }
  std::size_t bytes() const { return m_lu.size() * sizeof(float) + m_piv.size() * sizeof(int); }
  double trial_error() const { return m_trial; }

private:
  /// Column c's position among this rank's columns, or -1 when another rank holds it.
  int local_column(int c) const;

  const RankComm *m_comm = nullptr;
  int m_n = 0, m_ranks = 1, m_rank = 0;
  std::vector<float> m_lu;
  std::vector<int> m_piv;
  double m_trial = 0;
};

} // namespace hssbem::h2f
