/// \file scene_session.hpp
/// A scene, whatever face drives it (the driver's problem file with "frames", the library's
/// Scene, the Python module): the reference pattern factored once on the dense scene engine
/// (scene/dense_scene.hpp), W for the unknowns some frame may switch or load, then frame after
/// frame the engine's strategy, and each frame's fields. On one rank (the driver runs it on
/// rank 0).
#pragma once

#include "hssbem/core/size_limits.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/scene/dense_scene.hpp"
#include "hssbem/session/fingerprint.hpp"
#include "hssbem/session/options.hpp"
#include "hssbem/session/problem.hpp"
#include "hssbem/session/result_fields.hpp"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace hssbem {

/// What a scene factors once: the reference pattern (its values unused) and, per unknown, the
/// candidates (1 where some frame may switch or load it: W is computed for those only; empty:
/// every unknown).
struct SceneReference {
  SystemSelection selection;
  std::string name;             ///< for messages: "the base rules", "frame 0", "the reference pattern"
  std::vector<char> candidates;
  bool pressure = false;        ///< some frame has pressure loads (W_p = A₀⁻¹ Gn)
  long long count() const;      ///< the candidates (every unknown when none are named)
  std::vector<char> pattern() const; ///< per unknown (3 · node + component), 1 where the selection prescribes u
};

/// The reference of a problem file's scene: the base rules where they hold the body, else
/// frame 0's; the candidates: the unknowns that some frame switches or loads (with a body
/// force, its homogeneous data: gravity loads every unknown its particular traces reach).
SceneReference scene_reference(const ProblemSetup &s);

/// What a scene must pass before anything is allocated (set_up() checks it too; the driver asks
/// it on every rank first): the dense scene engine (-bem_mat_type dense or auto) and its memory
/// on this machine. Throws std::runtime_error.
void check_scene(const SessionProblem &problem, const SceneReference &reference, const SessionOptions &options, const MachineLimits &limits);

class SceneSession {
public:
  /// `krylov`: the Krylov solver of the krylov strategy (petsc/scene_krylov.h; null: that
  /// strategy is refused). Throws for -bem_mat_type hss or h2 (scenes run on the dense engine).
  SceneSession(std::shared_ptr<const SessionProblem> problem, SceneReference reference, const SessionOptions &options, const MachineLimits &limits,
               std::unique_ptr<KrylovSolver> krylov = nullptr);
  ~SceneSession();
  SceneSession(const SceneSession &) = delete;
  SceneSession &operator=(const SceneSession &) = delete;

  /// The precomputation: the memory check, then the reference LU and W's candidate columns.
  void set_up();
  /// Whether set_up() or load() made the precomputation.
  bool is_set_up() const { return m_scene != nullptr; }
  /// The precomputation saved to `path` (not one of `inputs`; session/precomputation_file.hpp),
  /// after set_up(). Throws std::invalid_argument before it, OutputError when it cannot be written.
  void save(const std::string &path, const std::vector<std::string> &inputs = {}) const;
  /// Instead of set_up(): the precomputation saved in `path` for this problem (the frames are
  /// those of the set-up that saved it, to the bit). Throws SavedFileError for a file that is not
  /// one, is damaged or was made for another problem (naming the first difference).
  void load(const std::string &path);
  /// Solves a frame (the problem's dof nodes; its pattern may switch the candidates only), under
  /// the problem's body force (ProblemSetup::body_force); solution() then holds it. set_up()
  /// first when not done.
  const SceneFrameReport &step(const SystemSelection &frame);
  /// Frame i of the problem file, under its gravity (frame_body_force); its error is
  /// "<file>: frames[i]: <what>" (a solution that is not finite included).
  const SceneFrameReport &step(std::size_t i);

  /// The last frame's solution per dof node, its selection and its report. With a body force,
  /// the solution and the selection are the homogeneous problem's (bem/body_force.hpp) and
  /// body_force() the frame's: surface_fields() adds its particular solution.
  const NodalSolution &solution() const { return m_sol; }
  const SystemSelection &selection() const { return m_sel; }
  const UniformBodyForce &body_force() const { return m_force; }
  const SceneFrameReport &report() const { return m_report; }
  /// The last frame's fields (`parts`, result_fields.hpp) and attributes, as a result file's frame.
  FrameData frame_data(unsigned parts = kFrameFields) const;
  /// The part of the result file that is no frame: the problem, the solver's attributes, the
  /// options used.
  ResultData base(int ranks) const;

  DenseScene &engine() { return *m_scene; }
  const DenseScene &engine() const { return *m_scene; }
  const SceneReference &reference() const { return m_ref; }
  const SessionProblem &problem() const { return *m_problem; }
  /// Seconds per phase ("scene_setup"; a face may add its own).
  std::map<std::string, double> &timings() { return m_seconds; }
  OptionValues options_used() const;
  Fingerprint fingerprint() const;

private:
  std::shared_ptr<const SessionProblem> m_problem;
  SceneReference m_ref;
  SessionOptions m_options;
  MachineLimits m_limits;
  std::unique_ptr<KrylovSolver> m_krylov;
  std::unique_ptr<DenseScene> m_scene;
  /// The engine's options: the session's, with the reference's pressure and candidates.
  SceneOptions engine_options() const;
  /// The frame's homogeneous system solved (the boundary data less the body force's traces).
  const SceneFrameReport &solve_homogeneous(const SystemSelection &homogeneous);

  SystemSelection m_sel;
  UniformBodyForce m_force;
  std::vector<double> m_x;
  NodalSolution m_sol;
  SceneFrameReport m_report;
  std::map<std::string, double> m_seconds;
};

} // namespace hssbem
