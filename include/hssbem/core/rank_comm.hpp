/// \file rank_comm.hpp
/// The collective operations a distributed engine needs from the ranks that share it (one per
/// MPI rank; the PETSc layer implements it on an MPI communicator, petsc/mpi_comm.h), so that the
/// plain C++ layers stay free of MPI. SerialComm is the one-rank case.
///
/// Every call is collective: all ranks make it, in the same order. A failure on one rank must
/// never leave the others waiting in a collective call it will not make. The rule that ensures
/// it: every function that makes collective calls is *failure-atomic* — it returns on every rank
/// or throws on every rank. The calls of RankComm are (its MPI implementation agrees internally
/// wherever it allocates between two MPI steps), and so is `collectively(comm, fn)`, the
/// agreement: it runs fn, a rank's local work that may fail (allocations, size checks, a
/// breakdown), then agrees with the other ranks on whether any failed. A distributed algorithm
/// is then a sequence of collective calls with all the local work between them inside
/// `collectively()`; nothing that can throw stands outside one.
#pragma once

#include <cstddef>
#include <exception>
#include <memory>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
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

/// Every call is collective and failure-atomic (see the file's notes): it returns on every rank or
/// throws on every rank, whatever it allocates.
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
  /// what q sends) is filled from rank q. Empty buffers are not sent. Counted in traffic(). Each
  /// buffer holds at most kMaxMessage values: the callers check it (message_count()) inside the
  /// agreement that prepares the buffers, as this call allocates nothing and agrees on nothing.
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
  /// interchanges, the same on every rank. Returns getrf's info, the same on every rank. Each
  /// rank's local array holds at most kMaxMessage entries (check_spread_size(), ScaLAPACK's
  /// 32-bit local indexing), checked by the caller's agreement.
  virtual int spread_getrf(int n, int nb, float *local, int *ipiv) const;

  const CommTraffic &traffic() const { return m_traffic; }

protected:
  mutable CommTraffic m_traffic;
};

/// How many of n columns in blocks of nb fall to `rank` of `ranks` (block j on rank j mod ranks).
int spread_columns(int n, int nb, int rank, int ranks);

/// The most values one message (and one rank's local array of a spread LU) may hold: MPI counts,
/// BLACS/ScaLAPACK local indices and the descriptors are 32-bit integers.
constexpr long long kMaxMessage = 2147483647;

/// `values` as an MPI count; std::length_error naming `what` (e.g. "rank 1's rows of the top")
/// beyond kMaxMessage.
int message_count(std::size_t values, const std::string &what);

/// Throws std::length_error when a spread LU of n unknowns in blocks of nb over `ranks` ranks
/// would give some rank more than kMaxMessage local entries (n × its columns: on 2 ranks from
/// n = 65 536 on).
void check_spread_size(long long n, int nb, int ranks);

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

namespace detail {

/// The agreement's collective step: the worst of the ranks' outcomes (0 done, 1 a soft failure,
/// 2 any other failure).
int worst_outcome(const RankComm &comm, int mine);
/// The message of the lowest rank with `mine` set, on every rank (collective).
std::string lowest_message(const RankComm &comm, bool mine, const std::string &message);

/// Whether e is a Soft (never with Soft = void); its message in *message.
template <class Soft>
bool is_soft(const std::exception_ptr &e, std::string *message)
{
  if constexpr (std::is_void_v<Soft>) {
    (void)e, (void)message;
    return false;
  } else {
    try {
      std::rethrow_exception(e);
    } catch (const Soft &s) {
      *message = s.what();
      return true;
    } catch (...) {
      return false;
    }
  }
}

} // namespace detail

/// The agreement. Run fn on this rank (its local work before the next collective call) and
/// agree with the others: when fn threw on any rank, every rank throws (the failing ranks their
/// own exception, the others PeerFault); otherwise every rank returns fn's result.
///
/// With Soft (collectively<H2Breakdown>(comm, fn)): a failure of type Soft is one every rank must
/// see as such (a factorization's breakdown, which a PC reports as a failed set-up rather than an
/// error). When some rank threw Soft and none failed otherwise, every rank throws Soft with the
/// message of the lowest rank that threw it; another failure on any rank wins as above.
template <class Soft = void, class Fn>
auto collectively(const RankComm &comm, Fn &&fn) -> decltype(fn())
{
  using Result = decltype(fn());
  std::exception_ptr err;
  std::conditional_t<std::is_void_v<Result>, char, std::optional<Result>> out{};
  try {
    if constexpr (std::is_void_v<Result>) fn();
    else out.emplace(fn());
  } catch (...) {
    err = std::current_exception();
  }
  std::string message;
  const bool soft = err && detail::is_soft<Soft>(err, &message);
  const int worst = detail::worst_outcome(comm, !err ? 0 : soft ? 1 : 2);
  if (worst == 2 || (std::is_void_v<Soft> && worst == 1)) {
    if (err && !soft) std::rethrow_exception(err);
    throw PeerFault();
  }
  if constexpr (!std::is_void_v<Soft>) {
    if (worst == 1) throw Soft(detail::lowest_message(comm, soft, message));
  }
  if constexpr (!std::is_void_v<Result>) return std::move(*out);
}

/// A T built by a collective (failure-atomic) constructor, in a shared_ptr: the storage comes
/// first, in an agreement, so that no rank misses the construction for want of memory.
template <class T, class... Args>
std::shared_ptr<T> make_shared_collectively(const RankComm &comm, Args &&...args)
{
  const std::shared_ptr<std::optional<T>> slot = collectively(comm, [] { return std::make_shared<std::optional<T>>(); });
  slot->emplace(std::forward<Args>(args)...);
  return std::shared_ptr<T>(slot, &**slot); // sharing the slot's ownership: no allocation
}

/// The same in a unique_ptr (its storage, from the global operator new, agreed first).
template <class T, class... Args>
std::unique_ptr<T> make_unique_collectively(const RankComm &comm, Args &&...args)
{
  // The storage is owned from the start: when another rank fails the agreement (PeerFault here)
  // or T's constructor throws, it is released on the way out.
  using Storage = std::unique_ptr<void, void (*)(void *)>;
  Storage storage = collectively(comm, [] { return Storage(::operator new(sizeof(T)), [](void *p) { ::operator delete(p); }); });
  T *object = new (storage.get()) T(std::forward<Args>(args)...);
  storage.release();
  return std::unique_ptr<T>(object);
}

} // namespace hssbem
