/// \file h2_breakdown.hpp
/// The H² factorization's one failure of its own: a pivot block singular to the working
/// precision (e.g. a pure-traction problem without its rigid-mode regularisation). A PC reports
/// it as a failed set-up (KSP: DIVERGED_PC_FAILED), not as an error.
#pragma once

#include <stdexcept>

namespace hssbem {

class H2Breakdown : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

} // namespace hssbem
