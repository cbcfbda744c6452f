#include "hssbem/bem/quadrature.hpp"

#include <algorithm>
#include <cmath>

namespace hssbem {

namespace {

// Symmetric triangle rules as {l0, l1, l2, weight}, weights summing to 1.
const double rule3[3][4] = {
  {2.0 / 3, 1.0 / 6, 1.0 / 6, 1.0 / 3}, {1.0 / 6, 2.0 / 3, 1.0 / 6, 1.0 / 3}, {1.0 / 6, 1.0 / 6, 2.0 / 3, 1.0 / 3}};

// Radon's 7-point rule, exact for polynomials of degree 5.
constexpr double s15 = 3.872983346207416885; // sqrt(15)
constexpr double ra = (6.0 - s15) / 21.0, rb = (6.0 + s15) / 21.0;
constexpr double wa = (155.0 - s15) / 1200.0, wb = (155.0 + s15) / 1200.0;
const double rule7[7][4] = {
  {1.0 / 3, 1.0 / 3, 1.0 / 3, 9.0 / 40},
  {ra, ra, 1 - 2 * ra, wa}, {ra, 1 - 2 * ra, ra, wa}, {1 - 2 * ra, ra, ra, wa},
  {rb, rb, 1 - 2 * rb, wb}, {rb, 1 - 2 * rb, rb, wb}, {1 - 2 * rb, rb, rb, wb}};

/// Gauss-Legendre nodes and weights on [0, 1] by Newton's method on P_n.
void gauss_legendre(int n, std::vector<double> &x, std::vector<double> &w)
{
  x.resize(n);
  w.resize(n);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      const double pn = n == 1 ? z : p1, pm = n == 1 ? 1 : p0;
      dp = n * (z * pn - pm) / (z * z - 1);
      const double dz = pn / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    x[i] = 0.5 * (1 - z);
    w[i] = 1.0 / ((1 - z * z) * dp * dp);
  }
}

double diameter(const std::array<Vec3, 3> &p)
{
  return std::sqrt(std::max({dot(p[1] - p[0], p[1] - p[0]), dot(p[2] - p[1], p[2] - p[1]), dot(p[0] - p[2], p[0] - p[2])}));
}

double area_of(const std::array<Vec3, 3> &p) { return 0.5 * norm(cross(p[1] - p[0], p[2] - p[0])); }

/// Shape-weighted kernel sums of one triangle, in the few numbers that define them: u* is
/// symmetric (6 entries); p* is a symmetric part (6) plus an antisymmetric part (3). Expanded into
/// 3x3 blocks once per triangle, not once per quadrature point.
struct KernelSums {
  double u[3][6] = {}, s[3][6] = {}, a[3][3] = {};

  /// Add the kernels at y (weight wt) times the shape values Nu (for u*) and Np (for p*).
  inline void add(const KelvinConstants &k, const Vec3 &x, const Vec3 &y, const Vec3 &n, double wt, const double *Nu, const double *Np)
  {
    const double d0 = y[0] - x[0], d1 = y[1] - x[1], d2 = y[2] - x[2];
    const double inv_r = 1.0 / std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
    const double g0 = d0 * inv_r, g1 = d1 * inv_r, g2 = d2 * inv_r;
    const double drdn = g0 * n[0] + g1 * n[1] + g2 * n[2];
    const double su = wt * k.cu * inv_r, sp = wt * k.cp * inv_r * inv_r, ts = sp * drdn, ta = -sp * k.one_m_2nu;
    const double U[6] = {su * (k.cu_diag + g0 * g0), su * (k.cu_diag + g1 * g1), su * (k.cu_diag + g2 * g2), su * g0 * g1, su * g0 * g2, su * g1 * g2};
    const double S[6] = {ts * (k.one_m_2nu + 3 * g0 * g0), ts * (k.one_m_2nu + 3 * g1 * g1), ts * (k.one_m_2nu + 3 * g2 * g2),
                         3 * ts * g0 * g1, 3 * ts * g0 * g2, 3 * ts * g1 * g2};
    const double A[3] = {ta * (g0 * n[1] - g1 * n[0]), ta * (g0 * n[2] - g2 * n[0]), ta * (g1 * n[2] - g2 * n[1])};
    for (int c = 0; c < 3; ++c) {
      for (int m = 0; m < 6; ++m) u[c][m] += Nu[c] * U[m];
      for (int m = 0; m < 6; ++m) s[c][m] += Np[c] * S[m];
      for (int m = 0; m < 3; ++m) a[c][m] += Np[c] * A[m];
    }
  }

  /// Add the sums to the 3x3 blocks of `out` (row-major; (0,1) holds entry 01, (1,0) its mirror).
  void expand_into(ElementIntegrals &out) const
  {
    for (int c = 0; c < 3; ++c) {
      const double *U = u[c], *S = s[c], *A = a[c];
      const double G[9] = {U[0], U[3], U[4], U[3], U[1], U[5], U[4], U[5], U[2]};
      const double H[9] = {S[0], S[3] + A[0], S[4] + A[1], S[3] - A[0], S[1], S[5] + A[2], S[4] - A[1], S[5] - A[2], S[2]};
      for (int m = 0; m < 9; ++m) {
        out.G[c][m] += G[m];
        out.H[c][m] += H[m];
      }
    }
  }
};

} // namespace

KelvinConstants::KelvinConstants(const Material &m)
{
  cu = 1.0 / (16.0 * M_PI * m.mu() * (1.0 - m.nu));
  cu_diag = 3.0 - 4.0 * m.nu;
  cp = -1.0 / (8.0 * M_PI * (1.0 - m.nu));
  one_m_2nu = 1.0 - 2.0 * m.nu;
}

void ElementIntegrals::clear()
{
  for (int a = 0; a < 3; ++a) {
    G[a].fill(0.0);
    H[a].fill(0.0);
  }
}

ElementQuadrature::ElementQuadrature(const Material &material, const QuadratureOptions &options) : m_k(material), m_opt(options)
{
  gauss_legendre(m_opt.duffy_order, m_gl_x, m_gl_w);
}

template <int NQ>
void ElementQuadrature::apply_rule(const Vec3 &x, const Sub &s, const Vec3 &n, const double (&rule)[NQ][4], ElementIntegrals &out) const
{
  // Structure of arrays over the quadrature points so that each step vectorises.
  const double A = area_of(s.p);
  double g[3][NQ], N[3][NQ], su[NQ], ts[NQ], ta[NQ];
  for (int q = 0; q < NQ; ++q) {
    const double *l = rule[q];
    double d[3];
    for (int c = 0; c < 3; ++c) {
      d[c] = l[0] * s.p[0][c] + l[1] * s.p[1][c] + l[2] * s.p[2][c] - x[c];
      N[c][q] = l[0] * s.b[0][c] + l[1] * s.b[1][c] + l[2] * s.b[2][c];
    }
    const double inv_r = 1.0 / std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), w = A * l[3];
    for (int c = 0; c < 3; ++c) g[c][q] = d[c] * inv_r;
    const double sp = w * m_k.cp * inv_r * inv_r;
    su[q] = w * m_k.cu * inv_r;
    ts[q] = sp * (g[0][q] * n[0] + g[1][q] * n[1] + g[2][q] * n[2]);
    ta[q] = -sp * m_k.one_m_2nu;
  }
  double K[15][NQ];
  for (int q = 0; q < NQ; ++q) {
    const double g0 = g[0][q], g1 = g[1][q], g2 = g[2][q];
    K[0][q] = su[q] * (m_k.cu_diag + g0 * g0);
    K[1][q] = su[q] * (m_k.cu_diag + g1 * g1);
    K[2][q] = su[q] * (m_k.cu_diag + g2 * g2);
    K[3][q] = su[q] * g0 * g1;
    K[4][q] = su[q] * g0 * g2;
    K[5][q] = su[q] * g1 * g2;
    K[6][q] = ts[q] * (m_k.one_m_2nu + 3 * g0 * g0);
    K[7][q] = ts[q] * (m_k.one_m_2nu + 3 * g1 * g1);
    K[8][q] = ts[q] * (m_k.one_m_2nu + 3 * g2 * g2);
    K[9][q] = 3 * ts[q] * g0 * g1;
    K[10][q] = 3 * ts[q] * g0 * g2;
    K[11][q] = 3 * ts[q] * g1 * g2;
    K[12][q] = ta[q] * (g0 * n[1] - g1 * n[0]);
    K[13][q] = ta[q] * (g0 * n[2] - g2 * n[0]);
    K[14][q] = ta[q] * (g1 * n[2] - g2 * n[1]);
  }
  KernelSums sums;
  for (int c = 0; c < 3; ++c)
    for (int m = 0; m < 15; ++m) {
      double acc = 0;
      for (int q = 0; q < NQ; ++q) acc += N[c][q] * K[m][q];
      if (m < 6) sums.u[c][m] = acc;
      else if (m < 12) sums.s[c][m - 6] = acc;
      else sums.a[c][m - 12] = acc;
    }
  sums.expand_into(out);
}

void ElementQuadrature::subdivide(const Vec3 &x, const Sub &s, const Vec3 &n, int depth, ElementIntegrals &out) const
{
  const Vec3 centre = (1.0 / 3) * (s.p[0] + s.p[1] + s.p[2]);
  const double h = diameter(s.p), d = norm(x - centre);
  if (m_opt.far_ratio > 0 && d >= m_opt.far_ratio * h) return apply_rule(x, s, n, rule3, out);
  if (d >= m_opt.near_ratio * h || depth >= m_opt.max_depth) return apply_rule(x, s, n, rule7, out);
  Sub mid;
  for (int k = 0; k < 3; ++k) {
    mid.p[k] = 0.5 * (s.p[(k + 1) % 3] + s.p[(k + 2) % 3]);
    for (int c = 0; c < 3; ++c) mid.b[k][c] = 0.5 * (s.b[(k + 1) % 3][c] + s.b[(k + 2) % 3][c]);
  }
  subdivide(x, mid, n, depth + 1, out);
  for (int k = 0; k < 3; ++k) {
    Sub child;
    child.p = {s.p[k], mid.p[(k + 2) % 3], mid.p[(k + 1) % 3]};
    child.b = {s.b[k], mid.b[(k + 2) % 3], mid.b[(k + 1) % 3]};
    subdivide(x, child, n, depth + 1, out);
  }
}

void ElementQuadrature::regular(const Vec3 &x, const Triangle &tri, ElementIntegrals &out) const
{
  Sub s{tri.p, {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}};
  subdivide(x, s, tri.n, 0, out);
}

void ElementQuadrature::duffy(const Vec3 &x, const std::array<double, 3> &bx, const Sub &s, const Vec3 &n, ElementIntegrals &out) const
{
  // s.p[0] is the singular point; y = q0 + ξ(q1 - q0) + ξη(q2 - q1), dA = 2 A ξ dξ dη.
  const double twoA = 2.0 * area_of(s.p);
  const int m = m_opt.duffy_order;
  KernelSums sums;
  for (int i = 0; i < m; ++i) {
    const double xi = m_gl_x[i];
    for (int j = 0; j < m; ++j) {
      const double eta = m_gl_x[j], wt = twoA * xi * m_gl_w[i] * m_gl_w[j];
      Vec3 y;
      double N[3], Np[3];
      for (int c = 0; c < 3; ++c) {
        y[c] = s.p[0][c] + xi * (s.p[1][c] - s.p[0][c]) + xi * eta * (s.p[2][c] - s.p[1][c]);
        N[c] = s.b[0][c] + xi * (s.b[1][c] - s.b[0][c]) + xi * eta * (s.b[2][c] - s.b[1][c]);
        Np[c] = N[c] - bx[c];
      }
      sums.add(m_k, x, y, n, wt, N, Np);
    }
  }
  sums.expand_into(out);
}

void ElementQuadrature::duffy_split(const Vec3 &x, const std::array<double, 3> &bx, const Sub &s, const Vec3 &n, ElementIntegrals &out) const
{
  // Split at the foot of the altitude from the singular point: each half then spans at most a
  // right angle and its distance to the point is monotone along the edge, so the angular
  // integrand stays smooth even when the point is close to the opposite edge.
  const Vec3 e = s.p[2] - s.p[1];
  const double f = dot(x - s.p[1], e) / dot(e, e);
  if (f <= 0.02 || f >= 0.98) return duffy(x, bx, s, n, out);
  const Vec3 foot = s.p[1] + f * e;
  std::array<double, 3> bf;
  for (int c = 0; c < 3; ++c) bf[c] = s.b[1][c] + f * (s.b[2][c] - s.b[1][c]);
  duffy(x, bx, Sub{{x, s.p[1], foot}, {bx, s.b[1], bf}}, n, out);
  duffy(x, bx, Sub{{x, foot, s.p[2]}, {bx, bf, s.b[2]}}, n, out);
}

void ElementQuadrature::singular(const Vec3 &x, const std::array<double, 3> &bx, const Triangle &tri, ElementIntegrals &out) const
{
  const std::array<std::array<double, 3>, 3> id = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    if (bx[k] > 1.0 - 1e-14) {
      // The point is corner k: one sub-triangle, the whole triangle.
      duffy_split(x, bx, Sub{{x, tri.p[k1], tri.p[k2]}, {bx, id[k1], id[k2]}}, tri.n, out);
      return;
    }
  }
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    if (bx[k] < 1e-14) continue; // the sub-triangle opposite corner k collapses
    duffy_split(x, bx, Sub{{x, tri.p[k1], tri.p[k2]}, {bx, id[k1], id[k2]}}, tri.n, out);
  }
}

} // namespace hssbem
