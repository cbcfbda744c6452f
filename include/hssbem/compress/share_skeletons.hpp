/// \file share_skeletons.hpp
/// The skeleton index lists of a distributed compression shared by every rank (HSS and H²): each
/// rank skeletonizes its own clusters, and every rank must know every skeleton (the next level's
/// candidates and the couplings or far blocks between skeletons are made of them).
#pragma once

#include "hssbem/compress/nested_basis.hpp"
#include "hssbem/core/rank_comm.hpp"

#include <functional>
#include <vector>

namespace hssbem {

/// Collective: the row (columns = false) or column skeletons and forced counts of the listed
/// clusters that this rank holds go to every rank, and each rank writes the others' into
/// bases[c] (row_skel and row_forced, or col_skel and col_forced). Interpolation matrices stay.
void share_skeletons(const std::vector<int> &clusters, const std::vector<NestedBasis *> &bases, const std::function<bool(int)> &holds, const RankComm &comm,
                     bool columns);

} // namespace hssbem
