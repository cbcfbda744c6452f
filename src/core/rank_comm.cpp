// The one-rank RankComm (see rank_comm.hpp).
#include "hssbem/core/rank_comm.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cstdio>

namespace hssbem {

std::vector<int> SerialComm::allgather(const std::vector<int> &mine, std::vector<int> &counts) const
{
  counts.assign(1, static_cast<int>(mine.size()));
  return mine;
}

std::vector<std::vector<int>> SerialComm::exchange(const std::vector<std::vector<int>> &send) const { return send; }

void SerialComm::exchange(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) const { recv = send; }

int spread_columns(int n, int nb, int rank, int ranks)
{
  const int blocks = (n + nb - 1) / nb;
  int count = 0;
  for (int j = rank; j < blocks; j += ranks) count += std::min(nb, n - j * nb);
  return count;
}

int RankComm::spread_getrf(int n, int nb, float *local, int *ipiv) const
{
  if (size() != 1) throw std::logic_error("spread_getrf: no distributed LU on this communicator");
  return lapack::getrf(n, local, n, ipiv);
}

int message_count(std::size_t values, const std::string &what)
{
  if (values > static_cast<std::size_t>(kMaxMessage)) {
    char n[32];
    std::snprintf(n, sizeof n, "%.3g", static_cast<double>(values));
    throw std::length_error(what + ": " + n + " values, more than one message carries (2^31 - 1: MPI counts are 32-bit integers)");
  }
  return static_cast<int>(values);
}

void check_spread_size(long long n, int nb, int ranks)
{
  // Rank 0 holds the most columns (the first block, and one more when they do not divide evenly).
  const long long blocks = (n + nb - 1) / nb, most = std::min<long long>(n, ((blocks + ranks - 1) / ranks) * nb);
  if (n * most > kMaxMessage)
    throw std::length_error("the dense top of " + std::to_string(n) + " unknowns spread over " + std::to_string(ranks) + " ranks: " + std::to_string(n * most) +
                            " entries on rank 0, more than ScaLAPACK's 32-bit local indexing allows (2^31 - 1): use more ranks, or a smaller top (-pc_h2_top_size, -pc_h2_top_when_cheaper)");
}

namespace detail {

int worst_outcome(const RankComm &comm, int mine) { return static_cast<int>(comm.max(static_cast<double>(mine))); }

std::string lowest_message(const RankComm &comm, bool mine, const std::string &message)
{
  const int lowest = static_cast<int>(-comm.max(-static_cast<double>(mine ? comm.rank() : comm.size())));
  std::vector<int> chars, counts;
  collectively(comm, [&] {
    if (comm.rank() == lowest) chars.assign(message.begin(), message.end());
  });
  const std::vector<int> all = comm.allgather(chars, counts);
  return std::string(all.begin(), all.end());
}

} // namespace detail

} // namespace hssbem
