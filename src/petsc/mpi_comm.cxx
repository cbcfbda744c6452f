/* hssbem::RankComm on MPI (see mpi_comm.h). */
#include "hssbem/petsc/mpi_comm.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

void Check(int err, const char *what)
{
  if (err == MPI_SUCCESS) return;
  char msg[MPI_MAX_ERROR_STRING];
  int  len = 0;
  MPI_Error_string(err, msg, &len);
  throw std::runtime_error(std::string(what) + ": " + std::string(msg, (size_t)len));
}

const int tag_ints = 7101, tag_doubles = 7102;

} // namespace

/* BLACS and ScaLAPACK (libscalapack-openmpi), single precision LU. */
extern "C" {
int  Csys2blacs_handle(MPI_Comm comm);
void Cfree_blacs_system_handle(int handle);
void Cblacs_gridinit(int *context, const char *order, int rows, int cols);
void Cblacs_gridinfo(int context, int *rows, int *cols, int *row, int *col);
void Cblacs_gridexit(int context);
void descinit_(int *desc, const int *m, const int *n, const int *mb, const int *nb, const int *irsrc, const int *icsrc, const int *context, const int *lld, int *info);
void psgetrf_(const int *m, const int *n, float *a, const int *ia, const int *ja, const int *desc, int *ipiv, int *info);
}

HssbemMpiComm::HssbemMpiComm(MPI_Comm comm, bool owned) : m_comm(comm), m_owned(owned)
{
  Check(MPI_Comm_rank(comm, &m_rank), "MPI_Comm_rank");
  Check(MPI_Comm_size(comm, &m_size), "MPI_Comm_size");
  m_req.reserve(2 * (std::size_t)m_size); /* the exchanges' requests: never allocated between two MPI steps */
}

HssbemMpiComm::~HssbemMpiComm()
{
  if (m_owned) MPI_Comm_free(&m_comm);
}

void HssbemMpiComm::Post(void *buf, int count, MPI_Datatype type, int peer, int tag, bool receive) const
{
  m_req.emplace_back(); /* within the capacity reserved at construction: 2 per peer */
  if (receive) Check(MPI_Irecv(buf, count, type, peer, tag, m_comm, &m_req.back()), "MPI_Irecv");
  else Check(MPI_Isend(buf, count, type, peer, tag, m_comm, &m_req.back()), "MPI_Isend");
}

void HssbemMpiComm::WaitAll() const
{
  const int err = MPI_Waitall((int)m_req.size(), m_req.data(), MPI_STATUSES_IGNORE);
  m_req.clear();
  Check(err, "MPI_Waitall");
}

std::vector<int> HssbemMpiComm::allgather(const std::vector<int> &mine, std::vector<int> &counts) const
{
  std::vector<int> displs, all;
  const int n = hssbem::collectively(*this, [&] {
    counts.assign(m_size, 0);
    displs.assign(m_size, 0);
    return hssbem::message_count(mine.size(), "allgather");
  });
  Check(MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, m_comm), "MPI_Allgather");
  hssbem::collectively(*this, [&] {
    long long total = 0;
    for (int q = 0; q < m_size; ++q) displs[q] = (int)total, total += counts[q];
    all.resize((std::size_t)hssbem::message_count((std::size_t)total, "allgather"));
  });
  Check(MPI_Allgatherv(mine.data(), n, MPI_INT, all.data(), counts.data(), displs.data(), MPI_INT, m_comm), "MPI_Allgatherv");
  return all;
}

std::vector<std::vector<int>> HssbemMpiComm::exchange(const std::vector<std::vector<int>> &send) const
{
  std::vector<int>              out, in;
  std::vector<std::vector<int>> recv;
  hssbem::collectively(*this, [&] {
    out.resize(m_size);
    in.resize(m_size);
    recv.resize(m_size);
    for (int q = 0; q < m_size; ++q) out[q] = hssbem::message_count(send[q].size(), "exchange");
  });
  Check(MPI_Alltoall(out.data(), 1, MPI_INT, in.data(), 1, MPI_INT, m_comm), "MPI_Alltoall");
  hssbem::collectively(*this, [&] {
    for (int q = 0; q < m_size; ++q) recv[q].resize((size_t)in[q]);
  });
  for (int q = 0; q < m_size; ++q)
    if (in[q] > 0) Post(recv[q].data(), in[q], MPI_INT, q, tag_ints, true);
  for (int q = 0; q < m_size; ++q)
    if (out[q] > 0) Post(const_cast<int *>(send[q].data()), out[q], MPI_INT, q, tag_ints, false);
  WaitAll();
  return recv;
}

void HssbemMpiComm::exchange(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) const
{
  /* No allocation and no agreement: the callers sized recv and checked the counts in theirs. */
  for (int q = 0; q < m_size; ++q)
    if (!recv[q].empty()) Post(recv[q].data(), (int)recv[q].size(), MPI_DOUBLE, q, tag_doubles, true);
  for (int q = 0; q < m_size; ++q)
    if (!send[q].empty()) {
      Post(const_cast<double *>(send[q].data()), (int)send[q].size(), MPI_DOUBLE, q, tag_doubles, false);
      m_traffic.bytes += (long long)(send[q].size() * sizeof(double));
      m_traffic.messages += 1;
    }
  WaitAll();
}

bool HssbemMpiComm::any(bool mine) const
{
  int in = mine ? 1 : 0, out = 0;
  Check(MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_MAX, m_comm), "MPI_Allreduce");
  return out != 0;
}

void HssbemMpiComm::sum(double *v, int n) const { Check(MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_SUM, m_comm), "MPI_Allreduce"); }

int HssbemMpiComm::spread_getrf(int n, int nb, float *local, int *ipiv) const
{
  std::vector<int> piv;
  hssbem::collectively(*this, [&] {
    hssbem::check_spread_size(n, nb, m_size);
    piv.resize((size_t)n + (size_t)nb); /* LOCr(n) + MB */
  });
  if (n == 0) return 0;
  const int handle = Csys2blacs_handle(m_comm);
  int       context = handle, rows = 0, cols = 0, row = -1, col = -1;
  Cblacs_gridinit(&context, "Row", 1, m_size);
  Cblacs_gridinfo(context, &rows, &cols, &row, &col);
  const bool grid_ok = rows == 1 && cols == m_size && col == m_rank;
  int        desc[9], info = 0;
  const int  zero = 0, one = 1, lld = n;
  if (grid_ok) {
    /* Square blocks (psgetrf needs MB = NB); with one process row every row is local. */
    descinit_(desc, &n, &n, &nb, &nb, &zero, &zero, &context, &lld, &info);
    if (info == 0) psgetrf_(&n, &n, local, &one, &one, desc, piv.data(), &info);
  }
  if (row >= 0) Cblacs_gridexit(context);
  Cfree_blacs_system_handle(handle);
  if (any(!grid_ok)) throw std::runtime_error("spread LU: the BLACS grid does not follow the ranks");
  std::copy(piv.begin(), piv.begin() + n, ipiv);
  int worst = info;
  Check(MPI_Allreduce(&info, &worst, 1, MPI_INT, MPI_MAX, m_comm), "MPI_Allreduce");
  return worst != 0 ? (info != 0 ? info : worst) : 0;
}

double HssbemMpiComm::max(double v) const
{
  double out = v;
  Check(MPI_Allreduce(&v, &out, 1, MPI_DOUBLE, MPI_MAX, m_comm), "MPI_Allreduce");
  return out;
}
