// The driver's options (see options.hpp): read once by their rows of the table of options
// (petsc/options.h), -help from the table, -version, and the check that every option was used.
// PETSc's option macros need functions that return a PetscErrorCode: CheckUnusedOptions_Private
// is written like PETSc code, and check_unused_options() turns its error code into an exception.
#include "hssbem/app/options.hpp"

#include "hssbem/petsc/options.h"
#include "hssbem/petsc/system.h"
#include "hssbem/session/petsc_call.hpp"

#include <H5public.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#ifndef HSSBEM_GIT_REVISION
#define HSSBEM_GIT_REVISION "unknown"
#endif
#ifndef HSSBEM_BUILD_TYPE
#define HSSBEM_BUILD_TYPE "unknown"
#endif

namespace hssbem {

namespace {

/// Options that PETSc reads only at PetscFinalize() or that steer the run itself, and those of
/// the GMRES a scene's krylov strategy and an H² reference's accurate solves create when they
/// need one (-scene_ksp_*, -contact_h2_ksp_*).
bool is_late_option(const char *name)
{
  static const char *late[] = {"log_view", "options_left", "help", "malloc_dump", "malloc_debug", "memory_view", "log_view_memory", "log_trace", "info", "malloc", "checkstack", "objects_dump", "fp_trap", "options_view", "history"};
  for (const char *k : late)
    if (!std::strcmp(name, k)) return true;
  return !std::strncmp(name, "scene_ksp_", 10) || !std::strncmp(name, "contact_h2_ksp_", 15);
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

/// The value given for `name`, or its default.
const OptionValue &given_or_default(const OptionValues &given, const char *name, OptionValue &fallback)
{
  const auto it = given.find(name);
  if (it != given.end()) return it->second;
  fallback = OptionValue::default_of(*find_option(name));
  return fallback;
}

} // namespace

DriverOptions read_driver_options(MPI_Comm comm)
{
  OptionValues given;
  HssbemCallThrow(HssbemOptionsGetValues(comm, NULL, OptionReader::Driver, kEvery, &given));
  HssbemCallThrow(HssbemOptionsGetValues(comm, NULL, OptionReader::System, kEvery, &given));
  DriverOptions o;
  o.session = session_options(given);
  OptionValue d;
  o.problem = given_or_default(given, "problem", d).text;
  if (given.count("mesh")) o.overrides.mesh = given.at("mesh").text;
  if (given.count("o")) o.overrides.output = given.at("o").text;
  if (given.count("E")) o.overrides.E = given.at("E").number;
  if (given.count("nu")) o.overrides.nu = given.at("nu").number;
  o.overrides.feature_angle_deg = given_or_default(given, "bem_feature_angle", d).number;
  o.scene_monitor = given_or_default(given, "scene_monitor", d).number != 0;
  o.scene_keep_partial = given_or_default(given, "scene_keep_partial", d).number != 0;
  o.contact_monitor = given_or_default(given, "contact_monitor", d).number != 0;
  o.save = given_or_default(given, "hssbem_save", d).text;
  o.load = given_or_default(given, "hssbem_load", d).text;
  o.help = given_or_default(given, "help", d).number != 0;
  return o;
}

void print_help(MPI_Comm comm, unsigned jobs)
{
  const std::string text = "hssbem's options (" + (jobs == kEvery ? std::string("every job") : "this problem's job: " + option_jobs_text(jobs)) +
                           "; the default in <>, the values it takes in []):\n" + option_help(jobs);
  HssbemCallThrow(PetscPrintf(comm, "%s", text.c_str()));
}

void print_version(MPI_Comm comm)
{
  char petsc[128], mpi[MPI_MAX_LIBRARY_VERSION_STRING];
  int  len = 0;
  unsigned h5_major = 0, h5_minor = 0, h5_release = 0;
  HssbemCallThrow(PetscGetVersion(petsc, sizeof(petsc)));
  HssbemCallMPIThrow(MPI_Get_library_version(mpi, &len));
  std::string mpi_line(mpi, static_cast<std::size_t>(len));
  mpi_line = mpi_line.substr(0, mpi_line.find_first_of("\n,"));
  if (H5get_libversion(&h5_major, &h5_minor, &h5_release) < 0) throw std::runtime_error("HDF5 does not say its version");
  HssbemCallThrow(PetscPrintf(comm, "hssbem %s (git %s, %s build)\n%s\nMPI: %s\nHDF5 %u.%u.%u\n", HSSBEM_VERSION, HSSBEM_GIT_REVISION, HSSBEM_BUILD_TYPE, petsc,
                              mpi_line.c_str(), h5_major, h5_minor, h5_release));
}

double read_error_timeout()
{
  const OptionRow *row = find_option("hssbem_error_timeout");
  OptionValue      v   = OptionValue::default_of(*row);
  PetscBool        set;
  HssbemCallThrow(HssbemOptionsGetValue(PETSC_COMM_SELF, NULL, *row, &v, &set));
  return v.number;
}

void check_unused_options(MPI_Comm comm, bool before_solve) { HssbemCallThrow(CheckUnusedOptions_Private(comm, before_solve)); }

} // namespace hssbem
