// The BEM system through the HSS engine, in mesh order (see hss_system.hpp).
#include "hssbem/hss/hss_system.hpp"

#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/compress/pattern_columns.hpp"

#include <cmath>
#include <stdexcept>

namespace hssbem {

HssBemSystem::HssBemSystem(const BemOperator &op, const HssOptions &options) : m_op(op), m_K(compress_bem_operator_hss(op, options)) {}

HssBemSystem::HssBemSystem(const BemOperator &op, HssMatrix K) : m_op(op), m_K(std::move(K))
{
  if (m_K.tree().num_points() != op.num_nodes()) throw std::invalid_argument("HSS: the compressed matrix does not belong to this operator");
}

std::vector<double> HssBemSystem::rhs(const SystemSelection &sel) const
{
  std::vector<double> b(3L * m_K.tree().num_points());
  apply_compressed_k(m_K, pattern_rhs_input(sel, m_K.tree().num_points(), m_K.col_block()), b.data());
  return b;
}

void HssBemSystem::apply(const SystemSelection &sel, const double *x, double *y) const
{
  apply_compressed_k(m_K, pattern_product_input(sel, x, m_K.tree().num_points(), m_K.col_block()), y);
}

std::vector<double> HssBemSystem::diagonal(const SystemSelection &sel) const
{
  return pattern_diagonal(m_K, sel, [this](int leaf, int i, int j) { return m_K.cluster(leaf).D(i, j); });
}

namespace {

/// The rigid-mode regularisation c Φ Φᵀ as a low-rank term.
LowRankTerm rigid_mode_term(const std::vector<double> &modes)
{
  LowRankTerm t;
  t.p = 6;
  t.Z = modes;
  t.Y = modes;
  for (double &v : t.Y) v *= rigid_regularization_weight;
  return t;
}

} // namespace

std::unique_ptr<UlvFactorization> HssBemSystem::factor(const SystemSelection &sel, const std::vector<double> *rigid_modes) const
{
  if (!rigid_modes) return std::make_unique<UlvFactorization>(m_K, sel.displacement_known);
  const LowRankTerm t = rigid_mode_term(*rigid_modes);
  return std::make_unique<UlvFactorization>(m_K, sel.displacement_known, &t);
}

std::vector<double> HssBemSystem::solve(const UlvFactorization &F, const std::vector<double> &b) const
{
  std::vector<double> bc(b.size()), x(b.size());
  m_K.tree().to_cluster_order(b.data(), bc.data(), 3);
  F.solve(bc.data());
  m_K.tree().to_mesh_order(bc.data(), x.data(), 3);
  return x;
}

HssDistributedSystem::HssDistributedSystem(const BemOperator &op, const HssOptions &options, const std::vector<int> &node_part, const RankComm &comm)
  : HssDistributedSystem(op, compress_bem_operator_hss(op, options, node_part, comm), comm)
{
}

HssDistributedSystem::HssDistributedSystem(const BemOperator &op, HssMatrix K, const RankComm &comm)
  : m_op(op), m_comm(comm)
{
  collectively(comm, [&] {
    if (K.tree().num_points() != op.num_nodes()) throw std::invalid_argument("HSS: the compressed matrix does not belong to this operator");
    m_K = std::make_unique<HssMatrix>(std::move(K));
  });
  m_product = make_unique_collectively<HssDistributedProduct>(comm, *m_K, comm);
}

std::vector<double> HssDistributedSystem::rhs(const SystemSelection &sel) const
{
  const int n = num_points();
  std::vector<double> xk, b;
  collectively(m_comm, [&] {
    xk = local_k_input(*m_K, first_point(), n, sel, nullptr);
    b.resize(3L * n);
  });
  m_product->apply(xk.data(), m_K->col_block() * n, b.data(), 3 * n);
  return b;
}

void HssDistributedSystem::apply(const SystemSelection &sel, const double *x, double *y) const
{
  const int n = num_points();
  const std::vector<double> xk = collectively(m_comm, [&] { return local_k_input(*m_K, first_point(), n, sel, x); });
  m_product->apply(xk.data(), m_K->col_block() * n, y, 3 * n);
}

std::vector<double> HssDistributedSystem::diagonal(const SystemSelection &sel) const
{
  return local_pattern_diagonal(*m_K, first_point(), num_points(), sel, [this](int leaf, int i, int j) { return m_K->cluster(leaf).D(i, j); });
}

std::unique_ptr<UlvFactorization> HssDistributedSystem::factor(const SystemSelection &sel, const std::vector<double> *rigid_modes) const
{
  if (!rigid_modes) return make_unique_collectively<UlvFactorization>(m_comm, *m_K, m_comm, sel.displacement_known);
  const LowRankTerm t = collectively(m_comm, [&] { return rigid_mode_term(*rigid_modes); });
  return make_unique_collectively<UlvFactorization>(m_comm, *m_K, m_comm, sel.displacement_known, &t);
}

} // namespace hssbem
