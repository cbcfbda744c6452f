// The one-rank RankComm (see rank_comm.hpp).
#include "hssbem/core/rank_comm.hpp"

namespace hssbem {

std::vector<int> SerialComm::allgather(const std::vector<int> &mine, std::vector<int> &counts) const
{
  counts.assign(1, static_cast<int>(mine.size()));
  return mine;
}

std::vector<std::vector<int>> SerialComm::exchange(const std::vector<std::vector<int>> &send) const { return send; }

void SerialComm::exchange(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) const { recv = send; }

} // namespace hssbem
