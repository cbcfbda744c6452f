// From a boundary-condition pattern to products with a compressed K (see pattern_columns.hpp).
#include "hssbem/compress/pattern_columns.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hssbem {

void pattern_rhs_node(const SystemSelection &sel, int j, int w, double *out)
{
  std::fill(out, out + w, 0.0);
  const bool pressure = !sel.pressure.empty() && !std::isnan(sel.pressure[j]);
  if (pressure) {
    if (w < 7) throw std::logic_error("pressure loads need the pressure columns of K (pressure_columns)");
    out[6] = -sel.pressure[j];
  }
  for (int c = 0; c < 3; ++c) {
    if (sel.displacement_known[j][c]) out[c] = -sel.known[j][c];
    else if (!pressure) out[3 + c] = sel.known[j][c];
  }
}

void pattern_product_node(const SystemSelection &sel, int j, const double *x3, int w, double *out)
{
  std::fill(out, out + w, 0.0);
  for (int c = 0; c < 3; ++c) {
    if (sel.displacement_known[j][c]) out[3 + c] = -x3[c];
    else out[c] = x3[c];
  }
}

std::vector<double> pattern_rhs_input(const SystemSelection &sel, int n, int w)
{
  std::vector<double> xk(static_cast<std::size_t>(w) * n);
  for (int j = 0; j < n; ++j) pattern_rhs_node(sel, j, w, &xk[static_cast<std::size_t>(w) * j]);
  return xk;
}

std::vector<double> pattern_product_input(const SystemSelection &sel, const double *x, int n, int w)
{
  std::vector<double> xk(static_cast<std::size_t>(w) * n);
  for (int j = 0; j < n; ++j) pattern_product_node(sel, j, x + 3L * j, w, &xk[static_cast<std::size_t>(w) * j]);
  return xk;
}

} // namespace hssbem
