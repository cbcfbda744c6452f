/// \file rank_stats.hpp
/// Per-level rank statistics of nested bases, filled the same way for every compressed format
/// (HssLevelStats, H2LevelStats: any type with clusters, max_row_rank, max_col_rank,
/// mean_row_rank and mean_col_rank members).
#pragma once

#include "hssbem/compress/nested_basis.hpp"

#include <algorithm>
#include <vector>

namespace hssbem {

/// Count one more cluster in a level's rank statistics (Level: clusters, max_row_rank,
/// max_col_rank, mean_row_rank, mean_col_rank; the means hold sums until finish_level_means).
template <class Level>
void add_level_ranks(Level &s, int kr, int kc)
{
  s.clusters += 1;
  s.max_row_rank = std::max(s.max_row_rank, kr);
  s.max_col_rank = std::max(s.max_col_rank, kc);
  s.mean_row_rank += kr;
  s.mean_col_rank += kc;
}

/// Turn the rank sums of add_level_ranks into means.
template <class Level>
void finish_level_means(std::vector<Level> &levels)
{
  for (Level &s : levels)
    if (s.clusters > 0) {
      s.mean_row_rank /= s.clusters;
      s.mean_col_rank /= s.clusters;
    }
}

/// The same from a nested basis.
template <class Level>
void add_level_ranks(Level &s, const NestedBasis &b)
{
  add_level_ranks(s, static_cast<int>(b.row_skel.size()), static_cast<int>(b.col_skel.size()));
}

/// Largest row (rows = true) or column rank over per-level statistics (any type with
/// max_row_rank and max_col_rank members).
template <class Level>
int max_level_rank(const std::vector<Level> &levels, bool rows)
{
  int r = 0;
  for (const Level &l : levels) r = std::max(r, rows ? l.max_row_rank : l.max_col_rank);
  return r;
}

} // namespace hssbem
