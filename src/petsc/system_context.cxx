/* The system context, the layout of a distributed system and the guard (see system_context.hpp). */
#include "system_context.hpp"

#include "hssbem/petsc/log.h"
#include "hssbem/petsc/pc_h2.h"
#include "hssbem/petsc/pc_hss.h"
#include "hssbem/petsc/system.h"
#include "hssbem/bem/rigid_modes.hpp"

#include <optional>

PetscErrorCode HssbemLayoutCreate(MPI_Comm comm, const hssbem::BemOperator &op, std::unique_ptr<HssbemLayout> *layout)
{
  const PetscInt nn = op.num_nodes();
  PetscMPIInt    rank, size;
  HssbemGuard    guard;
  double         figures[7] = {0, 0, 0, 0, 0, 0, 0};
  MPI_Comm       dup;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscLogEventBegin(BEM_Partition, 0, 0, 0, 0));
  /* The engines' own communicator, duplicated on every rank before anything can fail on one. */
  PetscCallMPI(MPI_Comm_dup(comm, &dup));
  guard.Run([&] {
    std::unique_ptr<HssbemLayout> L;
    try {
      L       = std::make_unique<HssbemLayout>();
      L->comm = std::make_unique<HssbemMpiComm>(dup, true);
    } catch (...) {
      MPI_Comm_free(&dup); /* not adopted */
      throw;
    }
    *layout = std::move(L);
    hssbem::fault_point("Partition");
    HssbemLayout &l = **layout;
    l.node_part.resize((std::size_t)nn);
    if (rank != 0) return;
    l.node_part                        = hssbem::partition_nodes(op.discretization(), size, &l.partition);
    const hssbem::NodePartitionStats &s = l.partition;
    const double f[7] = {(double)s.parts, (double)s.edge_cut, (double)s.edges, s.imbalance, (double)s.min_nodes, (double)s.max_nodes, (double)s.disconnected_parts};
    std::copy(f, f + 7, figures);
  });
  PetscCall(guard.Check(comm, "the partition of the surface failed"));
  HssbemLayout &l = **layout;
  PetscCallMPI(MPI_Bcast(l.node_part.data(), (PetscMPIInt)nn, MPI_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(figures, 7, MPI_DOUBLE, 0, comm));
  l.partition = hssbem::NodePartitionStats{(int)figures[0], (long)figures[1], (long)figures[2], figures[3], (int)figures[4], (int)figures[5], (int)figures[6]};
  PetscCall(PetscLogEventEnd(BEM_Partition, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

std::vector<PetscInt> HssbemSystemRows(const hssbem::ClusterTree &tree)
{
  const std::size_t     n = 3 * (std::size_t)tree.num_points();
  std::vector<PetscInt> rows(n);
  for (std::size_t d = 0; d < n; ++d) rows[d] = 3 * (PetscInt)tree.iperm()[d / 3] + (PetscInt)(d % 3);
  return rows;
}

static PetscErrorCode SystemContextDestroy_Private(void *ctx)
{
  PetscFunctionBegin;
  delete static_cast<HssbemSystemContext *>(ctx);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemMatComposeSystemContext(Mat A, HssbemSystemContext *ctx)
{
  PetscContainer c;

  PetscFunctionBegin;
  PetscCall(PetscContainerCreate(PetscObjectComm((PetscObject)A), &c));
  PetscCall(PetscContainerSetPointer(c, ctx));
  PetscCall(PetscContainerSetUserDestroy(c, SystemContextDestroy_Private));
  PetscCall(PetscObjectCompose((PetscObject)A, "HssbemSystemContext", (PetscObject)c));
  PetscCall(PetscContainerDestroy(&c));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemMatGetSystemContext(Mat A, HssbemSystemContext **ctx)
{
  PetscContainer c = NULL;

  PetscFunctionBegin;
  *ctx = NULL;
  PetscCall(PetscObjectQuery((PetscObject)A, "HssbemSystemContext", (PetscObject *)&c));
  if (c) PetscCall(PetscContainerGetPointer(c, (void **)ctx));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemOperatorTypeFromName(MPI_Comm comm, const char *mat_type, hssbem::OperatorType *type)
{
  PetscFunctionBegin;
  const std::optional<hssbem::OperatorType> t = hssbem::parse_operator_type(mat_type ? mat_type : "");
  PetscCheck(t, comm, PETSC_ERR_ARG_UNKNOWN_TYPE, "unknown BEM matrix type '%s': use %s, %s or %s", mat_type, HSSBEM_MAT_HSS, HSSBEM_MAT_H2, HSSBEM_MAT_DENSE);
  *type = *t;
  PetscFunctionReturn(PETSC_SUCCESS);
}

const char *HssbemDefaultPCType(hssbem::OperatorType type) { return type == hssbem::OperatorType::Hss ? PCHSS : type == hssbem::OperatorType::H2 ? PCH2 : PCLU; }

PetscErrorCode HssbemOwnedNodes(MPI_Comm comm, PetscInt nnodes, PetscInt *nstart, PetscInt *nlocal)
{
  PetscInt n = PETSC_DECIDE, N = nnodes;

  PetscFunctionBegin;
  PetscCall(PetscSplitOwnership(comm, &n, &N));
  PetscCallMPI(MPI_Scan(&n, nstart, 1, MPIU_INT, MPI_SUM, comm));
  *nstart -= n;
  *nlocal = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemRowScatterCreate(Vec x, Vec y, const std::vector<PetscInt> &map, VecScatter *sc)
{
  PetscInt lo, hi;
  IS       from, to;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(x, &lo, &hi));
  PetscCall(ISCreateStride(PetscObjectComm((PetscObject)x), hi - lo, lo, 1, &from));
  if (map.empty()) PetscCall(ISDuplicate(from, &to)); /* the same global rows */
  else PetscCall(ISCreateGeneral(PetscObjectComm((PetscObject)x), hi - lo, map.data() + lo, PETSC_COPY_VALUES, &to));
  PetscCall(VecScatterCreate(x, from, y, to, sc));
  PetscCall(ISDestroy(&from));
  PetscCall(ISDestroy(&to));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemRowScatterOnce(Vec x, Vec y, const std::vector<PetscInt> &map, ScatterMode mode)
{
  const bool forward = mode == SCATTER_FORWARD;
  VecScatter sc;

  PetscFunctionBegin;
  PetscCall(HssbemRowScatterCreate(x, y, map, &sc));
  PetscCall(VecScatterBegin(sc, forward ? x : y, forward ? y : x, INSERT_VALUES, mode));
  PetscCall(VecScatterEnd(sc, forward ? x : y, forward ? y : x, INSERT_VALUES, mode));
  PetscCall(VecScatterDestroy(&sc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The rigid modes of local row i of the distributed system s: its mesh-order dof's row of Q. */
static const double *ModesOfRow_Private(const hssbem::DistributedBemSystem &s, const std::vector<double> &modes, int i)
{
  return &modes[6 * (3 * (std::size_t)s.tree().perm()[s.first_point() + i / 3] + (std::size_t)(i % 3))];
}

void HssbemAddRegularization(const hssbem::DistributedBemSystem &s, const hssbem::RankComm &comm, const std::vector<double> &modes, const PetscScalar *x, PetscScalar *y)
{
  const int n = 3 * s.num_points();
  double    qx[6] = {0, 0, 0, 0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const double *q = ModesOfRow_Private(s, modes, i);
    for (int m = 0; m < 6; ++m) qx[m] += q[m] * x[i];
  }
  comm.sum(qx, 6);
  for (int m = 0; m < 6; ++m) qx[m] *= hssbem::rigid_regularization_weight;
  for (int i = 0; i < n; ++i) {
    const double *q = ModesOfRow_Private(s, modes, i);
    for (int m = 0; m < 6; ++m) y[i] += q[m] * qx[m];
  }
}

void HssbemAddRegularizationDiagonal(const hssbem::DistributedBemSystem &s, const std::vector<double> &modes, PetscScalar *diag)
{
  const int n = 3 * s.num_points();
  for (int i = 0; i < n; ++i) {
    const double *q = ModesOfRow_Private(s, modes, i);
    diag[i] += hssbem::rigid_regularization_weight * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] + q[4] * q[4] + q[5] * q[5]);
  }
}

PetscErrorCode HssbemAgreeOnError(MPI_Comm comm, PetscErrorCode *code, std::string *message, PetscMPIInt *lowest, PetscMPIInt *nfailed)
{
  PetscMPIInt rank, size, key, failed = *code ? 1 : 0;
  int         head[2] = {(int)*code, 0};

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  key = failed ? rank : size;
  PetscCallMPI(MPI_Allreduce(&key, lowest, 1, MPI_INT, MPI_MIN, comm));
  PetscCallMPI(MPI_Allreduce(&failed, nfailed, 1, MPI_INT, MPI_SUM, comm));
  if (*lowest == size) {
    *lowest = -1;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  if (rank == *lowest) head[1] = (int)message->size();
  PetscCallMPI(MPI_Bcast(head, 2, MPI_INT, *lowest, comm));
  *code = (PetscErrorCode)head[0];
  PetscCallCXX(message->resize((size_t)head[1]));
  if (head[1] > 0) PetscCallMPI(MPI_Bcast(&(*message)[0], head[1], MPI_CHAR, *lowest, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

void HssbemGuard::Fail(PetscErrorCode code, const char *message) noexcept
{
  m_code = code;
  try {
    m_message = message ? message : "out of memory";
  } catch (...) {
    m_code = PETSC_ERR_MEM; /* the message itself did not fit: say what is sure */
    m_message.clear();
  }
}

PetscErrorCode HssbemGuard::Check(MPI_Comm comm, const char *what)
{
  PetscMPIInt lowest, nfailed, size;

  PetscFunctionBegin;
  PetscCall(HssbemAgreeOnError(comm, &m_code, &m_message, &lowest, &nfailed));
  if (lowest < 0) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCallMPI(MPI_Comm_size(comm, &size));
  const std::string where = nfailed < size ? " (on rank " + std::to_string(lowest) + ")" : "";
  SETERRQ(comm, m_code, "%s: %s%s", what, m_message.empty() ? "out of memory" : m_message.c_str(), where.c_str());
}
