/// \file rigid_body_blocks.hpp
/// The rigid-body terms of H (DESIGN §2) for a compressed K that lacks them: since H annihilates
/// the rigid translations, D_i = −Σ_j H⁰(i, j), and the sum is one fast product of the compressed
/// H⁰ with the three translations. Shared by the HSS and H² compressions.
#pragma once

#include <cstddef>
#include <vector>

namespace hssbem {

/// D (9 values per point, cluster order): D[9k + 3r + c] = −(H⁰ t_c)(3k + r), t_c the unit
/// translation along c. M is HssMatrix or H2Matrix; its slots 0–2 are H's (scale 1).
template <class M>
std::vector<double> rigid_body_blocks(const M &K)
{
  const int n = K.tree().num_points(), w = K.col_block();
  std::vector<double> X(static_cast<std::size_t>(w) * n * 3, 0.0), Y(static_cast<std::size_t>(3) * n * 3), D(static_cast<std::size_t>(9) * n);
  for (int k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c) X[static_cast<std::size_t>(w) * k + c + static_cast<std::size_t>(c) * w * n] = 1.0;
  K.apply(X.data(), w * n, Y.data(), 3 * n, 3);
  for (int k = 0; k < n; ++k)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) D[9 * static_cast<std::size_t>(k) + 3 * r + c] = -Y[3 * static_cast<std::size_t>(k) + r + static_cast<std::size_t>(c) * 3 * n];
  return D;
}

} // namespace hssbem
