/// \file compressed_system.hpp
/// The interface every compressed format of the BEM system offers (HssBemSystem in hss/,
/// H2BemSystem in h2/), so that the PETSc face and the benchmarks serve them alike.
#pragma once

#include "hssbem/bem/bem_operator.hpp"

#include <vector>

namespace hssbem {

/// What a Krylov solver needs from a compressed operator, whatever its format (HSS, H²): the
/// right-hand side, products and the diagonal of A for a pattern, all in mesh order.
class CompressedBemSystem {
public:
  virtual ~CompressedBemSystem() = default;
  /// b = Σ_known −H u + G t (pressure nodes: −p Gn), 3 values per node, mesh order.
  virtual std::vector<double> rhs(const SystemSelection &sel) const = 0;
  /// y = A x for the selection's pattern (x and y: 3 per node, mesh order), by a fast product.
  virtual void apply(const SystemSelection &sel, const double *x, double *y) const = 0;
  /// The diagonal of A for the selection (3 per node, mesh order): true entries.
  virtual std::vector<double> diagonal(const SystemSelection &sel) const = 0;
};

} // namespace hssbem
