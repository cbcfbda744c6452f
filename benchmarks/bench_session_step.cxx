// The C++ side of benchmarks/bench_python.py: the frames of a contact problem file stepped
// through the session API (ContactSession) as hssbem.Scene steps them from Python (the same
// set-up: the job's frames given per step, not ahead; the same fields per frame: displacement,
// traction, the prescribed mask, the contact arrays), each frame and haptic call timed.
//
//   bench_session_step -problem FILE [-hssbem_load F | -hssbem_save F] [-passes 2] [-haptic 20]
//
// Every pass steps all the problem's frames; the last pass is the measured one (the first ones
// fill the cache of W's columns, as a simulator's first sweep does). Prints per measured frame
// "frame <i> wall <s> cpu <s> engine <s> active <n>", then per haptic call of that pass
// "haptic <wall s>" (the instrument 1 % of the way to the next frame, and on).
#include "hssbem/app/options.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/system.h"
#include "hssbem/post/post.hpp"
#include "hssbem/problem/setup.hpp"
#include "hssbem/session/choice.hpp"
#include "hssbem/session/contact_session.hpp"
#include "hssbem/session/petsc_call.hpp"

#include <petscsys.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>

namespace {

using namespace hssbem;

double wall()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double cpu()
{
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// One frame as hssbem.Scene's step takes it: the session's step, then the frame's fields.
void step(ContactSession &session, const NodeConditions &frame, const std::vector<Pose> &poses, bool print, int i)
{
  const double w = wall(), c = cpu();
  const ContactFrameReport &rep = session.step(selection_of(frame), poses);
  const FrameData f = session.frame_data(kMotion | kPrescribed);
  if (print)
    std::printf("frame %d wall %.6e cpu %.6e engine %.6e active %lld\n", i, wall() - w, cpu() - c, rep.seconds, rep.active_vertices);
}

/// The haptic calls between frame i and i + 1: the tool's poses moved 1 %, 2 %, ... of the way.
void haptic(ContactSession &session, const std::vector<Pose> &from, const std::vector<Pose> &to, int calls)
{
  for (int h = 0; h < calls; ++h) {
    std::vector<Pose> poses = from;
    const double s = 0.01 * (h + 1);
    for (std::size_t o = 0; o < poses.size(); ++o)
      for (int d = 0; d < 3; ++d) poses[o].translate[d] = (1 - s) * from[o].translate[d] + s * to[o].translate[d];
    const double w = wall();
    (void)session.haptic_forces(poses);
    std::printf("haptic %.6e\n", wall() - w);
  }
}

int run(int passes, int calls)
{
  const DriverOptions o = read_driver_options(PETSC_COMM_WORLD);
  const auto setup = std::make_shared<ProblemSetup>(setup_problem(o.problem, o.overrides));
  const auto problem = std::make_shared<SessionProblem>(setup, o.session.quad);
  MachineLimits limits;
  HssbemCallThrow(HssbemMachineLimits(PETSC_COMM_WORLD, &limits));
  check_unused_options(PETSC_COMM_WORLD, false);
  ContactJob job = contact_job(*setup);
  const std::vector<NodeConditions> frames = std::move(job.frames);
  const std::vector<std::vector<Pose>> placements = std::move(job.placements);
  job.frames.clear(), job.placements.clear();
  ContactSession session(problem, std::move(job), o.session, limits);
  const double w = wall();
  if (!o.load.empty()) session.load(o.load);
  session.set_up();
  if (!o.save.empty()) session.save(o.save, setup->input_files);
  std::printf("set-up %.3f s, %zu frames\n", wall() - w, frames.size());
  for (int p = 0; p < passes; ++p)
    for (std::size_t i = 0; i < frames.size(); ++i) {
      step(session, frames[i], placements[i], p + 1 == passes, static_cast<int>(i));
      if (p + 1 == passes && i + 1 < frames.size()) haptic(session, placements[i], placements[i + 1], calls);
    }
  return 0;
}

} // namespace

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(HssbemInitializePackage());
  PetscInt  passes = 2, calls = 20;
  PetscBool set;
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-passes", &passes, &set));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-haptic", &calls, &set));
  int rc = 0;
  try {
    rc = run(static_cast<int>(passes), static_cast<int>(calls));
  } catch (const std::exception &e) {
    std::fprintf(stderr, "bench_session_step: error: %s\n", e.what());
    rc = 1;
  }
  PetscCall(PetscFinalize());
  return rc;
}
