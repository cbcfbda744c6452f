/// \file cluster_exchange.hpp
/// Per-cluster blocks sent between the ranks of a distributed tree (RankComm, rank_comm.hpp):
/// the exchanges of the distributed products (H² and HSS: moments up, potentials down) and of the
/// distributed HSS factorization and truncation (the parts' roots to rank 0 and back).
///
/// ClusterExchange is planned once (who sends which clusters' blocks to whom) and run per
/// product, with sizes both sides know. exchange_values() carries records whose sizes only the
/// sender knows (two rounds: the sizes, then the values), written with append_matrix() and read
/// with read_matrix().
#pragma once

#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/core/rank_comm.hpp"

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace hssbem {

class ClusterExchange {
public:
  ClusterExchange() = default;
  /// Collective: need[q] lists the clusters whose blocks this rank receives from rank q; the
  /// ranks learn from it what they send. comm must outlive this object.
  ClusterExchange(const RankComm &comm, std::vector<std::vector<int>> need);

  /// Per rank: the clusters whose blocks go there, and those that come from there (ascending).
  const std::vector<std::vector<int>> &sends() const { return m_send; }
  const std::vector<std::vector<int>> &receives() const { return m_recv; }

  /// Collective (failure-atomic): send blocks[c] (rows(c) × nrhs each, rows(c) known on both
  /// sides) along the plan; a received block replaces the local one, or is added to it (add, when
  /// the local one has that shape already). Throws std::logic_error for a block to send of the
  /// wrong shape, std::length_error for a message beyond 32-bit counts.
  template <class Rows>
  void run(std::vector<DenseMatrix> &blocks, int nrhs, bool add, const Rows &rows) const;

private:
  const RankComm *m_comm = nullptr;
  std::vector<std::vector<int>> m_send, m_recv;
};

/// Collective (failure-atomic): send[q] goes to rank q, and the result's entry q is what rank q
/// sent here, of any length (empty lists are not sent, but the lengths cross in one round
/// first); `what` names the records in the error for one beyond 32-bit counts. A fault site,
/// "Exchange", fails the allocation of what arrives.
std::vector<std::vector<double>> exchange_values(const RankComm &comm, const std::vector<std::vector<double>> &send, const char *what = "exchange");

/// One round of records of any length between the ranks (exchange_values), failure-atomic:
/// write(send) fills this rank's records (send[q] for rank q, P lists ready), read(recv) takes
/// what came (recv[q] from rank q), each in an agreement.
template <class Write, class Read>
void exchange_records(const RankComm &comm, const char *what, Write &&write, Read &&read)
{
  std::vector<std::vector<double>> send;
  collectively(comm, [&] {
    send.resize(comm.size());
    write(send);
  });
  std::vector<std::vector<double>> recv = exchange_values(comm, send, what);
  collectively(comm, [&] {
    std::vector<std::vector<double>>().swap(send);
    read(recv);
  });
}

/// M appended to a record: its size, then its entries.
void append_matrix(std::vector<double> &record, const DenseMatrix &M);
/// The matrix at record[at], at moved past it. Throws std::logic_error past the record's end.
DenseMatrix read_matrix(const std::vector<double> &record, std::size_t &at);

template <class Rows>
void ClusterExchange::run(std::vector<DenseMatrix> &blocks, int nrhs, bool add, const Rows &rows) const
{
  if (!m_comm) return;
  const int P = m_comm->size();
  std::vector<std::vector<double>> send, recv;
  collectively(*m_comm, [&] {
    send.resize(P);
    recv.resize(P);
    for (int q = 0; q < P; ++q) {
      std::size_t out = 0, in = 0;
      for (int c : m_send[q]) {
        if (blocks[c].m != rows(c) || blocks[c].n != nrhs) throw std::logic_error("cluster exchange: a block to send is missing");
        out += blocks[c].a.size();
      }
      for (int c : m_recv[q]) in += static_cast<std::size_t>(rows(c)) * nrhs;
      message_count(out, "cluster exchange");
      message_count(in, "cluster exchange");
      send[q].reserve(out);
      for (int c : m_send[q]) send[q].insert(send[q].end(), blocks[c].a.begin(), blocks[c].a.end());
      recv[q].resize(in);
    }
  });
  m_comm->exchange(send, recv);
  collectively(*m_comm, [&] {
    for (int q = 0; q < P; ++q) {
      std::size_t at = 0;
      for (int c : m_recv[q]) {
        const std::size_t n = static_cast<std::size_t>(rows(c)) * nrhs;
        if (add && blocks[c].m == rows(c) && blocks[c].n == nrhs) {
          for (std::size_t k = 0; k < n; ++k) blocks[c].a[k] += recv[q][at + k];
        } else {
          blocks[c] = DenseMatrix(rows(c), nrhs);
          std::copy(recv[q].begin() + static_cast<long>(at), recv[q].begin() + static_cast<long>(at + n), blocks[c].a.begin());
        }
        at += n;
      }
    }
  });
}

} // namespace hssbem
