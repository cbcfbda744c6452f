#include "hssbem/app/options.hpp"
#include "hssbem/petsc/system.h"

#include <cstring>
#include <optional>
#include <string>

static PetscErrorCode OptionString_Private(const char *key, const char *text, std::string *value, PetscOptionItems *PetscOptionsObject)
{
  char      buf[PETSC_MAX_PATH_LEN];
  PetscBool set;

  PetscFunctionBegin;
  PetscCall(PetscStrncpy(buf, value->c_str(), sizeof(buf)));
  PetscCall(PetscOptionsString(key, text, "", buf, buf, sizeof(buf), &set));
  if (set) *value = buf;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemProcessOptions - Reads the driver's options; with -help, PETSc prints each with its default.

  Options Database Keys:
+ -problem <file.json>        - problem file
. -mesh <file>                - mesh file (overrides the problem file)
. -E <real>, -nu <real>       - Young's modulus and Poisson's ratio (override the problem file)
. -o <file.h5>                - result file (overrides the problem file)
. -bem_feature_angle <deg>    - dihedral angle above which an edge is sharp (double nodes)
. -bem_mat_type <hss|h2|dense> - operator representation: HSS-compressed MatShell (default), H²-compressed MatShell, or dense
. -mat_bem_quad_order <n>     - Gauss points per direction on singular triangles
. -mat_bem_near_ratio <r>     - subdivide triangles closer than r diameters
. -mat_bem_far_ratio <r>      - 3-point rule beyond r diameters (0: never, the default)
- -mat_bem_max_depth <n>      - subdivision levels for nearly singular triangles

  Level: beginner
@*/
PetscErrorCode HssbemProcessOptions(MPI_Comm comm, HssbemAppOptions *opts)
{
  PetscBool   set;
  std::string mat_type = hssbem::operator_type_name(opts->operator_type);

  PetscFunctionBegin;
  PetscCall(PetscOptionsHasHelp(NULL, &opts->help));
  PetscOptionsBegin(comm, NULL, "hssbem: 3D linear elastostatics by the boundary element method", "hssbem");
  PetscCall(OptionString_Private("-problem", "Problem file (JSON)", &opts->problem, PetscOptionsObject));
  PetscCall(OptionString_Private("-mesh", "Mesh file (.msh, .stl, .off, .obj); overrides the problem file", &opts->mesh, PetscOptionsObject));
  PetscCall(OptionString_Private("-o", "Result file (.h5); overrides the problem file", &opts->output, PetscOptionsObject));
  PetscCall(PetscOptionsReal("-E", "Young's modulus (default: the problem file's)", "", opts->E, &opts->E, &opts->has_E));
  PetscCall(PetscOptionsReal("-nu", "Poisson's ratio (default: the problem file's)", "", opts->nu, &opts->nu, &opts->has_nu));
  PetscCall(PetscOptionsReal("-bem_feature_angle", "Dihedral angle (degrees) above which an edge is sharp", "", opts->feature_angle, &opts->feature_angle, NULL));
  PetscCall(OptionString_Private("-bem_mat_type", "Operator representation: hss (compressed, MatShell), h2 (compressed, strong admissibility, MatShell) or dense", &mat_type, PetscOptionsObject));
  PetscCall(PetscOptionsInt("-mat_bem_quad_order", "Gauss points per direction on singular triangles", "", opts->quad.duffy_order, &opts->quad.duffy_order, NULL));
  PetscCall(PetscOptionsReal("-mat_bem_near_ratio", "Subdivide triangles closer than this many diameters", "", opts->quad.near_ratio, &opts->quad.near_ratio, NULL));
  PetscCall(PetscOptionsReal("-mat_bem_far_ratio", "Use the 3-point rule beyond this many diameters (0: never)", "", opts->quad.far_ratio, &opts->quad.far_ratio, NULL));
  PetscCall(PetscOptionsInt("-mat_bem_max_depth", "Subdivision levels for nearly singular triangles", "", opts->quad.max_depth, &opts->quad.max_depth, &set));
  PetscOptionsEnd();
  const std::optional<hssbem::OperatorType> type = hssbem::parse_operator_type(mat_type);
  PetscCheck(type, comm, PETSC_ERR_ARG_UNKNOWN_TYPE, "-bem_mat_type %s is not available; use hss, h2 or dense", mat_type.c_str());
  opts->operator_type = *type;
  if (opts->operator_type == hssbem::OperatorType::Hss || opts->help) {
    hssbem::HssOptions hss;
    hss.rel_tol = 1e-8;
    PetscCall(HssbemHssOptionsFromDatabase(comm, NULL, &hss));
  }
  if (opts->operator_type == hssbem::OperatorType::H2 || opts->help) {
    hssbem::H2Options h2;
    PetscCall(HssbemH2OptionsFromDatabase(comm, NULL, &h2));
  }
  PetscCheck(opts->quad.far_ratio == 0 || !hssbem::is_compressed(opts->operator_type), comm, PETSC_ERR_ARG_INCOMP,
             "-mat_bem_far_ratio must be 0 with -bem_mat_type %s: the 3-point far rule breaks the smooth far field the compression relies on", mat_type.c_str());
  PetscCheck(opts->quad.duffy_order >= 2 && opts->quad.duffy_order <= 64, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_bem_quad_order must lie in [2, 64]");
  PetscCheck(opts->quad.near_ratio > 0 && (opts->quad.far_ratio == 0 || opts->quad.far_ratio >= opts->quad.near_ratio), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "need -mat_bem_near_ratio > 0 and -mat_bem_far_ratio either 0 (off) or at least -mat_bem_near_ratio");
  PetscCheck(opts->quad.max_depth >= 0 && opts->quad.max_depth <= 20, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_bem_max_depth must lie in [0, 20]");
  PetscCheck(opts->feature_angle > 0 && opts->feature_angle < 180, comm, PETSC_ERR_ARG_OUTOFRANGE, "-bem_feature_angle must lie in (0, 180)");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Options that PETSc reads only at PetscFinalize() or that steer the run itself. */
static PetscBool IsLateOption_Private(const char *name)
{
  static const char *late[] = {"log_view", "options_left", "help", "malloc_dump", "malloc_debug", "memory_view", "log_view_memory", "log_trace", "info", "malloc", "checkstack", "objects_dump", "fp_trap", "options_view", "history"};
  for (const char *k : late)
    if (!std::strcmp(name, k)) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Options that PETSc reads only when the preconditioner is set up, inside KSPSolve(): those of
   sub-solvers (-sub_pc_type of PCBJACOBI/PCASM, -fieldsplit_*, -redundant_*) and of external
   factorization packages (-mat_mumps_icntl_14, ...). Checked after the solve instead. */
static PetscBool IsSetUpTimeOption_Private(const char *name)
{
  static const char *prefixes[] = {"sub_", "fieldsplit_", "redundant_", "mat_mumps_", "mat_superlu", "mat_scalapack_", "mat_strumpack_", "mat_cholmod_", "mat_umfpack_", "mat_klu_"};
  for (const char *p : prefixes)
    if (!std::strncmp(name, p, std::strlen(p))) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Options read only during or after KSPSolve()/MatAssemblyEnd() (viewers and reports), or when
   the preconditioner is set up (IsSetUpTimeOption_Private). */
static PetscBool IsSolveTimeOption_Private(const char *name)
{
  const std::string n(name);
  return (n.find("view") != std::string::npos || n.find("converged_reason") != std::string::npos || IsSetUpTimeOption_Private(name)) ? PETSC_TRUE : PETSC_FALSE;
}

/*@C
  HssbemCheckUnusedOptions - Errors out naming any option that no object has read (a typo such as
  -ksp_rtoll would otherwise be ignored). Before the solve (before_solve true), options that are
  read only during it (viewers, sub-solver and factorization-package options) are let through;
  the check after the solve catches those.

  Level: developer
@*/
PetscErrorCode HssbemCheckUnusedOptions(MPI_Comm comm, PetscBool before_solve)
{
  PetscInt    n;
  char      **names, **values;
  std::string unused;

  PetscFunctionBegin;
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  for (PetscInt i = 0; i < n; ++i)
    if (!IsLateOption_Private(names[i]) && !(before_solve && IsSolveTimeOption_Private(names[i]))) unused += std::string(unused.empty() ? "" : ", ") + "-" + names[i];
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscCheck(unused.empty(), comm, PETSC_ERR_ARG_WRONG, "unknown or unused option(s): %s (run with -help to list the options)", unused.c_str());
  PetscFunctionReturn(PETSC_SUCCESS);
}
