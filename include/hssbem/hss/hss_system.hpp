/// \file hss_system.hpp
/// The collocation system of a problem through the HSS engine, in mesh order (docs/hss.md, A = K E_S):
/// compress K = [H, G(, Gn)] once; per boundary-condition pattern, a right-hand side by one fast
/// product and a ULV factorization. The PETSc layer and the benchmarks build on this.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/compress/compressed_system.hpp"
#include "hssbem/hss/hss_compression.hpp"
#include "hssbem/hss/hss_distributed.hpp"
#include "hssbem/hss/ulv.hpp"

#include <memory>
#include <vector>

namespace hssbem {

class HssBemSystem : public CompressedBemSystem {
public:
  /// Compress the operator (see compress_bem_operator_hss). Pressure loads need
  /// options.pressure_columns.
  HssBemSystem(const BemOperator &op, const HssOptions &options);
  /// Adopt a compression of op's K made elsewhere (e.g. truncate_hss() of another system's).
  HssBemSystem(const BemOperator &op, HssMatrix K);

  const HssMatrix &matrix() const { return m_K; }
  const BemOperator &op() const { return m_op; }

  std::vector<double> rhs(const SystemSelection &sel) const override;
  /// By the HSS product.
  void apply(const SystemSelection &sel, const double *x, double *y) const override;
  /// From the leaves' diagonal blocks.
  std::vector<double> diagonal(const SystemSelection &sel) const override;
  /// Factor A (+ c Φ Φᵀ when `rigid_modes` is given: row-major 3N × 6, as orthonormal_rigid_modes).
  /// Throws HssBreakdown.
  std::unique_ptr<UlvFactorization> factor(const SystemSelection &sel, const std::vector<double> *rigid_modes = nullptr) const;
  /// x = A⁻¹ b with a factorization from factor(), both in mesh order.
  std::vector<double> solve(const UlvFactorization &F, const std::vector<double> &b) const;

private:
  const BemOperator &m_op;
  HssMatrix m_K;
};

/// The collocation system through an HSS matrix distributed over ranks (hss_distributed.hpp),
/// rows and unknowns as DistributedBemSystem says, and its ULV factorization distributed likewise
/// (ulv.hpp).
class HssDistributedSystem : public DistributedBemSystem {
public:
  /// Collective: compress (compress_bem_operator_hss with node_part) and plan the products.
  HssDistributedSystem(const BemOperator &op, const HssOptions &options, const std::vector<int> &node_part, const RankComm &comm);
  /// Collective: adopt a distributed compression of op's K made elsewhere (truncate_hss() of
  /// another system's, say).
  HssDistributedSystem(const BemOperator &op, HssMatrix K, const RankComm &comm);

  const HssMatrix &matrix() const { return *m_K; }
  const HssDistributedProduct &product() const { return *m_product; }
  const BemOperator &op() const { return m_op; }
  const RankComm &comm() const { return m_comm; }
  const ClusterTree &tree() const override { return m_K->tree(); }
  int first_point() const override { return m_product->first_point(); }
  int num_points() const override { return m_product->num_points(); }
  std::size_t memory_bytes() const override { return m_K->stats().memory_bytes; }

  std::vector<double> rhs(const SystemSelection &sel) const override;
  void apply(const SystemSelection &sel, const double *x, double *y) const override;
  std::vector<double> diagonal(const SystemSelection &sel) const override;
  /// Collective: factor A (+ c Φ Φᵀ when `rigid_modes` is given, whole on every rank: row-major
  /// 3N × 6, mesh order). Throws HssBreakdown on every rank when it broke down on any.
  std::unique_ptr<UlvFactorization> factor(const SystemSelection &sel, const std::vector<double> *rigid_modes = nullptr) const;

private:
  const BemOperator &m_op;
  const RankComm &m_comm;
  std::unique_ptr<HssMatrix> m_K;
  std::unique_ptr<HssDistributedProduct> m_product;
};

} // namespace hssbem
