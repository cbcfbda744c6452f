// Contact problems in the driver: a problem file with "contact", solved once or frame by frame
// by the contact session on rank 0, written as one result file. See run.hpp.
#include "hssbem/app/run.hpp"

#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/system.h"
#include "hssbem/session/choice.hpp"
#include "hssbem/session/contact_session.hpp"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/precomputation_file.hpp"

#include <algorithm>
#include <stdexcept>
#include <memory>

namespace hssbem {

namespace {

/// What the set-up built: the references (per body, or the H² one) and the engine.
void print_set_up(const ContactSession &session, double seconds)
{
  const std::vector<ContactBodyReport> &bodies = session.body_reports();
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const ContactBodyReport &r = bodies[b];
    if (r.h2)
      HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: H2 reference%s: compressed in %.2f s, factored in %.2f s (%.0f MB)\n",
                                  bodies.size() > 1 ? (" of body " + std::to_string(b)).c_str() : "", r.compress_seconds, r.factor_seconds, r.bytes / 1e6));
    if (bodies.size() > 1)
      HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: body %zu: %d unknowns, %s reference, set up in %.2f s (%.0f MB)\n", b, r.unknowns, r.h2 ? "H2" : "dense",
                                  r.seconds, r.bytes / 1e6));
  }
  const ContactEngine &e = session.engine();
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: set up in %.2f s (%d obstacles, %d bodies, reach %.3g; %.0f MB)\n", seconds, e.num_obstacles(), e.bodies().count,
                              e.reach(), (session.reference().memory_bytes() + e.memory_bytes()) / 1e6));
}

/// The single solve: what it found, and the result file.
void contact_single(ContactSession &session, const std::string &output, int ranks)
{
  session.obstacles().note_depth(0, session.job().placements[0]);
  const ContactFrameReport &rep = session.step(0);
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: %lld vertices touching (%lld stick, %lld slip) after %lld iterations, %.3f ms\n", rep.active_vertices, rep.stick,
                              rep.slip, rep.iterations, 1e3 * rep.seconds));
  if (session.mat_type() != "dense") {
    const H2ReferenceStats st = session.h2_stats();
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF,
                                "hssbem: contact: %d corrections by accurate H2 solves (%.2f s; last change %.1e); H2 reference: %lld columns in %.2f s, %lld accurate solves "
                                "(%lld GMRES iterations) in %.2f s\n",
                                rep.corrections, rep.correct_seconds, rep.correction, st.columns, st.column_seconds, st.solves, st.iterations, st.solve_seconds));
  }
  if (output.empty()) return;
  const ResultData r = session.result(ranks);
  const EventScope event(BEM_Output);
  write_result(output, r);
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: wrote %s\n", output.c_str()));
}

/// A scene of frames, streamed into the result file; `frame` follows the frame being solved (for
/// the monitor).
void contact_frames(ContactSession &session, const std::string &output, int ranks, long long &frame)
{
  std::unique_ptr<FrameWriter> writer;
  if (!output.empty()) writer = std::make_unique<FrameWriter>(output, session.base(ranks));
  const std::size_t nframes = session.job().frames.size();
  double total = 0, slowest = 0;
  long long iterations = 0;
  { // the progress line ends before the summary
    const Progress progress("contact frames");
    const std::vector<std::vector<Pose>> &poses = session.job().placements;
    for (std::size_t i = 0; i < nframes; ++i) {
      frame = static_cast<long long>(i);
      session.obstacles().note_depth(frame, poses[i]);
      const ContactFrameReport &rep = session.step(i);
      total += rep.seconds, slowest = std::max(slowest, rep.seconds), iterations += rep.iterations;
      progress.report(static_cast<double>(i + 1) / static_cast<double>(nframes));
      if (!writer) continue;
      const FrameData f = session.frame_data(kFrameFields);
      const EventScope event(BEM_Output);
      writer->append(i, f);
    }
  }
  const double n = static_cast<double>(nframes);
  session.timings()["frames"] += total;
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: %zu frames in %.3f s (%.2f ms per frame, %.0f Hz; slowest %.2f ms); %.2f iterations per frame\n", nframes, total,
                              1e3 * total / n, n / std::max(total, 1e-12), 1e3 * slowest, iterations / n));
  if (!writer) return;
  writer->commit(session.timings(), {{"num_frames", static_cast<long long>(nframes)}}, {{"frame_seconds_mean", total / n}});
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: wrote %s\n", output.c_str()));
}

/// -hssbem_load: the precomputation of the file instead of the set-up's.
void load_set_up(ContactSession &session, const std::string &path)
{
  const Timer timer;
  session.load(path);
  session.timings()["contact_load"] += timer.seconds();
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: loaded the precomputation from %s in %.2f s\n", path.c_str(), timer.seconds()));
}

/// -hssbem_save: the precomputation after the set-up (not over an input, nor the result file).
void save_set_up(const ContactSession &session, const std::string &path, std::vector<std::string> inputs)
{
  const Timer timer;
  session.save(path, inputs);
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: saved the precomputation to %s in %.2f s\n", path.c_str(), timer.seconds()));
}

/// What -hssbem_save and -hssbem_load can do, checked on every rank before the set-up.
void check_persistence(const DriverOptions &o, const std::string &mat_type, const std::string &output)
{
  if (!o.save.empty() || !o.load.empty()) check_contact_reference_saveable(mat_type, o.save.empty() ? "-hssbem_load" : "-hssbem_save", " (-bem_mat_type dense)");
  check_save_load(o, output);
}

} // namespace

void run_contact(MPI_Comm comm, const DriverOptions &o, std::shared_ptr<const SessionProblem> problem, std::map<std::string, double> seconds)
{
  PetscMPIInt   rank, size;
  MachineLimits limits;
  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  HssbemCallThrow(HssbemMachineLimits(comm, &limits));
  const ProblemSetup &s = problem->setup();
  print_summary(comm, *problem, "");
  check_unused_options(comm, false);
  const std::string mat_type = reference_mat_type(contact_references_on_h2(problem->disc(), o.session.operator_type, limits)); // every rank: the same error everywhere
  HssbemCallThrow(PetscPrintf(comm, "hssbem: contact: %zu obstacles%s, %zu frames, on the %s reference factorization (rank 0)\n", s.spec.contact.obstacles.size(),
                              s.spec.contact.bodies ? " and the bodies" : "", std::max<std::size_t>(1, s.spec.frames.size()),
                              mat_type == "dense,h2" ? "dense and H2" : mat_type == "h2" ? "H2" : "dense"));
  check_persistence(o, mat_type, s.output);
  run_collectively(comm, [&] {
    if (rank != 0) return;
    SessionOptions so = o.session;
    long long frame = 0;
    if (o.contact_monitor)
      so.contact.monitor = [&frame](const ContactIteration &it) {
        HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: frame %lld iteration %d: %lld touching, %lld changed, residual %.3e\n", frame, it.iteration, it.active, it.changed,
                                    it.residual));
      };
    ContactSession session(problem, contact_job(s), so, limits);
    session.timings() = std::move(seconds);
    const std::vector<std::string> inputs = save_load_inputs(o, s);
    const Timer timer;
    if (!o.load.empty()) load_set_up(session, o.load);
    session.set_up();
    print_set_up(session, timer.seconds());
    if (!o.save.empty()) save_set_up(session, o.save, inputs);
    if (s.spec.frames.empty()) contact_single(session, s.output, size);
    else contact_frames(session, s.output, size, frame);
  });
}

} // namespace hssbem
