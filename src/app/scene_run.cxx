// Scenes in the driver: the frames of a problem file solved by the scene session on rank 0 and
// streamed into one result file (io/ FrameWriter). See run.hpp.
#include "hssbem/app/run.hpp"

#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/krylov.h"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/system.h"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/scene_session.hpp"

#include <algorithm>
#include <memory>

namespace hssbem {

namespace {

/// What the frame loop counts for the summary line.
struct FrameTally {
  double seconds = 0, slowest = 0, output = 0;
  std::map<std::string, long long> used; ///< frames per strategy taken
};

/// Frame i: solved, printed with -scene_monitor, streamed into the writer.
void scene_frame(SceneSession &session, std::size_t i, const DriverOptions &o, FrameWriter *writer, FrameTally &tally)
{
  const SceneFrameReport &rep = session.step(i);
  tally.seconds += rep.seconds;
  tally.slowest = std::max(tally.slowest, rep.seconds);
  tally.used[scene_strategy_name(rep.strategy)]++;
  if (o.scene_monitor)
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: frame %zu: %s, %lld switched, %lld changed, %lld iterations, %.3f ms (predicted %.3f ms)\n", i, scene_strategy_name(rep.strategy),
                                rep.switched, rep.changed, rep.iterations, 1e3 * rep.seconds, 1e3 * rep.predicted));
  if (!writer) return;
  const Timer      post;
  const FrameData  f = session.frame_data(kFrameFields);
  const EventScope event(BEM_Output);
  writer->append(i, f);
  tally.output += post.seconds();
}

/// Every frame; a frame that fails ends the scene with its error, after the frames solved so
/// far are committed when -scene_keep_partial asks for them (the error then says so).
void scene_frames(SceneSession &session, const DriverOptions &o, FrameWriter *writer, FrameTally &tally)
{
  const ProblemSetup &s = session.problem().setup();
  const std::size_t nframes = s.spec.frames.size();
  const Progress progress("scene frames");
  for (std::size_t i = 0; i < nframes; ++i) {
    try {
      scene_frame(session, i, o, writer, tally);
      progress.report(static_cast<double>(i + 1) / static_cast<double>(nframes));
    } catch (const std::exception &e) {
      if (!o.scene_keep_partial || !writer) throw;
      session.timings()["frames"] += tally.seconds;
      writer->commit(session.timings(), {{"num_frames", static_cast<long long>(i)}, {"complete", 0}, {"failed_frame", static_cast<long long>(i)}}, {}, {{"failure", e.what()}});
      throw std::runtime_error(std::string(e.what()) + " (-scene_keep_partial: the " + std::to_string(i) + " frames solved before it are in " + s.output + ")");
    }
  }
}

/// -hssbem_load: the precomputation of the file instead of the set-up.
void scene_load(SceneSession &session, const std::string &path)
{
  const Timer timer;
  session.load(path);
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: scene: loaded the precomputation from %s in %.2f s\n", path.c_str(), timer.seconds()));
}

/// -hssbem_save: the precomputation after the set-up.
void scene_save(const SceneSession &session, const std::string &path, const std::vector<std::string> &inputs)
{
  const Timer timer;
  session.save(path, inputs);
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: scene: saved the precomputation to %s in %.2f s\n", path.c_str(), timer.seconds()));
}

} // namespace

void run_scene(MPI_Comm comm, const DriverOptions &o, std::shared_ptr<const SessionProblem> problem, std::map<std::string, double> seconds)
{
  PetscMPIInt   rank, size;
  MachineLimits limits;
  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  HssbemCallThrow(HssbemMachineLimits(comm, &limits));
  const ProblemSetup &s = problem->setup();
  print_summary(comm, *problem, "");
  check_unused_options(comm, false);
  SceneReference ref = scene_reference(s);
  check_scene(*problem, ref, o.session, limits); // every rank: the same error everywhere
  const std::size_t nframes = s.spec.frames.size();
  HssbemCallThrow(PetscPrintf(comm, "hssbem: scene: %zu frames on the dense scene engine (rank 0), strategy %s\n", nframes, scene_strategy_name(o.session.scene.strategy)));
  check_save_load(o, s.output);
  run_collectively(comm, [&] {
    if (rank != 0) return;
    SceneSession session(problem, std::move(ref), o.session, limits, HssbemSceneKrylovCreate());
    session.timings() = std::move(seconds);
    const std::vector<std::string> inputs = save_load_inputs(o, s);
    if (!o.load.empty()) scene_load(session, o.load);
    session.set_up(); // nothing left to do after a load
    if (!o.save.empty()) scene_save(session, o.save, inputs);
    const SceneReference &r = session.reference();
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: scene: set up in %.2f s (reference pattern: %s; W for %lld of %zu unknowns, those the frames switch or load; %.0f MB)\n",
                                session.engine().setup_seconds(), r.name.c_str(), r.count(), r.candidates.size(), session.engine().memory_bytes() / 1e6));
    std::unique_ptr<FrameWriter> writer;
    if (!s.output.empty()) writer = std::make_unique<FrameWriter>(s.output, session.base(size));
    FrameTally tally;
    scene_frames(session, o, writer.get(), tally);
    session.timings()["frames"] += tally.seconds;
    session.timings()["output"] += tally.output;
    std::string summary;
    for (const auto &[k, n] : tally.used) summary += (summary.empty() ? "" : ", ") + k + " " + std::to_string(n);
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: scene: %zu frames in %.3f s (%.2f ms per frame, %.0f Hz; slowest %.2f ms); %s\n", nframes, tally.seconds,
                                1e3 * tally.seconds / nframes, nframes / std::max(tally.seconds, 1e-12), 1e3 * tally.slowest, summary.c_str()));
    if (!writer) return;
    writer->commit(session.timings(), {{"num_frames", static_cast<long long>(nframes)}, {"complete", 1}}, {{"frame_seconds_mean", tally.seconds / nframes}});
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: wrote %s\n", s.output.c_str()));
  });
}

} // namespace hssbem
