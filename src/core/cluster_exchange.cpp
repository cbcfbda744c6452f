// Per-cluster blocks between ranks (see cluster_exchange.hpp).
#include "hssbem/core/cluster_exchange.hpp"

#include "hssbem/core/fault.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hssbem {

ClusterExchange::ClusterExchange(const RankComm &comm, std::vector<std::vector<int>> need) : m_comm(&comm), m_recv(std::move(need))
{
  collectively(comm, [&] {
    m_recv.resize(comm.size());
    for (std::vector<int> &v : m_recv) {
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());
    }
  });
  m_send = comm.exchange(m_recv);
}

std::vector<std::vector<double>> exchange_values(const RankComm &comm, const std::vector<std::vector<double>> &send, const char *what)
{
  const int P = comm.size();
  std::vector<std::vector<int>> sizes;
  collectively(comm, [&] {
    sizes.resize(P);
    for (int q = 0; q < P; ++q)
      if (!send[q].empty()) sizes[q] = {message_count(send[q].size(), std::string(what) + " to rank " + std::to_string(q))};
  });
  const std::vector<std::vector<int>> from = comm.exchange(sizes);
  std::vector<std::vector<double>> recv;
  collectively(comm, [&] {
    fault_point("Exchange");
    recv.resize(P);
    for (int q = 0; q < P; ++q)
      if (!from[q].empty()) recv[q].resize(static_cast<std::size_t>(from[q][0]));
  });
  comm.exchange(send, recv);
  return recv;
}

void append_matrix(std::vector<double> &record, const DenseMatrix &M)
{
  record.push_back(M.m);
  record.push_back(M.n);
  record.insert(record.end(), M.a.begin(), M.a.end());
}

DenseMatrix read_matrix(const std::vector<double> &record, std::size_t &at)
{
  if (at + 2 > record.size()) throw std::logic_error("exchange: a truncated record");
  const double m = record[at], n = record[at + 1];
  if (!(m >= 0 && n >= 0 && m == std::floor(m) && n == std::floor(n)) || at + 2 + static_cast<std::size_t>(m) * static_cast<std::size_t>(n) > record.size())
    throw std::logic_error("exchange: a corrupt record");
  DenseMatrix M(static_cast<int>(m), static_cast<int>(n));
  at += 2;
  std::copy(record.begin() + static_cast<long>(at), record.begin() + static_cast<long>(at + M.a.size()), M.a.begin());
  at += M.a.size();
  return M;
}

} // namespace hssbem
