/// \file h2_system.hpp
/// The collocation system of a problem through the H² engine, in mesh order: compress
/// K = [H, G(, Gn)] once (strong admissibility, h2_compression.hpp); per boundary-condition
/// pattern, the right-hand side, products with A and its diagonal, for Krylov solvers. There is
/// no H² factorization yet: a direct solve goes through HSS (hss/hss_system.hpp, PC hss).
#pragma once

#include "hssbem/compress/compressed_system.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/h2/h2_distributed.hpp"

#include <memory>

namespace hssbem {

class H2BemSystem : public CompressedBemSystem {
public:
  H2BemSystem(const BemOperator &op, const H2Options &options);
  /// Around a matrix compressed already (gathered from a distributed one, say).
  explicit H2BemSystem(H2Matrix K) : m_K(std::move(K)) {}

  const H2Matrix &matrix() const { return m_K; }
  std::vector<double> rhs(const SystemSelection &sel) const override;
  /// By the H² product.
  void apply(const SystemSelection &sel, const double *x, double *y) const override;
  /// From the leaves' diagonal near blocks.
  std::vector<double> diagonal(const SystemSelection &sel) const override;

private:
  H2Matrix m_K;
};

/// The collocation system through an H² matrix distributed over ranks (h2_distributed.hpp):
/// this rank's rows and unknowns are the 3 dofs of each of its points, in cluster order
/// (positions first_point() … first_point() + num_points() − 1; the node of local point k is
/// matrix().tree().perm()[first_point() + k]).
class H2DistributedSystem {
public:
  /// Collective: compress (compress_bem_operator_h2 with node_part) and plan the products.
  H2DistributedSystem(const BemOperator &op, const H2Options &options, const std::vector<int> &node_part, const RankComm &comm);

  const H2Matrix &matrix() const { return *m_K; }
  const H2DistributedProduct &product() const { return *m_product; }
  int first_point() const { return m_product->first_point(); }
  int num_points() const { return m_product->num_points(); }

  /// This rank's rows of b (3 per local point). Collective.
  std::vector<double> rhs(const SystemSelection &sel) const;
  /// This rank's rows of A x from this rank's unknowns x (3 per local point each). Collective.
  void apply(const SystemSelection &sel, const double *x, double *y) const;
  /// This rank's entries of A's diagonal.
  std::vector<double> diagonal(const SystemSelection &sel) const;

private:
  void apply_k(std::vector<double> xk, double *y) const;

  std::unique_ptr<H2Matrix> m_K;
  std::unique_ptr<H2DistributedProduct> m_product;
};

} // namespace hssbem
