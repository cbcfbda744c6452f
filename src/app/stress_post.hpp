// Private to app/: the stress in a result file. The surface's stress fields (from the traction and
// the tangential gradient of the displacement, post/surface_stress.hpp) and, inside the body, the
// displacement and stress at the problem's interior points and grid (Somigliana's identities,
// evaluated fast over the ranks: interior/interior_evaluation.hpp, near the surface
// post/near_surface.hpp).
#pragma once

#include "hssbem/app/options.hpp"
#include "hssbem/post/post.hpp"
#include "hssbem/post/surface_stress.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/problem/setup.hpp"

#include <petscsys.h>

#include <map>
#include <string>
#include <vector>

namespace hssbem {

/// The surface's stress fields of a solution, with the stress at each dof node in `nodes`; the
/// corners (nt × 3 × 6) only when `corners` (result files, not frames).
StressFields surface_stress_fields(const ProblemSetup &s, const NodalSolution &sol, std::vector<NodeStress> &nodes, bool corners);

/// Refuses an explicit interior point that lies outside the body (points on its surface are
/// accepted): ProblemError naming the point.
void check_interior_points(const ProblemSetup &s);

/// Displacement and stress at the problem's interior points and grid points into r (interior_*),
/// NaN at grid points outside the body; the evaluation's points are shared out over the ranks of
/// comm and the values summed (collective). Adds the time to seconds["interior"].
void interior_fields(MPI_Comm comm, const ProblemSetup &s, const NodalSolution &sol, const std::vector<NodeStress> &nodes, const InteriorRunOptions &o,
                     ResultData &r, std::map<std::string, double> &seconds);

/// Read the -bem_interior_* options (with -help, list them).
PetscErrorCode InteriorOptionsFromDatabase_Private(MPI_Comm comm, InteriorRunOptions *o);

} // namespace hssbem
