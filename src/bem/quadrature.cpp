#include "hssbem/bem/quadrature.hpp"
#include "kernel_numbers.hpp"

#include <algorithm>
#include <cmath>

namespace hssbem {

/// The quadrature points of one (point, triangle) pair, gathered from every sub-triangle of a
/// subdivision or a Duffy split before one pass sums them with the points as SIMD lanes:
/// position y, weight w (area included), the corners' shape values for u* (nu) and for p* (np;
/// nu − w_a on a singular triangle). The length is padded to whole lanes with zero weights.
struct PointList {
  static constexpr int lanes = 8;
  std::vector<double> y[3], w, nu[3], np[3];
  std::size_t n = 0;

  void clear() { n = 0; }
  void push(const Vec3 &at, double weight, const double *Nu, const double *Np)
  {
    if (n == w.size()) grow(std::max<std::size_t>(64, 2 * n));
    for (int c = 0; c < 3; ++c) {
      y[c][n] = at[c];
      nu[c][n] = Nu[c];
      np[c][n] = Np[c];
    }
    w[n++] = weight;
  }
  /// Pad to a multiple of PointList::lanes with points one unit away from x and no weight.
  void pad(const Vec3 &x)
  {
    static const double zero[3] = {0, 0, 0};
    while (n % lanes != 0) push(x + Vec3{1.0, 0.0, 0.0}, 0.0, zero, zero);
  }

private:
  void grow(std::size_t cap)
  {
    for (int c = 0; c < 3; ++c) {
      y[c].resize(cap);
      nu[c].resize(cap);
      np[c].resize(cap);
    }
    w.resize(cap);
  }
};

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

/// Every thread gathers into its own list (the quadrature object is shared).
PointList &point_list()
{
  thread_local PointList list;
  list.clear();
  return list;
}

/// The kernel sums of the gathered points at x for a triangle of normal n (the list is padded).
KernelSums sum_points(const KelvinConstants &k, const Vec3 &x, const Vec3 &n, PointList &P)
{
  P.pad(x);
  alignas(64) double acc[3][15][PointList::lanes] = {};
  const double x0 = x[0], x1 = x[1], x2 = x[2], n0 = n[0], n1 = n[1], n2 = n[2];
  const double cu = k.cu, cp = k.cp, cd = k.cu_diag, om = k.one_m_2nu;
  for (std::size_t q0 = 0; q0 < P.n; q0 += PointList::lanes) {
    const double *y0 = &P.y[0][q0], *y1 = &P.y[1][q0], *y2 = &P.y[2][q0], *w = &P.w[q0];
    alignas(64) double K[15][PointList::lanes];
#pragma omp simd aligned(K : 64)
    for (int l = 0; l < PointList::lanes; ++l) {
      const double d0 = y0[l] - x0, d1 = y1[l] - x1, d2 = y2[l] - x2;
      const double inv_r = 1.0 / std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
      const double g0 = d0 * inv_r, g1 = d1 * inv_r, g2 = d2 * inv_r;
      const double su = w[l] * cu * inv_r, sp = w[l] * cp * inv_r * inv_r;
      kernel_numbers(g0, g1, g2, su, sp, n0, n1, n2, cd, om, &K[0][l], PointList::lanes);
    }
    for (int c = 0; c < 3; ++c) {
      const double *Nu = &P.nu[c][q0], *Np = &P.np[c][q0];
      for (int m = 0; m < 15; ++m) {
        const double *N = m < 6 ? Nu : Np;
#pragma omp simd aligned(K : 64)
        for (int l = 0; l < PointList::lanes; ++l) acc[c][m][l] += N[l] * K[m][l];
      }
    }
  }
  KernelSums sums;
  for (int c = 0; c < 3; ++c)
    for (int m = 0; m < 15; ++m) {
      double t = 0;
      for (int l = 0; l < PointList::lanes; ++l) t += acc[c][m][l];
      if (m < 6) sums.u[c][m] = t;
      else if (m < 12) sums.s[c][m - 6] = t;
      else sums.a[c][m - 12] = t;
    }
  return sums;
}

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
void ElementQuadrature::gather_rule(const Sub &s, const double (&rule)[NQ][4], PointList &P) const
{
  const double A = area_of(s.p);
  for (int q = 0; q < NQ; ++q) {
    const double *l = rule[q];
    Vec3 y;
    double N[3];
    for (int c = 0; c < 3; ++c) {
      y[c] = l[0] * s.p[0][c] + l[1] * s.p[1][c] + l[2] * s.p[2][c];
      N[c] = l[0] * s.b[0][c] + l[1] * s.b[1][c] + l[2] * s.b[2][c];
    }
    P.push(y, A * l[3], N, N);
  }
}

void ElementQuadrature::subdivide(const Vec3 &x, const Sub &s, int depth, PointList &P) const
{
  const Vec3 centre = (1.0 / 3) * (s.p[0] + s.p[1] + s.p[2]);
  const double h = diameter(s.p), d = norm(x - centre);
  if (m_opt.far_ratio > 0 && d >= m_opt.far_ratio * h) return gather_rule(s, rule3, P);
  if (d >= m_opt.near_ratio * h || depth >= m_opt.max_depth) return gather_rule(s, rule7, P);
  Sub mid;
  for (int k = 0; k < 3; ++k) {
    mid.p[k] = 0.5 * (s.p[(k + 1) % 3] + s.p[(k + 2) % 3]);
    for (int c = 0; c < 3; ++c) mid.b[k][c] = 0.5 * (s.b[(k + 1) % 3][c] + s.b[(k + 2) % 3][c]);
  }
  subdivide(x, mid, depth + 1, P);
  for (int k = 0; k < 3; ++k) {
    Sub child;
    child.p = {s.p[k], mid.p[(k + 2) % 3], mid.p[(k + 1) % 3]};
    child.b = {s.b[k], mid.b[(k + 2) % 3], mid.b[(k + 1) % 3]};
    subdivide(x, child, depth + 1, P);
  }
}

void ElementQuadrature::regular(const Vec3 &x, const Triangle &tri, ElementIntegrals &out) const
{
  PointList &P = point_list();
  subdivide(x, Sub{tri.p, {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}}, 0, P);
  sum_points(m_k, x, tri.n, P).expand_into(out);
}

void ElementQuadrature::duffy(const Vec3 &x, const std::array<double, 3> &bx, const Sub &s, PointList &P) const
{
  // s.p[0] is the singular point; y = q0 + ξ(q1 - q0) + ξη(q2 - q1), dA = 2 A ξ dξ dη.
  const double twoA = 2.0 * area_of(s.p);
  const int m = m_opt.duffy_order;
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
      P.push(y, wt, N, Np);
    }
  }
}

void ElementQuadrature::duffy_split(const Vec3 &x, const std::array<double, 3> &bx, const Sub &s, PointList &P) const
{
  // Split at the foot of the altitude from the singular point: each half then spans at most a
  // right angle and its distance to the point is monotone along the edge, so the angular
  // integrand stays smooth even when the point is close to the opposite edge.
  const Vec3 e = s.p[2] - s.p[1];
  const double f = dot(x - s.p[1], e) / dot(e, e);
  if (f <= 0.02 || f >= 0.98) return duffy(x, bx, s, P);
  const Vec3 foot = s.p[1] + f * e;
  std::array<double, 3> bf;
  for (int c = 0; c < 3; ++c) bf[c] = s.b[1][c] + f * (s.b[2][c] - s.b[1][c]);
  duffy(x, bx, Sub{{x, s.p[1], foot}, {bx, s.b[1], bf}}, P);
  duffy(x, bx, Sub{{x, foot, s.p[2]}, {bx, bf, s.b[2]}}, P);
}

void ElementQuadrature::singular(const Vec3 &x, const std::array<double, 3> &bx, const Triangle &tri, ElementIntegrals &out) const
{
  const std::array<std::array<double, 3>, 3> id = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  PointList &P = point_list();
  int corner = -1;
  for (int k = 0; k < 3; ++k)
    if (bx[k] > 1.0 - 1e-14) corner = k;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    // The point is corner k: one sub-triangle, the whole triangle. Otherwise the sub-triangle
    // opposite corner k, unless it collapses.
    if (corner >= 0 ? k != corner : bx[k] < 1e-14) continue;
    duffy_split(x, bx, Sub{{x, tri.p[k1], tri.p[k2]}, {bx, id[k1], id[k2]}}, P);
  }
  sum_points(m_k, x, tri.n, P).expand_into(out);
}

} // namespace hssbem
