/// \file main.hpp
/// The driver's one error path. Between PetscInitialize() and PetscFinalize(), driver_main()
/// runs the application (app/run.hpp) so that every failure — problem file, mesh, option
/// (PETSc's own checks and the unused-option check included), factorization breakdown, diverged
/// solve, allocation failure, I/O, on one rank or on all — ends the same way: one line
/// `hssbem: error: <what>` on rank 0's standard error, exit status 1 on every rank, and no PETSc
/// traceback (PETSc's error handler returns instead of printing; -hssbem_traceback keeps its
/// traceback for debugging). The caller then calls PetscFinalize() on every rank.
#pragma once

#include <mpi.h>

#include <string>

namespace hssbem {

/// Removes -version and --version from the command line before PetscInitialize() sees them (it
/// would print PETSc's banner for -version and go on) and says whether one was there.
bool take_version_option(int *argc, char **argv);

/// Run the driver on comm and return the exit status (0, or 1 after an error); with `version`,
/// print the versions instead (print_version()). Errors are made collective where they arise
/// (run_collectively, HssbemGuard); as a last resort, a rank whose error the other ranks do not
/// join within -hssbem_error_timeout seconds (they are stuck in a collective call it left) prints
/// its message and calls MPI_Abort.
int driver_main(MPI_Comm comm, bool version = false);

/// `message` with the option at fault named, when it is PETSc's complaint about a value it
/// cannot parse ("Input string abc has no numeric value" does not say which option had it).
std::string name_the_option(const std::string &message);

} // namespace hssbem
