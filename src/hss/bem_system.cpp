// The BEM system through the HSS engine, in mesh order (see bem_system.hpp).
#include "hssbem/hss/bem_system.hpp"

#include "hssbem/bem/rigid_modes.hpp"

#include <cmath>
#include <stdexcept>

namespace hssbem {

HssBemSystem::HssBemSystem(const BemOperator &op, const HssOptions &options) : m_op(op), m_K(compress_bem_operator(op, options)) {}

HssBemSystem::HssBemSystem(const BemOperator &op, HssMatrix K) : m_op(op), m_K(std::move(K))
{
  if (m_K.tree().num_points() != op.num_nodes()) throw std::invalid_argument("HSS: the compressed matrix does not belong to this operator");
}

void HssBemSystem::apply_k(std::vector<double> xk, double *y) const
{
  const int n = m_K.tree().num_points(), w = m_K.col_block();
  for (int j = 0; j < n; ++j) // the matrix holds K S (column scales); feed it S⁻¹ x
    for (int q = 0; q < w; ++q) xk[static_cast<std::size_t>(w) * j + q] /= m_K.col_scale(q);
  std::vector<double> xc(xk.size()), yc(3L * n);
  m_K.tree().to_cluster_order(xk.data(), xc.data(), w);
  m_K.apply(xc.data(), w * n, yc.data(), 3 * n);
  m_K.tree().to_mesh_order(yc.data(), y, 3);
}

std::vector<double> HssBemSystem::rhs(const SystemSelection &sel) const
{
  const int n = m_K.tree().num_points(), w = m_K.col_block();
  std::vector<double> xk(static_cast<std::size_t>(w) * n, 0.0), b(3L * n);
  for (int j = 0; j < n; ++j) {
    const bool pressure = !sel.pressure.empty() && !std::isnan(sel.pressure[j]);
    if (pressure) {
      if (w < 7) throw std::logic_error("HSS: pressure loads need the pressure columns (HssOptions::pressure_columns)");
      xk[w * j + 6] = -sel.pressure[j];
    }
    for (int c = 0; c < 3; ++c) {
      if (sel.displacement_known[j][c]) xk[w * j + c] = -sel.known[j][c];
      else if (!pressure) xk[w * j + 3 + c] = sel.known[j][c];
    }
  }
  apply_k(xk, b.data());
  return b;
}

void HssBemSystem::apply(const SystemSelection &sel, const double *x, double *y) const
{
  const int n = m_K.tree().num_points(), w = m_K.col_block();
  std::vector<double> xk(static_cast<std::size_t>(w) * n, 0.0);
  for (int j = 0; j < n; ++j)
    for (int c = 0; c < 3; ++c) {
      if (sel.displacement_known[j][c]) xk[w * j + 3 + c] = -x[3 * j + c];
      else xk[w * j + c] = x[3 * j + c];
    }
  apply_k(xk, y);
}

std::vector<double> HssBemSystem::diagonal(const SystemSelection &sel) const
{
  const ClusterTree &tree = m_K.tree();
  const int w = m_K.col_block();
  std::vector<double> d(3L * tree.num_points());
  for (int c : tree.leaves()) {
    const Cluster &cl = tree.cluster(c);
    const DenseMatrix &D = m_K.cluster(c).D;
    for (int k = cl.begin; k < cl.end; ++k) {
      const int j = tree.perm()[k], local = k - cl.begin;
      for (int r = 0; r < 3; ++r) {
        const bool known = sel.displacement_known[j][r];
        const int slot = known ? 3 + r : r;
        d[3L * j + r] = (known ? -1.0 : 1.0) * D(3 * local + r, w * local + slot) / m_K.col_scale(slot);
      }
    }
  }
  return d;
}

std::unique_ptr<UlvFactorization> HssBemSystem::factor(const SystemSelection &sel, const std::vector<double> *rigid_modes) const
{
  if (!rigid_modes) return std::make_unique<UlvFactorization>(m_K, sel.displacement_known);
  LowRankTerm t;
  t.p = 6;
  t.Z = *rigid_modes;
  t.Y = *rigid_modes;
  for (double &v : t.Y) v *= rigid_regularization_weight;
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

} // namespace hssbem
