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

HssbemMpiComm::HssbemMpiComm(MPI_Comm comm, bool duplicate) : m_comm(comm)
{
  if (duplicate) {
    Check(MPI_Comm_dup(comm, &m_comm), "MPI_Comm_dup");
    m_owned = true;
  }
  Check(MPI_Comm_rank(comm, &m_rank), "MPI_Comm_rank");
  Check(MPI_Comm_size(comm, &m_size), "MPI_Comm_size");
}

HssbemMpiComm::~HssbemMpiComm()
{
  if (m_owned) MPI_Comm_free(&m_comm);
}

std::vector<int> HssbemMpiComm::allgather(const std::vector<int> &mine, std::vector<int> &counts) const
{
  int n = (int)mine.size();
  counts.assign(m_size, 0);
  Check(MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, m_comm), "MPI_Allgather");
  std::vector<int> displs(m_size, 0);
  std::partial_sum(counts.begin(), counts.end() - 1, displs.begin() + 1);
  std::vector<int> all((size_t)(displs.back() + counts.back()));
  Check(MPI_Allgatherv(mine.data(), n, MPI_INT, all.data(), counts.data(), displs.data(), MPI_INT, m_comm), "MPI_Allgatherv");
  return all;
}

std::vector<std::vector<int>> HssbemMpiComm::exchange(const std::vector<std::vector<int>> &send) const
{
  std::vector<int> out(m_size), in(m_size);
  for (int q = 0; q < m_size; ++q) out[q] = (int)send[q].size();
  Check(MPI_Alltoall(out.data(), 1, MPI_INT, in.data(), 1, MPI_INT, m_comm), "MPI_Alltoall");
  std::vector<std::vector<int>> recv(m_size);
  std::vector<MPI_Request>      req;
  for (int q = 0; q < m_size; ++q) {
    recv[q].resize((size_t)in[q]);
    if (in[q] > 0) {
      req.emplace_back();
      Check(MPI_Irecv(recv[q].data(), in[q], MPI_INT, q, tag_ints, m_comm, &req.back()), "MPI_Irecv");
    }
  }
  for (int q = 0; q < m_size; ++q)
    if (out[q] > 0) {
      req.emplace_back();
      Check(MPI_Isend(send[q].data(), out[q], MPI_INT, q, tag_ints, m_comm, &req.back()), "MPI_Isend");
    }
  Check(MPI_Waitall((int)req.size(), req.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  return recv;
}

void HssbemMpiComm::exchange(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) const
{
  std::vector<MPI_Request> req;
  for (int q = 0; q < m_size; ++q)
    if (!recv[q].empty()) {
      req.emplace_back();
      Check(MPI_Irecv(recv[q].data(), (int)recv[q].size(), MPI_DOUBLE, q, tag_doubles, m_comm, &req.back()), "MPI_Irecv");
    }
  for (int q = 0; q < m_size; ++q)
    if (!send[q].empty()) {
      req.emplace_back();
      Check(MPI_Isend(send[q].data(), (int)send[q].size(), MPI_DOUBLE, q, tag_doubles, m_comm, &req.back()), "MPI_Isend");
      m_traffic.bytes += (long long)(send[q].size() * sizeof(double));
      m_traffic.messages += 1;
    }
  Check(MPI_Waitall((int)req.size(), req.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
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
  if (n == 0) return 0;
  const int handle = Csys2blacs_handle(m_comm);
  int       context = handle, rows = 0, cols = 0, row = -1, col = -1;
  Cblacs_gridinit(&context, "Row", 1, m_size);
  Cblacs_gridinfo(context, &rows, &cols, &row, &col);
  if (rows != 1 || cols != m_size || col != m_rank) {
    if (row >= 0) Cblacs_gridexit(context);
    Cfree_blacs_system_handle(handle);
    throw std::runtime_error("spread LU: the BLACS grid does not follow the ranks");
  }
  int       desc[9], info = 0;
  const int zero = 0, one = 1, lld = n;
  // Square blocks (psgetrf needs MB = NB); with one process row every row is local.
  descinit_(desc, &n, &n, &nb, &nb, &zero, &zero, &context, &lld, &info);
  if (info == 0) {
    std::vector<int> piv(static_cast<std::size_t>(n) + nb); // LOCr(n) + MB

    psgetrf_(&n, &n, local, &one, &one, desc, piv.data(), &info);
    std::copy(piv.begin(), piv.begin() + n, ipiv);
  }
  Cblacs_gridexit(context);
  Cfree_blacs_system_handle(handle);
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
