/// \file capacitance.hpp
/// The inverse of a principal submatrix C = W(J, J) of a fixed dense matrix W, kept up to date
/// while the index set J gains and loses indices: the capacitance matrix of a Woodbury update.
///
/// A scene's reference factorization turns every boundary-condition pattern into "the reference
/// plus |J| switched columns", and the solve needs C⁻¹ for the switched set J (see
/// dense_scene.hpp). A moving contact changes J by a few indices per frame; rebuilding C⁻¹ costs
/// 8/3 |J|³ flops, while removing r indices and adding a (block inverse by Schur complements)
/// costs about 2|J|²r + 4|J|²a. Errors of the incremental steps accumulate slowly; the owner
/// rebuilds now and then (DenseScene: every `refresh_every` updates).
#pragma once

#include <cstddef>
#include <vector>

namespace hssbem {

class CapacitanceInverse {
public:
  /// W is n×n, column-major with leading dimension n; it must outlive this object and not change.
  CapacitanceInverse(const double *W, int n);

  /// C⁻¹ for the index set J from scratch (LU of W(J, J), then its inverse). Throws
  /// std::runtime_error when W(J, J) is singular.
  void rebuild(const std::vector<int> &J);
  /// Remove the indices `drop` (each in the set) and add `add` (none in it), in that order.
  /// Throws std::runtime_error when a Schur complement is singular (the caller then rebuilds).
  void update(const std::vector<int> &drop, const std::vector<int> &add);

  /// The current index set, in the order of C⁻¹'s rows and columns.
  const std::vector<int> &indices() const { return m_J; }
  /// Position of index j in indices(), or -1.
  int position(int j) const { return m_pos[j]; }
  int size() const { return static_cast<int>(m_J.size()); }
  /// C⁻¹, size()×size(), column-major (leading dimension size()).
  const double *inverse() const { return m_inv.data(); }
  /// s = C⁻¹ r for r of length size().
  void apply(const double *r, double *s) const;

  /// Flops of rebuild(J) for |J| = k, and of update() dropping r and adding a indices from |J| = k.
  static double rebuild_flops(double k) { return 8.0 / 3.0 * k * k * k; }
  static double update_flops(double k, double r, double a);

private:
  void drop_indices(const std::vector<int> &drop);
  void add_indices(const std::vector<int> &add);
  double w(int i, int j) const { return m_W[i + static_cast<std::size_t>(j) * m_n]; }

  const double *m_W;
  int m_n;
  std::vector<int> m_J, m_pos;
  std::vector<double> m_inv;
};

} // namespace hssbem
