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
/// rows of A then carry r (returned in `r`).
std::vector<double> open_rows(const std::vector<double> &y, const std::vector<int> &rows, const std::function<const std::vector<double> &(int)> &column, std::vector<double> &r)
{
  const int q = static_cast<int>(rows.size()), m = static_cast<int>(y.size());
  std::vector<double> lambda = y, Y(static_cast<std::size_t>(q) * q);
  r.assign(q, 0.0);
  if (q == 0) return lambda;
  for (int j = 0; j < q; ++j) {
    const std::vector<double> &c = column(rows[j]);
    for (int i = 0; i < q; ++i) Y[i + static_cast<std::size_t>(j) * q] = c[rows[i]];
  }
  for (int i = 0; i < q; ++i) r[i] = -y[rows[i]];
  std::vector<int> piv(q);
  if (lapack::getrf(q, Y.data(), q, piv.data()) != 0) throw std::runtime_error("the haptic call's reduced contact system is singular");
  lapack::getrs('N', q, 1, Y.data(), q, piv.data(), r.data(), q);
  for (int j = 0; j < q; ++j) {
    const std::vector<double> &c = column(rows[j]);
    for (int p = 0; p < m; ++p) lambda[p] += c[p] * r[j];
  }
  for (int i = 0; i < q; ++i) lambda[rows[i]] = 0;
  return lambda;
}

} // namespace

std::vector<double> open_pulling_points(const Compliance &D, const std::vector<int> &points, int k, const std::vector<double> &y,
                                        const std::function<void(int, double *)> &inverse_column, double tol_gap)
{
  const int np = static_cast<int>(points.size());
  const std::vector<int> lead = lead_positions(D, points);
  std::unordered_map<int, std::vector<double>> cache; // columns of A⁻¹ computed so far
  const auto column = [&](int row) -> const std::vector<double> & {
    auto it = cache.find(row);
    if (it == cache.end()) {
      it = cache.emplace(row, std::vector<double>(y.size())).first;
      inverse_column(row, it->second.data());
    }
    return it->second;
  };
  std::vector<char> open(np, 0);
  for (int pass = 0; pass <= np; ++pass) {
    std::vector<int> rows;
    for (int a = 0; a < np; ++a)
      if (open[lead[a]])
        for (int i = 0; i < k; ++i) rows.push_back(k * a + i);
    std::vector<double> r;
    const std::vector<double> lambda = open_rows(y, rows, column, r);
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
