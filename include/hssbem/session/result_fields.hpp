/// \file result_fields.hpp
/// The one builder of a solution's fields, for every job and face: what a result file holds
/// (io/hdf5_output.hpp: ResultData for a solve, FrameData for a frame), what the library's scenes
/// hand out per vertex, and what the Python module will show as arrays. From a solution per dof
/// node (u and t, post/post.hpp): the vertex fields, the corners' tractions, the prescribed
/// components, the reactions per region, the surface stress (post/surface_stress.hpp), and inside
/// the body the displacement and stress at the problem's interior points and grid (Somigliana's
/// identities, evaluated fast over the ranks: interior/interior_evaluation.hpp, near the surface
/// post/near_surface.hpp).
#pragma once

#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/post/post.hpp"
#include "hssbem/post/surface_stress.hpp"
#include "hssbem/problem/setup.hpp"
#include "hssbem/session/options.hpp"

#include <mpi.h>

#include <map>
#include <string>
#include <vector>

namespace hssbem {

/// Which fields surface_fields() builds (or'ed). Motion alone is what a simulator reads per
/// frame; a scene's frame adds the prescribed components and the stress; a whole result adds
/// the corners (tractions and stress) and the reactions.
enum FieldParts : unsigned {
  kMotion = 1,     ///< displacement and traction per vertex (the mean over its dof nodes)
  kPrescribed = 2, ///< the prescribed components per vertex
  kStress = 4,     ///< the surface stress per vertex (and per dof node, for the interior)
  kWhole = 8,      ///< the corners' tractions and stress, and the reactions per region
  kFrameFields = kMotion | kPrescribed | kStress,
  kResultFields = kMotion | kPrescribed | kStress | kWhole,
};

/// A solution's surface fields, in mesh vertex order (corners: triangle order).
struct SurfaceFields {
  std::vector<Vec3> displacement, traction;
  std::vector<std::array<Vec3, 3>> traction_corner;
  std::vector<std::array<bool, 3>> displacement_prescribed;
  std::map<std::string, Vec3> reactions;
  StressFields stress;
  std::vector<NodeStress> nodes; ///< the stress per dof node (what the interior evaluation starts from)
};

/// The fields `parts` of the solution `sol` (per dof node) of problem `s`, whose prescribed
/// components per vertex are `prescribed` (kPrescribed). The stress's seconds go to
/// seconds["stress"] when given (an event BEM_Stress times it).
SurfaceFields surface_fields(const ProblemSetup &s, const NodalSolution &sol, const std::vector<std::array<bool, 3>> &prescribed, unsigned parts,
                             std::map<std::string, double> *seconds = nullptr);

/// The fields into a result (all of them) or a frame (those a frame holds); moves them.
void put_fields(SurfaceFields &&f, ResultData &r);
void put_fields(SurfaceFields &&f, FrameData &frame);

/// The part of a result file that describes the problem and the run, whatever solved it: the
/// mesh (/mesh/...: vertices, triangles, regions, sharp vertices) and the root attributes of the
/// material, the sizes, the number of ranks, the versions and the input files.
ResultData result_base(const ProblemSetup &s, int ranks);

/// The options a run used, into the result file (/options: one attribute per option, named
/// without its dash).
void put_options(const OptionValues &values, ResultData &r);

/// A contact solution's /contact (or /frames/<i>/contact): pressure, gap, status, the forces per
/// obstacle and, with `bodies`, per body (body_<k>), and the frame's iterations.
ContactData contact_data(const ContactEngine &engine, const ContactSolution &sol, const ContactFrameReport &rep, bool bodies);

/// Refuses an explicit interior point that lies outside the body (points on its surface are
/// accepted): ProblemError naming the point.
void check_interior_points(const ProblemSetup &s);

/// Displacement and stress at the problem's interior points and grid points into r (interior_*),
/// NaN at grid points outside the body; the evaluation's points are shared out over the ranks of
/// comm and the values summed (collective). `nodes`: the stress per dof node (SurfaceFields).
/// Adds the time to seconds["interior"].
void interior_fields(MPI_Comm comm, const ProblemSetup &s, const NodalSolution &sol, const std::vector<NodeStress> &nodes, const InteriorRunOptions &o,
                     ResultData &r, std::map<std::string, double> &seconds);

} // namespace hssbem
