// The BEM system through the H² engine, in mesh order (see h2_system.hpp).
#include "hssbem/h2/h2_system.hpp"

#include "hssbem/hss/pattern_columns.hpp"

#include <algorithm>
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
  const ClusterTree &tree = m_K.tree();
  const int w = m_K.col_block();
  std::vector<double> d(3L * tree.num_points());
  for (int c : tree.leaves()) {
    const std::vector<int> &near = m_K.partition().near[c];
    const auto it = std::lower_bound(near.begin(), near.end(), c);
    if (it == near.end() || *it != c) throw std::logic_error("H2: a leaf without its diagonal block");
    const H2Block &D = m_K.near_blocks(c)[it - near.begin()];
    const Cluster &cl = tree.cluster(c);
    for (int k = cl.begin; k < cl.end; ++k) {
      const int j = tree.perm()[k], local = k - cl.begin;
      for (int r = 0; r < 3; ++r) {
        double sign;
        const int slot = pattern_slot(sel, j, r, &sign);
        d[3L * j + r] = sign * D.entry(3 * local + r, w * local + slot) / m_K.col_scale(slot);
      }
    }
  }
  return d;
}

} // namespace hssbem
