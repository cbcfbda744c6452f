static const char help[] = "clamped_block: a body clamped at its base and pressed on its top, solved with hssbem's operator\n"
                           "and the program's own KSP (GMRES preconditioned by the HSS factorization, PC type \"hss\").\n"
                           "Usage: mpirun -n P clamped_block -mesh FILE [-E 3000] [-nu 0.45] [-pressure 100] [PETSc options]\n\n";

/* How a program uses hssbem as a library: the core (mesh, discretization, BEM operator) is plain
   C++, HssbemCreateSystem() turns it into a PETSc Mat and right-hand side, and everything after
   that is ordinary PETSc, so -ksp_type, -pc_type, -pc_hss_rel_tol, -ksp_monitor, -log_view work. */

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/mesh/mesh.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/pc_hss.h"
#include "hssbem/petsc/system.h"

#include <petscksp.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

struct Options {
  char      mesh[PETSC_MAX_PATH_LEN] = "";
  PetscReal E = 3000.0, nu = 0.45; /* Young's modulus (Pa), Poisson's ratio: a soft solid */
  PetscReal pressure = 100.0;      /* downward traction on the top (Pa) */
};

/* The core objects. The discretization keeps a pointer to the mesh and the operator one to the
   discretization, so they live together, and the operator outlives the Mat made from it. */
struct Problem {
  hssbem::SurfaceMesh                     mesh;
  std::unique_ptr<hssbem::Discretization> disc;
  std::unique_ptr<hssbem::BemOperator>    op;
};

static PetscErrorCode ProcessOptions(MPI_Comm comm, Options *o, PetscBool *has_mesh)
{
  PetscFunctionBegin;
  PetscOptionsBegin(comm, NULL, "clamped_block options", NULL);
  PetscCall(PetscOptionsString("-mesh", "Surface mesh (.msh, .stl, .off, .obj)", NULL, o->mesh, o->mesh, sizeof(o->mesh), has_mesh));
  PetscCall(PetscOptionsReal("-E", "Young's modulus (Pa)", NULL, o->E, &o->E, NULL));
  PetscCall(PetscOptionsReal("-nu", "Poisson's ratio", NULL, o->nu, &o->nu, NULL));
  PetscCall(PetscOptionsReal("-pressure", "Downward traction on the top 10 % (Pa)", NULL, o->pressure, &o->pressure, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every rank reads the mesh and builds the operator; the core reports problems by exceptions,
   which PetscCallCXX turns into PETSc errors. 40 degrees: edges sharper than that get double nodes. */
static PetscErrorCode LoadProblem(const Options &o, Problem *pb)
{
  std::vector<std::string> notices; /* e.g. "component flipped to outward normals" */

  PetscFunctionBegin;
  PetscCallCXX(pb->mesh = hssbem::read_mesh(o.mesh));
  PetscCallCXX(hssbem::validate_and_orient(pb->mesh, notices));
  PetscCallCXX(pb->disc = std::make_unique<hssbem::Discretization>(pb->mesh, 40.0));
  PetscCallCXX(pb->op = std::make_unique<hssbem::BemOperator>(*pb->disc, hssbem::Material::from_young(o.E, o.nu)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Boundary conditions, one entry per dof node: nodes in the bottom 10 % of the z range are clamped
   (u = 0, traction unknown); the others have a known traction and unknown displacement: (0, 0, -p)
   on the upward-facing part of the top 10 %, zero elsewhere. Nodes are classified by the vertex
   they belong to; the normal keeps the side faces of a box free up to their top edge. */
static hssbem::SystemSelection ClampedBlockSelection(const hssbem::Discretization &disc, double p)
{
  const int n    = disc.num_nodes();
  double    zmin = INFINITY, zmax = -INFINITY;
  for (const hssbem::Vec3 &v : disc.mesh().vertices) {
    zmin = std::fmin(zmin, v[2]);
    zmax = std::fmax(zmax, v[2]);
  }
  const double h = zmax - zmin;

  hssbem::SystemSelection sel;
  sel.displacement_known.resize(n);
  sel.known.resize(n);
  for (int i = 0; i < n; ++i) {
    const double z       = disc.node_position(i)[2];
    const bool   clamped = z <= zmin + 0.1 * h;
    const bool   loaded  = !clamped && z >= zmax - 0.1 * h && disc.node(i).normal[2] > 0.0;
    sel.displacement_known[i] = {clamped, clamped, clamped};
    sel.known[i]              = {0.0, 0.0, loaded ? -p : 0.0};
  }
  return sel;
}

/* max |u_z| over the nodes whose displacement is unknown: x holds (u or t) per node and component,
   3 rows per node in node order, contiguous per rank (the mesh order of HssbemVecToMeshOrder()). */
static PetscErrorCode MaxVerticalDisplacement(Vec x, const hssbem::SystemSelection &sel, PetscReal *umax)
{
  const PetscScalar *xa;
  PetscInt           lo, hi;
  PetscReal          local = 0.0;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(x, &lo, &hi));
  PetscCall(VecGetArrayRead(x, &xa));
  for (PetscInt r = lo + 2; r < hi; r += 3)
    if (!sel.displacement_known[r / 3][2]) local = PetscMax(local, PetscAbsScalar(xa[r - lo]));
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCallMPI(MPI_Allreduce(&local, umax, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)x)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Build A x = b from the operator and solve it with a KSP of our own. Sets *diverged on failure. */
static PetscErrorCode Solve(MPI_Comm comm, const Options &o, PetscBool *diverged)
{
  Problem            pb;
  Mat                A;
  Vec                b, x;
  KSP                ksp;
  PC                 pc;
  KSPType            ksp_type;
  PCType             pc_type;
  KSPConvergedReason reason;
  PetscInt           its, N;
  PetscReal          umax;

  PetscFunctionBegin;
  PetscCall(LoadProblem(o, &pb));
  const hssbem::SystemSelection sel = ClampedBlockSelection(*pb.disc, o.pressure);
  PetscCall(HssbemCreateSystem(comm, *pb.op, sel, nullptr, HSSBEM_MAT_HSS, &A, &b)); /* clamped: no rigid modes */
  PetscCall(VecDuplicate(b, &x));

  PetscCall(KSPCreate(comm, &ksp));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPSetType(ksp, KSPGMRES));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCHSS));
  PetscCall(PCHSSSetRelTol(pc, 1e-3)); /* a loose factorization: a preconditioner, not a direct solver */
  PetscCall(KSPSetTolerances(ksp, 1e-8, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  PetscCall(KSPSetFromOptions(ksp)); /* the command line has the last word */
  PetscCall(KSPSolve(ksp, b, x));

  PetscCall(KSPGetIterationNumber(ksp, &its));
  PetscCall(KSPGetConvergedReason(ksp, &reason));
  PetscCall(KSPGetType(ksp, &ksp_type));
  PetscCall(PCGetType(pc, &pc_type));
  PetscCall(VecGetSize(b, &N));
  {
    /* On several ranks A's rows are in cluster order (each rank a part of the surface): the
       solution in mesh order, to read it node by node. */
    Vec xm;
    PetscCall(HssbemMatCreateMeshOrderVec(A, &xm));
    PetscCall(HssbemVecToMeshOrder(A, x, xm));
    PetscCall(MaxVerticalDisplacement(xm, sel, &umax));
    PetscCall(VecDestroy(&xm));
  }
  PetscCall(PetscPrintf(comm, "example: %" PetscInt_FMT " unknowns, %s/%s: %" PetscInt_FMT " iterations (%s), max |u_z| = %.6e\n", N, ksp_type, pc_type, its,
                        KSPConvergedReasons[reason], (double)umax));
  *diverged = reason < 0 ? PETSC_TRUE : PETSC_FALSE;

  PetscCall(KSPDestroy(&ksp));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscCall(MatDestroy(&A)); /* before pb (the operator) goes out of scope */
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  Options   opts;
  PetscBool has_mesh = PETSC_FALSE, has_help = PETSC_FALSE, diverged = PETSC_FALSE;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(HssbemInitializePackage()); /* log events and PC type "hss" */
  PetscCall(ProcessOptions(PETSC_COMM_WORLD, &opts, &has_mesh));
  PetscCall(PetscOptionsHasHelp(NULL, &has_help));
  if (has_mesh) PetscCall(Solve(PETSC_COMM_WORLD, opts, &diverged));
  else if (!has_help) PetscCall(PetscPrintf(PETSC_COMM_WORLD, "clamped_block: error: no mesh; give -mesh FILE (-help lists the options)\n"));
  PetscCall(PetscFinalize());
  return ((!has_mesh && !has_help) || diverged) ? 1 : 0;
}
