/* Private to the PETSc layer: the BEM system behind a matrix of HssbemCreateSystem(), composed
   with the Mat so that its MatShell operations and PC hss find the operator, the pattern and the
   compression. */
#pragma once

#include "hssbem/petsc/compat.h"
#include "hssbem/petsc/errors.h"

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/operator_type.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/hss/hss_system.hpp"
#include "hssbem/bem/node_partition.hpp"
#include "hssbem/petsc/mpi_comm.h"

#include <petscmat.h>

#include <exception>
#include <memory>
#include <new>
#include <string>
#include <vector>

struct HssbemSystemContext {
  const hssbem::BemOperator *op = nullptr;
  hssbem::SystemSelection    sel;
  std::vector<double>        modes; /* rigid modes (3N × 6, row-major) of the regularisation; empty: none */
  hssbem::OperatorType       type = hssbem::OperatorType::Dense;
  hssbem::HssOptions         hss_options;                 /* of the compression below */
  std::shared_ptr<const hssbem::HssBemSystem> hss;        /* rank 0 only, HSS matrices only */
  hssbem::H2Options          h2_options;                  /* of the compression below */
  std::shared_ptr<const hssbem::H2BemSystem> h2;          /* rank 0 only, H² matrices only: the
                                                             whole matrix (gathered on demand when
                                                             it is distributed) */
  /* H² or HSS on several ranks: the matrix distributed over them (every rank its part), the
     ranks' communicator (a duplicate, declared first so that it outlives the system), the METIS
     partition (part of each dof node, on every rank) and its figures, and the global row of each
     mesh-order dof (3 per node): the system's rows are in cluster order, rank p's block holding
     part p's nodes. */
  std::unique_ptr<HssbemMpiComm>                      comm;
  std::shared_ptr<const hssbem::H2DistributedSystem>  h2dist;
  std::shared_ptr<const hssbem::HssDistributedSystem> hssdist;
  std::vector<int>                                    node_part;
  hssbem::NodePartitionStats                          partition;
  std::vector<PetscInt>                               system_of_dof; /* empty: mesh order */
  bool                                                h2_gathered = false; /* h2 holds the gathered matrix (rank 0) */

  /* The compressed operator behind a MatShell (rank 0), or NULL. */
  const hssbem::CompressedBemSystem *compressed() const
  {
    if (hss) return hss.get();
    return h2.get();
  }
  /* The distributed operator behind a MatShell on several ranks, or NULL. */
  const hssbem::DistributedBemSystem *distributed() const
  {
    if (h2dist) return h2dist.get();
    return hssdist.get();
  }
};

/* The system composed with A, or NULL when A did not come from HssbemCreateSystem(). */
PetscErrorCode HssbemMatGetSystemContext(Mat A, HssbemSystemContext **ctx);

/* The operator type named mat_type (HSSBEM_MAT_*); an error on comm for any other name. */
PetscErrorCode HssbemOperatorTypeFromName(MPI_Comm comm, const char *mat_type, hssbem::OperatorType *type);

/* The main solver's default PC for an operator type on comm (PCHSS, PCH2 for H² on any number of
   ranks, PCLU for dense), and whether the H² operator will be factored by PC h2 (the
   -pc_type of the options database, else that default). */
PetscErrorCode HssbemDefaultPCType(MPI_Comm comm, hssbem::OperatorType type, const char **pc_type);
PetscErrorCode HssbemH2WillBeFactored(MPI_Comm comm, bool *factored);

/* Dof nodes owned by this rank: a contiguous block [nstart, nstart + nlocal), 3 rows each. */
PetscErrorCode HssbemOwnedNodes(MPI_Comm comm, PetscInt nnodes, PetscInt *nstart, PetscInt *nlocal);

/* Vectors gathered whole on rank 0 and scattered back, for what runs on rank 0 only (PC h2, and PC hss
   on a dense matrix or on one rank). */
class HssbemRootExchange {
public:
  HssbemRootExchange() = default;
  /* The root's arrays in mesh order: entry d is row order[d] of the distributed vectors. */
  explicit HssbemRootExchange(std::vector<PetscInt> order) : m_order(std::move(order)) {}
  HssbemRootExchange(const HssbemRootExchange &) = delete;
  HssbemRootExchange &operator=(const HssbemRootExchange &) = delete;
  ~HssbemRootExchange();
  /* Set up for vectors laid out like x (once; later calls do nothing). */
  PetscErrorCode SetUp(Vec x);
  /* x gathered into the root's array (valid on rank 0 until Restore). */
  PetscErrorCode Gather(Vec x, const PetscScalar **a);
  PetscErrorCode RestoreGather(const PetscScalar **a);
  /* The root's array out, scattered into y. */
  PetscErrorCode GetOut(PetscScalar **a);
  PetscErrorCode ScatterOut(PetscScalar **a, Vec y);

private:
  std::vector<PetscInt> m_order; /* empty: the identity */
  VecScatter            m_scatter = nullptr;
  Vec                   m_in = nullptr, m_out = nullptr;
};

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

/* y += c Q (Qᵀ x) for the rigid-mode regularisation (full vectors on one rank). */
void HssbemAddRegularization(const std::vector<double> &modes, const PetscScalar *x, PetscScalar *y);
