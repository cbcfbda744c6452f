/// \file contact_scene.hpp
/// The library API of contact for simulators: build once for a surface, a material, what holds
/// the bodies and the obstacles; then per frame place the obstacles, solve, and read the surface
/// displacement and traction, the contact pressure, status and forces — or, in a haptic loop,
/// only the obstacles' forces for new positions. Everything is in mesh vertex order.
///
///   std::vector<hssbem::Obstacle> tools{hssbem::Obstacle::plane("table", {0, 0, -1}, {0, 0, 1}),
///                                       hssbem::Obstacle::sphere("tool", {0, 0, 1.3}, 0.3)};
///   hssbem::ContactScene scene(mesh, hssbem::Material::from_young(3000, 0.45), held, tools);
///   for (;;) {                                        // each frame of the simulation
///     scene.set_obstacle_offset("tool", tool_position - tool_base);   // or set_obstacle_pose("tool", pose)
///     scene.solve();
///     draw(scene.displacement(), scene.pressure());
///     for (int k = 0; k < 10; ++k)                    // the haptic loop, between frames
///       feel(scene.haptic_forces({{0, 0, 0}, tool_now - tool_base})[1]);
///   }
///
/// The scene is a face of the session layer (contact_session.hpp), as the driver's contact runs
/// are: the engine is contact_engine.hpp's over the reference factorization of the pattern
/// `held` that ContactSceneReference chooses — dense, H², one per body, or auto (dense while it
/// fits the machine's memory) — and the same problem gives the same numbers through either
/// face. Needs PetscInitialize() and HssbemInitializePackage() (the H² reference's GMRES and the
/// size check go through the PETSc face).
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/mesh/mesh.hpp"
#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/session/contact_session.hpp"

#include <optional>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace hssbem {

/// Which reference factorization a ContactScene stands on: what -bem_mat_type, -mat_h2_*,
/// -contact_h2_rtol and -contact_h2_factor_tol choose for the driver.
struct ContactSceneReference {
  /// Dense, H2 (every body), or none: auto (the bodies in order take the dense reference while
  /// they fit the machine's memory together, the others the H² one). Several bodies take one
  /// reference each (no integral across bodies).
  std::optional<OperatorType> type;
  H2Options h2;                                                         ///< the H² references' compression
  double h2_rtol = option_default::contact_h2_rtol;                     ///< their accurate solves' GMRES tolerance
  double h2_factor_tol = option_default::contact_h2_factor_tol;         ///< their factorization's tolerance
  /// A file ContactScene::save() wrote for the same scene: its precomputation is loaded instead
  /// of set up (a second start in seconds); refused (SavedFileError, naming what differs) when it
  /// was made for another mesh, material, pattern, candidates or options. Empty: set up.
  std::string load;
};

class ContactScene {
public:
  using Pattern = std::vector<std::array<bool, 3>>; ///< per vertex: displacement prescribed (else traction)

  /// The mesh must be valid, closed and oriented outward (validate_and_orient()); the scene keeps
  /// a copy. `held` says which displacement components are prescribed (the reference pattern); a
  /// body it leaves free is held by contact alone (pinned: floating_pins(); its rigid motion
  /// solved each step, a step refused when nothing it touches balances it). Throws
  /// std::invalid_argument for bad obstacles or sizes, std::runtime_error when the reference
  /// asked for does not fit the machine.
  ContactScene(const SurfaceMesh &mesh, const Material &material, const Pattern &held, std::vector<Obstacle> obstacles, const ContactSettings &settings = {},
               const ContactOptions &options = {}, double feature_angle_deg = option_default::bem_feature_angle, const ContactSceneReference &reference = {});
  ~ContactScene();
  ContactScene(const ContactScene &) = delete;
  ContactScene &operator=(const ContactScene &) = delete;

  /// The prescribed values (one per vertex): the displacement where `held`, a traction load
  /// elsewhere (default zero).
  void set_values(const std::vector<Vec3> &values);
  /// Obstacle `name` at its base position translated by `offset` (absolute, not cumulative).
  void set_obstacle_offset(const std::string &name, const Vec3 &offset);
  /// Obstacle `name` at `pose` (a turn about a centre and a translation of its base position;
  /// absolute, not cumulative): Pose::turn(axis, degrees, ObstacleGeometry::default_centre(), t).
  void set_obstacle_pose(const std::string &name, const Pose &pose);
  /// Every obstacle's offset, in the order given to the constructor.
  void set_obstacle_offsets(const std::vector<Vec3> &offsets);
  /// Every obstacle's pose, in the order given to the constructor.
  void set_obstacle_poses(const std::vector<Pose> &poses);

  /// Solves the frame; then the accessors below hold it.
  const ContactFrameReport &solve();
  const std::vector<Vec3> &displacement() const { return m_u; }
  const std::vector<Vec3> &traction() const { return m_t; }
  const std::vector<double> &pressure() const { return m_sol().pressure; }
  const std::vector<double> &gap() const { return m_sol().gap; }
  const std::vector<std::int8_t> &status() const { return m_sol().status; }
  /// Per obstacle, the force it exerts on the bodies; per body, the force of the other bodies.
  const std::vector<Vec3> &obstacle_forces() const { return m_sol().obstacle_force; }
  const std::vector<Vec3> &body_forces() const { return m_sol().body_force; }
  /// The vertices touching (status not 0), ascending.
  std::vector<int> active_vertices() const;

  /// The haptic call: each obstacle's force for new offsets (or poses), with the last solve's
  /// contact points and active set (one small solve with the factored active block; with
  /// friction the obstacles' tangential motion drags as in a frame; a retracting tool feels no
  /// pulling force). Throws std::runtime_error after a failed solve.
  std::vector<Vec3> haptic_forces(const std::vector<Vec3> &offsets) { return m_session->haptic_forces(offsets); }
  std::vector<Vec3> haptic_forces(const std::vector<Pose> &poses) { return m_session->haptic_forces(poses); }

  /// Saves the precomputation (the dense references and the columns of W computed so far) to
  /// `path`, for a later scene's ContactSceneReference::load (docs/persistence.md). Throws
  /// std::invalid_argument on an H² reference (not saved yet), OutputError when it cannot write.
  void save(const std::string &path) const { m_session->save(path); }

  int obstacle_index(const std::string &name) const;
  const Discretization &discretization() const { return m_problem->disc(); }
  const ContactEngine &engine() const { return m_session->engine(); }
  /// The session it is a face of (its reference: session().reference(), session().mat_type()).
  ContactSession &session() { return *m_session; }
  const ContactSession &session() const { return *m_session; }

private:
  const ContactSolution &m_sol() const { return m_session->solution(); }

  std::shared_ptr<const SessionProblem> m_problem;
  std::unique_ptr<ContactSession> m_session;
  SystemSelection m_sel;
  std::vector<Pose> m_poses;
  std::vector<Vec3> m_u, m_t;
};

} // namespace hssbem
