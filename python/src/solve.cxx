// hssbem.solve(): a problem solved once, as the command line solves it (run_problem), its result
// handed to Python instead of (or besides) a file. See bind.hpp.
#include "bind.hpp"

#include "hssbem/app/options.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/petsc/system.h"
#include "hssbem/session/choice.hpp"
#include "hssbem/session/contact_session.hpp"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/static_session.hpp"

#include <pybind11/stl.h>

namespace hssbem::py_module {

namespace {

struct SolveResult;
void write_output(const SolveResult &r, const std::string &output);

/// A solve's result: what the result file holds, on every rank (a static solve) or on rank 0
/// (a contact, which runs on rank 0 as in the driver).
struct SolveResult {
  std::shared_ptr<ResultData> data = std::make_shared<ResultData>();
  MPI_Comm comm = MPI_COMM_NULL;
  bool on_every_rank = true;
  std::vector<std::string> notices;

  /// The same file as the command line writes (collective on the solve's communicator).
  void write(const std::string &path) const
  {
    const CallEnvironment env({});
    guarded([&] { write_output(*this, path); });
  }
};

void write_output(const SolveResult &r, const std::string &output)
{
  if (output.empty()) return;
  if (r.on_every_rank) return write_result(r.comm, output, *r.data);
  PetscMPIInt rank;
  HssbemCallMPIThrow(MPI_Comm_rank(r.comm, &rank));
  run_collectively(r.comm, [&] {
    if (rank == 0) write_result(output, *r.data);
  });
}

/// A static solve on every rank (StaticSession), as run_static.
void solve_static(SolveResult &r, std::shared_ptr<const SessionProblem> problem, const DriverOptions &o, std::map<std::string, double> seconds)
{
  StaticSession session(r.comm, problem, o.session);
  session.timings() = std::move(seconds);
  session.create_solver();
  check_unused_options(r.comm, true);
  session.solve();
  check_unused_options(r.comm, false);
  *r.data = session.result();
}

/// A contact's single solve on rank 0 (ContactSession), as run_contact.
void solve_contact(SolveResult &r, std::shared_ptr<const SessionProblem> problem, const DriverOptions &o, std::map<std::string, double> seconds)
{
  PetscMPIInt   rank, size;
  MachineLimits limits;
  HssbemCallMPIThrow(MPI_Comm_rank(r.comm, &rank));
  HssbemCallMPIThrow(MPI_Comm_size(r.comm, &size));
  HssbemCallThrow(HssbemMachineLimits(r.comm, &limits));
  check_unused_options(r.comm, false);
  (void)contact_references_on_h2(problem->disc(), o.session.operator_type, limits); // every rank: the same error everywhere
  r.on_every_rank = false;
  run_collectively(r.comm, [&] {
    if (rank != 0) return;
    ContactSession session(problem, contact_job(problem->setup()), o.session, limits);
    session.timings() = std::move(seconds);
    session.set_up();
    session.step(0);
    *r.data = session.result(size);
  });
}

std::shared_ptr<SolveResult> solve_in(std::shared_ptr<SolveResult> r, const ProblemInput &in);

std::shared_ptr<SolveResult> solve(const ProblemInput &in, const OptionList &options, std::optional<long long> comm_handle)
{
  auto r = std::make_shared<SolveResult>();
  r->comm = comm_of(comm_handle);
  const CallEnvironment env(options, r->comm);
  return guarded([&] { return solve_in(r, in); });
}

std::shared_ptr<SolveResult> solve_in(std::shared_ptr<SolveResult> r, const ProblemInput &in)
{
  const DriverOptions o = read_driver_options(r->comm);
  const Timer timer;
  const std::shared_ptr<const ProblemSetup> s = set_up(r->comm, in, o.overrides);
  check_output(r->comm, *s);
  r->notices = s->notices;
  std::shared_ptr<const SessionProblem> problem;
  run_collectively(r->comm, [&] { problem = std::make_shared<SessionProblem>(s, o.session.quad); });
  std::map<std::string, double> seconds{{"setup", timer.seconds()}};
  switch (problem->job()) {
  case JobKind::Static: solve_static(*r, problem, o, std::move(seconds)); break;
  case JobKind::Contact:
    if (!s->spec.frames.empty()) throw std::invalid_argument(problem->where() + "the problem has \"frames\": hssbem.Scene solves them frame by frame");
    solve_contact(*r, problem, o, std::move(seconds));
    break;
  case JobKind::Scene: throw std::invalid_argument(problem->where() + "the problem has \"frames\": a scene, which hssbem.Scene solves frame by frame");
  }
  write_output(*r, s->output);
  return r;
}

template <class Map>
py::dict dict_of(const Map &m)
{
  py::dict d;
  for (const auto &[k, v] : m) d[py::str(k)] = v;
  return d;
}

} // namespace

void bind_solve(py::module_ &m)
{
  py::class_<ProblemInput>(m, "ProblemInput", "A problem as hssbem.solve() hands it over (internal).")
      .def(py::init([](std::string path, std::string json, py::object vertices, py::object triangles) {
             ProblemInput in{std::move(path), std::move(json), nullptr};
             if (!vertices.is_none()) in.mesh = mesh_of_arrays(vertices, triangles);
             return in;
           }),
           py::arg("path"), py::arg("json"), py::arg("vertices"), py::arg("triangles"));

  py::class_<SolveResult, std::shared_ptr<SolveResult>>(m, "SolveResult", "What a solve returns (internal: hssbem.Result wraps it).")
      .def("fields", [](py::object self) { return fields_of(*self.cast<SolveResult &>().data, self); })
      .def("bc", [](py::object self) {
        py::dict d;
        const ResultData &r = *self.cast<SolveResult &>().data;
        if (!r.displacement_prescribed.empty()) d["displacement_prescribed"] = view_mask(r.displacement_prescribed, self);
        return d;
      })
      .def("mesh", [](py::object self) {
        const ResultData &r = *self.cast<SolveResult &>().data;
        py::dict d;
        if (r.vertices.empty()) return d;
        d["vertices"] = view_vec3(r.vertices, self);
        d["triangles"] = view_triangles(r.triangles, self);
        d["triangle_region"] = py::array(py::dtype::of<int>(), {static_cast<py::ssize_t>(r.triangle_region.size())}, {}, r.triangle_region.data(), self);
        d["sharp_vertex"] = py::array(py::dtype::of<int>(), {static_cast<py::ssize_t>(r.sharp_vertex.size())}, {}, r.sharp_vertex.data(), self);
        return d;
      })
      .def("interior", [](py::object self) {
        const ResultData &r = *self.cast<SolveResult &>().data;
        py::dict d;
        if (!r.interior_points.empty()) {
          d["points"] = view_vec3(r.interior_points, self);
          d["displacement"] = view_vec3(r.interior_displacement, self);
          if (!r.interior_stress.empty()) d["stress"] = view_voigt(r.interior_stress, self);
          if (!r.interior_von_mises.empty()) d["von_mises"] = view_doubles(r.interior_von_mises, self);
        }
        const InteriorGridData &g = r.interior_grid;
        if (!g.empty()) {
          py::dict gd;
          const std::vector<py::ssize_t> dims{g.points[2], g.points[1], g.points[0]};
          auto shaped = [&](py::array a, py::ssize_t last) {
            std::vector<py::ssize_t> sh = dims;
            if (last) sh.push_back(last);
            return a.reshape(sh);
          };
          gd["displacement"] = shaped(view_vec3(g.displacement, self), 3);
          if (!g.stress.empty()) gd["stress"] = shaped(view_voigt(g.stress, self), 6);
          if (!g.von_mises.empty()) gd["von_mises"] = shaped(view_doubles(g.von_mises, self), 0);
          gd["inside"] = shaped(py::array(py::dtype::of<int>(), {static_cast<py::ssize_t>(g.inside.size())}, {}, g.inside.data(), self), 0);
          gd["origin"] = copy_vec3(g.origin);
          gd["spacing"] = copy_vec3(g.spacing);
          gd["points"] = py::make_tuple(g.points[0], g.points[1], g.points[2]);
          d["grid"] = gd;
        }
        return d;
      })
      .def("contact", [](py::object self) { return contact_of(self.cast<SolveResult &>().data->contact, self); })
      .def("reactions", [](const SolveResult &r) {
        py::dict d;
        for (const auto &[region, f] : r.data->reactions) d[py::str(region)] = copy_vec3(f);
        return d;
      })
      .def("attributes", [](const SolveResult &r) {
        py::dict d = dict_of(r.data->attributes_real);
        d.attr("update")(dict_of(r.data->attributes_int));
        d.attr("update")(dict_of(r.data->attributes_str));
        return d;
      })
      .def("options", [](const SolveResult &r) {
        py::dict d = dict_of(r.data->options_real);
        d.attr("update")(dict_of(r.data->options_int));
        d.attr("update")(dict_of(r.data->options_str));
        return d;
      })
      .def("timings", [](const SolveResult &r) { return dict_of(r.data->timings); })
      .def_readonly("notices", &SolveResult::notices)
      .def_readonly("on_every_rank", &SolveResult::on_every_rank)
      .def("write", &SolveResult::write, py::arg("path"));

  m.def("solve", &solve, py::arg("problem"), py::arg("options"), py::arg("comm"), "hssbem.solve's compiled part (internal).");
}

} // namespace hssbem::py_module
