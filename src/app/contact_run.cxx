// Contact problems in the driver: a problem file with "contact", solved once or frame by frame by
// the contact engine (contact/contact_engine.hpp) on the dense reference factorization or, with
// -bem_mat_type h2 (or auto where dense does not fit), the H² one (scene/h2_reference.hpp), on rank 0.
#include "hssbem/app/run.hpp"
#include "result_base.hpp"
#include "stress_post.hpp"

#include "hssbem/app/petsc_call.hpp"
#include "hssbem/bem/post.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/system.h"
#include "hssbem/scene/composite_reference.hpp"
#include "hssbem/scene/h2_reference.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace hssbem {

namespace {

Obstacle obstacle_of(const ObstacleSpec &o, const SurfaceMesh &mesh)
{
  Obstacle ob;
  switch (o.shape) {
  case ObstacleSpec::Shape::Plane: ob = Obstacle::plane(o.name, o.point, o.normal); break;
  case ObstacleSpec::Shape::Sphere: ob = Obstacle::sphere(o.name, o.center, o.radius); break;
  case ObstacleSpec::Shape::Mesh: ob = Obstacle::mesh(o.name, mesh); break;
  }
  ob.friction = o.friction;
  return ob;
}

/// The obstacles, checked (a degenerate triangle of an obstacle mesh, say) with the file named.
std::vector<Obstacle> obstacles_of(const ProblemSetup &s)
{
  std::vector<Obstacle> list;
  for (std::size_t i = 0; i < s.spec.contact.obstacles.size(); ++i) {
    list.push_back(obstacle_of(s.spec.contact.obstacles[i], s.obstacle_meshes[i]));
    try {
      const ObstacleGeometry check(list.back());
    } catch (const std::invalid_argument &e) {
      const std::string where = s.spec.contact.obstacles[i].shape == ObstacleSpec::Shape::Mesh ? " (" + s.spec.contact.obstacles[i].mesh_path + ")" : "";
      throw ProblemError(s.spec.file + ": contact.obstacles[" + std::to_string(i) + "]" + where + ": " + e.what());
    }
  }
  return list;
}

ContactSettings settings_of(const ProblemSetup &s)
{
  ContactSettings c;
  c.friction = s.spec.contact.friction;
  c.bodies = s.spec.contact.bodies;
  if (s.spec.contact.where) {
    c.candidate.assign(s.mesh->vertices.size(), 0);
    for (int v : select_vertices(*s.spec.contact.where, *s.mesh, s.spec.file, "contact.where")) c.candidate[v] = 1;
  }
  return c;
}

/// Per frame (or the single solve), the obstacles' poses in the engine's order: x ↦ R (x − c) + c + t,
/// c the frame's "about" or the obstacle's default centre.
std::vector<std::vector<Pose>> placements_of(const ProblemSpec &spec, const std::vector<Obstacle> &obstacles)
{
  const std::size_t no = spec.contact.obstacles.size();
  std::vector<std::vector<Pose>> out(std::max<std::size_t>(1, spec.frames.size()), std::vector<Pose>(no));
  for (std::size_t f = 0; f < spec.frames.size(); ++f)
    for (const auto &[name, offset] : spec.frames[f].obstacles)
      for (std::size_t o = 0; o < no; ++o) {
        if (spec.contact.obstacles[o].name != name) continue;
        const auto turn = spec.frames[f].turns.find(name);
        if (turn == spec.frames[f].turns.end()) {
          out[f][o] = Pose::translation(offset);
          continue;
        }
        const ObstacleTurn &r = turn->second;
        out[f][o] = Pose::turn(r.axis, r.angle_deg, r.about ? *r.about : ObstacleGeometry(obstacles[o]).default_centre(), offset);
      }
  return out;
}

/// Every frame's conditions, checked before frame 0: a contact scene keeps the base pattern.
std::vector<NodeConditions> frames_of(const ProblemSetup &s, const NodeConditions &base)
{
  std::vector<NodeConditions> out;
  if (s.spec.frames.empty()) return {base};
  for (std::size_t f = 0; f < s.spec.frames.size(); ++f) {
    out.push_back(frame_conditions(s.spec, f, *s.disc));
    if (out.back().displacement_prescribed != base.displacement_prescribed)
      throw ProblemError(s.spec.file + ": frames[" + std::to_string(f) +
                         "].boundary: a contact scene's frames may change the values of the base rules, not which components they prescribe (the reference factorization's pattern)");
  }
  return out;
}

ContactData contact_data(const ContactEngine &engine, const ContactSolution &sol, const ContactFrameReport &rep, bool bodies)
{
  ContactData c;
  c.pressure = sol.pressure;
  c.gap = sol.gap;
  c.status = sol.status;
  for (int o = 0; o < engine.num_obstacles(); ++o) c.forces[engine.obstacle_name(o)] = sol.obstacle_force[o];
  if (bodies)
    for (int b = 0; b < engine.bodies().count; ++b) c.forces["body_" + std::to_string(b)] = sol.body_force[b];
  c.iterations = rep.iterations;
  c.active_vertices = rep.active_vertices;
  return c;
}

/// A contact solution with a non-finite value (a singular or overflowing system) is an error
/// before anything of it is written.
void check_finite(const ContactSolution &sol, long long frame)
{
  for (const std::vector<Vec3> *field : {&sol.u, &sol.t})
    for (const Vec3 &v : *field)
      for (double c : v)
        if (!std::isfinite(c))
          throw std::runtime_error("contact: the solution" + (frame < 0 ? std::string() : " of frame " + std::to_string(frame)) +
                                   " is not finite (the contact system is singular or overflows)");
}

/// The columns of K₀′ a dense reference keeps (DenseReferenceOptions::kept_columns): those the
/// contact may load (contact_loaded_unknowns) and those of every unknown that carries a non-zero
/// known value, or a pressure, in the base rules or a frame (the free responses' right-hand sides).
std::vector<char> kept_columns(std::vector<char> kept, const std::vector<NodeConditions> &frames)
{
  for (std::size_t i = 0; 3 * i < kept.size(); ++i)
    for (const NodeConditions &nc : frames)
      for (int k = 0; k < 3; ++k)
        if (nc.value[i][k] != 0 || (!nc.pressure.empty() && !std::isnan(nc.pressure[i]))) kept[3 * i + k] = 1;
  return kept;
}

/// "dense", "h2", or "dense,h2" (bodies on both).
std::string mat_type_of(const std::vector<char> &h2)
{
  const bool any = std::any_of(h2.begin(), h2.end(), [](char c) { return c != 0; }), all = std::all_of(h2.begin(), h2.end(), [](char c) { return c != 0; });
  return all ? "h2" : any ? "dense,h2" : "dense";
}

/// The H² references' statistics under `ref` (itself, or a composite's bodies'), summed.
H2ReferenceStats h2_stats(const ReferenceFactorization &ref)
{
  std::vector<const ReferenceFactorization *> parts{&ref};
  if (const auto *c = dynamic_cast<const CompositeReference *>(&ref)) {
    parts.clear();
    for (int b = 0; b < c->num_bodies(); ++b) parts.push_back(&c->body_reference(b));
  }
  H2ReferenceStats sum;
  for (const ReferenceFactorization *p : parts)
    if (const auto *h = dynamic_cast<const H2Reference *>(p)) {
      const H2ReferenceStats &st = h->stats();
      sum.columns += st.columns, sum.column_seconds += st.column_seconds, sum.solves += st.solves, sum.iterations += st.iterations, sum.solve_seconds += st.solve_seconds;
    }
  return sum;
}

/// What the driver keeps of a contact run on rank 0.
struct ContactRun {
  const ProblemSetup &s;
  const BemOperator &op;
  const ContactRunOptions &o;
  const InteriorRunOptions &interior;
  PetscMPIInt size;
  std::map<std::string, double> &seconds;
  const H2Options *h2 = nullptr;     ///< the H² path's compression options (used by the bodies on it)
  std::vector<char> body_h2;         ///< per body: its reference is the H² one (else dense)
  std::unique_ptr<ReferenceFactorization> reference;
  std::unique_ptr<ContactEngine> engine;
  std::vector<std::vector<Pose>> placements; ///< per frame, the obstacles' poses
  long long frame = 0;

  std::unique_ptr<ReferenceFactorization> body_reference(const BemOperator &body_op, std::vector<char> pattern, std::vector<char> kept, bool pressure, int body) const;
  void make_reference(const NodeConditions &base, const std::vector<NodeConditions> &frames, const std::vector<Obstacle> &obstacles, const ContactSettings &settings,
                      const ContactOptions &opt);
  void set_up(const NodeConditions &base, const std::vector<NodeConditions> &frames);
  void single(const NodeConditions &nc);
  void scene(const std::vector<NodeConditions> &frames);
};

/// One body's reference (the whole mesh's when it is one body): the dense LU with K₀′'s kept
/// columns, or the H² one.
std::unique_ptr<ReferenceFactorization> ContactRun::body_reference(const BemOperator &body_op, std::vector<char> pattern, std::vector<char> kept, bool pressure, int body) const
{
  if (!body_h2[body]) {
    DenseReferenceOptions ro;
    ro.with_pressure = pressure;
    ro.reference_columns_only = true; // contact reads K₀′ alone: 16 N² bytes at most, not 24 N²
    ro.kept_columns = std::move(kept);
    return std::make_unique<DenseReference>(body_op, std::move(pattern), ro);
  }
  H2ReferenceOptions ho;
  ho.compression = *h2;
  ho.with_pressure = pressure;
  ho.rtol = o.h2_rtol;
  ho.factor.rel_tol = o.h2_factor_tol;
  auto ref = std::make_unique<H2Reference>(body_op, std::move(pattern), ho);
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: H2 reference%s: compressed in %.2f s, factored in %.2f s (%.0f MB)\n",
                              body_h2.size() > 1 ? (" of body " + std::to_string(body)).c_str() : "", ref->stats().compress_seconds, ref->stats().factor_seconds,
                              ref->memory_bytes() / 1e6));
  return ref;
}

/// One body: its reference on the whole operator. Several: a CompositeReference, each body on
/// its own surface and operator (no integral across bodies), dense or H² per body_h2.
void ContactRun::make_reference(const NodeConditions &base, const std::vector<NodeConditions> &frames, const std::vector<Obstacle> &obstacles, const ContactSettings &settings,
                                const ContactOptions &opt)
{
  const bool pressure = std::any_of(base.pressure.begin(), base.pressure.end(), [](double p) { return !std::isnan(p); });
  std::vector<char> pattern = base.unknown_pattern();
  std::vector<NodeConditions> all = frames;
  all.push_back(base);
  std::vector<char> kept = kept_columns(contact_loaded_unknowns(*s.disc, pattern, obstacles, settings, opt), all);
  if (body_h2.size() == 1) {
    reference = body_reference(op, std::move(pattern), std::move(kept), pressure, 0);
    return;
  }
  const BodyReferenceFactory make = [&](const BemOperator &body_op, std::vector<char> p, std::vector<char> k, int body) {
    return body_reference(body_op, std::move(p), std::move(k), pressure, body);
  };
  auto composite = std::make_unique<CompositeReference>(op, node_bodies(*s.disc), std::move(pattern), std::move(kept), make);
  for (int b = 0; b < composite->num_bodies(); ++b)
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: body %d: %d unknowns, %s reference, set up in %.2f s (%.0f MB)\n", b, composite->body_reference(b).num_unknowns(),
                                body_h2[b] ? "H2" : "dense", composite->body_seconds(b), composite->body_reference(b).memory_bytes() / 1e6));
  reference = std::move(composite);
}

void ContactRun::set_up(const NodeConditions &base, const std::vector<NodeConditions> &frames)
{
  const EventScope event(CNT_Setup);
  const Timer timer;
  const Progress progress("contact set-up"); // reported when it ends (the reference LU and the engine's columns)
  std::vector<Obstacle> obstacles = obstacles_of(s);
  const ContactSettings settings = settings_of(s);
  ContactOptions opt;
  opt.tol = o.tol, opt.max_it = o.max_it, opt.reach = o.reach;
  if (o.monitor)
    opt.monitor = [this](const ContactIteration &it) {
      HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: frame %lld iteration %d: %lld touching, %lld changed, residual %.3e\n", frame, it.iteration, it.active, it.changed, it.residual));
    };
  try {
    check_bodies_held(*s.disc, base.displacement_prescribed, obstacles, settings, opt);
  } catch (const ConstraintError &e) {
    throw ConstraintError(s.spec.file + ": " + e.what());
  }
  fault_point("ContactSetup");
  placements = placements_of(s.spec, obstacles);
  make_reference(base, frames, obstacles, settings, opt);
  engine = std::make_unique<ContactEngine>(*s.disc, *reference, std::move(obstacles), settings, opt);
  engine->prefetch(placements);
  seconds["contact_setup"] += timer.seconds();
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: set up in %.2f s (%d obstacles, %d bodies, reach %.3g; %.0f MB)\n", timer.seconds(), engine->num_obstacles(),
                              engine->bodies().count, engine->reach(), (reference->memory_bytes() + engine->memory_bytes()) / 1e6));
}

void ContactRun::single(const NodeConditions &nc)
{
  ContactSolution sol;
  const ContactFrameReport rep = engine->solve(selection_of(nc), placements[0], sol);
  seconds["contact_solve"] += rep.seconds;
  check_finite(sol, -1);
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: %lld vertices touching (%lld stick, %lld slip) after %lld iterations, %.3f ms\n", rep.active_vertices, rep.stick,
                              rep.slip, rep.iterations, 1e3 * rep.seconds));
  if (std::any_of(body_h2.begin(), body_h2.end(), [](char c) { return c != 0; })) {
    const H2ReferenceStats st = h2_stats(*reference);
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF,
                                "hssbem: contact: %d corrections by accurate H2 solves (%.2f s; last change %.1e); H2 reference: %lld columns in %.2f s, %lld accurate solves "
                                "(%lld GMRES iterations) in %.2f s\n",
                                rep.corrections, rep.correct_seconds, rep.correction, st.columns, st.column_seconds, st.solves, st.iterations, st.solve_seconds));
  }
  if (s.output.empty()) return;
  ResultData r = result_base(s, size);
  r.attributes_str["solver"] = "contact";
  r.attributes_str["mat_type"] = mat_type_of(body_h2);
  r.displacement = vertex_average(*s.disc, sol.u);
  r.traction = vertex_average(*s.disc, sol.t);
  r.traction_corner = corner_values(*s.disc, sol.t);
  r.displacement_prescribed = vertex_displacement_prescribed(*s.disc, nc);
  r.reactions = reactions(*s.disc, sol.t);
  const NodalSolution nodal{sol.u, sol.t};
  std::vector<NodeStress> nodes;
  {
    const Timer timer;
    const EventScope event(BEM_Stress);
    r.stress = surface_stress_fields(s, nodal, nodes, true);
    seconds["stress"] += timer.seconds();
  }
  interior_fields(PETSC_COMM_SELF, s, nodal, nodes, interior, r, seconds); // the contact run is rank 0's
  r.contact = contact_data(*engine, sol, rep, s.spec.contact.bodies);
  r.timings = seconds;
  const EventScope event(BEM_Output);
  write_result(s.output, r);
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: wrote %s\n", s.output.c_str()));
}

void ContactRun::scene(const std::vector<NodeConditions> &frames)
{
  std::unique_ptr<FrameWriter> writer;
  if (!s.output.empty()) {
    ResultData base = result_base(s, size);
    base.attributes_str["solver"] = "contact";
    base.attributes_str["mat_type"] = mat_type_of(body_h2);
    writer = std::make_unique<FrameWriter>(s.output, base);
  }
  double total = 0, slowest = 0;
  long long iterations = 0;
  { // the progress line ends before the summary
    const Progress progress("contact frames");
    for (frame = 0; frame < static_cast<long long>(frames.size()); ++frame) {
      fault_point("Frame");
      ContactSolution sol;
      ContactFrameReport rep;
      {
        const EventScope event(SCN_Frame);
        rep = engine->solve(selection_of(frames[frame]), placements[frame], sol);
      }
      total += rep.seconds, slowest = std::max(slowest, rep.seconds), iterations += rep.iterations;
      check_finite(sol, frame);
      progress.report(static_cast<double>(frame + 1) / static_cast<double>(frames.size()));
      if (!writer) continue;
      FrameData f;
      f.displacement = vertex_average(*s.disc, sol.u);
      f.traction = vertex_average(*s.disc, sol.t);
      f.displacement_prescribed = vertex_displacement_prescribed(*s.disc, frames[frame]);
      f.attributes_real = {{"seconds", rep.seconds}};
      f.attributes_int = {{"iterations", rep.iterations}, {"active_vertices", rep.active_vertices}};
      std::vector<NodeStress> nodes;
      f.stress = surface_stress_fields(s, NodalSolution{sol.u, sol.t}, nodes, false);
      f.contact = contact_data(*engine, sol, rep, s.spec.contact.bodies);
      const EventScope event(BEM_Output);
      writer->append(static_cast<std::size_t>(frame), f);
    }
  }
  const double n = static_cast<double>(frames.size());
  seconds["frames"] += total;
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: %zu frames in %.3f s (%.2f ms per frame, %.0f Hz; slowest %.2f ms); %.2f iterations per frame\n", frames.size(),
                              total, 1e3 * total / n, n / std::max(total, 1e-12), 1e3 * slowest, iterations / n));
  if (!writer) return;
  writer->commit(seconds, {{"num_frames", static_cast<long long>(frames.size())}}, {{"frame_seconds_mean", total / n}});
  HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: wrote %s\n", s.output.c_str()));
}

/// Per body (one entry when the mesh is one body), whether its reference is the H² one: all
/// when asked (-bem_mat_type h2), none when dense is asked (an error if they do not fit the node's
/// memory together); with auto, the bodies in order take the dense reference while the dense
/// ones fit the node's memory together, the others the H² one. HSS is refused.
std::vector<char> references_on_h2(MPI_Comm comm, const ProblemSetup &s, std::optional<OperatorType> asked)
{
  if (asked && *asked == OperatorType::Hss)
    throw std::runtime_error("-bem_mat_type hss: contact runs on the dense or the H2 reference factorization; use -bem_mat_type dense, h2 or auto");
  const std::vector<int> node_body = node_bodies(*s.disc);
  std::vector<double> unknowns(node_body.empty() ? 1 : *std::max_element(node_body.begin(), node_body.end()) + 1, 0.0);
  for (int i = 0; i < s.disc->num_nodes(); ++i) unknowns[node_body.empty() ? 0 : node_body[i]] += 3;
  MachineLimits limits;
  HssbemCallThrow(HssbemMachineLimits(comm, &limits));
  const double room = 0.9 * static_cast<double>(limits.node_memory_bytes);
  std::vector<char> h2(unknowns.size(), asked && *asked == OperatorType::H2);
  double need = 0, total = 0;
  for (std::size_t b = 0; b < unknowns.size(); ++b) {
    const double nb = 8.0 * unknowns[b] * unknowns[b] * 3.0; // the LU, K₀′ (at most), W's columns (at most N_b)
    total += nb;
    if (asked) continue;
    h2[b] = need + nb > room;
    if (!h2[b]) need += nb;
  }
  if (asked && *asked == OperatorType::Dense && total > room)
    throw std::runtime_error("contact needs about " + std::to_string(static_cast<long long>(total / 1e9 + 0.5)) + " GB for " + std::to_string(3LL * s.disc->num_nodes()) +
                             " unknowns (dense reference factorization, the operator's columns, W's columns), more than this node's " +
                             std::to_string(static_cast<long long>(limits.node_memory_bytes / 1e9)) + " GB; use -bem_mat_type h2");
  return h2;
}

} // namespace

void run_contact(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, std::optional<OperatorType> asked, const ContactRunOptions &o, const InteriorRunOptions &interior,
                 std::map<std::string, double> seconds)
{
  PetscMPIInt rank, size;
  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  const std::vector<char> body_h2 = references_on_h2(comm, s, asked);
  const bool on_h2 = std::any_of(body_h2.begin(), body_h2.end(), [](char c) { return c != 0; });
  H2Options h2;
  if (on_h2) { // the driver's H² defaults (petsc/system.cxx), then -mat_h2_*
    h2.rel_tol = 1e-5, h2.single_precision = true;
    HssbemCallThrow(HssbemH2OptionsFromDatabase(comm, NULL, &h2));
  }
  HssbemCallThrow(PetscPrintf(comm, "hssbem: contact: %zu obstacles%s, %zu frames, on the %s reference factorization (rank 0)\n", s.spec.contact.obstacles.size(),
                              s.spec.contact.bodies ? " and the bodies" : "", std::max<std::size_t>(1, s.spec.frames.size()), mat_type_of(body_h2) == "dense,h2" ? "dense and H2" : on_h2 ? "H2" : "dense"));
  run_collectively(comm, [&] {
    if (rank != 0) return;
    const NodeConditions base = apply_rules(s.spec.rules, *s.disc, s.spec.file);
    const std::vector<NodeConditions> frames = frames_of(s, base);
    ContactRun run{s, op, o, interior, size, seconds, on_h2 ? &h2 : nullptr, body_h2, nullptr, nullptr, {}};
    run.set_up(base, frames);
    if (s.spec.frames.empty()) run.single(frames[0]);
    else run.scene(frames);
  });
}

} // namespace hssbem
