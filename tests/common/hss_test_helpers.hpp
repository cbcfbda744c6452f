// Shared by the HSS unit tests: the dense K = [H, G(, Gn)] and the error of an HSS product.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/hss/hss_matrix.hpp"

#include <cmath>
#include <numeric>
#include <random>
#include <vector>

namespace hssbem::test {

/// Dense K = [H, G, Gn] in mesh order, row-major 3n × w n (rigid-body terms included).
inline std::vector<double> dense_k(const BemOperator &op, int w)
{
  const int n = op.num_nodes();
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  std::vector<double> H(9L * n * n), G(9L * n * n), Gn(w > 6 ? 3L * n * n : 0), K(3L * n * w * n);
  BemOperator::Workspace ws(op);
  op.fill_hg(all, all, H.data(), G.data(), 3L * n, w > 6 ? Gn.data() : nullptr, n, ws);
  for (long r = 0; r < 3L * n; ++r)
    for (int j = 0; j < n; ++j)
      for (int s = 0; s < w; ++s)
        K[r * w * n + w * j + s] = s < 3 ? H[r * 3 * n + 3 * j + s] : s < 6 ? G[r * 3 * n + 3 * j + s - 3] : Gn[r * n + j];
  return K;
}

inline double matvec_error(const HssMatrix &K, const std::vector<double> &Kd, int seed)
{
  const int n = K.tree().num_points(), w = K.col_block();
  std::mt19937 gen(seed);
  std::normal_distribution<double> N01;
  std::vector<double> x(static_cast<size_t>(w) * n), xc(x.size()), yc(3L * n), y(3L * n), yd(3L * n, 0.0);
  for (double &v : x) v = N01(gen);
  std::vector<double> xs(x);
  for (int j = 0; j < n; ++j)
    for (int q = 0; q < w; ++q) xs[static_cast<size_t>(w) * j + q] /= K.col_scale(q);
  K.tree().to_cluster_order(xs.data(), xc.data(), w);
  K.apply(xc.data(), w * n, yc.data(), 3 * n);
  K.tree().to_mesh_order(yc.data(), y.data(), 3);
  for (long r = 0; r < 3L * n; ++r)
    for (long q = 0; q < static_cast<long>(w) * n; ++q) yd[r] += Kd[r * w * n + q] * x[q];
  double e = 0, s = 0;
  for (long r = 0; r < 3L * n; ++r) {
    e += (y[r] - yd[r]) * (y[r] - yd[r]);
    s += yd[r] * yd[r];
  }
  return std::sqrt(e / s);
}

} // namespace hssbem::test
