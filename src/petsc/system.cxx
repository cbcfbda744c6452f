/* HssbemCreateSystem, the top of the PETSc layer: the options of the compressions, the size check,
   the system's matrix and right-hand side; conversions between its rows and mesh order. */
#include "hssbem/petsc/system.h"
#include "hssbem/petsc/dense.h"
#include "hssbem/petsc/log.h"
#include "hssbem/bem/rigid_modes.hpp"

#include "mat_compressed.hpp"
#include "system_context.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

/*@C
  HssbemMatIsCompressed - Tells whether A is a compressed (HSS or H²) MatShell of
  HssbemCreateSystem(), which has no entries to factor.

  Not Collective

  Level: intermediate
@*/
PetscErrorCode HssbemMatIsCompressed(Mat A, PetscBool *compressed)
{
  HssbemSystemContext *p;

  PetscFunctionBegin;
  PetscCall(HssbemMatGetSystemContext(A, &p));
  *compressed = p && hssbem::is_compressed(p->type) ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The options every compression of the operator has, -mat_<family>_rel_tol, _leaf_size,
   _max_rank, _proxy_ratio and _proxy_points (family "hss" or "h2"), inside the caller's
   PetscOptionsBegin/End. Opts is hssbem::HssOptions or hssbem::H2Options. */
template <class Opts>
static PetscErrorCode CompressionOptions_Private(const char *family, Opts *opts, PetscOptionItems *PetscOptionsObject)
{
  const std::string key = std::string("-mat_") + family + "_";
  PetscInt          leaf = opts->leaf_size, rank = opts->max_rank, np = opts->proxy_points;

  PetscFunctionBegin;
  PetscCall(PetscOptionsReal((key + "rel_tol").c_str(), "Relative tolerance of the compression", "HssbemCreateSystem", opts->rel_tol, &opts->rel_tol, NULL));
  PetscCall(PetscOptionsInt((key + "leaf_size").c_str(), "Dof nodes per leaf cluster", "HssbemCreateSystem", leaf, &leaf, NULL));
  PetscCall(PetscOptionsInt((key + "max_rank").c_str(), "Cap on each skeleton (-1: none)", "HssbemCreateSystem", rank, &rank, NULL));
  PetscCall(PetscOptionsReal((key + "proxy_ratio").c_str(), "Proxy sphere radius over cluster radius", "HssbemCreateSystem", opts->proxy_ratio, &opts->proxy_ratio, NULL));
  PetscCall(PetscOptionsInt((key + "proxy_points").c_str(), "Points per proxy sphere (0: chosen from the tolerance)", "HssbemCreateSystem", np, &np, NULL));
  opts->leaf_size    = (int)leaf;
  opts->max_rank     = (int)rank;
  opts->proxy_points = (int)np;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The checks of those options. */
template <class Opts>
static PetscErrorCode CheckCompressionOptions_Private(MPI_Comm comm, const char *family, const Opts &opts)
{
  PetscFunctionBegin;
  PetscCheck(opts.rel_tol > 0 && opts.rel_tol < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_%s_rel_tol must lie in (0, 1), got %g", family, (double)opts.rel_tol);
  PetscCheck(opts.leaf_size >= 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_%s_leaf_size must be at least 1", family);
  PetscCheck(opts.max_rank == -1 || opts.max_rank > 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_%s_max_rank must be positive, or -1 for no cap", family);
  PetscCheck(opts.proxy_ratio > 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_%s_proxy_ratio must exceed 1", family);
  PetscCheck(opts.proxy_points >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_%s_proxy_points must be 0 (automatic) or positive", family);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemHssOptionsFromDatabase - Reads the options of the operator's HSS compression.

  Options Database Keys:
+ -mat_hss_rel_tol <tol>      - relative tolerance of each interpolative decomposition
. -mat_hss_leaf_size <n>      - dof nodes per leaf cluster
. -mat_hss_max_rank <k>       - cap on each skeleton (-1: none)
. -mat_hss_proxy_ratio <r>    - proxy sphere radius over cluster radius
- -mat_hss_proxy_points <n>   - points per proxy sphere (0: from the tolerance)

  Level: intermediate
@*/
PetscErrorCode HssbemHssOptionsFromDatabase(MPI_Comm comm, const char *prefix, hssbem::HssOptions *opts)
{
  PetscFunctionBegin;
  PetscOptionsBegin(comm, prefix, "HSS compression of the BEM operator (-bem_mat_type hss)", "Mat");
  PetscCall(CompressionOptions_Private("hss", opts, PetscOptionsObject));
  PetscOptionsEnd();
  PetscCall(CheckCompressionOptions_Private(comm, "hss", *opts));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemH2OptionsFromDatabase - Reads the options of the operator's H² compression.

  Options Database Keys:
+ -mat_h2_rel_tol <tol>      - relative tolerance of each interpolative decomposition
. -mat_h2_leaf_size <n>      - dof nodes per leaf cluster
. -mat_h2_max_rank <k>       - cap on each skeleton (-1: none)
. -mat_h2_proxy_ratio <r>    - proxy sphere radius over cluster radius
. -mat_h2_proxy_points <n>   - points per proxy sphere (0: from the tolerance)
. -mat_h2_eta <eta>          - clusters a, b are far when |c_a - c_b| > (1 + eta)(R_a + R_b)
- -mat_h2_single_precision   - store far and near blocks in single precision (half the memory)

  Level: intermediate
@*/
PetscErrorCode HssbemH2OptionsFromDatabase(MPI_Comm comm, const char *prefix, hssbem::H2Options *opts)
{
  PetscBool single = opts->single_precision ? PETSC_TRUE : PETSC_FALSE;

  PetscFunctionBegin;
  PetscOptionsBegin(comm, prefix, "H2 compression of the BEM operator (-bem_mat_type h2)", "Mat");
  PetscCall(CompressionOptions_Private("h2", opts, PetscOptionsObject));
  PetscCall(PetscOptionsReal("-mat_h2_eta", "Admissibility: far when |c_a - c_b| > (1 + eta)(R_a + R_b)", "HssbemCreateSystem", opts->eta, &opts->eta, NULL));
  PetscCall(PetscOptionsBool("-mat_h2_single_precision", "Store far and near blocks in single precision (half the memory)", "HssbemCreateSystem", single, &single, NULL));
  PetscOptionsEnd();
  opts->single_precision = single == PETSC_TRUE;
  PetscCall(CheckCompressionOptions_Private(comm, "h2", *opts));
  PetscCheck(opts->eta >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_h2_eta must be >= 0");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Bytes of memory of this node: MemTotal, or the cgroup's limit when lower. */
static double NodeMemoryBytes_Private(void)
{
  double        bytes = 0;
  std::ifstream meminfo("/proc/meminfo");
  std::string   key;
  double        kb;
  while (meminfo >> key >> kb) {
    if (key == "MemTotal:") {
      bytes = kb * 1024.0;
      break;
    }
    meminfo.ignore(1 << 10, '\n');
  }
  std::ifstream cgroup("/sys/fs/cgroup/memory.max");
  double        limit;
  if (cgroup >> limit && limit > 0 && (bytes == 0 || limit < bytes)) bytes = limit; /* "max" reads as no number */
  return bytes > 0 ? bytes : 1e300;
}

PetscErrorCode HssbemMachineLimits(MPI_Comm comm, hssbem::MachineLimits *limits)
{
  MPI_Comm    node;
  PetscMPIInt size, on_node;
  PetscReal   given = 0;
  PetscBool   set;
  double      memory;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCallMPI(MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node));
  PetscCallMPI(MPI_Comm_size(node, &on_node));
  PetscCallMPI(MPI_Comm_free(&node));
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-hssbem_memory_limit", &given, &set));
  PetscCheck(!set || (given >= 0 && given < 1e18), comm, PETSC_ERR_ARG_OUTOFRANGE, "-hssbem_memory_limit must be a finite number of bytes below 1e18 (0: the machine's), got %g", (double)given);
  memory = given > 0 ? (double)given : NodeMemoryBytes_Private();
  PetscCallMPI(MPI_Allreduce(&memory, &limits->node_memory_bytes, 1, MPI_DOUBLE, MPI_MIN, comm));
  PetscCallMPI(MPI_Allreduce(&on_node, &limits->ranks_per_node, 1, MPI_INT, MPI_MAX, comm));
  limits->ranks     = size;
  limits->index_max = PETSC_MAX_INT;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What else the size model needs of a factored H² system: PC h2's options (read, not listed:
   PCSetFromOptions_H2 lists and checks them) and the Krylov method's vectors. */
static PetscErrorCode H2SolverSizeOptions_Private(hssbem::SizeOptions *o)
{
  char      ksp[64] = "gmres";
  PetscInt  restart = 100, top = o->pc_h2_top_size, mixed = o->pc_h2_mixed_top;
  PetscReal tol = o->pc_h2_rel_tol;
  PetscBool spread = o->pc_h2_spread_top ? PETSC_TRUE : PETSC_FALSE;

  PetscFunctionBegin;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-ksp_type", ksp, sizeof(ksp), NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-ksp_gmres_restart", &restart, NULL));
  o->krylov_vectors = std::string(ksp) == KSPPREONLY ? 0 : (int)restart + 1;
  if (!o->h2_factored) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-pc_h2_rel_tol", &tol, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-pc_h2_top_size", &top, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-pc_h2_mixed_top", &mixed, NULL)); /* its former name */
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-pc_h2_single_top_from", &mixed, NULL));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-pc_h2_spread_top", &spread, NULL));
  o->pc_h2_rel_tol    = (double)tol;
  o->pc_h2_top_size   = top;
  o->pc_h2_mixed_top  = mixed;
  o->pc_h2_spread_top = spread == PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refuses (on comm) a system of `type` that does not fit this machine, before it is allocated. */
static PetscErrorCode CheckSize_Private(MPI_Comm comm, hssbem::OperatorType type, PetscInt nnodes, const hssbem::SizeOptions &o)
{
  hssbem::MachineLimits limits;
  std::string           why;

  PetscFunctionBegin;
  PetscCall(HssbemMachineLimits(comm, &limits));
  PetscCallCXX(why = hssbem::size_refusal(type, 3 * (long long)nnodes, o, limits));
  PetscCheck(why.empty(), comm, PETSC_ERR_MEM, "%s", why.c_str());
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemCreateSystem - Creates the system matrix A (dense, HSS or H²) and right-hand side b of a
  boundary-condition pattern; see system.h.

  Collective

  Level: beginner
@*/
PetscErrorCode HssbemCreateSystem(MPI_Comm comm, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, const char *mat_type, Mat *A,
                                  Vec *b)
{
  hssbem::OperatorType type;
  std::unique_ptr<HssbemSystemContext> ctx; /* owned here until A owns it: an error path frees it */
  hssbem::SizeOptions size_options;

  PetscFunctionBegin;
  PetscCall(HssbemOperatorTypeFromName(comm, mat_type, &type));
  PetscCallCXX(ctx = std::make_unique<HssbemSystemContext>());
  ctx->op   = &op;
  ctx->type = type;
  PetscCallCXX(ctx->sel = sel);
  if (rigid_modes) PetscCallCXX(ctx->modes = *rigid_modes);
  /* a pressure load needs the Gn columns */
  const bool pressure = std::any_of(sel.pressure.begin(), sel.pressure.end(), [](double p) { return !std::isnan(p); });
  if (type == hssbem::OperatorType::H2) {
    ctx->h2_options.pressure_columns = pressure;
    /* The driver's defaults (docs/performance.md, "Choosing the operator"): 1e-5 keeps the H² solution within
       ~5e-6 of dense LU's, well below the discretisation error of any mesh it pays on, and
       single-precision (low-rank) blocks halve the memory at that tolerance. */
    ctx->h2_options.rel_tol          = 1e-5;
    ctx->h2_options.single_precision = true;
    PetscCall(HssbemH2OptionsFromDatabase(comm, NULL, &ctx->h2_options));
    size_options.single_precision = ctx->h2_options.single_precision;
    size_options.h2_rel_tol       = ctx->h2_options.rel_tol;
    PetscCall(HssbemH2WillBeFactored(&size_options.h2_factored));
    PetscCall(H2SolverSizeOptions_Private(&size_options));
  } else if (type == hssbem::OperatorType::Hss) {
    ctx->hss_options.rel_tol          = 1e-8;
    ctx->hss_options.pressure_columns = pressure;
    PetscCall(HssbemHssOptionsFromDatabase(comm, NULL, &ctx->hss_options));
    size_options.hss_rel_tol = ctx->hss_options.rel_tol;
  }
  PetscCall(CheckSize_Private(comm, type, op.num_nodes(), size_options));
  if (type == hssbem::OperatorType::Dense) PetscCall(HssbemAssembleDense(comm, op, sel, rigid_modes, A, b));
  else PetscCall(HssbemMatCreateCompressed_Private(comm, ctx.get(), A, b));
  PetscCall(HssbemMatComposeSystemContext(*A, ctx.get()));
  ctx.release();
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Copies between x (A's layout) and y (mesh order): forward y := x, reverse x := y. */
static PetscErrorCode MeshOrderScatter_Private(Mat A, Vec x, Vec y, ScatterMode mode)
{
  HssbemSystemContext *p;

  PetscFunctionBegin;
  PetscCall(HssbemMatGetSystemContext(A, &p));
  /* the scatter from y to x; no map: mesh order already, perhaps in another layout (ScaLAPACK's) */
  PetscCall(HssbemRowScatterOnce(y, x, p ? p->system_of_dof : std::vector<PetscInt>(), mode == SCATTER_FORWARD ? SCATTER_REVERSE : SCATTER_FORWARD));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemVecToMeshOrder - Copies x, a vector of A's layout (HssbemCreateSystem()), into y, laid out
  like the dense system's vectors: mesh order (3 rows per dof node), nodes split in contiguous
  blocks across the ranks. The H² and HSS systems on several ranks order their rows by the METIS
  partition (cluster order); the other systems are in mesh order already (then this is a copy).

  Collective

  Level: intermediate
@*/
PetscErrorCode HssbemVecToMeshOrder(Mat A, Vec x, Vec y)
{
  PetscFunctionBegin;
  PetscCall(MeshOrderScatter_Private(A, x, y, SCATTER_FORWARD));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemVecFromMeshOrder - The inverse of HssbemVecToMeshOrder(): x (A's layout) from y (mesh
  order).

  Collective

  Level: intermediate
@*/
PetscErrorCode HssbemVecFromMeshOrder(Mat A, Vec y, Vec x)
{
  PetscFunctionBegin;
  PetscCall(MeshOrderScatter_Private(A, x, y, SCATTER_REVERSE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemMatCreateMeshOrderVec - A vector laid out like the dense system's (mesh order, nodes split
  in contiguous blocks), for HssbemVecToMeshOrder() and HssbemVecFromMeshOrder().

  Collective

  Level: intermediate
@*/
PetscErrorCode HssbemMatCreateMeshOrderVec(Mat A, Vec *y)
{
  PetscInt N, nstart, nlocal;

  PetscFunctionBegin;
  PetscCall(MatGetSize(A, &N, NULL));
  PetscCall(HssbemOwnedNodes(PetscObjectComm((PetscObject)A), N / 3, &nstart, &nlocal));
  PetscCall(VecCreateMPI(PetscObjectComm((PetscObject)A), 3 * nlocal, N, y));
  PetscCall(VecSetBlockSize(*y, 3));
  PetscFunctionReturn(PETSC_SUCCESS);
}
