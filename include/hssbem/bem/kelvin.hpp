/// \file kelvin.hpp
/// Isotropic linear elastic material and Kelvin's fundamental solutions u* and p*.
#pragma once

#include "hssbem/core/geometry.hpp"

#include <stdexcept>

namespace hssbem {

/// Isotropic material. Construct through from_young or from_lame; both validate.
struct Material {
  double E = 0, nu = 0;
  double mu() const { return E / (2.0 * (1.0 + nu)); }
  double lambda() const { return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)); }
  /// Throws std::invalid_argument unless 1e-30 <= E <= 1e30 and -1 < nu < 0.5.
  static Material from_young(double E, double nu);
  /// Throws std::invalid_argument unless mu > 0 and the implied nu lies in (-1, 0.5).
  static Material from_lame(double lambda, double mu);
};

} // namespace hssbem
