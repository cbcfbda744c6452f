/* hssbem::RankComm on an MPI communicator: the collectives of the distributed engines
   (core/rank_comm.hpp). MPI errors throw std::runtime_error. */
#pragma once

#include "hssbem/core/rank_comm.hpp"

#include <mpi.h>

#include <vector>

class HssbemMpiComm : public hssbem::RankComm {
public:
  /* On comm, which this object frees when `owned` (a duplicate the caller made with MPI_Comm_dup
     on every rank, so that its messages never meet the caller's). Not collective: construction
     on some ranks only (an allocation failure) leaves no rank waiting. */
  explicit HssbemMpiComm(MPI_Comm comm, bool owned = false);
  ~HssbemMpiComm() override;
  HssbemMpiComm(const HssbemMpiComm &)            = delete;
  HssbemMpiComm &operator=(const HssbemMpiComm &) = delete;

  MPI_Comm comm() const { return m_comm; }
  int rank() const override { return m_rank; }
  int size() const override { return m_size; }
  std::vector<int> allgather(const std::vector<int> &mine, std::vector<int> &counts) const override;
  std::vector<std::vector<int>> exchange(const std::vector<std::vector<int>> &send) const override;
  void exchange(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) const override;
  bool any(bool mine) const override;
  void sum(double *v, int n) const override;
  double max(double v) const override;
  /* ScaLAPACK's psgetrf on a 1 x size() BLACS grid of this communicator. */
  int spread_getrf(int n, int nb, float *local, int *ipiv) const override;

private:
  /* A point-to-point request into the requests reserved at construction, and their end. */
  void Post(void *buf, int count, MPI_Datatype type, int peer, int tag, bool receive) const;
  void WaitAll() const;

  MPI_Comm                         m_comm;
  bool                             m_owned = false;
  int                              m_rank = 0, m_size = 1;
  mutable std::vector<MPI_Request> m_req;
};
