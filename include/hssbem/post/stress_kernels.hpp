/// \file stress_kernels.hpp
/// Kelvin's kernels of Somigliana's identities at a point x inside the body, for the displacement
/// and for the stress (the derivative kernels of u* and p*, Brebbia & Dominguez §5):
///   u_i(x)  = ∫ U_ik(x, y) t_k(y) dΓ − ∫ P_ik(x, y) u_k(y) dΓ,
///   σ_ij(x) = ∫ D_kij(x, y) t_k(y) dΓ − ∫ S_kij(x, y) u_k(y) dΓ,
/// with r = |y − x|, g = (y − x) / r, n the outward normal at y:
///   U_ik  = cu / r [(3 − 4ν) δ_ik + g_i g_k],
///   P_ik  = cp / r² [∂r/∂n ((1 − 2ν) δ_ik + 3 g_i g_k) − (1 − 2ν)(g_i n_k − g_k n_i)],
///   D_kij = cd / r² [(1 − 2ν)(δ_ki g_j + δ_kj g_i − δ_ij g_k) + 3 g_i g_j g_k],
///   S_kij = cs / r³ {3 ∂r/∂n [(1 − 2ν) δ_ij g_k + ν (δ_ik g_j + δ_jk g_i) − 5 g_i g_j g_k]
///                   + 3ν (n_i g_j g_k + n_j g_i g_k) + (1 − 2ν)(3 n_k g_i g_j + n_j δ_ik + n_i δ_jk)
///                   − (1 − 4ν) n_k δ_ij},
/// cu = 1 / (16π μ (1 − ν)), cp = −1 / (8π (1 − ν)), cd = 1 / (8π (1 − ν)), cs = μ / (4π (1 − ν)).
/// D and S are the stresses (at x) of U and P, differentiated at x; tests check them against
/// finite differences of U and P.
///
/// Symmetric tensors are stored in the Voigt order of the result files: xx, yy, zz, yz, xz, xy.
/// The functions below are inline so that the callers' SIMD loops vectorise them.
#pragma once

#include "hssbem/bem/kelvin.hpp"

#include <array>
#include <cmath>

namespace hssbem {

/// The nine outputs of one evaluation: displacement (3) then stress (Voigt, 6).
constexpr int field_outputs = 9;

/// Row and column of each Voigt entry.
constexpr int voigt_row[6] = {0, 1, 2, 1, 0, 0};
constexpr int voigt_col[6] = {0, 1, 2, 2, 2, 1};

/// The material constants of the four kernels.
struct SomiglianaConstants {
  double cu, cu_diag; ///< U = cu / r [cu_diag δ + g g]
  double cp, om;      ///< P = cp / r² [...]; om = 1 − 2ν
  double cd;          ///< D = cd / r² [...]
  double cs, nu;      ///< S = cs / r³ {...}
  explicit SomiglianaConstants(const Material &m)
    : cu(1.0 / (16.0 * M_PI * m.mu() * (1.0 - m.nu))), cu_diag(3.0 - 4.0 * m.nu), cp(-1.0 / (8.0 * M_PI * (1.0 - m.nu))), om(1.0 - 2.0 * m.nu),
      cd(1.0 / (8.0 * M_PI * (1.0 - m.nu))), cs(m.mu() / (4.0 * M_PI * (1.0 - m.nu))), nu(m.nu)
  {
  }
};

/// The contribution of one source point at offset d = y − x to the displacement (u0, u1, u2)
/// and the stress (s0..s5, Voigt) at x: the force f (weight × t(y)) through U and D, minus the
/// double-layer density m (weight × u(y)) on the unit normal n through P and S. Outputs are set,
/// not added, one scalar each, so that loops over source points vectorise. T = double, or float
/// for the fast evaluation's sums (twice the SIMD lanes; see interior_evaluation.hpp).
template <class T>
inline void somigliana_point(const SomiglianaConstants &k, T d0, T d1, T d2, T f0, T f1, T f2, T m0, T m1, T m2, T n0, T n1, T n2, T &u0, T &u1, T &u2, T &s0,
                             T &s1, T &s2, T &s3, T &s4, T &s5)
{
  const T inv_r = T(1) / std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
  const T g0 = d0 * inv_r, g1 = d1 * inv_r, g2 = d2 * inv_r;
  const T gf = g0 * f0 + g1 * f1 + g2 * f2, gm = g0 * m0 + g1 * m1 + g2 * m2;
  const T gn = g0 * n0 + g1 * n1 + g2 * n2, nm = n0 * m0 + n1 * m1 + n2 * m2;
  const T inv_r2 = inv_r * inv_r, om = T(k.om), nu = T(k.nu), cu_diag = T(k.cu_diag);
  // Displacement: U f − P m.
  const T au = T(k.cu) * inv_r, ap = T(k.cp) * inv_r2;
  const T pu = ap * gn * om, pg = ap * (T(3) * gn * gm - om * nm), pn = ap * om * gm;
  const T uf = au * cu_diag, ug = au * gf - pg; // u = uf f + ug g − pu m − pn n
  u0 = uf * f0 + ug * g0 - pu * m0 - pn * n0;
  u1 = uf * f1 + ug * g1 - pu * m1 - pn * n1;
  u2 = uf * f2 + ug * g2 - pu * m2 - pn * n2;
  // Stress: D f − S m, the kernels above contracted with f and m and grouped by tensor product:
  // dgg g⊗g + dd I + (w⊗g + g⊗w) + dnm (n⊗m + m⊗n), w = dfg f + dmg m + dng n; computed with
  // h = dgg g + w and p = dnm m (the fewest multiplies: the near particles' sums are bound by them).
  const T ad = T(k.cd) * inv_r2, as = T(k.cs) * inv_r2 * inv_r;
  const T dgg = T(3) * ad * gf - as * (om * T(3) * nm - T(15) * gn * gm);
  const T dd = -ad * om * gf - as * (T(3) * gn * om * gm - (T(1) - T(4) * nu) * nm);
  const T dfg = ad * om, dmg = -as * T(3) * gn * nu, dng = -as * T(3) * nu * gm, dnm = -as * om;
  const T w0 = dfg * f0 + dmg * m0 + dng * n0, w1 = dfg * f1 + dmg * m1 + dng * n1, w2 = dfg * f2 + dmg * m2 + dng * n2;
  const T h0 = dgg * g0 + w0, h1 = dgg * g1 + w1, h2 = dgg * g2 + w2, p0 = dnm * m0, p1 = dnm * m1, p2 = dnm * m2;
  s0 = g0 * (h0 + w0) + T(2) * n0 * p0 + dd;
  s1 = g1 * (h1 + w1) + T(2) * n1 * p1 + dd;
  s2 = g2 * (h2 + w2) + T(2) * n2 * p2 + dd;
  s3 = g2 * h1 + g1 * w2 + n2 * p1 + n1 * p2;
  s4 = g2 * h0 + g0 * w2 + n2 * p0 + n0 * p2;
  s5 = g1 * h0 + g0 * w1 + n1 * p0 + n0 * p1;
}

/// The same, added to out[k · stride], k = 0..8 (displacement, then stress).
inline void somigliana_point(const SomiglianaConstants &k, double d0, double d1, double d2, double f0, double f1, double f2, double m0, double m1,
                             double m2, double n0, double n1, double n2, double *out, int stride)
{
  double v[field_outputs];
  somigliana_point(k, d0, d1, d2, f0, f1, f2, m0, m1, m2, n0, n1, n2, v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]);
  for (int c = 0; c < field_outputs; ++c) out[c * stride] += v[c];
}

/// The displacement part of somigliana_point (U f − P m) only, set into u0, u1, u2.
inline void somigliana_displacement_point(const SomiglianaConstants &k, double d0, double d1, double d2, double f0, double f1, double f2, double m0,
                                          double m1, double m2, double n0, double n1, double n2, double &u0, double &u1, double &u2)
{
  const double inv_r = 1.0 / std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
  const double g0 = d0 * inv_r, g1 = d1 * inv_r, g2 = d2 * inv_r;
  const double gf = g0 * f0 + g1 * f1 + g2 * f2, gm = g0 * m0 + g1 * m1 + g2 * m2;
  const double gn = g0 * n0 + g1 * n1 + g2 * n2, nm = n0 * m0 + n1 * m1 + n2 * m2;
  const double au = k.cu * inv_r, ap = k.cp * inv_r * inv_r, om = k.om;
  const double pu = ap * gn * om, pg = ap * (3.0 * gn * gm - om * nm), pn = ap * om * gm;
  u0 = au * (k.cu_diag * f0 + g0 * gf) - (pu * m0 + pg * g0 + pn * n0);
  u1 = au * (k.cu_diag * f1 + g1 * gf) - (pu * m1 + pg * g1 + pn * n1);
  u2 = au * (k.cu_diag * f2 + g2 * gf) - (pu * m2 + pg * g2 + pn * n2);
}

/// The displacement and stress at x of a point force q at offset d = y − x (U and D only): the
/// far field of the equivalent sources of a fast evaluation. Outputs are set, as above; T as above.
template <class T>
inline void kelvin_force_point(const SomiglianaConstants &k, T d0, T d1, T d2, T q0, T q1, T q2, T &u0, T &u1, T &u2, T &s0, T &s1, T &s2, T &s3, T &s4, T &s5)
{
  const T inv_r = T(1) / std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
  const T g0 = d0 * inv_r, g1 = d1 * inv_r, g2 = d2 * inv_r;
  const T gq = g0 * q0 + g1 * q1 + g2 * q2, om = T(k.om);
  const T au = T(k.cu) * inv_r, aq = au * gq, ud = au * T(k.cu_diag), ad = T(k.cd) * inv_r * inv_r;
  u0 = ud * q0 + aq * g0;
  u1 = ud * q1 + aq * g1;
  u2 = ud * q2 + aq * g2;
  // σ = dgg g⊗g + dd I + dfg (q⊗g + g⊗q), grouped as h = dgg g + w and w = dfg q (the fewest
  // multiplies: the far field's sums are bound by them).
  const T dgg = T(3) * ad * gq, dd = -ad * om * gq, dfg = ad * om;
  const T w0 = dfg * q0, w1 = dfg * q1, w2 = dfg * q2, h0 = dgg * g0 + w0, h1 = dgg * g1 + w1, h2 = dgg * g2 + w2;
  s0 = g0 * (h0 + w0) + dd;
  s1 = g1 * (h1 + w1) + dd;
  s2 = g2 * (h2 + w2) + dd;
  s3 = g2 * h1 + w2 * g1;
  s4 = g2 * h0 + w2 * g0;
  s5 = g1 * h0 + w1 * g0;
}

/// The same, added to out[k · stride], k = 0..8.
inline void kelvin_force_point(const SomiglianaConstants &k, double d0, double d1, double d2, double q0, double q1, double q2, double *out, int stride)
{
  double v[field_outputs];
  kelvin_force_point(k, d0, d1, d2, q0, q1, q2, v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]);
  for (int c = 0; c < field_outputs; ++c) out[c * stride] += v[c];
}

/// The displacement at x of a point force q at offset d = y − x (U only), set into u0, u1, u2; T as above.
template <class T>
inline void kelvin_displacement_point(const SomiglianaConstants &k, T d0, T d1, T d2, T q0, T q1, T q2, T &u0, T &u1, T &u2)
{
  const T inv_r = T(1) / std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
  const T gq = (d0 * q0 + d1 * q1 + d2 * q2) * inv_r * inv_r;
  const T au = T(k.cu) * inv_r, ad = au * T(k.cu_diag);
  u0 = ad * q0 + au * d0 * gq;
  u1 = ad * q1 + au * d1 * gq;
  u2 = ad * q2 + au * d2 * gq;
}

/// The von Mises equivalent stress of s.
inline double von_mises(const Voigt &s)
{
  const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

/// The principal stresses of s, largest first.
std::array<double, 3> principal_stresses(const Voigt &s);

/// The stress of the strain of displacement gradient G (G[3i + j] = ∂u_i/∂x_j) under Hooke's law.
Voigt hooke_stress(const Material &m, const Mat3 &G);

} // namespace hssbem
