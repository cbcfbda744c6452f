/// \file run.hpp
/// The hssbem driver: the command line read (app/options.hpp), the problem file set up, the
/// job's session made (session/: a static solve, a scene or a contact) and run, what it did
/// printed, and the result file written. The work itself is the session layer's; the driver
/// only reads, prints and writes. Errors are C++ exceptions: ProblemError, MeshError,
/// OutputError, ... from the layers below with a message naming the file and the item at fault,
/// and PetscFailure (session/petsc_call.hpp) when PETSc reported the error itself.
#pragma once

#include "hssbem/app/options.hpp"
#include "hssbem/session/problem.hpp"

#include <mpi.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace hssbem {

/// The hssbem driver, after PetscInitialize() and HssbemInitializePackage(): read the options,
/// then solve the problem file, or with -help and no problem file list the options. Throws
/// std::runtime_error without a problem file.
void run_driver(MPI_Comm comm);

/// Solve one problem file end to end on comm with the command line's options: set up (mesh,
/// material, boundary conditions, the operator: every rank reads the same files), then the job
/// of the file — a static solve (run_static), a scene (run_scene) or a contact (run_contact) —
/// and its result file.
void run_problem(MPI_Comm comm, const DriverOptions &o);

/// The problem's one summary line (collective): its mesh, dof nodes, unknowns and ranks; `tail`
/// adds what the job says there (a static solve's operator).
void print_summary(MPI_Comm comm, const SessionProblem &problem, const std::string &tail);

/// -hssbem_save and -hssbem_load's files, checked before the set-up: the file saved is not the
/// result file (`output`), nor the file loaded. Throws std::invalid_argument.
void check_save_load(const DriverOptions &o, const std::string &output);

/// The files a saved precomputation may not overwrite: the problem's inputs and the file loaded;
/// throws OutputError when -hssbem_save names one of them.
std::vector<std::string> save_load_inputs(const DriverOptions &o, const ProblemSetup &s);

/// A static solve on every rank of comm (StaticSession), the result file written together.
/// `seconds` holds the set-up's times so far.
void run_static(MPI_Comm comm, const DriverOptions &o, std::shared_ptr<const SessionProblem> problem, std::map<std::string, double> seconds);

/// A scene (frames) on rank 0 (SceneSession), every frame checked and streamed into the result
/// file (/frames/<i>, FrameWriter), which appears complete at the end (-scene_keep_partial: the
/// frames before a failed one are committed, and the run still fails).
void run_scene(MPI_Comm comm, const DriverOptions &o, std::shared_ptr<const SessionProblem> problem, std::map<std::string, double> seconds);

/// A contact, once or frame by frame, on rank 0 (ContactSession), written as a result file with
/// /contact (single solve: and the interior points) or /frames/<i>/contact.
void run_contact(MPI_Comm comm, const DriverOptions &o, std::shared_ptr<const SessionProblem> problem, std::map<std::string, double> seconds);

} // namespace hssbem
