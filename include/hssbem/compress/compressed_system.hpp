/// \file compressed_system.hpp
/// The interface every compressed format of the BEM system offers (HssBemSystem in hss/,
/// H2BemSystem in h2/), so that the PETSc face and the benchmarks serve them alike; and the same
/// for a format distributed over ranks (HssDistributedSystem, H2DistributedSystem).
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/cluster_tree.hpp"

#include <cstddef>

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

/// The same for a system distributed over ranks: this rank's rows and unknowns are the 3 dofs of
/// each of its points, in cluster order (positions first_point() … first_point() + num_points()
/// − 1 of tree(); the node of local point k is tree().perm()[first_point() + k]).
class DistributedBemSystem {
public:
  virtual ~DistributedBemSystem() = default;
  virtual const ClusterTree &tree() const = 0;
  virtual int first_point() const = 0;
  virtual int num_points() const = 0;
  /// This rank's rows of b (3 per local point). Collective.
  virtual std::vector<double> rhs(const SystemSelection &sel) const = 0;
  /// This rank's rows of A x from this rank's unknowns x (3 per local point each). Collective.
  virtual void apply(const SystemSelection &sel, const double *x, double *y) const = 0;
  /// This rank's entries of A's diagonal.
  virtual std::vector<double> diagonal(const SystemSelection &sel) const = 0;
  /// Bytes of the compressed matrix held on this rank.
  virtual std::size_t memory_bytes() const = 0;
};

} // namespace hssbem
