/// \file scene.hpp
/// The library API for simulators: build a scene once for a surface and a material, then per
/// frame set the boundary-condition pattern and the values, solve, and read the surface
/// displacement and traction — or only the forces on the contact (the haptic loop). Everything
/// is in mesh vertex order; the dof nodes of a sharp vertex (double nodes) share its conditions.
///
///   hssbem::Scene scene(mesh, hssbem::Material::from_young(3000, 0.49), clamped);
///   scene.save("organ.pre");                     // the next start: Scene(..., "organ.pre") loads it
///   for (;;) {                                   // each frame of the simulation
///     scene.set_pattern(prescribed);             // per vertex and component: u prescribed?
///     scene.set_values(values);                  // u where prescribed, t elsewhere
///     scene.solve();                             // or scene.contact_forces() alone
///     use(scene.displacement(), scene.traction());
///   }
///
/// The work per frame is the scene engine's (dense_scene.hpp): a Woodbury update of the
/// reference factorization when the pattern changed, a solve with it when only the values did.
/// The scene is a face of the session layer (scene_session.hpp), as the driver's scenes are:
/// the same problem gives the same numbers through either. Needs PetscInitialize() (the size
/// check reads the machine through the PETSc face).
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/mesh/mesh.hpp"
#include "hssbem/scene/dense_scene.hpp"
#include "hssbem/session/scene_session.hpp"

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace hssbem {

class Scene {
public:
  using Pattern = std::vector<std::array<bool, 3>>; ///< per vertex: displacement prescribed (else traction)

  /// The mesh must be a valid closed surface, oriented outward (validate_and_orient()); the
  /// scene keeps a copy. `reference` is the pattern factored once (e.g. the clamped base with the
  /// rest traction-free); it must hold the body. Pressure loads are not part of this API.
  /// `candidate_vertices` (one entry per vertex, or empty: all) names the vertices whose
  /// conditions a frame may switch or load with a non-zero value: the engine computes W only for
  /// them (a contact region: set-up time and memory in proportion), and a frame beyond them is
  /// refused (std::invalid_argument). options.candidates (per unknown) must be left empty. A
  /// scene that does not fit the machine's memory is refused before anything is allocated.
  /// `load` (a file save() wrote for a scene of the same mesh, material, reference, candidates
  /// and options): its precomputation instead of the set-up (SceneSession::load(); a file made
  /// for another scene is refused with SavedFileError naming the difference).
  Scene(const SurfaceMesh &mesh, const Material &material, const Pattern &reference, const SceneOptions &options = {},
        std::unique_ptr<KrylovSolver> krylov = nullptr, double feature_angle_deg = option_default::bem_feature_angle, const std::vector<char> &candidate_vertices = {},
        const std::string &load = {});
  ~Scene();
  Scene(const Scene &) = delete; // the discretization points into the scene's copy of the mesh
  Scene &operator=(const Scene &) = delete;

  /// The precomputation saved to `path` (docs/persistence.md), to be given as `load` next time.
  void save(const std::string &path) const { m_session->save(path); }

  /// The pattern of the next frames (one entry per vertex). Throws std::invalid_argument on a
  /// size mismatch.
  void set_pattern(const Pattern &displacement_prescribed);
  /// The prescribed values (one Vec3 per vertex): displacement where prescribed, traction elsewhere.
  void set_values(const std::vector<Vec3> &values);

  /// Solve the current frame; then displacement() and traction() hold it.
  const SceneFrameReport &solve();
  const std::vector<Vec3> &displacement() const { return m_u; }
  const std::vector<Vec3> &traction() const { return m_t; }

  /// The haptic loop, after a solve() with the same pattern: the force (traction × the vertex's
  /// lumped area, summed over its dof nodes) on every vertex with a component whose type differs
  /// from the reference (the contact), for the current values; O(|J| · nonzero values) instead
  /// of a full solve. Components that are not switched are 0.
  struct VertexForce {
    int vertex;
    Vec3 force;
  };
  std::vector<VertexForce> contact_forces();

  const Discretization &discretization() const { return m_problem->disc(); }
  const DenseScene &engine() const { return m_session->engine(); }
  /// The session it is a face of.
  SceneSession &session() { return *m_session; }

private:
  SystemSelection selection() const;

  std::shared_ptr<const SessionProblem> m_problem;
  std::unique_ptr<SceneSession> m_session;
  Pattern m_pattern;
  std::vector<Vec3> m_values, m_u, m_t;
  std::vector<double> m_area; ///< lumped area per dof node
};

} // namespace hssbem
