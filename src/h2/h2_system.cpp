// The BEM system through the H² engine, in mesh order (see h2_system.hpp).
#include "hssbem/h2/h2_system.hpp"

#include "hssbem/compress/pattern_columns.hpp"

#include <stdexcept>

namespace hssbem {

H2BemSystem::H2BemSystem(const BemOperator &op, const H2Options &options) : m_K(compress_bem_operator_h2(op, options)) {}

std::vector<double> H2BemSystem::rhs(const SystemSelection &sel) const
{
  std::vector<double> b(3L * m_K.tree().num_points());
  apply_compressed_k(m_K, pattern_rhs_input(sel, m_K.tree().num_points(), m_K.col_block()), b.data());
  return b;
}

void H2BemSystem::apply(const SystemSelection &sel, const double *x, double *y) const
{
  apply_compressed_k(m_K, pattern_product_input(sel, x, m_K.tree().num_points(), m_K.col_block()), y);
}

std::vector<double> H2BemSystem::diagonal(const SystemSelection &sel) const
{
  return pattern_diagonal(m_K, sel, [this](int leaf, int i, int j) {
    const H2Block *D = m_K.near_block(leaf, leaf);
    if (!D) throw std::logic_error("H2: a leaf without its diagonal block");
    return D->entry(i, j);
  });
}

H2DistributedSystem::H2DistributedSystem(const BemOperator &op, const H2Options &options, const std::vector<int> &node_part, const RankComm &comm)
{
  H2Matrix K = compress_bem_operator_h2(op, options, node_part, comm);
  collectively(comm, [&] { m_K = std::make_unique<H2Matrix>(std::move(K)); });
  m_product = make_unique_collectively<H2DistributedProduct>(comm, *m_K, comm);
}

H2DistributedSystem::H2DistributedSystem(H2Matrix K, const RankComm &comm)
{
  collectively(comm, [&] { m_K = std::make_unique<H2Matrix>(std::move(K)); });
  m_product = make_unique_collectively<H2DistributedProduct>(comm, *m_K, comm);
}

std::vector<double> H2DistributedSystem::rhs(const SystemSelection &sel) const
{
  const int n = num_points();
  std::vector<double> xk, b;
  collectively(m_product->comm(), [&] {
    xk = local_k_input(*m_K, first_point(), n, sel, nullptr);
    b.resize(3L * n);
  });
  m_product->apply(xk.data(), m_K->col_block() * n, b.data(), 3 * n);
  return b;
}

void H2DistributedSystem::apply(const SystemSelection &sel, const double *x, double *y) const
{
  const int n = num_points();
  const std::vector<double> xk = collectively(m_product->comm(), [&] { return local_k_input(*m_K, first_point(), n, sel, x); });
  m_product->apply(xk.data(), m_K->col_block() * n, y, 3 * n);
}

std::vector<double> H2DistributedSystem::diagonal(const SystemSelection &sel) const
{
  return local_pattern_diagonal(*m_K, first_point(), num_points(), sel, [this](int leaf, int i, int j) {
    const H2Block *D = m_K->near_block(leaf, leaf);
    if (!D) throw std::logic_error("H2: a leaf without its diagonal block");
    return D->entry(i, j);
  });
}

} // namespace hssbem
