// The 7-point rule on many triangles at once, triangles as SIMD lanes (see regular_rule.hpp).
#include "hssbem/bem/regular_rule.hpp"
#include "kernel_numbers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#ifdef __AVX512F__
#include <immintrin.h>
#endif

namespace hssbem {

namespace {

// Radon's 7-point rule (quadrature.cpp's rule7): the centroid, then two orbits of three points
// (r, r, 1 - 2r); point 1 + k (4 + k) of an orbit has its large coordinate at corner 2 - k.
constexpr double s15 = 3.872983346207416885;
constexpr double ra = (6.0 - s15) / 21.0, rb = (6.0 + s15) / 21.0;
constexpr double wa = (155.0 - s15) / 1200.0, wb = (155.0 + s15) / 1200.0, w0 = 9.0 / 40.0;
constexpr double bary[7][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {ra, ra, 1 - 2 * ra}, {ra, 1 - 2 * ra, ra}, {1 - 2 * ra, ra, ra},
                               {rb, rb, 1 - 2 * rb},        {rb, 1 - 2 * rb, rb}, {1 - 2 * rb, rb, rb}};
constexpr double weight[7] = {w0, wa, wa, wa, wb, wb, wb};

/// out[k] = 1/sqrt(r2[k]) for 8 lanes. With AVX-512: the 14-bit estimate and two Newton steps
/// (to within an ulp or two of the rounded result), several times the throughput of sqrt and
/// division.
inline void inv_sqrt8(const double *r2, double *out)
{
#ifdef __AVX512F__
  const __m512d x = _mm512_load_pd(r2), half = _mm512_set1_pd(0.5), three_halves = _mm512_set1_pd(1.5);
  __m512d y = _mm512_maskz_rsqrt14_pd(0xFF, x);
  const __m512d hx = _mm512_mul_pd(half, x);
  for (int it = 0; it < 2; ++it) y = _mm512_mul_pd(y, _mm512_fnmadd_pd(hx, _mm512_mul_pd(y, y), three_halves));
  _mm512_store_pd(out, y);
#else
  for (int k = 0; k < 8; ++k) out[k] = 1.0 / std::sqrt(r2[k]);
#endif
}

/// Corner c's sum of one kernel number over the 7 points, Σ_q N_c(q) K_q = K_0/3 + ra ΣA +
/// (1 − 3ra) K_{3−c} + rb ΣB + (1 − 3rb) K_{6−c}: K[q · qstride] in, out[c · cstride] out.
inline void corner_combination(const double *K, int qstride, double *out, int cstride)
{
  const double base = K[0] * (1.0 / 3) + ra * (K[qstride] + K[2 * qstride] + K[3 * qstride]) + rb * (K[4 * qstride] + K[5 * qstride] + K[6 * qstride]);
  for (int c = 0; c < 3; ++c) out[c * cstride] = base + (1 - 3 * ra) * K[(3 - c) * qstride] + (1 - 3 * rb) * K[(6 - c) * qstride];
}

} // namespace

void CornerSums::expand(const double *v, double G[9], double H[9])
{
  const double *U = v, *S = v + 6, *A = v + 12;
  G[0] = U[0], G[1] = U[3], G[2] = U[4], G[3] = U[3], G[4] = U[1], G[5] = U[5], G[6] = U[4], G[7] = U[5], G[8] = U[2];
  H[0] = S[0], H[1] = S[3] + A[0], H[2] = S[4] + A[1];
  H[3] = S[3] - A[0], H[4] = S[1], H[5] = S[5] + A[2];
  H[6] = S[4] - A[1], H[7] = S[5] - A[2], H[8] = S[2];
}

void CornerSums::compress(const double G[9], const double H[9], double *v)
{
  v[0] = G[0], v[1] = G[4], v[2] = G[8], v[3] = G[1], v[4] = G[2], v[5] = G[5];
  v[6] = H[0], v[7] = H[4], v[8] = H[8];
  v[9] = 0.5 * (H[1] + H[3]), v[10] = 0.5 * (H[2] + H[6]), v[11] = 0.5 * (H[5] + H[7]);
  v[12] = 0.5 * (H[1] - H[3]), v[13] = 0.5 * (H[2] - H[6]), v[14] = 0.5 * (H[5] - H[7]);
}

RegularRule::RegularRule(const Material &material, const QuadratureOptions &options, const std::vector<Triangle> &triangles) : m_k(material)
{
  m_tri.resize(triangles.size());
  const double inf = std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto &p = triangles[t].p;
    TriangleData &d = m_tri[t];
    for (int q = 0; q < 8; ++q)
      for (int c = 0; c < 3; ++c) d.q[c][q] = q < 7 ? bary[q][0] * p[0][c] + bary[q][1] * p[1][c] + bary[q][2] * p[2][c] : 0.0;
    for (int c = 0; c < 3; ++c) d.n[c] = triangles[t].n[c];
    d.area = 0.5 * norm(cross(p[1] - p[0], p[2] - p[0]));
    const Vec3 centre = (1.0 / 3) * (p[0] + p[1] + p[2]);
    for (int c = 0; c < 3; ++c) d.centroid[c] = centre[c];
    const double h2 = std::max({dot(p[1] - p[0], p[1] - p[0]), dot(p[2] - p[1], p[2] - p[1]), dot(p[0] - p[2], p[0] - p[2])});
    d.near2 = options.near_ratio * options.near_ratio * h2;
    d.far2 = options.far_ratio > 0 ? options.far_ratio * options.far_ratio * h2 : inf;
  }
}

template <int B>
void RegularRule::batch(const Vec3 &x, const int *tris, CornerSums *out) const
{
  // Gather B triangles into lanes.
  alignas(64) double qx[7][B], qy[7][B], qz[7][B], nx[B], ny[B], nz[B], su0[B], sp0[B];
  for (int k = 0; k < B; ++k) {
    const TriangleData &d = m_tri[tris[k]];
    for (int q = 0; q < 7; ++q) {
      qx[q][k] = d.q[0][q];
      qy[q][k] = d.q[1][q];
      qz[q][k] = d.q[2][q];
    }
    nx[k] = d.n[0], ny[k] = d.n[1], nz[k] = d.n[2];
    su0[k] = d.area * m_k.cu;
    sp0[k] = d.area * m_k.cp;
  }
  // The 15 kernel numbers at each point, weights included.
  alignas(64) double K[7][15][B];
  const double cd = m_k.cu_diag, om = m_k.one_m_2nu;
  static_assert(B % 8 == 0, "lanes come in groups of 8");
  for (int q = 0; q < 7; ++q) {
    alignas(64) double r2[B], ir[B];
#pragma omp simd
    for (int k = 0; k < B; ++k) {
      const double d0 = qx[q][k] - x[0], d1 = qy[q][k] - x[1], d2 = qz[q][k] - x[2];
      r2[k] = d0 * d0 + d1 * d1 + d2 * d2;
    }
    for (int k = 0; k < B; k += 8) inv_sqrt8(r2 + k, ir + k);
#pragma omp simd
    for (int k = 0; k < B; ++k) {
      const double d0 = qx[q][k] - x[0], d1 = qy[q][k] - x[1], d2 = qz[q][k] - x[2];
      const double inv_r = ir[k];
      const double g0 = d0 * inv_r, g1 = d1 * inv_r, g2 = d2 * inv_r;
      const double su = weight[q] * su0[k] * inv_r, sp = weight[q] * sp0[k] * inv_r * inv_r;
      kernel_numbers(g0, g1, g2, su, sp, nx[k], ny[k], nz[k], cd, om, &K[q][0][k], B);
    }
  }
  alignas(64) double S[3][15][B];
  for (int m = 0; m < 15; ++m) {
#pragma omp simd
    for (int k = 0; k < B; ++k) corner_combination(&K[0][m][k], 15 * B, &S[0][m][k], 15 * B);
  }
  for (int k = 0; k < B; ++k)
    for (int c = 0; c < 3; ++c)
      for (int m = 0; m < 15; ++m) out[k].v[c][m] = S[c][m][k];
}

unsigned RegularRule::regular_lanes(const double (&x)[3][lanes], int t) const
{
  const TriangleData &d = m_tri[t];
  unsigned bits = 0;
  for (int k = 0; k < lanes; ++k) {
    const double d0 = x[0][k] - d.centroid[0], d1 = x[1][k] - d.centroid[1], d2 = x[2][k] - d.centroid[2];
    const double r2 = d0 * d0 + d1 * d1 + d2 * d2;
    bits |= static_cast<unsigned>(r2 >= d.near2 && r2 < d.far2) << k;
  }
  return bits;
}

void RegularRule::lane_kernels(const double (&x)[3][lanes], int t, double (&K)[7][CornerSums::size][lanes]) const
{
  // As batch, with the points as lanes: the triangle's data are scalars, nothing is gathered.
  constexpr int L = lanes;
  static_assert(L == 8, "inv_sqrt8 serves 8 lanes");
  const TriangleData &d = m_tri[t];
  const double nx = d.n[0], ny = d.n[1], nz = d.n[2], su0 = d.area * m_k.cu, sp0 = d.area * m_k.cp;
  const double cd = m_k.cu_diag, om = m_k.one_m_2nu;
  for (int q = 0; q < 7; ++q) {
    const double yx = d.q[0][q], yy = d.q[1][q], yz = d.q[2][q], su1 = weight[q] * su0, sp1 = weight[q] * sp0;
    alignas(64) double r2[L], ir[L];
#pragma omp simd aligned(r2 : 64)
    for (int k = 0; k < L; ++k) {
      const double d0 = yx - x[0][k], d1 = yy - x[1][k], d2 = yz - x[2][k];
      r2[k] = d0 * d0 + d1 * d1 + d2 * d2;
    }
    inv_sqrt8(r2, ir);
#pragma omp simd aligned(ir : 64)
    for (int k = 0; k < L; ++k) {
      const double inv_r = ir[k];
      const double g0 = (yx - x[0][k]) * inv_r, g1 = (yy - x[1][k]) * inv_r, g2 = (yz - x[2][k]) * inv_r;
      const double su = su1 * inv_r, sp = sp1 * inv_r * inv_r;
      kernel_numbers(g0, g1, g2, su, sp, nx, ny, nz, cd, om, &K[q][0][k], L);
    }
  }
}

void RegularRule::lane_sums(const double (&x)[3][lanes], int t, double (&out)[3][CornerSums::size][lanes]) const
{
  constexpr int L = lanes;
  alignas(64) double K[7][CornerSums::size][L];
  lane_kernels(x, t, K);
  for (int m = 0; m < CornerSums::size; ++m) {
#pragma omp simd
    for (int k = 0; k < L; ++k) corner_combination(&K[0][m][k], CornerSums::size * L, &out[0][m][k], CornerSums::size * L);
  }
}

void RegularRule::add_lane_sums(const double (&x)[3][lanes], int t, double *const dest[3]) const
{
  constexpr int L = lanes;
  alignas(64) double K[7][CornerSums::size][L];
  lane_kernels(x, t, K);
  for (int m = 0; m < CornerSums::size; ++m) {
    alignas(64) double S[3][L];
#pragma omp simd
    for (int k = 0; k < L; ++k) corner_combination(&K[0][m][k], CornerSums::size * L, &S[0][k], L);
    for (int c = 0; c < 3; ++c) {
      if (!dest[c]) continue;
      double *to = dest[c] + m * L;
#pragma omp simd
      for (int k = 0; k < L; ++k) to[k] += S[c][k];
    }
  }
}

void RegularRule::sums(const Vec3 &x, const int *tris, int n, CornerSums *out) const
{
  constexpr int B = 8;
  int k = 0;
  for (; k + B <= n; k += B) batch<B>(x, tris + k, out + k);
  if (k == n) return;
  int pad[B];
  CornerSums tmp[B];
  for (int j = 0; j < B; ++j) pad[j] = tris[std::min(k + j, n - 1)];
  batch<B>(x, pad, tmp);
  std::copy(tmp, tmp + (n - k), out + k);
}

} // namespace hssbem
