/// \file benchmark_problem.hpp
/// The boundary-condition pattern of the benchmarks (bench_hss, bench_ksp) and of the solver
/// tests that mirror them: a body standing on its lower half.
#pragma once

#include "hssbem/bem/bem_operator.hpp"

namespace hssbem {

/// Nodes below the median height clamped (u = 0, traction unknown); the others loaded by the
/// uniform traction `traction` (displacement unknown).
SystemSelection clamped_lower_half(const Discretization &disc, const Vec3 &traction);

} // namespace hssbem
