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

/// pick_of for every component and kind.
struct PickTable {
  Pick p[3][7];
  constexpr PickTable() : p{}
  {
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < 7; ++k) p[a][k] = pick_of(a, k);
  }
  constexpr const Pick *operator[](int a) const { return p[a]; }
};
constexpr PickTable pick_table;

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

void BemOperator::selected_points(const RowPoint *pts, int np, const EntrySelection::Group &cols, bool gn, double *out, long rs, long cs,
                                      Workspace &ws) const
{
  // Sum each column node's corner sums over its triangles for every point first, then hand out
  // the requested entries once. acc holds, per column node and sum, one number per lane.
  constexpr int L = RegularRule::lanes;
  const std::size_t nj = cols.nodes.size();
  ws.acc.assign(nj * acc_size * L, 0.0);
  double *acc = ws.acc.data();
  alignas(64) double x[3][L];
  for (int k = 0; k < L; ++k)
    for (int c = 0; c < 3; ++c) x[c][k] = pts[std::min(k, np - 1)].x[c]; // spare lanes repeat the last point
  const unsigned used = (1u << np) - 1;
  // The points' bounding ball: a triangle far enough from all of it is regular at every point.
  Vec3 centre{0.0, 0.0, 0.0};
  for (int k = 0; k < np; ++k) centre = centre + pts[k].x;
  centre = (1.0 / np) * centre;
  double radius = 0;
  for (int k = 0; k < np; ++k) radius = std::max(radius, norm(pts[k].x - centre));
  radius *= 1.0 + 1e-12;
  // Lanes whose collocation point lies on a triangle, by triangle: those take the singular rule.
  alignas(64) double S[3][CornerSums::size][L];
  ElementIntegrals ei;
  double v[CornerSums::size];
  const std::size_t ne = ws.elems.size();
  for (std::size_t e = 0; e < ne; ++e) {
    const int t = ws.elems[e], *p = &ws.elem_pos[3 * e];
    unsigned regular = used;
    if (!m_regular.regular_in_ball(centre, radius, t)) {
      // A point on t is within its diameter, inside the near zone: only those need the check.
      regular = m_regular.regular_lanes(x, t) & used;
      for (int k = 0; k < np; ++k)
        if (pts[k].row >= 0 && (regular >> k & 1u) && contains(pts[k].row, t)) regular &= ~(1u << k);
    }
    if (regular == used && !gn) {
      // Every point regular: the sums go straight into the corners' accumulators.
      double *dest[3];
      for (int c = 0; c < 3; ++c) dest[c] = p[c] < 0 ? nullptr : acc + static_cast<std::size_t>(p[c]) * acc_size * L;
      m_regular.add_lane_sums(x, t, dest);
      continue;
    }
    if (regular) {
      m_regular.lane_sums(x, t, S);
      alignas(64) double keep[L];
      for (int k = 0; k < L; ++k) keep[k] = regular >> k & 1u;
      const Vec3 &n = m_tri[t].n;
      for (int c = 0; c < 3; ++c) {
        if (p[c] < 0) continue;
        double *a = acc + static_cast<std::size_t>(p[c]) * acc_size * L;
        for (int m = 0; m < CornerSums::size; ++m) {
#pragma omp simd
          for (int k = 0; k < L; ++k) a[m * L + k] += keep[k] != 0.0 ? S[c][m][k] : 0.0;
        }
        if (!gn) continue;
        for (int d = 0; d < 3; ++d) {
          const double *s0 = S[c][sym_index(d, 0)], *s1 = S[c][sym_index(d, 1)], *s2 = S[c][sym_index(d, 2)];
#pragma omp simd
          for (int k = 0; k < L; ++k) a[(acc_gn + d) * L + k] += keep[k] != 0.0 ? s0[k] * n[0] + s1[k] * n[1] + s2[k] * n[2] : 0.0;
        }
      }
    }
    for (unsigned special = used & ~regular; special; special &= special - 1) {
      const int k = __builtin_ctz(special);
      element_integrals(pts[k].x, pts[k].row, t, ei);
      for (int c = 0; c < 3; ++c) {
        if (p[c] < 0) continue;
        CornerSums::compress(ei.G[c].data(), ei.H[c].data(), v);
        double *a = acc + static_cast<std::size_t>(p[c]) * acc_size * L + k;
        for (int m = 0; m < CornerSums::size; ++m) a[m * L] += v[m];
        if (gn)
          for (int d = 0; d < 3; ++d) a[(acc_gn + d) * L] += v[sym_index(d, 0)] * m_tri[t].n[0] + v[sym_index(d, 1)] * m_tri[t].n[1] + v[sym_index(d, 2)] * m_tri[t].n[2];
      }
    }
  }
  // The common case: every point asks for its three components, in rows 3k + 0, 1, 2 after the
  // first point's. Its hand-out needs no per-entry lookups.
  bool whole = true;
  for (int k = 0; k < np && whole; ++k)
    whole = pts[k].nr == 3 && pts[k].comp[0] == 0 && pts[k].comp[1] == 1 && pts[k].comp[2] == 2 && pts[k].out_row[0] == pts[0].out_row[0] + 3 * k &&
            pts[k].out_row[1] == pts[k].out_row[0] + 1 && pts[k].out_row[2] == pts[k].out_row[0] + 2;
  if (whole) {
    const long first = pts[0].out_row[0] * rs;
    for (std::size_t q = 0; q < nj; ++q) {
      const double *a = acc + q * acc_size * L;
      for (int e = cols.start[q]; e < cols.start[q + 1]; ++e) {
        double *o = out + cols.out[e] * cs + first;
        for (int i = 0; i < 3; ++i) {
          const Pick &pk = pick_table[i][cols.what[e]];
          const double *ai = a + pk.i * L, *aj = a + pk.j * L;
          for (int k = 0; k < np; ++k) o[(3 * k + i) * rs] = ai[k] + pk.sign * aj[k];
        }
      }
    }
    return;
  }
  for (std::size_t q = 0; q < nj; ++q) {
    const double *a = acc + q * acc_size * L;
    for (int e = cols.start[q]; e < cols.start[q + 1]; ++e) {
      double *o = out + cols.out[e] * cs;
      for (int k = 0; k < np; ++k)
        for (int i = 0; i < pts[k].nr; ++i) {
          const Pick &pk = pick_table[pts[k].comp[i]][cols.what[e]];
          o[pts[k].out_row[i] * rs] = a[pk.i * L + k] + pk.sign * a[pk.j * L + k];
        }
    }
  }
}

void BemOperator::corner_positions(Workspace &ws) const
{
  ws.elem_pos.resize(3 * ws.elems.size());
  for (std::size_t e = 0; e < ws.elems.size(); ++e)
    for (int c = 0; c < 3; ++c) ws.elem_pos[3 * e + c] = ws.col_pos[m_disc->element_node(ws.elems[e], c)];
}

void BemOperator::selected(const EntrySelection &sel, double *out, long rs, long cs, Workspace &ws) const
{
  constexpr int L = RegularRule::lanes;
  const EntrySelection::Group &R = sel.rows(), &C = sel.cols();
  for (std::size_t p = 0; p < C.nodes.size(); ++p) ws.col_pos[C.nodes[p]] = static_cast<int>(p);
  elements_touching(C.nodes, ws);
  corner_positions(ws);
  const bool gn = std::find(C.what.begin(), C.what.end(), 6) != C.what.end();
  RowPoint pts[L];
  const int nr = static_cast<int>(R.nodes.size());
  for (int r0 = 0; r0 < nr; r0 += L) {
    const int np = std::min(L, nr - r0);
    for (int k = 0; k < np; ++k) {
      const int i = R.nodes[r0 + k], b = R.start[r0 + k], e = R.start[r0 + k + 1];
      pts[k] = {m_disc->node(i).point, i, R.what.data() + b, R.out.data() + b, e - b};
    }
    selected_points(pts, np, C, gn, out, rs, cs, ws);
  }
  for (int j : C.nodes) ws.col_pos[j] = -1;
}

void BemOperator::selected_at_points(const std::vector<Vec3> &X, const EntrySelection &sel, double *out, long rs, long cs, Workspace &ws) const
{
  constexpr int L = RegularRule::lanes;
  const EntrySelection::Group &C = sel.cols();
  for (std::size_t p = 0; p < C.nodes.size(); ++p) ws.col_pos[C.nodes[p]] = static_cast<int>(p);
  elements_touching(C.nodes, ws);
  corner_positions(ws);
  const bool gn = std::find(C.what.begin(), C.what.end(), 6) != C.what.end();
  static constexpr int comp[3] = {0, 1, 2};
  int out_row[L][3];
  RowPoint pts[L];
  const int nx = static_cast<int>(X.size());
  for (int r0 = 0; r0 < nx; r0 += L) {
    const int np = std::min(L, nx - r0);
    for (int k = 0; k < np; ++k) {
      for (int c = 0; c < 3; ++c) out_row[k][c] = 3 * (r0 + k) + c;
      pts[k] = {X[r0 + k], -1, comp, out_row[k], 3};
    }
    selected_points(pts, np, C, gn, out, rs, cs, ws);
  }
  for (int j : C.nodes) ws.col_pos[j] = -1;
}

} // namespace hssbem
