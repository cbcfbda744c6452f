/* HssbemCreateSystem, the top of the PETSc layer: the options of the compressions, the size check,
   the system's matrix and right-hand side; conversions between its rows and mesh order. */
#include "hssbem/petsc/system.h"
#include "hssbem/petsc/dense.h"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/options.h"
#include "hssbem/petsc/pc_h2.h"
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

/* The -<prefix>mat_<family>_* options of the table given in the database, onto opts (Opts is
   hssbem::HssOptions or hssbem::H2Options; `bind` maps each option to its field). */
template <class Opts, class Bind>
static PetscErrorCode CompressionOptions_Private(MPI_Comm comm, const char *prefix, const char *family, Opts *opts, Bind &&bind)
{
  hssbem::OptionValues given;
  std::string          head;

  PetscFunctionBegin;
  PetscCallCXX(head = std::string("mat_") + family + "_");
  PetscCall(HssbemOptionsGetValues(comm, prefix, hssbem::OptionReader::System, hssbem::kEvery, &given));
  for (const auto &[name, v] : given)
    if (name.rfind(head, 0) == 0) PetscCallCXX(bind(name.substr(head.size()), v.number, *opts));
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

  The defaults and ranges are the table's (core/option_table.def).

  Level: intermediate
@*/
PetscErrorCode HssbemHssOptionsFromDatabase(MPI_Comm comm, const char *prefix, hssbem::HssOptions *opts)
{
  PetscFunctionBegin;
  PetscCall(CompressionOptions_Private(comm, prefix, "hss", opts, [](const std::string &k, double v, hssbem::HssOptions &o) {
    if (k == "rel_tol") o.rel_tol = v;
    else if (k == "leaf_size") o.leaf_size = (int)v;
    else if (k == "max_rank") o.max_rank = (int)v;
    else if (k == "proxy_ratio") o.proxy_ratio = v;
    else if (k == "proxy_points") o.proxy_points = (int)v;
  }));
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

  The defaults and ranges are the table's (core/option_table.def).

  Level: intermediate
@*/
PetscErrorCode HssbemH2OptionsFromDatabase(MPI_Comm comm, const char *prefix, hssbem::H2Options *opts)
{
  PetscFunctionBegin;
  PetscCall(CompressionOptions_Private(comm, prefix, "h2", opts, [](const std::string &k, double v, hssbem::H2Options &o) {
    if (k == "rel_tol") o.rel_tol = v;
    else if (k == "leaf_size") o.leaf_size = (int)v;
    else if (k == "max_rank") o.max_rank = (int)v;
    else if (k == "proxy_ratio") o.proxy_ratio = v;
    else if (k == "proxy_points") o.proxy_points = (int)v;
    else if (k == "eta") o.eta = v;
    else if (k == "single_precision") o.single_precision = v != 0;
  }));
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

/* The solver's part of the size model as the options database sets it, for HssbemCreateSystem()
   (which has no KSP): the Krylov method, -pc_type h2 and PC h2's options (read, not listed:
   PCSetFromOptions_H2 lists and checks them). */
static PetscErrorCode SolverSizeOptions_Private(hssbem::SizeOptions *o)
{
  char      ksp[64] = "", pc[64] = "";
  PetscInt  restart = o->krylov_vectors - 1, top = o->pc_h2_top_size, mixed = o->pc_h2_mixed_top;
  PetscReal tol = o->pc_h2_rel_tol;
  PetscBool spread = o->pc_h2_spread_top ? PETSC_TRUE : PETSC_FALSE, set;

  PetscFunctionBegin;
  PetscCall(PetscStrncpy(ksp, std::string(hssbem::option_default::ksp_type).c_str(), sizeof(ksp)));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-ksp_type", ksp, sizeof(ksp), NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-ksp_gmres_restart", &restart, NULL));
  o->krylov_vectors = std::string(ksp) == KSPPREONLY ? 0 : (int)restart + 1;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-pc_type", pc, sizeof(pc), &set));
  o->h2_factored = !set || std::string(pc) == PCH2;
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

/* Refuses (on comm) a system of `type` that does not fit this machine (`given`, or measured),
   before it is allocated. */
static PetscErrorCode CheckSize_Private(MPI_Comm comm, hssbem::OperatorType type, PetscInt nnodes, const hssbem::SizeOptions &o, const hssbem::MachineLimits *given)
{
  hssbem::MachineLimits limits;
  std::string           why;

  PetscFunctionBegin;
  if (given) limits = *given;
  else PetscCall(HssbemMachineLimits(comm, &limits));
  PetscCallCXX(why = hssbem::size_refusal(type, 3 * (long long)nnodes, o, limits));
  PetscCheck(why.empty(), comm, PETSC_ERR_MEM, "%s", why.c_str());
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemCreateSystem - Creates the system matrix A (dense, HSS or H²) and right-hand side b of a
  boundary-condition pattern; see system.h. Reads the compression's options (-mat_h2_*,
  -mat_hss_*) and what the size check needs of the solver (-ksp_type, -pc_type, -pc_h2_*) from the
  options database.

  Collective

  Level: beginner
@*/
PetscErrorCode HssbemCreateSystem(MPI_Comm comm, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, const char *mat_type, Mat *A,
                                  Vec *b)
{
  HssbemSystemOptions opts;

  PetscFunctionBegin;
  PetscCall(HssbemH2OptionsFromDatabase(comm, NULL, &opts.h2));
  PetscCall(HssbemHssOptionsFromDatabase(comm, NULL, &opts.hss));
  PetscCall(SolverSizeOptions_Private(&opts.solver));
  PetscCall(HssbemCreateSystemWithOptions(comm, op, sel, rigid_modes, mat_type, opts, A, b));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemCreateSystemWithOptions - HssbemCreateSystem() with the options given, typed.

  Collective

  Level: intermediate
@*/
PetscErrorCode HssbemCreateSystemWithOptions(MPI_Comm comm, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, const char *mat_type,
                                             const HssbemSystemOptions &opts, Mat *A, Vec *b)
{
  hssbem::OperatorType type;
  std::unique_ptr<HssbemSystemContext> ctx; /* owned here until A owns it: an error path frees it */
  hssbem::SizeOptions size_options = opts.solver;

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
    ctx->h2_options                  = opts.h2;
    ctx->h2_options.pressure_columns = pressure;
    size_options.single_precision    = ctx->h2_options.single_precision;
    size_options.h2_rel_tol          = ctx->h2_options.rel_tol;
    ctx->h2_source                   = opts.h2_source;
  } else if (type == hssbem::OperatorType::Hss) {
    ctx->hss_options                  = opts.hss;
    ctx->hss_options.pressure_columns = pressure;
    size_options.hss_rel_tol          = ctx->hss_options.rel_tol;
  }
  PetscCall(CheckSize_Private(comm, type, op.num_nodes(), size_options, opts.limits));
  if (type == hssbem::OperatorType::Dense) PetscCall(HssbemAssembleDense(comm, op, sel, rigid_modes, A, b));
  else PetscCall(HssbemMatCreateCompressed_Private(comm, ctx.get(), A, b));
  PetscCall(HssbemMatComposeSystemContext(*A, ctx.get()));
  ctx.release();
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemMatGetH2System - The H² system behind A (every rank its part) and the partition of its
  layout, or null and an empty partition when A is not HssbemCreateSystem()'s H² operator.

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemMatGetH2System(Mat A, std::shared_ptr<const hssbem::H2DistributedSystem> *sys, std::vector<int> *node_part)
{
  HssbemSystemContext *p;

  PetscFunctionBegin;
  PetscCall(HssbemMatGetSystemContext(A, &p));
  sys->reset();
  node_part->clear();
  if (p && p->h2 && p->layout) {
    *sys = p->h2;
    PetscCallCXX(*node_part = p->layout->node_part);
  }
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
