// The driver's options (see options.hpp). PETSc's option macros need functions that return a
// PetscErrorCode: ProcessOptions_Private and CheckUnusedOptions_Private are written like PETSc
// code, and read_app_options() and check_unused_options() turn their error codes into
// exceptions, once each.
#include "hssbem/app/options.hpp"

#include "hssbem/app/petsc_call.hpp"
#include "hssbem/petsc/system.h"
#include "stress_post.hpp"

#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

PetscErrorCode OptionString_Private(const char *key, const char *text, std::string *value, PetscOptionItems *PetscOptionsObject)
{
  char      buf[PETSC_MAX_PATH_LEN];
  PetscBool set;

  PetscFunctionBegin;
  PetscCall(PetscStrncpy(buf, value->c_str(), sizeof(buf)));
  PetscCall(PetscOptionsString(key, text, "", buf, buf, sizeof(buf), &set));
  if (set) *value = buf;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads the driver's options; with -help, PETSc prints each with its default.

  Options Database Keys:
+ -problem <file.json>        - problem file
. -mesh <file>                - mesh file (overrides the problem file)
. -E <real>, -nu <real>       - Young's modulus and Poisson's ratio (override the problem file)
. -o <file.h5>                - result file (overrides the problem file)
. -bem_feature_angle <deg>    - dihedral angle above which an edge is sharp (double nodes)
. -bem_mat_type <auto|dense|h2|hss> - operator: auto (default: dense below a measured size, H² above), dense, H²- or HSS-compressed MatShell
. -hssbem_memory_limit <bytes> - memory per node that the size check assumes (default: the machine's)
. -hssbem_traceback           - keep PETSc's error traceback (for debugging; the driver prints one line otherwise)
. -mat_bem_quad_order <n>     - Gauss points per direction on singular triangles
. -mat_bem_near_ratio <r>     - subdivide triangles closer than r diameters
. -mat_bem_far_ratio <r>      - 3-point rule beyond r diameters (0: never, the default)
. -mat_bem_max_depth <n>      - subdivision levels for nearly singular triangles
. -scene_strategy <auto|solve|update|refactor|krylov> - per-frame strategy of a scene (auto: the cost model's cheapest)
. -scene_refresh <n>          - incremental capacitance updates before a rebuild
. -scene_single_from <n>      - single-precision capacitance inverse from this many switched unknowns (-1: never)
. -scene_single_fields_from <n> - the fields' product with W(:, J) in single precision from this many switched unknowns (-1: never)
. -scene_krylov_rtol <r>      - GMRES tolerance of the krylov strategy
. -scene_monitor              - print one line per frame
. -scene_keep_partial         - when a frame fails, keep the frames solved before it in the result file (the run still fails)
. -hssbem_error_timeout <s>   - seconds the ranks wait for a rank whose error they have not joined before aborting (default 10)
. -contact_tol <r>            - contact: relative tolerance of the gaps (times the mesh's size) and of friction's Newton residual
. -contact_max_it <n>         - contact: active-set (or Newton) iterations per frame before it is an error
. -contact_reach <length>     - contact: vertices within this gap of an obstacle or body are candidates (0: 5 % of the mesh's size)
. -contact_depth <length>     - contact: a vertex deeper than this behind an open mesh obstacle is not in contact with it (0: the reach)
. -contact_monitor            - contact: print one line per iteration
. -contact_h2_rtol <r>        - contact on -bem_mat_type h2: GMRES tolerance (true residual) of the reference's accurate solves
- -contact_h2_factor_tol <r>  - contact on -bem_mat_type h2: tolerance of the reference's H2 factorization (its columns' accuracy)
*/
PetscErrorCode ProcessOptions_Private(MPI_Comm comm, AppOptions *opts)
{
  PetscBool   help, has_E, has_nu, traceback = PETSC_FALSE; /* -hssbem_traceback is acted on by app/main.cxx; listed here for -help */
  PetscReal   memory_limit = 0;                               /* -hssbem_memory_limit: read and checked by HssbemMachineLimits() */
  PetscReal   E = 0, nu = 0, feature_angle = opts->overrides.feature_angle_deg;
  std::string mesh = opts->overrides.mesh.value_or(""), output = opts->overrides.output.value_or(""), mat_type = opts->operator_type ? operator_type_name(*opts->operator_type) : "auto";
  QuadratureOptions &quad = opts->quad;
  std::string strategy = scene_strategy_name(opts->scene.strategy);
  PetscInt    refresh  = opts->scene.refresh_every, single_from = opts->scene.single_from;
  PetscInt    single_fields_from = opts->scene.single_fields_from;
  PetscBool   monitor  = opts->scene.monitor ? PETSC_TRUE : PETSC_FALSE, keep_partial = opts->scene.keep_partial ? PETSC_TRUE : PETSC_FALSE;
  PetscReal   error_timeout = k_default_error_timeout; /* -hssbem_error_timeout: acted on by app/main.cxx (read_error_timeout); listed here for -help */
  PetscBool   contact_monitor = opts->contact.monitor ? PETSC_TRUE : PETSC_FALSE;
  PetscInt    contact_max_it  = opts->contact.max_it;

  PetscFunctionBegin;
  PetscCall(PetscOptionsHasHelp(NULL, &help));
  opts->help = help;
  PetscOptionsBegin(comm, NULL, "hssbem: 3D linear elastostatics by the boundary element method", "hssbem");
  PetscCall(OptionString_Private("-problem", "Problem file (JSON)", &opts->problem, PetscOptionsObject));
  PetscCall(OptionString_Private("-mesh", "Mesh file (.msh, .stl, .off, .obj); overrides the problem file", &mesh, PetscOptionsObject));
  PetscCall(OptionString_Private("-o", "Result file (.h5); overrides the problem file", &output, PetscOptionsObject));
  PetscCall(PetscOptionsReal("-E", "Young's modulus (default: the problem file's)", "", E, &E, &has_E));
  PetscCall(PetscOptionsReal("-nu", "Poisson's ratio (default: the problem file's)", "", nu, &nu, &has_nu));
  PetscCall(PetscOptionsReal("-bem_feature_angle", "Dihedral angle (degrees) above which an edge is sharp", "", feature_angle, &feature_angle, NULL));
  PetscCall(OptionString_Private("-bem_mat_type", "Operator: auto (dense below a measured size, H2 above), dense, h2 (compressed, strong admissibility, MatShell) or hss (compressed, MatShell)", &mat_type, PetscOptionsObject));
  PetscCall(PetscOptionsReal("-hssbem_memory_limit", "Memory per node (bytes) that the size check assumes (0: the machine's)", "", memory_limit, &memory_limit, NULL));
  PetscCall(PetscOptionsBool("-hssbem_traceback", "Keep PETSc's error traceback (debugging)", "", traceback, &traceback, NULL));
  PetscCall(PetscOptionsInt("-mat_bem_quad_order", "Gauss points per direction on singular triangles", "", quad.duffy_order, &quad.duffy_order, NULL));
  PetscCall(PetscOptionsReal("-mat_bem_near_ratio", "Subdivide triangles closer than this many diameters", "", quad.near_ratio, &quad.near_ratio, NULL));
  PetscCall(PetscOptionsReal("-mat_bem_far_ratio", "Use the 3-point rule beyond this many diameters (0: never)", "", quad.far_ratio, &quad.far_ratio, NULL));
  PetscCall(PetscOptionsInt("-mat_bem_max_depth", "Subdivision levels for nearly singular triangles", "", quad.max_depth, &quad.max_depth, NULL));
  PetscCall(OptionString_Private("-scene_strategy", "Scenes (frames): per-frame strategy: auto (cheapest by the cost model), solve, update, refactor or krylov", &strategy, PetscOptionsObject));
  PetscCall(PetscOptionsInt("-scene_refresh", "Scenes: incremental capacitance updates before a rebuild from scratch", "", opts->scene.refresh_every, &refresh, NULL));
  PetscCall(PetscOptionsInt("-scene_single_from", "Scenes: switched sets of at least this size keep the capacitance inverse in single precision, refined in double (-1: never)", "", single_from, &single_from, NULL));
  PetscCall(PetscOptionsInt("-scene_single_fields_from", "Scenes: switched sets of at least this size take the fields' product with W(:, J) in single precision (switched unknowns stay double; -1: never)", "", single_fields_from, &single_fields_from, NULL));
  PetscCall(PetscOptionsReal("-scene_krylov_rtol", "Scenes: GMRES relative tolerance (true residual) of the krylov strategy", "", opts->scene.krylov_rtol, &opts->scene.krylov_rtol, NULL));
  PetscCall(PetscOptionsBool("-scene_monitor", "Scenes: print one line per frame (strategy, switched unknowns, time)", "", monitor, &monitor, NULL));
  PetscCall(PetscOptionsBool("-scene_keep_partial", "Scenes: when a frame fails, commit the frames solved before it (the run still fails)", "", keep_partial, &keep_partial, NULL));
  PetscCall(PetscOptionsReal("-hssbem_error_timeout", "Seconds the ranks wait for a rank whose error they have not joined before aborting the job", "", error_timeout, &error_timeout, NULL));
  PetscCall(PetscOptionsReal("-contact_tol", "Contact: relative tolerance of the gaps (times the mesh's size) and of friction's Newton residual", "", opts->contact.tol, &opts->contact.tol, NULL));
  PetscCall(PetscOptionsInt("-contact_max_it", "Contact: active-set (or Newton) iterations per frame before it is an error", "", contact_max_it, &contact_max_it, NULL));
  PetscCall(PetscOptionsReal("-contact_reach", "Contact: vertices within this gap of an obstacle or another body are candidates (0: 5 % of the mesh's size)", "", opts->contact.reach, &opts->contact.reach, NULL));
  PetscCall(PetscOptionsReal("-contact_depth", "Contact: a vertex deeper than this behind an open mesh obstacle is not in contact with it (0: the reach)", "", opts->contact.depth, &opts->contact.depth, NULL));
  PetscCall(PetscOptionsBool("-contact_monitor", "Contact: print one line per iteration (active points, changes, residual)", "", contact_monitor, &contact_monitor, NULL));
  PetscCall(PetscOptionsReal("-contact_h2_rtol", "Contact on -bem_mat_type h2: GMRES relative tolerance (true residual) of the H2 reference's accurate solves", "", opts->contact.h2_rtol, &opts->contact.h2_rtol, NULL));
  PetscCall(PetscOptionsReal("-contact_h2_factor_tol", "Contact on -bem_mat_type h2: tolerance of the H2 reference's factorization (the accuracy of its columns)", "", opts->contact.h2_factor_tol, &opts->contact.h2_factor_tol, NULL));
  PetscOptionsEnd();
  opts->scene.monitor      = monitor == PETSC_TRUE;
  opts->scene.keep_partial = keep_partial == PETSC_TRUE;
  opts->contact.monitor = contact_monitor == PETSC_TRUE;
  PetscCheck(opts->contact.tol > 0 && opts->contact.tol < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-contact_tol must lie in (0, 1)");
  PetscCheck(contact_max_it >= 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-contact_max_it must be at least 1");
  PetscCheck(opts->contact.reach >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-contact_reach must be >= 0 (0: automatic)");
  PetscCheck(opts->contact.depth >= 0 && std::isfinite(opts->contact.depth), comm, PETSC_ERR_ARG_OUTOFRANGE, "-contact_depth must be finite and >= 0 (0: the reach)");
  opts->contact.max_it = (int)contact_max_it;
  PetscCheck(opts->contact.h2_rtol > 0 && opts->contact.h2_rtol < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-contact_h2_rtol must lie in (0, 1)");
  PetscCheck(opts->contact.h2_factor_tol > 0 && opts->contact.h2_factor_tol < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-contact_h2_factor_tol must lie in (0, 1)");
  {
    const std::optional<SceneStrategy> st = parse_scene_strategy(strategy);
    PetscCheck(st, comm, PETSC_ERR_ARG_UNKNOWN_TYPE, "-scene_strategy %s is not available; use auto, solve, update, refactor or krylov", strategy.c_str());
    opts->scene.strategy = *st;
  }
  PetscCheck(refresh >= 1 && refresh <= 1000000, comm, PETSC_ERR_ARG_OUTOFRANGE, "-scene_refresh must lie in [1, 1000000]");
  opts->scene.refresh_every = (int)refresh;
  PetscCheck(single_from >= -1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-scene_single_from must be -1 (never) or a number of switched unknowns");
  opts->scene.single_from = single_from < 0 ? INT_MAX : (int)single_from;
  PetscCheck(single_fields_from >= -1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-scene_single_fields_from must be -1 (never) or a number of switched unknowns");
  opts->scene.single_fields_from = single_fields_from < 0 ? INT_MAX : (int)single_fields_from;
  PetscCheck(opts->scene.krylov_rtol > 0 && opts->scene.krylov_rtol < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-scene_krylov_rtol must lie in (0, 1)");
  if (!mesh.empty()) opts->overrides.mesh = mesh;
  if (!output.empty()) opts->overrides.output = output;
  if (has_E) opts->overrides.E = E;
  if (has_nu) opts->overrides.nu = nu;
  opts->overrides.feature_angle_deg = feature_angle;
  const std::optional<OperatorType> type = parse_operator_type(mat_type);
  PetscCheck(type || mat_type == "auto", comm, PETSC_ERR_ARG_UNKNOWN_TYPE, "-bem_mat_type %s is not available; use auto, dense, h2 or hss", mat_type.c_str());
  opts->operator_type = type;
  /* auto reads (and checks) the options of both compressed formats: whichever it picks uses them */
  if (!type || *type == OperatorType::Hss || opts->help) {
    HssOptions hss;
    hss.rel_tol = 1e-8;
    PetscCall(HssbemHssOptionsFromDatabase(comm, NULL, &hss));
  }
  if (!type || *type == OperatorType::H2 || opts->help) {
    H2Options h2;
    PetscCall(HssbemH2OptionsFromDatabase(comm, NULL, &h2));
  }
  PetscCheck(quad.far_ratio == 0 || (type && !is_compressed(*type)), comm, PETSC_ERR_ARG_INCOMP,
             "-mat_bem_far_ratio must be 0 with -bem_mat_type %s: the 3-point far rule breaks the smooth far field the compression relies on (use -bem_mat_type dense)", mat_type.c_str());
  PetscCheck(quad.duffy_order >= 2 && quad.duffy_order <= 64, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_bem_quad_order must lie in [2, 64]");
  PetscCheck(quad.near_ratio > 0 && quad.near_ratio <= 100 && (quad.far_ratio == 0 || (quad.far_ratio >= quad.near_ratio && quad.far_ratio <= 1e6)), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "need -mat_bem_near_ratio in (0, 100] and -mat_bem_far_ratio either 0 (off) or in [-mat_bem_near_ratio, 1e6]");
  PetscCheck(quad.max_depth >= 0 && quad.max_depth <= 20, comm, PETSC_ERR_ARG_OUTOFRANGE, "-mat_bem_max_depth must lie in [0, 20]");
  PetscCheck(feature_angle > 0 && feature_angle < 180, comm, PETSC_ERR_ARG_OUTOFRANGE, "-bem_feature_angle must lie in (0, 180)");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/// Options that PETSc reads only at PetscFinalize() or that steer the run itself, and those of
/// a scene's GMRES (-scene_ksp_*).
bool is_late_option(const char *name)
{
  static const char *late[] = {"log_view", "options_left", "help", "malloc_dump", "malloc_debug", "memory_view", "log_view_memory", "log_trace", "info", "malloc", "checkstack", "objects_dump", "fp_trap", "options_view", "history"};
  for (const char *k : late)
    if (!std::strcmp(name, k)) return true;
  return !std::strncmp(name, "scene_ksp_", 10); /* a scene's GMRES reads them only if a frame takes the krylov strategy */
}

/// Options that PETSc reads only when the preconditioner is set up, inside KSPSolve(): those of
/// sub-solvers (-sub_pc_type of PCBJACOBI/PCASM, -fieldsplit_*, -redundant_*) and of external
/// factorization packages (-mat_mumps_icntl_14, ...). Checked after the solve instead.
bool is_set_up_time_option(const char *name)
{
  static const char *prefixes[] = {"sub_", "fieldsplit_", "redundant_", "mat_mumps_", "mat_superlu", "mat_scalapack_", "mat_strumpack_", "mat_cholmod_", "mat_umfpack_", "mat_klu_"};
  for (const char *p : prefixes)
    if (!std::strncmp(name, p, std::strlen(p))) return true;
  return false;
}

/// Options read only during or after KSPSolve()/MatAssemblyEnd() (viewers and reports), or when
/// the preconditioner is set up (is_set_up_time_option).
bool is_solve_time_option(const char *name)
{
  const std::string n(name);
  return n.find("view") != std::string::npos || n.find("converged_reason") != std::string::npos || is_set_up_time_option(name);
}

/* Errors out naming any option that no object has read (a typo such as -ksp_rtoll would
   otherwise be ignored); see check_unused_options(). */
PetscErrorCode CheckUnusedOptions_Private(MPI_Comm comm, bool before_solve)
{
  PetscInt    n;
  char      **names, **values;
  std::string unused;

  PetscFunctionBegin;
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  for (PetscInt i = 0; i < n; ++i)
    if (!is_late_option(names[i]) && !(before_solve && is_solve_time_option(names[i]))) unused += std::string(unused.empty() ? "" : ", ") + "-" + names[i];
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscCheck(unused.empty(), comm, PETSC_ERR_ARG_WRONG, "unknown or unused option(s): %s (run with -help to list the options)", unused.c_str());
  PetscFunctionReturn(PETSC_SUCCESS);
}

} // namespace

AppOptions read_app_options(MPI_Comm comm)
{
  AppOptions opts;
  HssbemCallThrow(ProcessOptions_Private(comm, &opts));
  HssbemCallThrow(InteriorOptionsFromDatabase_Private(comm, &opts.interior));
  return opts;
}

OperatorType choose_operator(long long unknowns, const MachineLimits &limits)
{
  if (unknowns < k_auto_dense_max_unknowns && size_refusal(OperatorType::Dense, unknowns, SizeOptions{}, limits).empty()) return OperatorType::Dense;
  return OperatorType::H2;
}

double read_error_timeout()
{
  PetscReal seconds = k_default_error_timeout;
  HssbemCallThrow(PetscOptionsGetReal(NULL, NULL, "-hssbem_error_timeout", &seconds, NULL));
  if (!(seconds > 0 && seconds <= k_max_error_timeout)) { /* NaN fails too */
    char text[160];
    std::snprintf(text, sizeof(text), "option -hssbem_error_timeout %g: the time-out must be positive and finite, at most %g seconds (default %g)", (double)seconds, k_max_error_timeout,
                  k_default_error_timeout);
    throw std::invalid_argument(text);
  }
  return seconds;
}

void check_unused_options(MPI_Comm comm, bool before_solve) { HssbemCallThrow(CheckUnusedOptions_Private(comm, before_solve)); }

} // namespace hssbem
