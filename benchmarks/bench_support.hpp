// Shared by the benchmark programs: peak memory, relative differences, and the dense
// reference (collocation assembly + LU of the same system).
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace bench {

/// Peak resident memory of this process (VmHWM), MB.
inline double peak_rss_mb()
{
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0;
}

/// ‖a − b‖ / ‖b‖.
inline double rel_diff(const std::vector<double> &a, const std::vector<double> &b)
{
  double e = 0, s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    e += (a[i] - b[i]) * (a[i] - b[i]);
    s += b[i] * b[i];
  }
  return std::sqrt(e / s);
}

/// The dense reference: assembly (OpenMP over row blocks) and LU solve of the pattern's system.
struct DenseReference {
  double t_assembly = NAN, t_lu = NAN;
  std::vector<double> x; ///< 3 per node, mesh order
};

inline DenseReference dense_reference(const hssbem::BemOperator &op, const hssbem::SystemSelection &sel)
{
  const int n = op.num_nodes();
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  const long N = 3L * n;
  std::vector<double> A(N * N);
  DenseReference ref;
  ref.x.resize(N);
  hssbem::Timer timer;
#pragma omp parallel
  {
    hssbem::BemOperator::Workspace ws(op);
#pragma omp for schedule(dynamic, 1)
    for (int r0 = 0; r0 < n; r0 += 16) {
      const std::vector<int> rows(all.begin() + r0, all.begin() + std::min(n, r0 + 16));
      hssbem::fill_system_block(op, sel, rows, all, A.data() + 3L * r0 * N, N, ref.x.data() + 3L * r0, ws);
    }
  }
  ref.t_assembly = timer.seconds();
  timer.restart();
  std::vector<int> piv(N);
  if (hssbem::lapack::getrf(static_cast<int>(N), A.data(), static_cast<int>(N), piv.data()) != 0) throw std::runtime_error("dense LU failed");
  hssbem::lapack::getrs('T', static_cast<int>(N), 1, A.data(), static_cast<int>(N), piv.data(), ref.x.data(), static_cast<int>(N)); // A is row-major
  ref.t_lu = timer.seconds();
  return ref;
}

/// The dense columns of a CSV row: assembly and LU seconds of the dense reference and the
/// relative difference of x to its solution; all NaN when `run` is false (past dense reach).
struct DenseFigures {
  double t_assembly = NAN, t_lu = NAN, rel_diff = NAN;
};

inline DenseFigures dense_figures(bool run, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> &x)
{
  DenseFigures f;
  if (!run) return f;
  const DenseReference ref = dense_reference(op, sel);
  f.t_assembly = ref.t_assembly;
  f.t_lu = ref.t_lu;
  f.rel_diff = bench::rel_diff(x, ref.x);
  return f;
}

} // namespace bench
