/// \file setup.hpp
/// From a problem file (and command-line overrides) to everything the solver needs: validated
/// mesh, material, dof nodes and the boundary-condition selection, with rigid modes handled.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/body_force.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/problem/problem.hpp"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hssbem {

/// Values given on the command line; they win over the problem file.
struct ProblemOverrides {
  std::optional<std::string> mesh, output;
  std::optional<double> E, nu;
  double feature_angle_deg = option_default::bem_feature_angle;
  /// A mesh made in memory (the Python module's arrays) instead of the file the problem names:
  /// validated as a mesh read from a file, and no input file of the run.
  std::shared_ptr<const SurfaceMesh> mesh_data;
};

struct ProblemSetup {
  ProblemSpec spec;
  std::unique_ptr<SurfaceMesh> mesh;         ///< owned on the heap: disc points into it
  std::unique_ptr<Discretization> disc;
  Material material;
  std::vector<std::array<bool, 3>> vertex_displacement_prescribed; ///< per mesh vertex, for output
  /// The selection of the system the solver takes: the boundary data of the homogeneous problem,
  /// that is, the rules' values less the traces of the body force's particular solution
  /// (homogeneous_selection(); the rules' values themselves without a body force).
  SystemSelection selection;
  /// The body force of the base problem (density × gravity; zero without gravity), its origin the
  /// centroid of the mesh's vertices. Every field of the result adds its particular solution.
  UniformBodyForce body_force;
  /// Pure traction (no displacement prescribed, balanced load): the system is regularised along
  /// the rigid modes and the rigid motion is removed from the result.
  bool pure_traction = false;
  std::vector<std::string> notices;
  std::string output;
  /// The files the run reads (the problem file, the mesh): the result may not replace any of them.
  std::vector<std::string> input_files;
};

/// Read, validate and prepare. A scene (frames) is validated whole here, before any frame is
/// solved: every frame's rules applied and its constraints checked (check_every_frame). Throws
/// MeshError, ProblemError, ConstraintError or std::invalid_argument (material), each naming the
/// file and the item at fault.
ProblemSetup setup_problem(const std::string &problem_file, const ProblemOverrides &overrides);

/// Same, from a parsed specification (tests build one in code).
ProblemSetup setup_problem(ProblemSpec spec, const ProblemOverrides &overrides);

/// A problem made in memory (a simulator's surface: the library's Scene and ContactScene): a
/// copy of `mesh` (a valid closed surface, oriented outward: validate_and_orient()), its dof nodes
/// and the material; no file, no rules (the selection leaves every unknown traction-free: a
/// session takes its conditions separately).
ProblemSetup setup_in_memory(const SurfaceMesh &mesh, const Material &material, double feature_angle_deg = option_default::bem_feature_angle);

/// A scene (spec.frames not empty) or a contact problem (spec.contact.present, whose bodies are
/// checked one by one by the contact set-up) skips the base problem's constraint check in setup_problem;
/// each frame's pattern goes through this one instead: true when the prescribed displacements
/// fix all six rigid motions, else ConstraintError naming `what` (e.g. "frames[3]").
bool check_frame_constraints(const ProblemSetup &s, const std::vector<std::array<bool, 3>> &displacement_known, const std::string &what);

/// Every frame of the scene `s`, in order: its rules applied (frame_conditions) and its
/// constraints checked (check_frame_constraints), so that a bad frame is refused before frame 0
/// is solved. Throws the first frame's error (ProblemError, ConstraintError).
void check_every_frame(const ProblemSetup &s);

/// The system's selection (what the BEM system builder takes) of a set of node conditions.
SystemSelection selection_of(const NodeConditions &nc);

/// The body force of frame `frame` of the scene `s`: the frame's "gravity" when it gives one,
/// else the base's (s.body_force); same origin. Throws std::out_of_range for a frame past the end.
UniformBodyForce frame_body_force(const ProblemSetup &s, std::size_t frame);

/// Per mesh vertex, the components whose displacement `nc` prescribes (those of the vertex's
/// first dof node; none for a vertex without nodes): the result file's displacement_prescribed.
std::vector<std::array<bool, 3>> vertex_displacement_prescribed(const Discretization &disc, const NodeConditions &nc);

/// Relative load imbalance above which a pure-traction problem is refused.
constexpr double max_load_imbalance = 1e-2;

} // namespace hssbem
