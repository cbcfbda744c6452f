// Private to the H² factorization: the dense block left at the top of the elimination, and its
// solve.
#pragma once

#include "hssbem/core/dense_matrix.hpp"

#include <cstddef>
#include <vector>

namespace hssbem::h2f {

/// The top block A (n × n) factored once and solved many times. Below `mixed_from` unknowns (or
/// with mixed_from ≤ 0) it is an LU in double. From there on the LU runs in single precision,
/// twice the speed of dgetrf, and each solve refines its result in double against A itself
/// (LAPACK's dsgesv scheme: x += LU⁻¹ (b − A x) until the residual is at rounding level), so the
/// result is as accurate as the double LU's; the block is kept in double for the residuals (1.5×
/// the memory). A factor that the refinement does not contract on a trial solve is redone in
/// double.
class TopBlock {
public:
  /// Factor A. False when A is singular to working precision (the double LU's test).
  bool factor(DenseMatrix A, int mixed_from);
  /// x ← A⁻¹ x (n entries).
  void solve(double *x) const;
  int size() const { return m_A.m; }
  bool mixed() const { return m_mixed; }
  std::size_t bytes() const { return m_A.bytes() + m_lu.size() * sizeof(float) + m_piv.size() * sizeof(int); }
  /// Refinement steps of the last solve (0 with the double LU).
  int last_steps() const { return m_steps; }

private:
  /// The refined solve; false when it stopped before the residual reached rounding level.
  bool refine(const double *b, double *x) const;

  DenseMatrix m_A; ///< the double LU's factors, or (mixed) the block itself
  std::vector<float> m_lu;
  std::vector<int> m_piv;
  double m_norm = 0; ///< ‖A‖_F (mixed)
  bool m_mixed = false;
  mutable int m_steps = 0;
};

} // namespace hssbem::h2f
