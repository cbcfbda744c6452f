// Scenes in the driver: a problem file with "frames" solved frame by frame with the scene engine
// (scene/dense_scene.hpp) and streamed into one result file (io/ FrameWriter). See run.hpp.
#include "hssbem/app/run.hpp"
#include "result_base.hpp"
#include "stress_post.hpp"

#include "hssbem/app/petsc_call.hpp"
#include "hssbem/bem/post.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/scene_krylov.h"
#include "hssbem/scene/dense_scene.hpp"

#include <algorithm>
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

} // namespace

void run_scene(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, std::optional<OperatorType> asked, const SceneRunOptions &o, std::map<std::string, double> seconds)
{
  PetscMPIInt rank, size;
  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  if (asked && *asked != OperatorType::Dense)
    throw std::runtime_error(std::string("-bem_mat_type ") + operator_type_name(*asked) + ": scenes (problem files with \"frames\") run on the dense scene engine; use -bem_mat_type dense or auto");
  const long long N = 3LL * s.disc->num_nodes();
  MachineLimits limits;
  HssbemCallThrow(HssbemMachineLimits(comm, &limits));
  const double need = 8.0 * N * N * (uses_pressure(s.spec) ? 6.7 : 6.0) * (o.strategy == SceneStrategy::Refactor || o.strategy == SceneStrategy::Auto ? 1.0 : 5.0 / 6.0);
  if (need > 0.9 * static_cast<double>(limits.node_memory_bytes))
    throw std::runtime_error("the scene needs about " + std::to_string(static_cast<long long>(need / 1e9 + 0.5)) + " GB for " + std::to_string(N) +
                             " unknowns (dense reference factorization, W = A0^-1 K0', H and G), more than this node's " +
                             std::to_string(static_cast<long long>(limits.node_memory_bytes / 1e9)) + " GB");
  const std::size_t nframes = s.spec.frames.size();
  HssbemCallThrow(PetscPrintf(comm, "hssbem: scene: %zu frames on the dense scene engine (rank 0), strategy %s\n", nframes, scene_strategy_name(o.strategy)));
  run_collectively(comm, [&] {
    if (rank != 0) return;
    // The reference pattern: the base rules where they hold the body, else frame 0's.
    NodeConditions ref_nc = apply_rules(s.spec.rules, *s.disc, s.spec.file);
    std::string ref_name = "the base rules";
    if (analyse_constraints(*s.disc, ref_nc.displacement_prescribed).rank != 6) ref_nc = frame_conditions(s.spec, 0, *s.disc), ref_name = "frame 0";
    check_frame_constraints(s, ref_nc.displacement_prescribed, "frames[0]");
    SceneOptions so;
    so.strategy      = o.strategy;
    so.with_pressure = uses_pressure(s.spec);
    so.refresh_every = o.refresh_every;
    so.single_from   = o.single_from;
    so.krylov_rtol   = o.krylov_rtol;
    const Timer      timer;
    fault_point("SceneSetup");
    DenseScene       scene(op, selection_of(ref_nc), so, HssbemSceneKrylovCreate());
    seconds["scene_setup"] += timer.seconds();
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: scene: set up in %.2f s (reference pattern: %s; %.0f MB)\n", scene.setup_seconds(), ref_name.c_str(), scene.memory_bytes() / 1e6));
    std::unique_ptr<FrameWriter> writer;
    if (!s.output.empty()) writer = std::make_unique<FrameWriter>(s.output, scene_base(s, size, o));
    std::map<std::string, long long> used;
    double                            frame_seconds = 0, slowest = 0;
    std::vector<double>               x;
    for (std::size_t i = 0; i < nframes; ++i) {
      const std::string    what = "frames[" + std::to_string(i) + "]";
      const NodeConditions nc   = frame_conditions(s.spec, i, *s.disc);
      check_frame_constraints(s, nc.displacement_prescribed, what);
      fault_point("Frame");
      const SystemSelection  sel = selection_of(nc);
      SceneFrameReport       rep;
      {
        const EventScope event(SCN_Frame);
        rep = scene.solve(sel, x);
      }
      frame_seconds += rep.seconds;
      slowest = std::max(slowest, rep.seconds);
      used[scene_strategy_name(rep.strategy)]++;
      if (o.monitor)
        HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: frame %zu: %s, %lld switched, %lld changed, %lld iterations, %.3f ms (predicted %.3f ms)\n", i, scene_strategy_name(rep.strategy),
                                    rep.switched, rep.changed, rep.iterations, 1e3 * rep.seconds, 1e3 * rep.predicted));
      if (!writer) continue;
      const Timer   post;
      NodalSolution sol = split_unknowns(sel, x);
      FrameData     f;
      f.displacement            = vertex_average(*s.disc, sol.u);
      f.traction                = vertex_average(*s.disc, sol.t);
      f.displacement_prescribed = vertex_displacement_prescribed(*s.disc, nc);
      std::vector<NodeStress> nodes;
      f.stress                  = surface_stress_fields(s, sol, nodes, false);
      f.attributes_real         = {{"seconds", rep.seconds}, {"predicted_seconds", rep.predicted}};
      f.attributes_int          = {{"switched_unknowns", rep.switched}, {"changed_unknowns", rep.changed}, {"iterations", rep.iterations}, {"capacitance_rebuilt", rep.rebuilt}};
      f.attributes_str          = {{"strategy", scene_strategy_name(rep.strategy)}};
      {
        const EventScope event(BEM_Output);
        writer->append(i, f);
      }
      seconds["output"] += post.seconds();
    }
    seconds["frames"] += frame_seconds;
    std::string summary;
    for (const auto &[k, n] : used) summary += (summary.empty() ? "" : ", ") + k + " " + std::to_string(n);
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: scene: %zu frames in %.3f s (%.2f ms per frame, %.0f Hz; slowest %.2f ms); %s\n", nframes, frame_seconds,
                                1e3 * frame_seconds / nframes, nframes / std::max(frame_seconds, 1e-12), 1e3 * slowest, summary.c_str()));
    if (!writer) return;
    writer->commit(seconds, {{"num_frames", static_cast<long long>(nframes)}}, {{"frame_seconds_mean", frame_seconds / nframes}});
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: wrote %s\n", s.output.c_str()));
  });
}

} // namespace hssbem
