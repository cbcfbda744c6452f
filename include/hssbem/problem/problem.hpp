/// \file problem.hpp
/// The problem file (JSON): mesh, material, boundary rules, interior points, output, and the
/// frames of a scene (each frame's rules on top of the base rules).
#pragma once

#include "hssbem/bem/discretization.hpp"
#include "hssbem/bem/kelvin.hpp"
#include "hssbem/mesh/mesh.hpp"
#include "hssbem/mesh/obstacle_shape.hpp"

#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem {

/// Any problem with the problem file or its boundary rules; the message names the file and the
/// rule (by index, 0-based) at fault.
class ProblemError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// What a rule selects (one of the alternatives is set).
struct Selector {
  enum class Kind { All, Region, Box, Sphere, Vertices } kind = Kind::All;
  std::string region_name; ///< Region: name, or empty when given by tag
  int region_tag = -1;     ///< Region: tag when given as a number
  Vec3 lo{}, hi{};         ///< Box
  Vec3 center{};           ///< Sphere
  double radius = 0;       ///< Sphere
  std::vector<int> vertices; ///< Vertices (0-based, file order)
};

/// One boundary rule: selector plus one of displacement / traction / pressure. Values are either one
/// row for all selected vertices or one row per selected vertex (in selection order: ascending
/// vertex index, which for "all" is mesh order); a NaN component means "null" (leave as it was).
struct BoundaryRule {
  enum class Kind { Displacement, Traction, Pressure } kind = Kind::Displacement;
  Selector where;
  std::vector<Vec3> rows;      ///< displacement / traction rows (size 1 or number selected)
  std::vector<double> pressure; ///< pressure values (size 1 or number selected)
};

/// A frame's "rotate" of an obstacle: the turn by `angle_deg` degrees (right-hand rule) about
/// `axis` through `about` (absent: the obstacle's default centre — a plane's point, a sphere's
/// centre, a mesh's centroid), before the frame's "translate".
struct ObstacleTurn {
  Vec3 axis{0, 0, 1};
  double angle_deg = 0;
  std::optional<Vec3> about;
};

/// One frame of a scene: its "boundary" rules, applied after the base rules (ProblemSpec::rules),
/// so that later rules win per node and component as within one list. No rules: the frame is the
/// base problem. A contact scene's frame also places obstacles: each named one at its base
/// position turned by `rotate` (if given) and translated by `translate` (absolute, not
/// cumulative: x ↦ R (x − c) + c + t); an obstacle not named stays at its base position.
struct FrameSpec {
  std::vector<BoundaryRule> rules;
  /// "gravity" of this frame (the patient turned): replaces the base's for this frame only;
  /// none: the base's (ProblemSpec::gravity, or no body force).
  std::optional<Vec3> gravity;
  std::vector<std::pair<std::string, Vec3>> obstacles; ///< "obstacles": {"name": {"translate": [dx, dy, dz]}} (zero when only "rotate" is given)
  std::map<std::string, ObstacleTurn> turns;           ///< "obstacles": {"name": {"rotate": {"axis": [..], "angle": deg, "about": [..]}}}
};

/// "contact": contact as physics (contact/): rigid obstacles, contact between the mesh's bodies.
struct ContactSpec {
  bool present = false;                  ///< the problem file has a "contact" object
  std::vector<Obstacle> obstacles;       ///< "obstacles" (default none; a mesh obstacle's triangles read by the set-up, setup.hpp)
  double friction = 0;                   ///< "friction": Coulomb coefficient of every pair (0: frictionless)
  bool bodies = false;                   ///< "bodies": contact between the mesh's separate bodies too
  std::optional<Selector> where;         ///< "where": candidate vertices (default all)
};

/// A regular grid of interior points ("interior_points": {"grid": {"box": [[lo], [hi]], "cells":
/// [nx, ny, nz]}}): cells[a] + 1 points along axis a from lo[a] to hi[a], numbered x fastest,
/// then y, then z.
struct InteriorGrid {
  Vec3 lo{}, hi{};
  std::array<int, 3> cells{};
  /// Points per axis (cells + 1).
  std::array<int, 3> points_per_axis() const { return {cells[0] + 1, cells[1] + 1, cells[2] + 1}; }
  long long num_points() const { return 1LL * (cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1); }
  Vec3 spacing() const { return {(hi[0] - lo[0]) / cells[0], (hi[1] - lo[1]) / cells[1], (hi[2] - lo[2]) / cells[2]}; }
  /// Every point, x fastest.
  std::vector<Vec3> points() const;
};

/// The most points a grid may have (its fields take about 100 bytes per point).
constexpr long long max_grid_points = 50'000'000;

/// Parsed problem file, before it meets a mesh. Paths are resolved relative to the file.
struct ProblemSpec {
  std::string file;            ///< problem file path (for messages)
  std::string mesh_path;
  std::optional<double> E, nu, lambda, mu;
  std::optional<double> density;  ///< "material.density": mass per volume (≥ 0), needed by gravity
  std::optional<Vec3> gravity;    ///< "gravity": acceleration; the body force is density × gravity
  std::vector<BoundaryRule> rules; ///< base rules ("boundary")
  std::vector<FrameSpec> frames;   ///< "frames" in file order; empty: an ordinary single solve
  ContactSpec contact;             ///< "contact"; contact.present false: none
  std::vector<Vec3> interior_points;  ///< explicit points: each must lie inside the body
  std::optional<InteriorGrid> interior_grid; ///< grid points: those outside the body are masked
  std::string output;          ///< may be empty
};

/// Parse a problem file. Throws ProblemError (file, key at fault) on malformed input.
ProblemSpec read_problem(const std::string &path);
/// Parse from a JSON string (for tests); `origin` is used in messages and to resolve paths.
ProblemSpec parse_problem(const std::string &json_text, const std::string &origin);

/// `spec` with one frame, parsed from JSON in the grammar of one element of "frames" (a frame
/// given on its own: the Python module's Scene.step); `what` names it in messages ("frame").
/// Throws ProblemError as parse_problem does.
ProblemSpec parse_frame(const ProblemSpec &spec, const std::string &json_text, const std::string &what);

/// The vertices a selector picks (ascending), for selectors outside boundary rules (the
/// contact's "where"); `what` names it in messages ("contact.where"). Throws ProblemError for a
/// selection that is empty, an unknown region or a vertex index out of range.
std::vector<int> select_vertices(const Selector &where, const SurfaceMesh &mesh, const std::string &origin, const std::string &what);

/// Boundary condition per vertex and component, in mesh order.
struct VertexConditions {
  std::vector<std::array<bool, 3>> displacement_prescribed; ///< else traction prescribed
  std::vector<Vec3> value;          ///< displacement or traction value
  std::vector<double> pressure;     ///< pressure p for components set by a pressure rule (NaN else)
  std::vector<std::array<bool, 3>> from_pressure; ///< component was last set by a pressure rule
};

/// Apply the rules in order (later rules win per vertex and component). Throws ProblemError for a
/// rule that selects no vertex, an out-of-range vertex index, a row count that does not match, or
/// an unknown region; the message names `origin` and the rule as `<list>[k]`, where `list` is the
/// JSON path of the rule list ("boundary", or "frames[3].boundary" for a frame's own rules).
VertexConditions apply_rules(const std::vector<BoundaryRule> &rules, const SurfaceMesh &mesh,
                             const std::string &origin, const std::string &list = "boundary");

/// Boundary condition per dof node and component (what the solver sees). Pressure becomes
/// traction -p n with the normal of each node's smooth group.
struct NodeConditions {
  std::vector<std::array<bool, 3>> displacement_prescribed;
  std::vector<Vec3> value;
  /// Pressure p of nodes whose three components come from a pressure rule (NaN otherwise): the
  /// solver loads their triangles with -p n of each flat triangle, exact on the polyhedron.
  std::vector<double> pressure;
  int num_displacement_prescribed() const;
  /// The boundary-condition pattern per unknown (3 · node + component): 1 where u is known, 0
  /// where t is (a reference factorization's S₀: reference/reference.hpp).
  std::vector<char> unknown_pattern() const;
};
NodeConditions node_conditions(const VertexConditions &vc, const Discretization &disc);

/// Apply the rules straight to dof nodes (what the solver uses). As apply_rules, except that a
/// traction or pressure rule on a region reaches only the nodes of a sharp vertex whose smooth
/// group has a triangle in the region, so a load on one face of a cube leaves the neighbouring
/// faces' copies of the edge vertices as they were. Same errors as apply_rules.
NodeConditions apply_rules(const std::vector<BoundaryRule> &rules, const Discretization &disc, const std::string &origin,
                           const std::string &list = "boundary");

/// Node conditions of frame `frame` of a scene: the base rules (spec.rules), then the frame's own
/// rules, in one pass (later rules win per node and component; a null component of a frame rule
/// keeps the base's value). Errors are those of apply_rules, naming `spec.file` and the rule as
/// "boundary[k]" (a base rule) or "frames[<frame>].boundary[k]" (a rule of the frame). Throws
/// std::out_of_range when `frame` >= spec.frames.size().
NodeConditions frame_conditions(const ProblemSpec &spec, std::size_t frame, const Discretization &disc);

} // namespace hssbem
