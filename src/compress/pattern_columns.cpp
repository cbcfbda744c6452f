// From a boundary-condition pattern to products with a compressed K (see pattern_columns.hpp).
#include "hssbem/compress/pattern_columns.hpp"

#include <cmath>
#include <stdexcept>

namespace hssbem {

std::vector<double> pattern_rhs_input(const SystemSelection &sel, int n, int w)
{
  std::vector<double> xk(static_cast<std::size_t>(w) * n, 0.0);
  for (int j = 0; j < n; ++j) {
    const bool pressure = !sel.pressure.empty() && !std::isnan(sel.pressure[j]);
    if (pressure) {
      if (w < 7) throw std::logic_error("pressure loads need the pressure columns of K (pressure_columns)");
      xk[w * j + 6] = -sel.pressure[j];
    }
    for (int c = 0; c < 3; ++c) {
      if (sel.displacement_known[j][c]) xk[w * j + c] = -sel.known[j][c];
      else if (!pressure) xk[w * j + 3 + c] = sel.known[j][c];
    }
  }
  return xk;
}

std::vector<double> pattern_product_input(const SystemSelection &sel, const double *x, int n, int w)
{
  std::vector<double> xk(static_cast<std::size_t>(w) * n, 0.0);
  for (int j = 0; j < n; ++j)
    for (int c = 0; c < 3; ++c) {
      if (sel.displacement_known[j][c]) xk[w * j + 3 + c] = -x[3 * j + c];
      else xk[w * j + c] = x[3 * j + c];
    }
  return xk;
}

} // namespace hssbem
