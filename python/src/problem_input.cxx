// The problem as the Python side hands it over, set up as the driver sets up a problem file (see
// bind.hpp).
#include "bind.hpp"

#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/result_fields.hpp"

#include <cmath>
#include <stdexcept>

namespace hssbem::py_module {

namespace {

/// arr as an (n, 3) array of `kind` ('f' real, 'i' integer; unsigned integers pass as integers).
py::array checked_rows(const py::object &obj, const std::string &name, char kind)
{
  py::array arr = py::array::ensure(obj);
  if (!arr) throw std::invalid_argument("mesh." + name + ": expected an array, got " + std::string(py::str(py::type::of(obj).attr("__name__"))));
  const char k = arr.dtype().kind();
  const bool ok = kind == 'f' ? (k == 'f' || k == 'i' || k == 'u') : (k == 'i' || k == 'u');
  if (!ok)
    throw std::invalid_argument("mesh." + name + ": expected " + (kind == 'f' ? "real numbers" : "integers") + ", got dtype " + std::string(py::str(arr.dtype())));
  if (arr.ndim() != 2 || arr.shape(1) != 3) {
    std::string shape;
    for (py::ssize_t d = 0; d < arr.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(arr.shape(d));
    throw std::invalid_argument("mesh." + name + ": expected shape (n, 3), got (" + shape + (arr.ndim() == 1 ? "," : "") + ")");
  }
  return arr;
}

} // namespace

std::shared_ptr<const SurfaceMesh> mesh_of_arrays(const py::object &vertices, const py::object &triangles)
{
  const py::array v = checked_rows(vertices, "vertices", 'f'), t = checked_rows(triangles, "triangles", 'i');
  const auto vd = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
  const auto td = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(t);
  auto mesh = std::make_shared<SurfaceMesh>();
  mesh->source = "<arrays>";
  const double *x = vd.data();
  for (py::ssize_t i = 0; i < vd.shape(0); ++i) {
    if (!std::isfinite(x[3 * i]) || !std::isfinite(x[3 * i + 1]) || !std::isfinite(x[3 * i + 2]))
      throw std::invalid_argument("mesh.vertices: vertex " + std::to_string(i) + " has a non-finite coordinate");
    mesh->vertices.push_back({x[3 * i], x[3 * i + 1], x[3 * i + 2]});
  }
  const long long *c = td.data(), nv = static_cast<long long>(mesh->vertices.size());
  for (py::ssize_t i = 0; i < td.shape(0); ++i) {
    for (int k = 0; k < 3; ++k)
      if (c[3 * i + k] < 0 || c[3 * i + k] >= nv)
        throw std::invalid_argument("mesh.triangles: triangle " + std::to_string(i) + " names vertex " + std::to_string(c[3 * i + k]) + ", outside 0.." + std::to_string(nv - 1));
    mesh->triangles.push_back({static_cast<int>(c[3 * i]), static_cast<int>(c[3 * i + 1]), static_cast<int>(c[3 * i + 2])});
  }
  if (mesh->triangles.empty()) throw std::invalid_argument("mesh.triangles: no triangle");
  mesh->triangle_region.assign(mesh->triangles.size(), -1);
  return mesh;
}

std::shared_ptr<const ProblemSetup> set_up(MPI_Comm comm, const ProblemInput &in, ProblemOverrides overrides)
{
  std::shared_ptr<ProblemSetup> s;
  overrides.mesh_data = in.mesh;
  run_collectively(comm, [&] {
    ProblemSpec spec = in.path.empty() ? parse_problem(in.json, "problem") : read_problem(in.path);
    if (in.mesh) spec.mesh_path = in.mesh->source;
    s = std::make_shared<ProblemSetup>(setup_problem(std::move(spec), overrides));
    check_interior_points(*s);
  });
  return s;
}

void check_output(MPI_Comm comm, const ProblemSetup &s)
{
  PetscMPIInt rank;
  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  run_collectively(comm, [&] {
    if (rank == 0 && !s.output.empty()) check_output_path(s.output, s.input_files);
  });
}

} // namespace hssbem::py_module
