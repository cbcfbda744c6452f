/// \file h2_system.hpp
/// The collocation system of a problem through the H² engine, in mesh order: compress
/// K = [H, G(, Gn)] once (strong admissibility, h2_compression.hpp); per boundary-condition
/// pattern, the right-hand side, products with A and its diagonal, for Krylov solvers. It is
/// factored by the H² factorization (h2factor/, PC h2): a preconditioner at a loose tolerance, a
/// direct solver at a tight one (docs/h2-factorization.md).
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

/// The collocation system through an H² matrix distributed over ranks (h2_distributed.hpp), rows
/// and unknowns as DistributedBemSystem says.
class H2DistributedSystem : public DistributedBemSystem {
public:
  /// Collective: compress (compress_bem_operator_h2 with node_part) and plan the products.
  H2DistributedSystem(const BemOperator &op, const H2Options &options, const std::vector<int> &node_part, const RankComm &comm);
  /// Collective: around this rank's part of a matrix compressed already (a saved one,
  /// H2Matrix::unpack), the products planned.
  H2DistributedSystem(H2Matrix K, const RankComm &comm);

  const H2Matrix &matrix() const { return *m_K; }
  const H2DistributedProduct &product() const { return *m_product; }
  const ClusterTree &tree() const override { return m_K->tree(); }
  int first_point() const override { return m_product->first_point(); }
  int num_points() const override { return m_product->num_points(); }
  std::size_t memory_bytes() const override { return m_K->stats().memory_bytes; }

  std::vector<double> rhs(const SystemSelection &sel) const override;
  void apply(const SystemSelection &sel, const double *x, double *y) const override;
  std::vector<double> diagonal(const SystemSelection &sel) const override;

private:
  std::unique_ptr<H2Matrix> m_K;
  std::unique_ptr<H2DistributedProduct> m_product;
};

} // namespace hssbem
