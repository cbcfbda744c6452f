// Private to the H² factorization: the dense block left at the top of the elimination, factored
// once and solved many times (top_assembly.hpp gathers it from the frontier).
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

/// A factored top: x ← A⁻¹ x with all n entries of x on the ranks that hold it.
class DenseTop {
public:
  virtual ~DenseTop() = default;
  virtual void solve(double *x) const = 0;
  virtual int size() const = 0;
  virtual std::size_t bytes() const = 0;
  /// A single-precision top's trial solve error, else 0.
  virtual double trial_error() const { return 0; }
};

/// The top in double precision on one rank. Below `mixed_from` unknowns (or with mixed_from ≤ 0)
/// an LU in double. From there on the LU runs in single precision, twice the speed of dgetrf, and
/// each solve refines its result in double against A itself (LAPACK's dsgesv scheme: x += LU⁻¹
/// (b − A x) until the residual is at rounding level), so the result is as accurate as the double
/// LU's. A is kept in double for the residuals as the frontier's own blocks (the grid), never
/// copied into one dense matrix (1.5× the memory of the double LU). A factor that the refinement
/// does not contract on a trial solve is redone in double.
class TopBlock : public DenseTop {
public:
  /// Factor A. False when A is singular to working precision (the double LU's test).
  bool factor(BlockGrid A, int mixed_from);
  void solve(double *x) const override;
  int size() const override { return m_n; }
  bool mixed() const { return m_mixed; }
  std::size_t bytes() const override { return m_A.bytes() + m_grid.bytes() + m_lu.size() * sizeof(float) + m_piv.size() * sizeof(int); }

private:
  /// The refined solve; false when it stopped before the residual reached rounding level.
  bool refine(const double *b, double *x) const;

  int m_n = 0;
  DenseMatrix m_A;  ///< the double LU's factors
  BlockGrid m_grid; ///< (mixed) the block itself
  std::vector<float> m_lu; ///< (mixed) n × n single-precision LU factors
  std::vector<int> m_piv;
  double m_norm = 0; ///< ‖A‖_∞ (mixed)
  bool m_mixed = false;
};

/// Every single-precision top (panels in single precision, a top of single_top_from or more): an
/// LU in single precision alone over the ranks of `comm` (one rank: on it alone), rank r holding
/// the columns of the blocks j ≡ r (mod P), kBlock wide (RankComm::spread_getrf, ScaLAPACK on
/// several ranks, getrf on one), so that the ranks share the top's flops and memory. No copy in
/// double is kept. The solves run in double arithmetic on the rounded factors, so the
/// preconditioner stays one linear operator (rounding the right-hand side, as sgetrs does, made
/// GMRES stall at a true residual of 1.9e-6 on the 80k sphere), block column by block column: the
/// owner of a block solves its diagonal block once the others' updates to its rows are summed
/// (one sum of kBlock values over the ranks per block and triangle).
class SpreadTop : public DenseTop {
public:
  static constexpr int kBlock = 128;
  /// Factor (collective on comm, failure-atomic). `local`: this rank's columns (n ×
  /// spread_columns(n, kBlock, rank, P)), `row_sums`: A·1 on this rank's rows of A, zero
  /// elsewhere (n entries). Throws H2Breakdown on every rank when the LU meets a zero pivot or
  /// its trial solve (A x = A·1) is off by more than trial_tol on any rank (fault site
  /// SpreadTopBreakdown: as if on this rank), std::length_error beyond ScaLAPACK's 32-bit local
  /// indexing. comm must outlive this object.
  void factor(const RankComm &comm, int n, std::vector<float> local, std::vector<double> row_sums, double trial_tol);
  /// x ← A⁻¹ x, all n entries on every rank, in and out (collective).
  void solve(double *x) const override;
  int size() const override { return m_n; }
  std::size_t bytes() const override { return m_lu.size() * sizeof(float) + m_piv.size() * sizeof(int); }
  double trial_error() const override { return m_trial; }

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
