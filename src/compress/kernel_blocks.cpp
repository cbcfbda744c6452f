// Entries of K = [H, G(, Gn)] by global indices in cluster order.
#include "hssbem/compress/kernel_blocks.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace hssbem {

KernelBlocks::KernelBlocks(const BemOperator &op, const ClusterTree &tree, int col_block, std::vector<double> col_scale)
  : m_op(op), m_tree(tree), m_w(col_block), m_scale(std::move(col_scale))
{
}

void KernelBlocks::block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, long rs, long cs, BemOperator::Workspace &ws) const
{
  if (rows.empty() || cols.empty()) return;
  EntrySelection sel;
  for (std::size_t r = 0; r < rows.size(); ++r) sel.add_row(m_tree.perm()[rows[r] / 3], rows[r] % 3, static_cast<int>(r));
  select_columns(cols, sel);
  if (rs == 1) {
    m_op.selected(sel, out, rs, cs, ws);
    apply_scales(rows.size(), cols, out, rs, cs);
    return;
  }
  // Rows far apart in `out` (a sample matrix with one candidate row per column): the entries
  // are summed into a tile whose rows are adjacent, which the evaluation's scattered additions
  // keep in cache, then copied out scaled.
  const std::size_t m = rows.size(), n = cols.size();
  thread_local std::vector<double> tile;
  tile.resize(m * n);
  m_op.selected(sel, tile.data(), 1, static_cast<long>(m), ws);
  std::vector<double> s(n);
  for (std::size_t q = 0; q < n; ++q) s[q] = m_scale[cols[q] % m_w];
  for (std::size_t r = 0; r < m; ++r)
    for (std::size_t q = 0; q < n; ++q) out[r * rs + q * cs] = s[q] * tile[r + q * m];
}

void KernelBlocks::at_points(const std::vector<Vec3> &X, const std::vector<int> &cols, double *out, long rs, long cs, BemOperator::Workspace &ws) const
{
  if (X.empty() || cols.empty()) return;
  EntrySelection sel;
  select_columns(cols, sel);
  m_op.selected_at_points(X, sel, out, rs, cs, ws);
  apply_scales(3 * X.size(), cols, out, rs, cs);
}

void KernelBlocks::select_columns(const std::vector<int> &cols, EntrySelection &sel) const
{
  for (std::size_t q = 0; q < cols.size(); ++q) sel.add_col(m_tree.perm()[cols[q] / m_w], cols[q] % m_w, static_cast<int>(q));
  sel.finish();
}

void KernelBlocks::apply_scales(std::size_t nrows, const std::vector<int> &cols, double *out, long rs, long cs) const
{
  for (std::size_t q = 0; q < cols.size(); ++q) {
    const double s = m_scale[cols[q] % m_w];
    if (s == 1.0) continue;
    for (std::size_t r = 0; r < nrows; ++r) out[r * rs + q * cs] *= s;
  }
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
