// Private to the H² factorization: the dense block left at the top of the elimination, and its
// solve.
#pragma once

#include "hssbem/core/dense_matrix.hpp"

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
  /// x ← A⁻¹ x (n entries).
  void solve(double *x) const;
  int size() const { return m_n; }
  bool mixed() const { return m_mixed; }
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
  mutable int m_steps = 0;
};

} // namespace hssbem::h2f
