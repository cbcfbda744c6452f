/// \file rank_comm.hpp
/// The collective operations a distributed engine needs from the ranks that share it (one per
/// MPI rank; the PETSc layer implements it on an MPI communicator, petsc/mpi_comm.h), so that the
/// plain C++ layers stay free of MPI. SerialComm is the one-rank case.
///
/// Every call is collective: all ranks make it, in the same order. A fault on one rank inside a
/// collective phase must not leave the others waiting: run the rank's work through
/// `collectively()`, which agrees on failure before the next collective call.
#pragma once

#include <exception>
#include <stdexcept>
#include <vector>

namespace hssbem {

/// Thrown on the ranks that did not fail when another rank failed inside `collectively()`: the
/// host reports the failing rank's own error, not this.
struct PeerFault : std::runtime_error {
  PeerFault() : std::runtime_error("another rank failed") {}
};

/// Bytes and messages this rank sent through exchange() (the per-product traffic is the change
/// across one product).
struct CommTraffic {
  long long bytes = 0, messages = 0;
};

class RankComm {
public:
  virtual ~RankComm() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  /// Every rank's `mine`, concatenated in rank order; counts[q] receives rank q's length.
  virtual std::vector<int> allgather(const std::vector<int> &mine, std::vector<int> &counts) const = 0;
  /// Point to point, sizes unknown to the receiver: send[q] goes to rank q; returns what each
  /// rank sent here (index = sender). Empty lists are not sent.
  virtual std::vector<std::vector<int>> exchange(const std::vector<std::vector<int>> &send) const = 0;
  /// Point to point with sizes both sides know: send[q] goes to rank q, recv[q] (already sized to
  /// what q sends) is filled from rank q. Empty buffers are not sent. Counted in traffic().
  virtual void exchange(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) const = 0;
  /// Whether `mine` is true on any rank.
  virtual bool any(bool mine) const = 0;
  /// Element-wise sum (in place) and maximum over the ranks.
  virtual void sum(double *v, int n) const = 0;
  virtual double max(double v) const = 0;
  /// LU with partial pivoting (getrf) of an n × n single-precision matrix spread over the ranks
  /// by blocks of nb columns, block j on rank j mod size() (ScaLAPACK's 1 × P process grid):
  /// `local` holds this rank's columns in order, n × spread_columns(n, nb) column-major. On
  /// return it holds their part of the factors, and ipiv (n entries, 1-based) the row
  /// interchanges, the same on every rank. Returns getrf's info, the same on every rank.
  virtual int spread_getrf(int n, int nb, float *local, int *ipiv) const;

  const CommTraffic &traffic() const { return m_traffic; }

protected:
  mutable CommTraffic m_traffic;
};

/// How many of n columns in blocks of nb fall to `rank` of `ranks` (block j on rank j mod ranks).
int spread_columns(int n, int nb, int rank, int ranks);

/// One rank: every collective is the identity.
class SerialComm : public RankComm {
public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  std::vector<int> allgather(const std::vector<int> &mine, std::vector<int> &counts) const override;
  std::vector<std::vector<int>> exchange(const std::vector<std::vector<int>> &send) const override;
  void exchange(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) const override;
  bool any(bool mine) const override { return mine; }
  void sum(double *, int) const override {}
  double max(double v) const override { return v; }
};

/// Run fn on this rank, then agree with the others: when fn threw on any rank, every rank
/// throws (the failing ranks their own exception, the others PeerFault); otherwise none does.
template <class Fn>
void collectively(const RankComm &comm, Fn &&fn)
{
  std::exception_ptr err;
  try {
    fn();
  } catch (...) {
    err = std::current_exception();
  }
  const bool failed = comm.any(err != nullptr);
  if (err) std::rethrow_exception(err);
  if (failed) throw PeerFault();
}

} // namespace hssbem
