// Shared by the HSS and H² unit tests: dense references (K, A for a pattern), errors, random patterns.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/hss/hss_matrix.hpp"
#include "hssbem/hss/ulv.hpp"

#include <array>

#include <cctype>
#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace hssbem::test {

/// A readable test name: mesh stem, tolerance exponent, leaf size (e.g. sphere_l1_tol1e6_leaf16).
inline std::string case_name(const std::string &mesh, double tol, int leaf)
{
  std::string stem = mesh.substr(0, mesh.find('.'));
  for (char &ch : stem)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return stem + "_tol1e" + std::to_string(static_cast<int>(std::lround(-std::log10(tol)))) + "_leaf" + std::to_string(leaf);
}

/// ‖a − b‖ / ‖b‖.
inline double rel(const std::vector<double> &a, const std::vector<double> &b)
{
  double e = 0, s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) e += (a[i] - b[i]) * (a[i] - b[i]), s += b[i] * b[i];
  return std::sqrt(e / s);
}

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

/// ‖(K_compressed − K)x‖ / ‖Kx‖ for a random x; M is HssMatrix or H2Matrix.
template <class M>
double matvec_error(const M &K, const std::vector<double> &Kd, int seed)
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
  return rel(y, yd);
}

/// Random pattern: u known (t unknown) with probability p per node and component.
inline std::vector<std::array<bool, 3>> random_pattern(int n, double p, int seed)
{
  std::mt19937 gen(seed);
  std::bernoulli_distribution B(p);
  std::vector<std::array<bool, 3>> k(n);
  for (auto &a : k)
    for (bool &b : a) b = B(gen);
  return k;
}

/// Dense A = K E_S (column-major, 3n × 3n) from the dense K (row-major 3n × w n, mesh order).
inline std::vector<double> dense_a(const std::vector<double> &Kd, int n, int w, const std::vector<std::array<bool, 3>> &known)
{
  std::vector<double> A(9L * n * n);
  for (long r = 0; r < 3L * n; ++r)
    for (int j = 0; j < n; ++j)
      for (int c = 0; c < 3; ++c) A[r + (3L * j + c) * 3 * n] = known[j][c] ? -Kd[r * w * n + w * j + 3 + c] : Kd[r * w * n + w * j + c];
  return A;
}

/// x = A⁻¹ b with a ULV factorization of K's pattern, b and x in mesh order (3 per node).
inline std::vector<double> ulv_solve(const HssMatrix &K, const UlvFactorization &F, const std::vector<double> &b)
{
  std::vector<double> bc(b.size()), x(b.size());
  K.tree().to_cluster_order(b.data(), bc.data(), 3);
  F.solve(bc.data());
  K.tree().to_mesh_order(bc.data(), x.data(), 3);
  return x;
}

} // namespace hssbem::test
