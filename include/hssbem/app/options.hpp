/// \file options.hpp
/// The driver's command line: hssbem's options (core/option_table.def) read once from the PETSc
/// options database and handed down typed (the session's SessionOptions, the driver's own
/// choices); -help and -version; the check that every option given was used. PETSc's own objects
/// (the main KSP, PC h2, PC hss) read theirs in their SetFromOptions.
#pragma once

#include "hssbem/core/option_table.hpp"
#include "hssbem/problem/setup.hpp"
#include "hssbem/session/options.hpp"

#include <mpi.h>

#include <string>

namespace hssbem {

/// Everything the command line sets besides the PETSc objects' options.
struct DriverOptions {
  std::string problem;        ///< -problem: the problem file (required unless -help or -version)
  ProblemOverrides overrides; ///< -mesh, -o, -E, -nu, -bem_feature_angle: they win over the problem file
  SessionOptions session;     ///< what the job's session takes (operator, quadrature, compressions, scene, contact, interior)
  bool scene_monitor = option_default::scene_monitor;           ///< -scene_monitor: one line per frame
  bool scene_keep_partial = option_default::scene_keep_partial; ///< -scene_keep_partial: a failed frame commits the frames before it
  bool contact_monitor = option_default::contact_monitor;       ///< -contact_monitor: one line per iteration
  std::string save{option_default::hssbem_save};               ///< -hssbem_save: the precomputation's file, written after the set-up
  std::string load{option_default::hssbem_load};               ///< -hssbem_load: the precomputation's file, read instead of the set-up
  bool help = false;          ///< -help
};

/// Reads every option of the driver and of the system builder that the database gives (each
/// checked against the table's range, then the rules between them: session_options()). Throws
/// PetscFailure (session/petsc_call.hpp) for a value PETSc cannot parse, std::invalid_argument
/// naming the option for one out of range.
DriverOptions read_driver_options(MPI_Comm comm);

/// -help: the options of the jobs `jobs` (OptionJob bits; kEvery without a problem file), from
/// the table, on rank 0's standard output.
void print_help(MPI_Comm comm, unsigned jobs);

/// -version / --version: hssbem's version and git revision (at configure time), the PETSc, MPI
/// and HDF5 libraries' versions and the build type, on rank 0's standard output.
void print_version(MPI_Comm comm);

/// The value of -hssbem_error_timeout (the table's default when not given). Throws PetscFailure
/// for a value PETSc cannot parse and std::invalid_argument for one outside its range, (0, a
/// day] (NaN included): 0 or less would abort successful runs, NaN and infinity would wait
/// forever.
double read_error_timeout();

/// Error out on options nobody used, naming them: typos must not pass silently. With
/// before_solve, options that are read only during or after the solve (viewers, converged
/// reason, sub-solvers, factorization packages) are let through; the check after the solve
/// catches everything. Throws PetscFailure (PETSC_ERR_ARG_WRONG), with PETSc's message printed.
void check_unused_options(MPI_Comm comm, bool before_solve);

} // namespace hssbem
