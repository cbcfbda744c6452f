/// \file capacitance.hpp
/// Solves with a principal submatrix C = W(J, J) of a fixed dense matrix W while the index set J
/// gains and loses indices: the capacitance matrix of a Woodbury update.
///
/// A scene's reference factorization turns every boundary-condition pattern into "the reference
/// plus |J| switched columns", and the solve needs C⁻¹ for the switched set J (see
/// dense_scene.hpp). A moving contact changes J by a few indices per frame; rebuilding C⁻¹ costs
/// 8/3 |J|³ flops, while removing r indices and adding a (block inverse by Schur complements)
/// costs about 2|J|²r + 6|J|²a.
///
/// Precision. C itself is kept explicitly in double. Its inverse is kept in double, or — for
/// large sets, where the updates' GEMMs dominate a frame — in single precision (twice the GEMM
/// rate, half the memory traffic), and then every solve is refined in double against C
/// (s ← s + C⁻¹(r − C s)) until ‖r − C s‖ ≤ 1e-13 ‖r‖: the answer is double-accurate as long as
/// the single-precision inverse contracts the residual. When it stops contracting (rounding
/// accumulated over many updates, or an ill-conditioned C), solve() says so and the owner
/// rebuilds (in double if that was single already).
#pragma once

#include <climits>
#include <cstddef>
#include <vector>

namespace hssbem {

class CapacitanceInverse {
public:
  /// W is n×n, column-major with leading dimension n; it must outlive this object and not change.
  /// Rebuilds keep the inverse in single precision for sets of at least `single_from` indices
  /// (INT_MAX: always double).
  CapacitanceInverse(const double *W, int n, int single_from = INT_MAX);

  /// C⁻¹ for the index set J from scratch (LU of W(J, J), then its inverse). Throws
  /// std::runtime_error when W(J, J) is singular. force_double: keep the inverse in double.
  void rebuild(const std::vector<int> &J, bool force_double = false);
  /// Remove the indices `drop` (each in the set) and add `add` (none in it), in that order.
  /// Throws std::runtime_error when a Schur complement is singular (the caller then rebuilds).
  void update(const std::vector<int> &drop, const std::vector<int> &add);

  /// The current index set, in the order of C's rows and columns.
  const std::vector<int> &indices() const { return m_J; }
  /// Position of index j in indices(), or -1.
  int position(int j) const { return m_pos[j]; }
  int size() const { return static_cast<int>(m_J.size()); }
  bool single() const { return m_single; }

  /// s = C⁻¹ r for r of length size(); in single precision refined to ‖r − C s‖ ≤ 1e-13 ‖r‖.
  /// Returns false when the refinement stopped contracting (s is then the best iterate): rebuild.
  bool solve(const double *r, double *s) const;
  /// Entry (p, q) of the current inverse (tests).
  double inverse_entry(int p, int q) const;

  /// Flops of rebuild(J) for |J| = k, and of update() dropping r and adding a indices from |J| = k.
  static double rebuild_flops(double k) { return 8.0 / 3.0 * k * k * k; }
  static double update_flops(double k, double r, double a);

private:
  void drop_indices(const std::vector<int> &drop);
  void add_indices(const std::vector<int> &add);
  double w(int i, int j) const { return m_W[i + static_cast<std::size_t>(j) * m_n]; }

  const double *m_W;
  int m_n;
  int m_single_from;
  bool m_single = false;
  std::vector<int> m_J, m_pos;
  std::vector<double> m_C;   ///< W(J, J), column-major
  std::vector<double> m_inv; ///< C⁻¹ in double (when !m_single)
  std::vector<float> m_invf; ///< C⁻¹ in single (when m_single)
};

} // namespace hssbem
