// Skeleton index lists shared by the ranks of a distributed compression (see share_skeletons.hpp).
#include "hssbem/compress/share_skeletons.hpp"

namespace hssbem {

void share_skeletons(const std::vector<int> &clusters, const std::vector<NestedBasis *> &bases, const std::function<bool(int)> &holds, const RankComm &comm,
                     bool columns)
{
  std::vector<int> mine;
  collectively(comm, [&] { // the agreement of a failure-atomic collective (rank_comm.hpp)
    for (int c : clusters) {
      if (!holds(c)) continue;
      const NestedBasis &b = *bases[c];
      const std::vector<int> &skel = columns ? b.col_skel : b.row_skel;
      mine.push_back(c);
      mine.push_back(columns ? b.col_forced : b.row_forced);
      mine.push_back(static_cast<int>(skel.size()));
      mine.insert(mine.end(), skel.begin(), skel.end());
    }
  });
  std::vector<int> counts;
  const std::vector<int> all = comm.allgather(mine, counts);
  collectively(comm, [&] {
    for (std::size_t at = 0; at < all.size();) {
      const int c = all[at], forced = all[at + 1], k = all[at + 2];
      if (!holds(c)) {
        NestedBasis &b = *bases[c];
        (columns ? b.col_skel : b.row_skel).assign(all.begin() + static_cast<long>(at) + 3, all.begin() + static_cast<long>(at) + 3 + k);
        (columns ? b.col_forced : b.row_forced) = forced;
      }
      at += 3 + static_cast<std::size_t>(k);
    }
  });
}

} // namespace hssbem
