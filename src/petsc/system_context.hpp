/* Private to the PETSc layer: the BEM system behind a matrix of HssbemCreateSystem(), composed
   with the Mat so that its MatShell operations and the PCs find the operator, the pattern and the
   compression; the layout of a distributed system; and the one guard of C++ work inside PETSc
   functions. Implemented in system_context.cxx; nothing here calls into the files that use it. */
#pragma once

#include "hssbem/petsc/compat.h"
#include "hssbem/petsc/errors.h"

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/node_partition.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/operator_type.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/hss/hss_system.hpp"
#include "hssbem/petsc/mpi_comm.h"

#include <petscmat.h>

#include <exception>
#include <functional>
#include <memory>
#include <new>
#include <string>
#include <vector>

/* How a distributed system lies on the ranks of a communicator (one rank is one part): the
   engines' communicator (a duplicate), the METIS partition (part of each dof node, on every rank)
   and its figures. */
struct HssbemLayout {
  std::unique_ptr<HssbemMpiComm> comm;
  std::vector<int>               node_part;
  hssbem::NodePartitionStats     partition;
};

/* The layout of a system of op on comm: METIS on rank 0 (one rank: one part), broadcast (log
   event BEMPartition, fault site Partition). Collective. */
PetscErrorCode HssbemLayoutCreate(MPI_Comm comm, const hssbem::BemOperator &op, std::unique_ptr<HssbemLayout> *layout);

/* The global row of each mesh-order dof (3 per node) of a distributed system on `tree`: its rows
   are in cluster order, rank p's block holding part p's nodes. */
std::vector<PetscInt> HssbemSystemRows(const hssbem::ClusterTree &tree);

struct HssbemSystemContext {
  const hssbem::BemOperator *op = nullptr;
  hssbem::SystemSelection    sel;
  std::vector<double>        modes; /* rigid modes (3N × 6, row-major) of the regularisation; empty: none */
  hssbem::OperatorType       type = hssbem::OperatorType::Dense;
  hssbem::HssOptions         hss_options; /* of the compression below */
  hssbem::H2Options          h2_options;  /* of the compression below */
  /* H² or HSS (any number of ranks): the layout (declared first, so that its communicator
     outlives the system), the matrix distributed over it (every rank its part), and the row of
     each mesh-order dof (empty: mesh order, the dense system). */
  std::unique_ptr<HssbemLayout>                       layout;
  std::shared_ptr<const hssbem::H2DistributedSystem>  h2;
  std::shared_ptr<const hssbem::HssDistributedSystem> hss;
  std::vector<PetscInt>                               system_of_dof;
  /* HssbemSystemOptions::h2_source: the H² matrix loaded instead of compressed (null: compress). */
  std::function<std::shared_ptr<const hssbem::H2DistributedSystem>(const std::vector<int> &, const hssbem::RankComm &)> h2_source;

  /* The distributed operator behind a MatShell, or NULL (dense). */
  const hssbem::DistributedBemSystem *distributed() const
  {
    if (h2) return h2.get();
    return hss.get();
  }
};

/* Compose the system context with A, which owns it from then on. */
PetscErrorCode HssbemMatComposeSystemContext(Mat A, HssbemSystemContext *ctx);
/* The system composed with A, or NULL when A did not come from HssbemCreateSystem(). */
PetscErrorCode HssbemMatGetSystemContext(Mat A, HssbemSystemContext **ctx);

/* The operator type named mat_type (HSSBEM_MAT_*); an error on comm for any other name. */
PetscErrorCode HssbemOperatorTypeFromName(MPI_Comm comm, const char *mat_type, hssbem::OperatorType *type);

/* The main solver's default PC for an operator type (PCHSS, PCH2 for H² on any number of ranks,
   PCLU for dense). */
const char *HssbemDefaultPCType(hssbem::OperatorType type);

/* Dof nodes owned by this rank: a contiguous block [nstart, nstart + nlocal), 3 rows each. */
PetscErrorCode HssbemOwnedNodes(MPI_Comm comm, PetscInt nnodes, PetscInt *nstart, PetscInt *nlocal);

/* The scatter from vectors like x to vectors like y that puts x's entry r at y's map[r] (x in mesh
   order and y in a distributed system's rows: map = its rows, y[map[d]] being dof d); an empty
   map: at y's entry r (the same global row in another layout). */
PetscErrorCode HssbemRowScatterCreate(Vec x, Vec y, const std::vector<PetscInt> &map, VecScatter *sc);
/* That scatter once: y from x (SCATTER_FORWARD), or x from y (SCATTER_REVERSE). */
PetscErrorCode HssbemRowScatterOnce(Vec x, Vec y, const std::vector<PetscInt> &map, ScatterMode mode);

/* y += c Q (Qᵀ x) for the rigid-mode regularisation (modes: Q, 3N × 6 row-major, mesh order) on
   this rank's rows of the distributed system s (Qᵀ x summed over its ranks, comm); and
   diag[i] += c |Q(row i, :)|². */
void HssbemAddRegularization(const hssbem::DistributedBemSystem &s, const hssbem::RankComm &comm, const std::vector<double> &modes, const PetscScalar *x, PetscScalar *y);
void HssbemAddRegularizationDiagonal(const hssbem::DistributedBemSystem &s, const std::vector<double> &modes, PetscScalar *diag);

/* The one guard of C++ work inside a PETSc function or callback (MatMult, MatGetDiagonal, PCSetUp,
   PCApply, the assembly, ...), on any number of ranks. Run() calls fn on this rank (every rank,
   or only those that have work) and keeps what it throws, std::bad_alloc included, instead of
   letting it cross PETSc; `site` names a fault point (core/fault.hpp) armed by tests. Check(),
   collective and called after the collective steps every rank takes anyway (the scatter of a
   product, say), raises the error of the lowest failing rank on every rank of comm, as
   PETSC_ERR_MEM for an allocation failure and PETSC_ERR_LIB otherwise, with the message
   "<what>: <message>": no rank is left waiting for one that has left. */
class HssbemGuard {
public:
  template <class Fn>
  void Run(const char *site, Fn &&fn) noexcept
  {
    try {
      if (site) hssbem::fault_point(site);
      fn();
    } catch (const hssbem::PeerFault &) {
      /* another rank failed inside a collective step: Check() reports that rank's error */
    } catch (const std::bad_alloc &) {
      Fail(PETSC_ERR_MEM, nullptr);
    } catch (const std::exception &e) {
      Fail(PETSC_ERR_LIB, e.what());
    } catch (...) {
      Fail(PETSC_ERR_LIB, "unknown exception");
    }
  }
  template <class Fn>
  void Run(Fn &&fn) noexcept
  {
    Run(nullptr, fn);
  }
  PetscErrorCode Check(MPI_Comm comm, const char *what);

private:
  void Fail(PetscErrorCode code, const char *message) noexcept;

  PetscErrorCode m_code = 0;
  std::string    m_message;
};
