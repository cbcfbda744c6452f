// The one-rank RankComm (see rank_comm.hpp).
#include "hssbem/core/rank_comm.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>

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

} // namespace hssbem
