/// \file material.cpp
/// Validated construction of an isotropic material.
#include "hssbem/bem/kelvin.hpp"

#include <charconv>
#include <cmath>
#include <string>

namespace hssbem {
namespace {

/// Shortest text that reads back to x: "0.49999999" rather than a rounded "0.5".
std::string shortest(double x)
{
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, res.ptr);
}

[[noreturn]] void refuse(const std::string &what)
{
  throw std::invalid_argument("invalid material: " + what);
}

} // namespace

Material Material::from_young(double E, double nu)
{
  if (!(E > 0) || !std::isfinite(E))
    refuse("E = " + shortest(E) + " must be positive and finite");
  // With lengths and loads within 1e±30 too (mesh and problem checks), every entry and product
  // of the system stays a normal double (E = 1e-300 gave a NaN residual).
  if (E < 1e-30 || E > 1e30)
    refuse("E = " + shortest(E) + " lies outside [1e-30, 1e30], where the solve overflows or underflows double precision; use other units");
  if (!(nu > -1 && nu < 0.5))
    refuse("nu = " + shortest(nu) + " must satisfy -1 < nu < 0.5" +
           (nu == 0.5 ? " (nu = 0.5 is incompressible, not supported)" : ""));
  Material m;
  m.E = E;
  m.nu = nu;
  return m;
}

Material Material::from_lame(double lambda, double mu)
{
  if (!(mu > 0) || !std::isfinite(mu))
    refuse("mu = " + shortest(mu) + " must be positive and finite");
  // -1 < nu < 0.5 is lambda > -2 mu / 3 for mu > 0; checking it here also keeps lambda + mu > 0.
  if (!(lambda > -2.0 * mu / 3.0) || !std::isfinite(lambda))
    refuse("lambda = " + shortest(lambda) + " must be finite and exceed -2 mu / 3 = " +
           shortest(-2.0 * mu / 3.0) + " (so that -1 < nu < 0.5)");
  const double nu = lambda / (2.0 * (lambda + mu));
  const double E = mu * (3.0 * lambda + 2.0 * mu) / (lambda + mu);
  return from_young(E, nu); // lambda >> mu rounds nu to 0.5: refused there as incompressible
}

} // namespace hssbem
