// Entries of K = [H, G(, Gn)] by global indices in cluster order.
#include "hssbem/compress/kernel_blocks.hpp"

#include <algorithm>
#include <cmath>

namespace hssbem {

namespace {

/// Distinct values of `v` (sorted) and, per entry, its index among them.
std::vector<int> distinct(const std::vector<int> &v, std::vector<int> &index_of)
{
  std::vector<int> u(v);
  std::sort(u.begin(), u.end());
  u.erase(std::unique(u.begin(), u.end()), u.end());
  index_of.resize(v.size());
  for (std::size_t k = 0; k < v.size(); ++k) index_of[k] = static_cast<int>(std::lower_bound(u.begin(), u.end(), v[k]) - u.begin());
  return u;
}

} // namespace

KernelBlocks::KernelBlocks(const BemOperator &op, const ClusterTree &tree, int col_block, std::vector<double> col_scale)
  : m_op(op), m_tree(tree), m_w(col_block), m_scale(std::move(col_scale))
{
}

KernelBlocks::Columns KernelBlocks::split_columns(const std::vector<int> &cols) const
{
  Columns J;
  std::vector<int> pos(cols.size());
  J.slot_of.resize(cols.size());
  for (std::size_t q = 0; q < cols.size(); ++q) {
    pos[q] = cols[q] / m_w;
    J.slot_of[q] = cols[q] % m_w;
  }
  J.nodes = distinct(pos, J.node_of);
  for (int &j : J.nodes) j = m_tree.perm()[j];
  return J;
}

void KernelBlocks::scatter(const Columns &J, std::size_t nrows, const std::vector<int> *row_node, const std::vector<int> *row_comp,
                           const std::vector<double> &H, const std::vector<double> &G, const std::vector<double> &Gn, double *out, long rs,
                           long cs) const
{
  const std::size_t ld = 3 * J.nodes.size(), ldn = J.nodes.size();
  for (std::size_t r = 0; r < nrows; ++r) {
    const std::size_t hr = row_node ? 3 * static_cast<std::size_t>((*row_node)[r]) + (*row_comp)[r] : r;
    for (std::size_t q = 0; q < J.slot_of.size(); ++q) {
      const int b = J.node_of[q], s = J.slot_of[q];
      const double v = s < 3 ? H[hr * ld + 3 * b + s] : s < 6 ? G[hr * ld + 3 * b + s - 3] : Gn[hr * ldn + b];
      out[r * rs + q * cs] = m_scale[s] * v;
    }
  }
}

void KernelBlocks::block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, long rs, long cs, BemOperator::Workspace &ws) const
{
  if (rows.empty() || cols.empty()) return;
  std::vector<int> pos(rows.size()), comp(rows.size()), node_of;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    pos[r] = rows[r] / 3;
    comp[r] = rows[r] % 3;
  }
  std::vector<int> I = distinct(pos, node_of);
  for (int &i : I) i = m_tree.perm()[i];
  const Columns J = split_columns(cols);
  const std::size_t ld = 3 * J.nodes.size();
  std::vector<double> H(3 * I.size() * ld), G(3 * I.size() * ld), Gn(m_w > 6 ? 3 * I.size() * J.nodes.size() : 0);
  m_op.fill_hg_without_rigid(I, J.nodes, H.data(), G.data(), static_cast<long>(ld), m_w > 6 ? Gn.data() : nullptr, static_cast<long>(J.nodes.size()),
                             ws);
  scatter(J, rows.size(), &node_of, &comp, H, G, Gn, out, rs, cs);
}

void KernelBlocks::at_points(const std::vector<Vec3> &X, const std::vector<int> &cols, double *out, long rs, long cs, BemOperator::Workspace &ws) const
{
  if (X.empty() || cols.empty()) return;
  const Columns J = split_columns(cols);
  const std::size_t ld = 3 * J.nodes.size();
  std::vector<double> H(3 * X.size() * ld), G(3 * X.size() * ld), Gn(m_w > 6 ? 3 * X.size() * J.nodes.size() : 0);
  m_op.fill_hg_at_points(X, J.nodes, H.data(), G.data(), static_cast<long>(ld), m_w > 6 ? Gn.data() : nullptr, static_cast<long>(J.nodes.size()), ws);
  scatter(J, 3 * X.size(), nullptr, nullptr, H, G, Gn, out, rs, cs);
}

std::vector<double> kernel_column_scales(const BemOperator &op, int w)
{
  const int n = op.num_nodes();
  std::vector<int> rows, cols;
  for (int i = 0; i < n; i += std::max(1, n / 40)) rows.push_back(i);
  for (int j = 0; j < n; j += std::max(1, n / 400)) cols.push_back(j);
  const std::size_t ld = 3 * cols.size();
  std::vector<double> H(3 * rows.size() * ld), G(H.size()), Gn(w > 6 ? 3 * rows.size() * cols.size() : 0);
  BemOperator::Workspace ws(op);
  op.fill_hg_without_rigid(rows, cols, H.data(), G.data(), static_cast<long>(ld), w > 6 ? Gn.data() : nullptr, static_cast<long>(cols.size()), ws);
  double h2 = 0, g2 = 0, gn2 = 0;
  for (std::size_t k = 0; k < H.size(); ++k) h2 += H[k] * H[k], g2 += G[k] * G[k];
  for (double v : Gn) gn2 += v * v;
  std::vector<double> s(w, 1.0);
  for (int q = 3; q < 6; ++q) s[q] = g2 > 0 ? std::sqrt(h2 / g2) : 1.0;
  if (w > 6) s[6] = gn2 > 0 ? std::sqrt(h2 / (3 * gn2)) : 1.0; // one Gn column per node against three of H
  return s;
}

} // namespace hssbem
