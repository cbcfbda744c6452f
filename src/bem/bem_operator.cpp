#include "hssbem/bem/bem_operator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

std::vector<Triangle> triangles_of(const SurfaceMesh &mesh)
{
  std::vector<Triangle> tri(mesh.triangles.size());
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const auto &v = mesh.triangles[t];
    tri[t] = Triangle{{mesh.vertices[v[0]], mesh.vertices[v[1]], mesh.vertices[v[2]]}, mesh.triangle_normal(t), mesh.triangle_area(t)};
  }
  return tri;
}

} // namespace

BemOperator::BemOperator(const Discretization &disc, const Material &material, const QuadratureOptions &options)
  : m_disc(&disc), m_material(material), m_quad_options(options), m_quad(material, options), m_tri(triangles_of(disc.mesh())),
    m_regular(material, options, m_tri)
{
  m_rigid.assign(disc.num_nodes(), Mat3{});
  m_has_rigid.assign(disc.num_nodes(), 0);
  m_workspace = std::make_unique<Workspace>(*this);
}

BemOperator::Workspace::Workspace(const BemOperator &op)
  : col_pos(op.num_nodes(), -1), elem_mark(op.m_tri.size(), 0)
{
}

bool BemOperator::contains(int row, int t) const
{
  const DofNode &node = m_disc->node(row);
  if (node.element >= 0) return node.element == t;
  const auto &tri = m_disc->mesh().triangles[t];
  return tri[0] == node.vertex || tri[1] == node.vertex || tri[2] == node.vertex;
}

void BemOperator::element_integrals(const Vec3 &x, int row, int t, ElementIntegrals &out) const
{
  out.clear();
  if (row < 0 || !contains(row, t)) return m_quad.regular(x, m_tri[t], out);
  const DofNode &node = m_disc->node(row);
  std::array<double, 3> bx = node.bary;
  if (node.element < 0) {
    const auto &tri = m_disc->mesh().triangles[t];
    for (int c = 0; c < 3; ++c) bx[c] = tri[c] == node.vertex ? 1.0 : 0.0;
  }
  m_quad.singular(x, bx, m_tri[t], out);
}

void BemOperator::compute_rigid_body_terms(const std::vector<int> &rows)
{
  ElementIntegrals ei;
  for (int i : rows) {
    Mat3 D{};
    const Vec3 &x = m_disc->node(i).point;
    for (int t = 0; t < static_cast<int>(m_tri.size()); ++t) {
      if (contains(i, t)) continue;
      element_integrals(x, -1, t, ei);
      for (int a = 0; a < 3; ++a)
        for (int m = 0; m < 9; ++m) D[m] -= ei.H[a][m];
    }
    m_rigid[i] = D;
    m_has_rigid[i] = 1;
  }
}

void BemOperator::set_rigid_body_terms(std::vector<Mat3> terms)
{
  if (static_cast<int>(terms.size()) != num_nodes()) throw std::invalid_argument("set_rigid_body_terms: one term per node expected");
  m_rigid = std::move(terms);
  m_has_rigid.assign(num_nodes(), 1);
}

bool BemOperator::has_rigid_body_term(int row) const { return m_has_rigid[row] != 0; }

void BemOperator::elements_touching(const std::vector<int> &J, Workspace &ws) const
{
  ws.elems.clear();
  for (int j : J)
    for (const int *t = m_disc->support_begin(j); t != m_disc->support_end(j); ++t)
      if (!ws.elem_mark[*t]) {
        ws.elem_mark[*t] = 1;
        ws.elems.push_back(*t);
      }
  for (int t : ws.elems) ws.elem_mark[t] = 0;
}

void BemOperator::add_rigid_body(int row, const Mat3 &D, const std::vector<int> &col_pos, double *Hrow, long ld) const
{
  const DofNode &node = m_disc->node(row);
  auto add = [&](int j, double w) {
    const int p = col_pos[j];
    if (p < 0 || w == 0.0) return;
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) Hrow[k * ld + 3 * p + c] += w * D[3 * k + c];
  };
  if (node.element < 0) return add(row, 1.0);
  for (int a = 0; a < 3; ++a) add(m_disc->element_node(node.element, a), node.bary[a]);
}

void BemOperator::BlockRows::zero(std::size_t ncols) const
{
  for (int k = 0; k < 3; ++k) {
    if (H) std::fill(H + k * ld, H + k * ld + 3 * ncols, 0.0);
    if (G) std::fill(G + k * ld, G + k * ld + 3 * ncols, 0.0);
    if (Gn) std::fill(Gn + k * ldn, Gn + k * ldn + ncols, 0.0);
  }
}

void BemOperator::scatter(int t, const ElementIntegrals &ei, const std::vector<int> &col_pos, const BlockRows &out) const
{
  for (int a = 0; a < 3; ++a) {
    const int p = col_pos[m_disc->element_node(t, a)];
    if (p < 0) continue; // this corner's node is not a column of the block
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) {
        if (out.H) out.H[k * out.ld + 3 * p + c] += ei.H[a][3 * k + c];
        if (out.G) out.G[k * out.ld + 3 * p + c] += ei.G[a][3 * k + c];
        if (out.Gn) out.Gn[k * out.ldn + p] += ei.G[a][3 * k + c] * m_tri[t].n[c];
      }
  }
}

void BemOperator::scatter(int t, const CornerSums &cs, const std::vector<int> &col_pos, const BlockRows &out, Mat3 *D) const
{
  double Ge[9], He[9];
  for (int a = 0; a < 3; ++a) {
    const int p = col_pos[m_disc->element_node(t, a)];
    if (p < 0 && !D) continue;
    cs.expand(a, Ge, He);
    if (D)
      for (int m = 0; m < 9; ++m) (*D)[m] -= He[m];
    if (p < 0) continue;
    for (int k = 0; k < 3; ++k) {
      if (out.H)
        for (int c = 0; c < 3; ++c) out.H[k * out.ld + 3 * p + c] += He[3 * k + c];
      if (out.G)
        for (int c = 0; c < 3; ++c) out.G[k * out.ld + 3 * p + c] += Ge[3 * k + c];
      if (out.Gn) out.Gn[k * out.ldn + p] += Ge[3 * k] * m_tri[t].n[0] + Ge[3 * k + 1] * m_tri[t].n[1] + Ge[3 * k + 2] * m_tri[t].n[2];
    }
  }
}

void BemOperator::point_integrals(const Vec3 &x, int row, const BlockRows &out, Workspace &ws, Mat3 *D) const
{
  // Triangles that see x through the 7-point rule go to the batched rule; the others (x on the
  // triangle: Duffy; x near it: subdivision) one by one.
  ElementIntegrals ei;
  ws.regular.clear();
  for (int t : ws.elems) {
    const bool on = row >= 0 && contains(row, t);
    if (!on && m_regular.is_regular(x, t)) {
      ws.regular.push_back(t);
      continue;
    }
    element_integrals(x, row, t, ei);
    scatter(t, ei, ws.col_pos, out);
    if (D && !on)
      for (int a = 0; a < 3; ++a)
        for (int m = 0; m < 9; ++m) (*D)[m] -= ei.H[a][m];
  }
  const int n = static_cast<int>(ws.regular.size());
  if (static_cast<int>(ws.sums.size()) < n) ws.sums.resize(n);
  m_regular.sums(x, ws.regular.data(), n, ws.sums.data());
  for (int k = 0; k < n; ++k) scatter(ws.regular[k], ws.sums[k], ws.col_pos, out, D);
}

void BemOperator::fill_hg(const std::vector<int> &I, const std::vector<int> &J, double *H, double *G, long ld) const
{
  fill_hg(I, J, H, G, ld, nullptr, 0, *m_workspace);
}

void BemOperator::fill_hg(const std::vector<int> &I, const std::vector<int> &J, double *H, double *G, long ld, double *Gn, long ldn, Workspace &ws) const
{
  fill_rows(I, J, H, G, ld, Gn, ldn, ws, Rigid::with);
}

void BemOperator::fill_hg_without_rigid(const std::vector<int> &I, const std::vector<int> &J, double *H, double *G, long ld, double *Gn, long ldn,
                                        Workspace &ws) const
{
  fill_rows(I, J, H, G, ld, Gn, ldn, ws, Rigid::without);
}

void BemOperator::fill_hg_at_points(const std::vector<Vec3> &X, const std::vector<int> &J, double *H, double *G, long ld, double *Gn, long ldn,
                                    Workspace &ws) const
{
  std::vector<int> &col_pos = ws.col_pos;
  for (std::size_t p = 0; p < J.size(); ++p) col_pos[J[p]] = static_cast<int>(p);
  elements_touching(J, ws);
  for (std::size_t r = 0; r < X.size(); ++r) {
    BlockRows out{H ? H + 3 * r * ld : nullptr, G ? G + 3 * r * ld : nullptr, Gn ? Gn + 3 * r * ldn : nullptr, ld, ldn};
    out.zero(J.size());
    point_integrals(X[r], -1, out, ws, nullptr);
  }
  for (int j : J) col_pos[j] = -1;
}

int BemOperator::rigid_body_columns(int row, int cols[3], double weights[3]) const
{
  const DofNode &node = m_disc->node(row);
  if (node.element < 0) {
    cols[0] = row;
    weights[0] = 1.0;
    return 1;
  }
  int n = 0;
  for (int a = 0; a < 3; ++a)
    if (node.bary[a] != 0.0) {
      cols[n] = m_disc->element_node(node.element, a);
      weights[n++] = node.bary[a];
    }
  return n;
}

void BemOperator::fill_rows(const std::vector<int> &I, const std::vector<int> &J, double *H, double *G, long ld, double *Gn, long ldn, Workspace &ws,
                            Rigid rigid) const
{
  std::vector<int> &col_pos = ws.col_pos;
  for (std::size_t p = 0; p < J.size(); ++p) col_pos[J[p]] = static_cast<int>(p);
  const bool all = rigid == Rigid::with && static_cast<int>(J.size()) == num_nodes();
  elements_touching(J, ws);
  for (std::size_t r = 0; r < I.size(); ++r) {
    const int i = I[r];
    if (rigid == Rigid::with && !all && !m_has_rigid[i]) {
      for (int j : J) col_pos[j] = -1;
      throw std::logic_error("fill_hg: row " + std::to_string(i) + " has no rigid-body term");
    }
    BlockRows out{H ? H + 3 * r * ld : nullptr, G ? G + 3 * r * ld : nullptr, Gn ? Gn + 3 * r * ldn : nullptr, ld, ldn};
    out.zero(J.size());
    Mat3 D{};
    point_integrals(m_disc->node(i).point, i, out, ws, all ? &D : nullptr);
    if (out.H && rigid == Rigid::with) add_rigid_body(i, all ? D : m_rigid[i], col_pos, out.H, ld);
  }
  for (int j : J) col_pos[j] = -1;
}

void fill_system_block(const BemOperator &op, const SystemSelection &sel, const std::vector<int> &I, const std::vector<int> &J,
                       double *A, long ld, double *rhs)
{
  BemOperator::Workspace ws(op);
  fill_system_block(op, sel, I, J, A, ld, rhs, ws);
}

void fill_system_block(const BemOperator &op, const SystemSelection &sel, const std::vector<int> &I, const std::vector<int> &J,
                       double *A, long ld, double *rhs, BemOperator::Workspace &ws)
{
  const long nj = 3 * static_cast<long>(J.size());
  const bool all = static_cast<int>(J.size()) == op.num_nodes();
  if (rhs && !all) throw std::logic_error("fill_system_block: the right-hand side needs every column");
  const bool pressure = rhs && !sel.pressure.empty();
  constexpr std::size_t chunk = 16; // rows per pass: bounded scratch, O(|J|)
  std::vector<double> H(3 * chunk * nj), G(3 * chunk * nj), Gn(pressure ? 3 * chunk * J.size() : 0);
  for (std::size_t r0 = 0; r0 < I.size(); r0 += chunk) {
    const std::vector<int> rows(I.begin() + r0, I.begin() + std::min(I.size(), r0 + chunk));
    op.fill_hg(rows, J, H.data(), G.data(), nj, pressure ? Gn.data() : nullptr, static_cast<long>(J.size()), ws);
    for (std::size_t r = 0; r < 3 * rows.size(); ++r) {
      const double *h = &H[r * nj], *g = &G[r * nj];
      double *a = A + (3 * r0 + r) * ld, b = 0;
      for (std::size_t p = 0; p < J.size(); ++p) {
        const int j = J[p];
        const bool by_pressure = pressure && !std::isnan(sel.pressure[j]);
        if (by_pressure) b -= sel.pressure[j] * Gn[r * J.size() + p];
        for (int c = 0; c < 3; ++c) {
          const long q = 3 * static_cast<long>(p) + c;
          if (sel.displacement_known[j][c]) {
            a[q] = -g[q];
            b -= h[q] * sel.known[j][c];
          } else {
            a[q] = h[q];
            if (!by_pressure) b += g[q] * sel.known[j][c];
          }
        }
      }
      if (rhs) rhs[3 * r0 + r] = b;
    }
  }
}

} // namespace hssbem
