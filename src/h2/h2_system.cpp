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
  : m_K(std::make_unique<H2Matrix>(compress_bem_operator_h2(op, options, node_part, comm))), m_product(std::make_unique<H2DistributedProduct>(*m_K, comm))
{
}

void H2DistributedSystem::apply_k(std::vector<double> xk, double *y) const
{
  const int w = m_K->col_block();
  for (std::size_t k = 0; k < xk.size(); ++k) xk[k] /= m_K->col_scale(static_cast<int>(k % w)); // the matrix holds K S
  m_product->apply(xk.data(), w * num_points(), y, 3 * num_points());
}

std::vector<double> H2DistributedSystem::rhs(const SystemSelection &sel) const
{
  const int n = num_points(), w = m_K->col_block();
  std::vector<double> xk(static_cast<std::size_t>(w) * n), b(3L * n);
  for (int k = 0; k < n; ++k) pattern_rhs_node(sel, m_K->tree().perm()[first_point() + k], w, &xk[static_cast<std::size_t>(w) * k]);
  apply_k(std::move(xk), b.data());
  return b;
}

void H2DistributedSystem::apply(const SystemSelection &sel, const double *x, double *y) const
{
  const int n = num_points(), w = m_K->col_block();
  std::vector<double> xk(static_cast<std::size_t>(w) * n);
  for (int k = 0; k < n; ++k) pattern_product_node(sel, m_K->tree().perm()[first_point() + k], x + 3L * k, w, &xk[static_cast<std::size_t>(w) * k]);
  apply_k(std::move(xk), y);
}

std::vector<double> H2DistributedSystem::diagonal(const SystemSelection &sel) const
{
  const ClusterTree &tree = m_K->tree();
  const int w = m_K->col_block(), first = first_point();
  std::vector<double> d(3L * num_points());
  for (int c : tree.leaves()) {
    if (!m_K->holds(c)) continue;
    const H2Block *D = m_K->near_block(c, c);
    if (!D) throw std::logic_error("H2: a leaf without its diagonal block");
    const Cluster &cl = tree.cluster(c);
    for (int k = cl.begin; k < cl.end; ++k) {
      const int j = tree.perm()[k], local = k - cl.begin;
      for (int r = 0; r < 3; ++r) {
        double sign;
        const int slot = pattern_slot(sel, j, r, &sign);
        d[3L * (k - first) + r] = sign * D->entry(3 * local + r, w * local + slot) / m_K->col_scale(slot);
      }
    }
  }
  return d;
}

} // namespace hssbem
