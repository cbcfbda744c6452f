// Scenes in the driver: a problem file with "frames" solved frame by frame with the scene engine
// (scene/dense_scene.hpp) and streamed into one result file (io/ FrameWriter). See run.hpp.
#include "hssbem/app/run.hpp"
#include "result_base.hpp"
#include "stress_post.hpp"

#include "hssbem/app/petsc_call.hpp"
#include "hssbem/post/post.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/scene_krylov.h"
#include "hssbem/scene/dense_scene.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace hssbem {

namespace {

bool uses_pressure(const ProblemSpec &spec)
{
  auto any = [](const std::vector<BoundaryRule> &rules) {
    return std::any_of(rules.begin(), rules.end(), [](const BoundaryRule &r) { return r.kind == BoundaryRule::Kind::Pressure; });
  };
  if (any(spec.rules)) return true;
  return std::any_of(spec.frames.begin(), spec.frames.end(), [&](const FrameSpec &f) { return any(f.rules); });
}

/// The static part of a scene's result file: the mesh, the material and the run's description.
ResultData scene_base(const ProblemSetup &s, PetscMPIInt size, const SceneRunOptions &o)
{
  ResultData r                      = result_base(s, size);
  r.attributes_str["solver"]         = "scene";
  r.attributes_str["mat_type"]       = "dense";
  r.attributes_str["scene_strategy"] = scene_strategy_name(o.strategy);
  return r;
}

/// The frame loop on rank 0: each frame solved by the scene engine, checked (a frame that fails or
/// whose solution is not finite is an error), and streamed into the writer.
class FrameLoop {
public:
  FrameLoop(const ProblemSetup &s, const SceneRunOptions &o, DenseScene &scene, FrameWriter *writer) : m_s(s), m_o(o), m_scene(scene), m_writer(writer) {}

  /// Solves frame i; throws "frames[i]: <what>" when it fails.
  void frame(std::size_t i)
  {
    const NodeConditions  nc  = frame_conditions(m_s.spec, i, *m_s.disc); // checked by setup_problem (check_every_frame)
    const SystemSelection sel = selection_of(nc);
    SceneFrameReport      rep;
    try {
      fault_point("Frame");
      const EventScope event(SCN_Frame);
      rep = m_scene.solve(sel, m_x);
      for (double v : m_x)
        if (!std::isfinite(v)) throw std::runtime_error("the solution is not finite (the frame's system is singular or overflows)");
    } catch (const std::exception &e) {
      throw std::runtime_error(m_s.spec.file + ": frames[" + std::to_string(i) + "]: " + e.what());
    }
    m_frame_seconds += rep.seconds;
    m_slowest = std::max(m_slowest, rep.seconds);
    m_used[scene_strategy_name(rep.strategy)]++;
    if (m_o.monitor)
      HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: frame %zu: %s, %lld switched, %lld changed, %lld iterations, %.3f ms (predicted %.3f ms)\n", i, scene_strategy_name(rep.strategy),
                                  rep.switched, rep.changed, rep.iterations, 1e3 * rep.seconds, 1e3 * rep.predicted));
    if (m_writer) write(i, nc, sel, rep);
  }

  double                                  frame_seconds() const { return m_frame_seconds; }
  double                                  slowest() const { return m_slowest; }
  double                                  output_seconds() const { return m_output_seconds; }
  const std::map<std::string, long long> &used() const { return m_used; }

private:
  void write(std::size_t i, const NodeConditions &nc, const SystemSelection &sel, const SceneFrameReport &rep)
  {
    const Timer   post;
    NodalSolution sol = split_unknowns(sel, m_x);
    FrameData     f;
    f.displacement            = vertex_average(*m_s.disc, sol.u);
    f.traction                = vertex_average(*m_s.disc, sol.t);
    f.displacement_prescribed = vertex_displacement_prescribed(*m_s.disc, nc);
    std::vector<NodeStress> nodes;
    f.stress                  = surface_stress_fields(m_s, sol, nodes, false);
    f.attributes_real         = {{"seconds", rep.seconds}, {"predicted_seconds", rep.predicted}};
    f.attributes_int          = {{"switched_unknowns", rep.switched}, {"changed_unknowns", rep.changed}, {"iterations", rep.iterations}, {"capacitance_rebuilt", rep.rebuilt}};
    f.attributes_str          = {{"strategy", scene_strategy_name(rep.strategy)}};
    {
      const EventScope event(BEM_Output);
      m_writer->append(i, f);
    }
    m_output_seconds += post.seconds();
  }

  const ProblemSetup              &m_s;
  const SceneRunOptions           &m_o;
  DenseScene                      &m_scene;
  FrameWriter                     *m_writer;
  std::vector<double>              m_x;
  std::map<std::string, long long> m_used;
  double                           m_frame_seconds = 0, m_slowest = 0, m_output_seconds = 0;
};

/// The reference pattern (the base rules where they hold the body, else frame 0's) and the
/// unknowns that some frame switches or loads: the only columns of W the scene computes.
struct SceneReference {
  SystemSelection   selection;
  std::string       name;
  std::vector<char> candidates;
  long long         count() const { return std::count(candidates.begin(), candidates.end(), 1); }
};

SceneReference scene_reference(const ProblemSetup &s)
{
  NodeConditions ref_nc   = apply_rules(s.spec.rules, *s.disc, s.spec.file);
  std::string    ref_name = "the base rules";
  if (analyse_constraints(*s.disc, ref_nc.displacement_prescribed).rank != 6) ref_nc = frame_conditions(s.spec, 0, *s.disc), ref_name = "frame 0";
  SceneReference ref{selection_of(ref_nc), ref_name, std::vector<char>(3 * static_cast<std::size_t>(s.disc->num_nodes()), 0)};
  for (std::size_t f = 0; f < s.spec.frames.size(); ++f) mark_scene_candidates(ref.selection, selection_of(frame_conditions(s.spec, f, *s.disc)), ref.candidates);
  return ref;
}

/// The scene engine set up on the reference pattern, with W for the candidates only.
std::unique_ptr<DenseScene> set_up_scene(const BemOperator &op, const SceneReference &ref, const SceneRunOptions &o, bool pressure, std::map<std::string, double> &seconds)
{
  SceneOptions so;
  so.strategy      = o.strategy;
  so.with_pressure = pressure;
  so.refresh_every = o.refresh_every;
  so.single_from   = o.single_from;
  so.single_fields_from = o.single_fields_from;
  so.krylov_rtol   = o.krylov_rtol;
  so.candidates    = ref.candidates;
  const Timer timer;
  fault_point("SceneSetup");
  auto scene = std::make_unique<DenseScene>(op, ref.selection, so, HssbemSceneKrylovCreate());
  seconds["scene_setup"] += timer.seconds();
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: scene: set up in %.2f s (reference pattern: %s; W for %lld of %zu unknowns, those the frames switch or load; %.0f MB)\n",
                              scene->setup_seconds(), ref.name.c_str(), ref.count(), ref.candidates.size(), scene->memory_bytes() / 1e6));
  return scene;
}

/// The dense scene's memory: W's candidate columns (and their single-precision copy), the reference LU, H and G (and the pressure columns).
void check_scene_size(MPI_Comm comm, const ProblemSetup &s, const SceneRunOptions &o, const SceneReference &ref)
{
  const long long N = 3LL * s.disc->num_nodes();
  MachineLimits   limits;
  HssbemCallThrow(HssbemMachineLimits(comm, &limits));
  const double need = 8.0 * N * N * (uses_pressure(s.spec) ? 6.7 : 6.0) * (o.strategy == SceneStrategy::Refactor || o.strategy == SceneStrategy::Auto ? 1.0 : 5.0 / 6.0) -
                      8.0 * N * static_cast<double>(N - ref.count()) + // W's columns that are no candidates
                      4.0 * N * static_cast<double>(ref.count());       // W's single-precision copy
  if (need > 0.9 * static_cast<double>(limits.node_memory_bytes))
    throw std::runtime_error("the scene needs about " + std::to_string(static_cast<long long>(need / 1e9 + 0.5)) + " GB for " + std::to_string(N) +
                             " unknowns (dense reference factorization, W = A0^-1 K0', H and G), more than this node's " +
                             std::to_string(static_cast<long long>(limits.node_memory_bytes / 1e9)) + " GB");
}

/// Solves every frame; a frame that fails ends the scene with its error, after the frames solved
/// so far are committed when -scene_keep_partial asks for them (the error then says so).
void solve_frames(const ProblemSetup &s, FrameLoop &loop, FrameWriter *writer, const SceneRunOptions &o, std::map<std::string, double> &seconds)
{
  const std::size_t nframes = s.spec.frames.size();
  const Progress    progress("scene frames");
  for (std::size_t i = 0; i < nframes; ++i) {
    try {
      loop.frame(i);
      progress.report(static_cast<double>(i + 1) / static_cast<double>(nframes));
    } catch (const std::exception &e) {
      if (!o.keep_partial || !writer) throw;
      seconds["frames"] += loop.frame_seconds();
      writer->commit(seconds, {{"num_frames", static_cast<long long>(i)}, {"complete", 0}, {"failed_frame", static_cast<long long>(i)}}, {}, {{"failure", e.what()}});
      throw std::runtime_error(std::string(e.what()) + " (-scene_keep_partial: the " + std::to_string(i) + " frames solved before it are in " + s.output + ")");
    }
  }
}

} // namespace

void run_scene(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, std::optional<OperatorType> asked, const SceneRunOptions &o, std::map<std::string, double> seconds)
{
  PetscMPIInt rank, size;
  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  if (asked && *asked != OperatorType::Dense)
    throw std::runtime_error(std::string("-bem_mat_type ") + operator_type_name(*asked) + ": scenes (problem files with \"frames\") run on the dense scene engine; use -bem_mat_type dense or auto");
  const SceneReference ref = scene_reference(s);
  check_scene_size(comm, s, o, ref);
  const std::size_t nframes = s.spec.frames.size();
  HssbemCallThrow(PetscPrintf(comm, "hssbem: scene: %zu frames on the dense scene engine (rank 0), strategy %s\n", nframes, scene_strategy_name(o.strategy)));
  run_collectively(comm, [&] {
    if (rank != 0) return;
    const std::unique_ptr<DenseScene> scene = set_up_scene(op, ref, o, uses_pressure(s.spec), seconds);
    std::unique_ptr<FrameWriter>      writer;
    if (!s.output.empty()) writer = std::make_unique<FrameWriter>(s.output, scene_base(s, size, o));
    FrameLoop loop(s, o, *scene, writer.get());
    solve_frames(s, loop, writer.get(), o, seconds);
    seconds["frames"] += loop.frame_seconds();
    seconds["output"] += loop.output_seconds();
    std::string summary;
    for (const auto &[k, n] : loop.used()) summary += (summary.empty() ? "" : ", ") + k + " " + std::to_string(n);
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: scene: %zu frames in %.3f s (%.2f ms per frame, %.0f Hz; slowest %.2f ms); %s\n", nframes, loop.frame_seconds(),
                                1e3 * loop.frame_seconds() / nframes, nframes / std::max(loop.frame_seconds(), 1e-12), 1e3 * loop.slowest(), summary.c_str()));
    if (!writer) return;
    writer->commit(seconds, {{"num_frames", static_cast<long long>(nframes)}, {"complete", 1}}, {{"frame_seconds_mean", loop.frame_seconds() / nframes}});
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: wrote %s\n", s.output.c_str()));
  });
}

} // namespace hssbem
