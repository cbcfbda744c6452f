// Somigliana's identities for displacement and stress at interior points (see interior_stress.hpp).
#include "hssbem/post/interior_stress.hpp"

#include "hssbem/post/post.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

namespace hssbem {

namespace {

// Radon's 7-point rule (degree 5) as {l0, l1, l2, weight}, weights summing to 1.
constexpr double s15 = 3.872983346207416885;
constexpr double ra = (6.0 - s15) / 21.0, rb = (6.0 + s15) / 21.0;
constexpr double wa = (155.0 - s15) / 1200.0, wb = (155.0 + s15) / 1200.0;
const double rule7[7][4] = {{1.0 / 3, 1.0 / 3, 1.0 / 3, 9.0 / 40}, {ra, ra, 1 - 2 * ra, wa}, {ra, 1 - 2 * ra, ra, wa}, {1 - 2 * ra, ra, ra, wa},
                            {rb, rb, 1 - 2 * rb, wb},            {rb, 1 - 2 * rb, rb, wb}, {1 - 2 * rb, rb, rb, wb}};

/// A piece of a triangle: its corners and their barycentric coordinates in the whole triangle.
struct Piece {
  std::array<Vec3, 3> p;
  std::array<Vec3, 3> b;
};

double diameter_of(const std::array<Vec3, 3> &p)
{
  return std::sqrt(std::max({dot(p[1] - p[0], p[1] - p[0]), dot(p[2] - p[1], p[2] - p[1]), dot(p[0] - p[2], p[0] - p[2])}));
}

/// Barycentric interpolation of corner values.
Vec3 interpolate(const std::array<Vec3, 3> &v, const Vec3 &b) { return b[0] * v[0] + b[1] * v[1] + b[2] * v[2]; }

/// The quadrature points of one (point, triangle) pair, gathered from the pieces of a split
/// before one vectorised pass sums them: position, weight and barycentric coordinates.
struct PieceRule {
  std::size_t size = 0, capacity = 0;
  std::unique_ptr<double[]> y[3], w, b[3]; ///< not value-initialised: a split fills thousands of entries per point
  void clear() { size = 0; }
  /// Room for `more` entries beyond size (the entries kept).
  void reserve_more(std::size_t more)
  {
    if (size + more <= capacity) return;
    const std::size_t cap = std::max<std::size_t>(2 * capacity, size + more + 64);
    auto grow = [&](std::unique_ptr<double[]> &a) {
      std::unique_ptr<double[]> n(new double[cap]);
      std::copy_n(a.get(), size, n.get());
      a = std::move(n);
    };
    for (int c = 0; c < 3; ++c) grow(y[c]), grow(b[c]);
    grow(w);
    capacity = cap;
  }
};

PieceRule &piece_rule()
{
  thread_local PieceRule rule; // the sources are shared by threads
  rule.clear();
  return rule;
}

/// Appends the 7-point rule of piece s (area A).
void gather_rule(const Piece &s, double A, PieceRule &R)
{
  R.reserve_more(7);
  const std::size_t at = R.size;
  for (int q = 0; q < 7; ++q) {
    const double *l = rule7[q];
    for (int c = 0; c < 3; ++c) {
      R.y[c][at + q] = l[0] * s.p[0][c] + l[1] * s.p[1][c] + l[2] * s.p[2][c];
      R.b[c][at + q] = l[0] * s.b[0][c] + l[1] * s.b[1][c] + l[2] * s.b[2][c];
    }
    R.w[at + q] = A * l[3];
  }
  R.size += 7;
}

void subdivide(const InteriorQuadrature &q, const Vec3 &x, const Piece &s, double A, int depth, PieceRule &R)
{
  const Vec3 c = (1.0 / 3) * (s.p[0] + s.p[1] + s.p[2]);
  const double h = diameter_of(s.p);
  if (dot(x - c, x - c) >= q.near_ratio * q.near_ratio * h * h || depth >= q.max_depth) return gather_rule(s, A, R);
  Piece mid;
  for (int j = 0; j < 3; ++j) {
    mid.p[j] = 0.5 * (s.p[(j + 1) % 3] + s.p[(j + 2) % 3]);
    mid.b[j] = 0.5 * (s.b[(j + 1) % 3] + s.b[(j + 2) % 3]);
  }
  subdivide(q, x, mid, A / 4, depth + 1, R);
  for (int j = 0; j < 3; ++j) {
    const Piece child{{s.p[j], mid.p[(j + 2) % 3], mid.p[(j + 1) % 3]}, {s.b[j], mid.b[(j + 2) % 3], mid.b[(j + 1) % 3]}};
    subdivide(q, x, child, A / 4, depth + 1, R);
  }
}

/// out[0..9) += the gathered rule at x for the triangle's normal n and corner data u, t.
void sum_rule(const SomiglianaConstants &k, const Vec3 &x, const Vec3 &n, const std::array<Vec3, 3> &u, const std::array<Vec3, 3> &t, const PieceRule &R,
              double *out)
{
  double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0, a8 = 0;
  const std::size_t np = R.size;
  const double *y0 = R.y[0].get(), *y1 = R.y[1].get(), *y2 = R.y[2].get(), *w = R.w.get(), *b0 = R.b[0].get(), *b1 = R.b[1].get(), *b2 = R.b[2].get();
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7, a8)
  for (std::size_t j = 0; j < np; ++j) {
    double f[3], m[3], v[field_outputs];
    for (int c = 0; c < 3; ++c) {
      f[c] = w[j] * (b0[j] * t[0][c] + b1[j] * t[1][c] + b2[j] * t[2][c]);
      m[c] = w[j] * (b0[j] * u[0][c] + b1[j] * u[1][c] + b2[j] * u[2][c]);
    }
    somigliana_point(k, y0[j] - x[0], y1[j] - x[1], y2[j] - x[2], f[0], f[1], f[2], m[0], m[1], m[2], n[0], n[1], n[2], v[0], v[1], v[2], v[3], v[4], v[5],
                     v[6], v[7], v[8]);
    a0 += v[0], a1 += v[1], a2 += v[2], a3 += v[3], a4 += v[4], a5 += v[5], a6 += v[6], a7 += v[7], a8 += v[8];
  }
  out[0] += a0, out[1] += a1, out[2] += a2, out[3] += a3, out[4] += a4, out[5] += a5, out[6] += a6, out[7] += a7, out[8] += a8;
}

} // namespace

std::vector<std::array<Vec3, 3>> corner_tractions(const Discretization &disc, const SystemSelection &sel, const NodalSolution &sol)
{
  const SurfaceMesh &mesh = disc.mesh();
  std::vector<std::array<Vec3, 3>> out(mesh.triangles.size());
  for (int e = 0; e < mesh.num_triangles(); ++e)
    for (int c = 0; c < 3; ++c) {
      const int i = disc.element_node(e, c);
      const bool pressure = !sel.pressure.empty() && !std::isnan(sel.pressure[i]);
      out[e][c] = sol.t[i];
      if (!pressure) continue;
      out[e][c] = -sel.pressure[i] * mesh.triangle_normal(e);
      for (int k = 0; k < 3; ++k) // beyond the pressure's nodal value (sel.known where the traction is known)
        out[e][c][k] += sol.t[i][k] - (sel.displacement_known[i][k] ? 0.0 : sel.known[i][k]);
    }
  return out;
}

std::vector<std::array<Vec3, 3>> corner_displacements(const Discretization &disc, const std::vector<Vec3> &u)
{
  std::vector<std::array<Vec3, 3>> out(disc.mesh().triangles.size());
  for (std::size_t e = 0; e < out.size(); ++e)
    for (int c = 0; c < 3; ++c) out[e][c] = u[disc.element_node(static_cast<int>(e), c)];
  return out;
}

SomiglianaSources::SomiglianaSources(const Discretization &disc, const Material &material, const std::vector<Vec3> &u, const std::vector<std::array<Vec3, 3>> &t,
                                     const InteriorQuadrature &quad)
  : m_k(material), m_quad(quad)
{
  const SurfaceMesh &mesh = disc.mesh();
  m_tri.resize(mesh.triangles.size());
  for (int e = 0; e < mesh.num_triangles(); ++e) {
    TriangleData &d = m_tri[e];
    for (int c = 0; c < 3; ++c) {
      d.p[c] = mesh.vertices[mesh.triangles[e][c]];
      d.u[c] = u[disc.element_node(e, c)];
      d.t[c] = t[e][c];
    }
    d.n = mesh.triangle_normal(e);
    d.area = mesh.triangle_area(e);
    d.centroid = (1.0 / 3) * (d.p[0] + d.p[1] + d.p[2]);
    d.diameter = diameter_of(d.p);
    d.radius = std::max({norm(d.p[0] - d.centroid), norm(d.p[1] - d.centroid), norm(d.p[2] - d.centroid)});
    d.near_radius = quad.near_ratio * d.diameter;
  }
  for (int c = 0; c < 3; ++c)
    for (auto *v : {&m_particles.y[c], &m_particles.f[c], &m_particles.m[c], &m_particles.n[c]}) v->resize(Particles::per_triangle * m_tri.size());
  for (std::size_t e = 0; e < m_tri.size(); ++e) {
    const TriangleData &d = m_tri[e];
    for (int q = 0; q < Particles::per_triangle; ++q) {
      const double *l = rule7[q];
      const Vec3 b{l[0], l[1], l[2]};
      const Vec3 y = interpolate(d.p, b), f = (d.area * l[3]) * interpolate(d.t, b), m = (d.area * l[3]) * interpolate(d.u, b);
      const std::size_t at = Particles::per_triangle * e + q;
      for (int c = 0; c < 3; ++c) {
        m_particles.y[c][at] = y[c];
        m_particles.f[c][at] = f[c];
        m_particles.m[c][at] = m[c];
        m_particles.n[c][at] = d.n[c];
      }
    }
  }
}

void SomiglianaSources::add_adaptive(const Vec3 &x, const TriangleData &tri, const std::array<Vec3, 3> &u, const std::array<Vec3, 3> &t, double *out) const
{
  PieceRule &R = piece_rule();
  subdivide(m_quad, x, Piece{tri.p, {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}}}, tri.area, 0, R);
  sum_rule(m_k, x, tri.n, u, t, R, out);
}

void SomiglianaSources::add_triangle(const Vec3 &x, int e, double *out) const
{
  const TriangleData &tri = m_tri[e];
  if (!is_regular(x, e)) return add_adaptive(x, tri, tri.u, tri.t, out);
  const Particles &P = m_particles;
  for (std::size_t q = Particles::per_triangle * static_cast<std::size_t>(e), end = q + Particles::per_triangle; q < end; ++q)
    somigliana_point(m_k, P.y[0][q] - x[0], P.y[1][q] - x[1], P.y[2][q] - x[2], P.f[0][q], P.f[1][q], P.f[2][q], P.m[0][q], P.m[1][q], P.m[2][q], P.n[0][q],
                     P.n[1][q], P.n[2][q], out, 1);
}

void SomiglianaSources::add_triangle_minus(const Vec3 &x, int e, const LinearField &f, double *out) const
{
  const TriangleData &tri = m_tri[e];
  std::array<Vec3, 3> u = tri.u, t = tri.t;
  Vec3 sn{};
  for (int v = 0; v < 6; ++v) {
    const int i = voigt_row[v], j = voigt_col[v];
    sn[i] += f.stress[v] * tri.n[j];
    if (i != j) sn[j] += f.stress[v] * tri.n[i];
  }
  for (int c = 0; c < 3; ++c) {
    const Vec3 &y = tri.p[c];
    for (int i = 0; i < 3; ++i) u[c][i] -= f.a[i] + f.G[3 * i] * y[0] + f.G[3 * i + 1] * y[1] + f.G[3 * i + 2] * y[2];
    t[c] = t[c] - sn;
  }
  if (!is_regular(x, e)) return add_adaptive(x, tri, u, t, out);
  PieceRule &R = piece_rule();
  gather_rule(Piece{tri.p, {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}}}, tri.area, R);
  sum_rule(m_k, x, tri.n, u, t, R, out);
}

void SomiglianaSources::add_all(const Vec3 &x, double *out) const
{
  for (int e = 0; e < num_triangles(); ++e) add_triangle(x, e, out);
}

} // namespace hssbem
