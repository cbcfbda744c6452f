/// \file h2_system.hpp
/// The collocation system of a problem through the H² engine, in mesh order: compress
/// K = [H, G(, Gn)] once (strong admissibility, h2_compression.hpp); per boundary-condition
/// pattern, the right-hand side, products with A and its diagonal, for Krylov solvers. There is
/// no H² factorization yet: a direct solve goes through HSS (hss/hss_system.hpp, PC hss).
#pragma once

#include "hssbem/compress/compressed_system.hpp"
#include "hssbem/h2/h2_compression.hpp"

namespace hssbem {

class H2BemSystem : public CompressedBemSystem {
public:
  H2BemSystem(const BemOperator &op, const H2Options &options);

  const H2Matrix &matrix() const { return m_K; }
  std::vector<double> rhs(const SystemSelection &sel) const override;
  /// By the H² product.
  void apply(const SystemSelection &sel, const double *x, double *y) const override;
  /// From the leaves' diagonal near blocks.
  std::vector<double> diagonal(const SystemSelection &sel) const override;

private:
  H2Matrix m_K;
};

} // namespace hssbem
