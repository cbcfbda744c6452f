// Private to the H² factorization: the dense block left at the top of the elimination, factored
// once and solved many times (top_assembly.hpp gathers it from the frontier).
#pragma once

#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/core/packed.hpp"
#include "hssbem/core/rank_comm.hpp"

#include <cstddef>
#include <memory>
#include <vector>

namespace hssbem::h2f {

/// A factored top: x ← A⁻¹ x with all n entries of x on the ranks that hold it.
class DenseTop {
public:
  virtual ~DenseTop() = default;
  virtual void solve(double *x) const = 0;
  virtual std::size_t bytes() const = 0;
  /// A single-precision top's trial solve error, else 0.
  virtual double trial_error() const { return 0; }
};

/// The top in double precision on one rank: an LU in double below `mixed_from` unknowns (or with
/// mixed_from ≤ 0), from there on an LU in single precision whose every solve refines in double
/// against A, kept beside it (LAPACK's dsgesv scheme; docs/h2-factorization.md, "The top").
class TopBlock : public DenseTop {
public:
  /// Factor A (square). False when A is singular to working precision (the double LU's test).
  bool factor(DenseMatrix A, int mixed_from);
  void solve(double *x) const override;
  bool mixed() const { return m_mixed; }
  /// The factored top in a stored form and back (persistence; unpack throws "damaged: ...").
  void pack(PackWriter &w) const;
  void unpack(PackReader &r);
  std::size_t bytes() const override { return m_A.bytes() + m_lu.size() * sizeof(float) + m_piv.size() * sizeof(int); }

private:
  /// The refined solve; false when it stopped before the residual reached rounding level.
  bool refine(const double *b, double *x) const;

  int m_n = 0;
  DenseMatrix m_A;         ///< the double LU's factors, or (mixed) the block itself
  std::vector<float> m_lu; ///< (mixed) n × n single-precision LU factors
  std::vector<int> m_piv;
  double m_norm = 0; ///< ‖A‖_∞ (mixed)
  bool m_mixed = false;
};

/// Every single-precision top (panels in single precision, a top of single_top_from or more): an
/// LU in single precision alone over the ranks of `comm` (one rank: on it alone), rank r holding
/// the columns of the blocks j ≡ r (mod P), kBlock wide (RankComm::spread_getrf). The solves run
/// in double arithmetic on the rounded factors, block column by block column: the owner of a
/// block solves its diagonal block once the others' updates to its rows are summed
/// (docs/h2-factorization.md, "The top").
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
  std::size_t bytes() const override { return m_lu.size() * sizeof(float) + m_piv.size() * sizeof(int); }
  double trial_error() const override { return m_trial; }
  /// This rank's share of the factored top in a stored form, and back on `comm` (of the same
  /// size and rank as the one it was factored on; unpack throws "damaged: ...").
  void pack(PackWriter &w) const;
  void unpack(const RankComm &comm, PackReader &r);

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
