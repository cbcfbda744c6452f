// Selected entries of H, G and Gn (see EntrySelection in bem_operator.hpp).
#include "hssbem/bem/bem_operator.hpp"

#include <algorithm>
#include <numeric>

namespace hssbem {

namespace {

/// Per column node of a selection: its corner sums over its triangles (CornerSums layout), a zero,
/// and Gn's three rows when some column asks for Gn.
constexpr int acc_zero = CornerSums::size, acc_gn = acc_zero + 1, acc_size = acc_gn + 3;

/// Where entry (component a, kind k) lives in a node's sums: acc[i] + sign·acc[j].
struct Pick {
  int i, j;
  double sign;
};

constexpr int sym_index(int a, int b) { return a == b ? a : a + b + 2; } // xx yy zz xy xz yz
constexpr int asym_index(int a, int b) { return a + b - 1; }             // xy xz yz (a ≠ b)

constexpr Pick pick_of(int a, int k)
{
  if (k < 3) return a == k ? Pick{6 + a, acc_zero, 0.0} : Pick{6 + sym_index(a, k), 12 + asym_index(a, k), a < k ? 1.0 : -1.0}; // H = S + A
  if (k < 6) return Pick{sym_index(a, k - 3), acc_zero, 0.0};                                                                   // G = U
  return Pick{acc_gn + a, acc_zero, 0.0};                                                                                       // Gn
}

/// acc += one corner's sums v; with Gn, also G n.
inline void add_sums(double *__restrict acc, const double *__restrict v, const Vec3 &n, bool gn)
{
  for (int m = 0; m < CornerSums::size; ++m) acc[m] += v[m];
  if (!gn) return;
  for (int a = 0; a < 3; ++a) acc[acc_gn + a] += v[sym_index(a, 0)] * n[0] + v[sym_index(a, 1)] * n[1] + v[sym_index(a, 2)] * n[2];
}

} // namespace

EntrySelection::Group EntrySelection::group(std::vector<Item> &items)
{
  std::stable_sort(items.begin(), items.end(), [](const Item &a, const Item &b) { return a.node < b.node; });
  Group g;
  for (std::size_t k = 0; k < items.size(); ++k) {
    if (k == 0 || items[k].node != items[k - 1].node) {
      g.nodes.push_back(items[k].node);
      g.start.push_back(static_cast<int>(k));
    }
    g.what.push_back(items[k].what);
    g.out.push_back(items[k].out);
  }
  g.start.push_back(static_cast<int>(items.size()));
  return g;
}

void EntrySelection::finish()
{
  m_row_groups = group(m_rows);
  m_col_groups = group(m_cols);
}

void BemOperator::add_selected_point(const Vec3 &x, int row, const int *comp, const int *out_row, int nr, const EntrySelection::Group &cols, double *out,
                                     long rs, long cs, Workspace &ws) const
{
  // Sum each column node's corner sums over its triangles first (the 7-point triangles batched,
  // the others one by one, as point_integrals), then hand out the requested entries once.
  const std::vector<int> &col_pos = ws.col_pos;
  const std::size_t nj = cols.nodes.size();
  const bool gn = std::find(cols.what.begin(), cols.what.end(), 6) != cols.what.end();
  ws.acc.assign(nj * acc_size, 0.0);
  ElementIntegrals ei;
  double v[CornerSums::size];
  ws.regular.clear();
  for (int t : ws.elems) {
    if (!(row >= 0 && contains(row, t)) && m_regular.is_regular(x, t)) {
      ws.regular.push_back(t);
      continue;
    }
    element_integrals(x, row, t, ei);
    for (int a = 0; a < 3; ++a) {
      const int p = col_pos[m_disc->element_node(t, a)];
      if (p < 0) continue;
      CornerSums::compress(ei.G[a].data(), ei.H[a].data(), v);
      add_sums(&ws.acc[p * acc_size], v, m_tri[t].n, gn);
    }
  }
  const int n = static_cast<int>(ws.regular.size());
  if (static_cast<int>(ws.sums.size()) < n) ws.sums.resize(n);
  m_regular.sums(x, ws.regular.data(), n, ws.sums.data());
  for (int k = 0; k < n; ++k) {
    const int t = ws.regular[k];
    for (int a = 0; a < 3; ++a) {
      const int p = col_pos[m_disc->element_node(t, a)];
      if (p >= 0) add_sums(&ws.acc[p * acc_size], ws.sums[k].v[a], m_tri[t].n, gn);
    }
  }
  for (std::size_t p = 0; p < nj; ++p) {
    const double *acc = &ws.acc[p * acc_size];
    for (int e = cols.start[p]; e < cols.start[p + 1]; ++e) {
      double *o = out + cols.out[e] * cs;
      for (int i = 0; i < nr; ++i) {
        const Pick pk = pick_of(comp[i], cols.what[e]);
        o[out_row[i] * rs] += acc[pk.i] + pk.sign * acc[pk.j];
      }
    }
  }
}

void BemOperator::add_selected(const EntrySelection &sel, double *out, long rs, long cs, Workspace &ws) const
{
  const EntrySelection::Group &R = sel.rows(), &C = sel.cols();
  for (std::size_t p = 0; p < C.nodes.size(); ++p) ws.col_pos[C.nodes[p]] = static_cast<int>(p);
  elements_touching(C.nodes, ws);
  for (std::size_t r = 0; r < R.nodes.size(); ++r) {
    const int i = R.nodes[r], b = R.start[r], e = R.start[r + 1];
    add_selected_point(m_disc->node(i).point, i, R.what.data() + b, R.out.data() + b, e - b, C, out, rs, cs, ws);
  }
  for (int j : C.nodes) ws.col_pos[j] = -1;
}

void BemOperator::add_selected_at_points(const std::vector<Vec3> &X, const EntrySelection &sel, double *out, long rs, long cs, Workspace &ws) const
{
  const EntrySelection::Group &C = sel.cols();
  for (std::size_t p = 0; p < C.nodes.size(); ++p) ws.col_pos[C.nodes[p]] = static_cast<int>(p);
  elements_touching(C.nodes, ws);
  const int comp[3] = {0, 1, 2};
  for (std::size_t r = 0; r < X.size(); ++r) {
    const int out_row[3] = {static_cast<int>(3 * r), static_cast<int>(3 * r + 1), static_cast<int>(3 * r + 2)};
    add_selected_point(X[r], -1, comp, out_row, 3, C, out, rs, cs, ws);
  }
  for (int j : C.nodes) ws.col_pos[j] = -1;
}

} // namespace hssbem
