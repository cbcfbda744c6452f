// The haptic call's small active set on the last solve's closed points (contact_points.hpp):
// Woodbury updates of the last solve's factored fixed-state system.
#include "contact_points.hpp"

#include "hssbem/core/lapack.hpp"

#include <stdexcept>
#include <unordered_map>

namespace hssbem::contact_detail {

namespace {

/// Per point of `points`: the position of its lead among them (its own where it leads, or where
/// its lead is not among them).
std::vector<int> lead_positions(const Compliance &D, const std::vector<int> &points)
{
  std::unordered_map<int, int> pos;
  for (std::size_t a = 0; a < points.size(); ++a) pos[points[a]] = static_cast<int>(a);
  std::vector<int> lead(points.size());
  for (std::size_t a = 0; a < points.size(); ++a) {
    const auto it = pos.find(D.point(points[a]).lead);
    lead[a] = it == pos.end() ? static_cast<int>(a) : it->second;
  }
  return lead;
}

/// λ = y + A⁻¹(:, rows) r with A⁻¹(rows, rows) r = −y(rows): λ vanishes on `rows`, whose own
/// rows of A then carry r (returned in `r`). `cache` holds the columns of A⁻¹ computed so far (by
/// row); the missing ones are computed in one call.
std::vector<double> open_rows(const std::vector<double> &y, const std::vector<int> &rows, const std::function<void(const std::vector<int> &, double *)> &inverse_columns,
                              std::unordered_map<int, std::vector<double>> &cache, std::vector<double> &r)
{
  const int q = static_cast<int>(rows.size()), m = static_cast<int>(y.size());
  std::vector<double> lambda = y, Y(static_cast<std::size_t>(q) * q);
  r.assign(q, 0.0);
  if (q == 0) return lambda;
  std::vector<int> missing;
  for (int row : rows)
    if (!cache.count(row)) missing.push_back(row);
  if (!missing.empty()) {
    std::vector<double> cols(static_cast<std::size_t>(m) * missing.size());
    inverse_columns(missing, cols.data());
    for (std::size_t j = 0; j < missing.size(); ++j) cache[missing[j]].assign(cols.begin() + j * m, cols.begin() + (j + 1) * m);
  }
  for (int j = 0; j < q; ++j) {
    const std::vector<double> &c = cache.at(rows[j]);
    for (int i = 0; i < q; ++i) Y[i + static_cast<std::size_t>(j) * q] = c[rows[i]];
  }
  for (int i = 0; i < q; ++i) r[i] = -y[rows[i]];
  std::vector<int> piv(q);
  if (lapack::getrf(q, Y.data(), q, piv.data()) != 0) throw std::runtime_error("the haptic call's reduced contact system is singular");
  lapack::getrs('N', q, 1, Y.data(), q, piv.data(), r.data(), q);
  for (int j = 0; j < q; ++j) {
    const std::vector<double> &c = cache.at(rows[j]);
    for (int p = 0; p < m; ++p) lambda[p] += c[p] * r[j];
  }
  for (int i = 0; i < q; ++i) lambda[rows[i]] = 0;
  return lambda;
}

} // namespace

std::vector<double> open_pulling_points(const Compliance &D, const std::vector<int> &points, int k, const std::vector<double> &y,
                                        const std::function<void(const std::vector<int> &, double *)> &inverse_columns, double tol_gap)
{
  const int np = static_cast<int>(points.size());
  bool pulling = false; // the common case (a tool that presses): every point closed, no update
  for (int a = 0; a < np && !pulling; ++a) pulling = D.point(points[a]).lead < 0 && y[static_cast<std::size_t>(k) * a] < 0;
  if (!pulling) return y;
  const std::vector<int> lead = lead_positions(D, points);
  std::unordered_map<int, std::vector<double>> cache; // columns of A⁻¹ computed so far
  std::vector<char> open(np, 0);
  for (int pass = 0; pass <= np; ++pass) {
    std::vector<int> rows;
    for (int a = 0; a < np; ++a)
      if (open[lead[a]])
        for (int i = 0; i < k; ++i) rows.push_back(k * a + i);
    std::vector<double> r;
    const std::vector<double> lambda = open_rows(y, rows, inverse_columns, cache, r);
    std::vector<double> gap(np, 0.0);
    for (std::size_t i = 0; i < rows.size(); ++i)
      if (rows[i] % k == 0) gap[rows[i] / k] = r[i]; // the normal row's residual: the open point's gap
    bool changed = false;
    for (int a = 0; a < np; ++a) {
      if (lead[a] != a) continue;
      if (!open[a] && lambda[k * a] < 0) open[a] = 1, changed = true;
      else if (open[a] && gap[a] < -tol_gap) open[a] = 0, changed = true;
    }
    if (!changed) return lambda;
  }
  throw std::runtime_error("the haptic call's contact set did not settle");
}

} // namespace hssbem::contact_detail
