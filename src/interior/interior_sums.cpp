// The kernel sums of the fast interior evaluation (see interior_evaluation.hpp), in single
// precision: point forces on spheres and the near leaves' particles, summed at points or at the
// check points of a fit. These loops are most of the evaluation's time; they run near the
// machine's arithmetic rate (a profile shows them bound by their multiplies, not by loads or by
// the square root), so what speeds the evaluation up is fewer kernels, not faster ones.
#include "interior_evaluation_impl.hpp"

#include <cmath>

namespace hssbem::detail {

void add_forces_to(const SomiglianaConstants &k, const float *const p[3], int m, const Vec3 &c, double r, const SpherePoints &s, const float *q, double *field)
{
  const int n = s.size();
  std::vector<float> acc(3 * static_cast<std::size_t>(m), 0.0f);
  float *A0 = acc.data(), *A1 = A0 + m, *A2 = A1 + m;
  const float *P0 = p[0], *P1 = p[1], *P2 = p[2], rf = static_cast<float>(r);
  const float c0 = static_cast<float>(c[0]), c1 = static_cast<float>(c[1]), c2 = static_cast<float>(c[2]);
  const float cu = static_cast<float>(k.cu), cu_diag = static_cast<float>(k.cu_diag);
  for (int j = 0; j < n; ++j) {
    // U q = cu cu_diag q / r + cu d (d · q) / r³ (kelvin_displacement_point), the force's factors taken out of the loop.
    const float y0 = c0 + rf * s.fx[j], y1 = c1 + rf * s.fy[j], y2 = c2 + rf * s.fz[j], q0 = cu * q[j], q1 = cu * q[n + j], q2 = cu * q[2 * n + j];
    const float a0 = cu_diag * q0, a1 = cu_diag * q1, a2 = cu_diag * q2;
#pragma omp simd
    for (int i = 0; i < m; ++i) {
      const float d0 = y0 - P0[i], d1 = y1 - P1[i], d2 = y2 - P2[i];
      const float inv_r = 1.0f / std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
      const float t = (d0 * q0 + d1 * q1 + d2 * q2) * (inv_r * inv_r * inv_r);
      A0[i] += a0 * inv_r + d0 * t, A1[i] += a1 * inv_r + d1 * t, A2[i] += a2 * inv_r + d2 * t;
    }
  }
  for (std::size_t i = 0; i < acc.size(); ++i) field[i] += acc[i];
}

void add_forces_field(const SomiglianaConstants &k, const Vec3 &x, const Vec3 &centre, double r, const SpherePoints &s, const float *q, double *out)
{
  const int n = s.size();
  const float ox = static_cast<float>(centre[0] - x[0]), oy = static_cast<float>(centre[1] - x[1]), oz = static_cast<float>(centre[2] - x[2]);
  const float rf = static_cast<float>(r);
  const float *SX = s.fx.data(), *SY = s.fy.data(), *SZ = s.fz.data(), *Q0 = q, *Q1 = q + n, *Q2 = q + 2 * n;
  float a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0, a8 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7, a8)
  for (int j = 0; j < n; ++j) {
    float w0, w1, w2, w3, w4, w5, w6, w7, w8;
    kelvin_force_point(k, ox + rf * SX[j], oy + rf * SY[j], oz + rf * SZ[j], Q0[j], Q1[j], Q2[j], w0, w1, w2, w3, w4, w5, w6, w7, w8);
    a0 += w0, a1 += w1, a2 += w2, a3 += w3, a4 += w4, a5 += w5, a6 += w6, a7 += w7, a8 += w8;
  }
  out[0] += a0, out[1] += a1, out[2] += a2, out[3] += a3, out[4] += a4, out[5] += a5, out[6] += a6, out[7] += a7, out[8] += a8;
}

namespace {

/// out[0..9) += the field at x (relative to the leaf's centre) of particles [begin, end), weighted
/// by W[j] if `weighted` (W indexed like the particles).
template <bool weighted>
void add_particles(const SomiglianaConstants &k, const OrderedParticles &o, const float x[3], std::size_t begin, std::size_t end, const float *W, double *out)
{
  float a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0, a8 = 0;
  const float x0 = x[0], x1 = x[1], x2 = x[2];
  // Raw pointers: the loop below must see plain arrays to vectorise with contiguous loads.
  const float *Y0 = o.ys[0].data(), *Y1 = o.ys[1].data(), *Y2 = o.ys[2].data(), *F0 = o.fs[0].data(), *F1 = o.fs[1].data(), *F2 = o.fs[2].data();
  const float *M0 = o.ms[0].data(), *M1 = o.ms[1].data(), *M2 = o.ms[2].data(), *N0 = o.ns[0].data(), *N1 = o.ns[1].data(), *N2 = o.ns[2].data();
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7, a8)
  for (std::size_t j = begin; j < end; ++j) {
    const float w = weighted ? W[j] : 1.0f;
    float v0, v1, v2, v3, v4, v5, v6, v7, v8;
    somigliana_point(k, Y0[j] - x0, Y1[j] - x1, Y2[j] - x2, w * F0[j], w * F1[j], w * F2[j], w * M0[j], w * M1[j], w * M2[j], N0[j], N1[j], N2[j], v0, v1, v2, v3,
                     v4, v5, v6, v7, v8);
    a0 += v0, a1 += v1, a2 += v2, a3 += v3, a4 += v4, a5 += v5, a6 += v6, a7 += v7, a8 += v8;
  }
  out[0] += a0, out[1] += a1, out[2] += a2, out[3] += a3, out[4] += a4, out[5] += a5, out[6] += a6, out[7] += a7, out[8] += a8;
}

} // namespace

void OrderedParticles::add_regular(const SomiglianaConstants &k, const Vec3 &x, const Vec3 &centre, std::size_t begin, std::size_t end, const float *weight,
                                   double *out) const
{
  const float xc[3] = {static_cast<float>(x[0] - centre[0]), static_cast<float>(x[1] - centre[1]), static_cast<float>(x[2] - centre[2])};
  if (weight) add_particles<true>(k, *this, xc, begin, end, weight - begin, out);
  else add_particles<false>(k, *this, xc, begin, end, nullptr, out);
}

} // namespace hssbem::detail
