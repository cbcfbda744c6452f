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
/// The engine is contact_engine.hpp's over the dense reference factorization (reference.hpp) of
/// the pattern `held`.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/mesh.hpp"
#include "hssbem/contact/contact_engine.hpp"

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace hssbem {

class ContactScene {
public:
  using Pattern = std::vector<std::array<bool, 3>>; ///< per vertex: displacement prescribed (else traction)

  /// The mesh must be valid, closed and oriented outward (validate_and_orient()); the scene keeps
  /// a copy. `held` says which displacement components are prescribed (the reference pattern):
  /// it must hold every body (check_bodies_held() throws ConstraintError otherwise). Throws
  /// std::invalid_argument for bad obstacles or sizes.
  ContactScene(const SurfaceMesh &mesh, const Material &material, const Pattern &held, std::vector<Obstacle> obstacles, const ContactSettings &settings = {},
               const ContactOptions &options = {}, double feature_angle_deg = 40.0);
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
  const std::vector<double> &pressure() const { return m_sol.pressure; }
  const std::vector<double> &gap() const { return m_sol.gap; }
  const std::vector<std::int8_t> &status() const { return m_sol.status; }
  /// Per obstacle, the force it exerts on the bodies; per body, the force of the other bodies.
  const std::vector<Vec3> &obstacle_forces() const { return m_sol.obstacle_force; }
  const std::vector<Vec3> &body_forces() const { return m_sol.body_force; }
  /// The vertices touching (status not 0), ascending.
  std::vector<int> active_vertices() const;

  /// The haptic call: each obstacle's force for new offsets (or poses), with the last solve's
  /// contact points and active set (one small solve with the factored active block; with
  /// friction the obstacles' tangential motion drags as in a frame; a retracting tool feels no
  /// pulling force). Throws std::runtime_error after a failed solve.
  std::vector<Vec3> haptic_forces(const std::vector<Vec3> &offsets) { return m_engine->haptic_forces(offsets); }
  std::vector<Vec3> haptic_forces(const std::vector<Pose> &poses) { return m_engine->haptic_forces(poses); }

  int obstacle_index(const std::string &name) const;
  const Discretization &discretization() const { return *m_disc; }
  const ContactEngine &engine() const { return *m_engine; }

private:
  SurfaceMesh m_mesh;
  std::unique_ptr<Discretization> m_disc;
  std::unique_ptr<BemOperator> m_op;
  std::unique_ptr<DenseReference> m_reference;
  std::unique_ptr<ContactEngine> m_engine;
  SystemSelection m_sel;
  std::vector<Pose> m_poses;
  std::vector<Vec3> m_u, m_t;
  ContactSolution m_sol;
};

} // namespace hssbem
