// Private to the H² factorization: what the elimination produces, as the solve replays it.
#pragma once

#include "hssbem/core/dense_matrix.hpp"

#include <cstddef>
#include <vector>

namespace hssbem::h2f {

/// The columns of A-hat on K: column g (dof 3k + c of cluster order) is sign[g] × (K S)(:, w k +
/// slot[g]); with a regularisation, A-hat also holds c Φ Ψᵀ (Φ: N × 6 column-major, Ψ = D Φ).
struct Pattern {
  std::vector<int> slot;
  std::vector<double> sign;
  std::vector<double> phi, psi; ///< empty without regularisation
  double c = 0;
  int dofs() const { return static_cast<int>(slot.size()); }
  bool regularised() const { return !phi.empty(); }
};

/// One box's elimination, as the solve replays it (dof indices of A-hat, on a rank its own rows).
struct Step {
  std::vector<int> box;     ///< the box's unknowns before the step (the order of D)
  DenseMatrix D;            ///< LU factors of the box's diagonal block A_XX: the unknowns became A_XX x (Frontier::precondition)
  std::vector<int> dpiv;
  std::vector<int> S, R, I; ///< skeleton, redundant, and the unknowns the Schur complement touched
  DenseMatrix T;            ///< |S| × |R| interpolation: rows R -= Tᵀ rows S, columns R -= columns S T
  DenseMatrix LU;           ///< |R| × |R| LU factors (getrf) of the sparsified R block
  std::vector<int> piv;
  DenseMatrix Lp, Up;       ///< A(I, R) U⁻¹ (|I| × |R|) and L⁻¹ P A(R, I) (|R| × |I|), in double ...
  std::vector<float> Lps, Ups; ///< ... or in single precision (then Lp, Up keep their sizes but no entries)
  int candidates = 0;          ///< active unknowns of the box before (statistics)
  std::size_t bytes() const;
  /// Forward and backward halves of the solve of this step on nrhs columns of X (column-major,
  /// leading dimension ld, all of this rank's rows); w holds the packed blocks between calls.
  struct Work {
    std::vector<double> s, r, i, panel;
  };
  void forward(double *X, std::size_t ld, int nrhs, Work &w) const;
  void backward(double *X, std::size_t ld, int nrhs, Work &w) const;
  /// Move the panels to single precision.
  void demote();
};

} // namespace hssbem::h2f
