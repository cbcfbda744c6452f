// Private to the H² factorization: what it keeps for the solve (see h2_factorization.hpp).
#pragma once

#include "elimination_step.hpp"
#include "top_block.hpp"

#include "hssbem/core/rank_comm.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"

#include <memory>
#include <vector>

namespace hssbem {

struct H2Factorization::Factors {
  h2f::Pattern pattern;
  std::vector<h2f::Step> steps;       ///< this rank's, in elimination order, on its own rows
  std::unique_ptr<h2f::DenseTop> top; ///< spread: every rank's share; else rank 0's (none on the others)
  bool spread = false;
  int top_n = 0;
  std::vector<int> top_own, top_pos; ///< this rank's top unknowns (its rows) and their positions in the top
  SerialComm one;                    ///< the ranks of a single-precision top on rank 0 alone
};

} // namespace hssbem
