/// \file run.hpp
/// The hssbem application: problem file → operator → solve → post-processing → result file,
/// on top of the PETSc face (petsc/system.h). Errors are C++ exceptions: ProblemError,
/// MeshError, OutputError, ... from the layers below with a message naming the file and the
/// item at fault, and PetscFailure (app/petsc_call.hpp) when PETSc reported the error itself.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/quadrature.hpp"
#include "hssbem/core/operator_type.hpp"
#include "hssbem/app/options.hpp"
#include "hssbem/petsc/system.h"
#include "hssbem/problem/setup.hpp"

#include <mpi.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace hssbem {

/// The hssbem driver, after PetscInitialize() and HssbemInitializePackage(): read the options,
/// then solve the problem file, or with -help and no problem file list the solver's options.
/// Throws std::runtime_error without a problem file.
void run_driver(MPI_Comm comm);

/// Solve one problem file end to end on comm: set up (mesh, material, boundary conditions),
/// build the system with the operator of `type`, solve it with the main KSP, post-process and
/// write the result file (rank 0). Input errors are the same on every rank, since every rank
/// reads the same files.
/// With no type (-bem_mat_type auto), the operator is chosen by choose_operator() (app/options.hpp)
/// once the problem's size is known, and the log line says so.
/// A problem file with "frames" is a scene: see run_scene().
void run_problem(MPI_Comm comm, const std::string &problem_file, const ProblemOverrides &overrides, const QuadratureOptions &quad, std::optional<OperatorType> type,
                 const SceneRunOptions &scene = {}, const InteriorRunOptions &interior = {}, const ContactRunOptions &contact = {});

/// Solve a scene (s.spec.frames not empty) on rank 0 with the dense scene engine: the reference
/// pattern (the base rules, or frame 0's when they do not hold the body) factored once, then
/// every frame by the strategy of o (auto: the cost model's cheapest), each frame checked to hold
/// the body, streamed into the result file (/frames/<i>, FrameWriter) that appears complete at
/// the end. `seconds` holds the set-up's times so far. Throws for -bem_mat_type hss or h2 and
/// for a scene that does not fit the node's memory.
void run_scene(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, std::optional<OperatorType> asked, const SceneRunOptions &o, std::map<std::string, double> seconds);

/// Solve a contact problem (s.spec.contact.present), once or frame by frame, on rank 0 with the
/// contact engine (contact/contact_engine.hpp) over the reference factorization of the base
/// rules — dense, or H² (reference/h2_reference.hpp) with -bem_mat_type h2 or where dense does not
/// fit (auto; one body only): every body checked to be held, every frame's conditions checked to keep the base
/// pattern, the columns every frame needs computed in one block, then the frames, written as a
/// result file with /contact (single solve) or /frames/<i>/contact, the surface stress (and, for
/// a single solve, the interior points and grid: `interior`) as in any other run. Throws for -bem_mat_type
/// hss, for several bodies on the H² path and for a dense run that does not fit the node's memory.
void run_contact(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, std::optional<OperatorType> asked, const ContactRunOptions &o,
                 const InteriorRunOptions &interior, std::map<std::string, double> seconds);

/// Build the system of a prepared problem with the operator of `type` and solve it: the unknowns
/// (3 per dof node, node order) on rank 0 (empty elsewhere), or on every rank with to_all.
/// Fills info when given, and adds the seconds of the assembly and the solve to `seconds`.
std::vector<double> solve_problem(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, OperatorType type, bool to_all, HssbemSolveInfo *info = nullptr,
                                  std::map<std::string, double> *seconds = nullptr);

} // namespace hssbem
