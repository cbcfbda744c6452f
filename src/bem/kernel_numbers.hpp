// The 15 numbers of Kelvin's kernels at one quadrature point, shared by the regular rule's SIMD
// loops (regular_rule.cpp) and the near-singular rules' point sums (quadrature.cpp).
#pragma once

namespace hssbem {

/// The rule's 15 kernel numbers at one quadrature point (CornerSums layout), weights included:
/// g the unit vector from the point x to the quadrature point, su and sp the scaled weights of
/// u* (1/r) and p* (1/r²), n the triangle's normal, cd and om the material's u* diagonal and
/// 1 − 2ν. Writes K[m · stride] (inlined into the SIMD loops of its callers).
inline void kernel_numbers(double g0, double g1, double g2, double su, double sp, double nx, double ny, double nz, double cd, double om, double *K, int stride)
{
  const double ts = sp * (g0 * nx + g1 * ny + g2 * nz), ta = -sp * om;
  K[0 * stride] = su * (cd + g0 * g0);
  K[1 * stride] = su * (cd + g1 * g1);
  K[2 * stride] = su * (cd + g2 * g2);
  K[3 * stride] = su * g0 * g1;
  K[4 * stride] = su * g0 * g2;
  K[5 * stride] = su * g1 * g2;
  K[6 * stride] = ts * (om + 3 * g0 * g0);
  K[7 * stride] = ts * (om + 3 * g1 * g1);
  K[8 * stride] = ts * (om + 3 * g2 * g2);
  K[9 * stride] = 3 * ts * g0 * g1;
  K[10 * stride] = 3 * ts * g0 * g2;
  K[11 * stride] = 3 * ts * g1 * g2;
  K[12 * stride] = ta * (g0 * ny - g1 * nx);
  K[13 * stride] = ta * (g0 * nz - g2 * nx);
  K[14 * stride] = ta * (g1 * nz - g2 * ny);
}

} // namespace hssbem
