// C++ storage as numpy arrays without copies (see bind.hpp).
#include "bind.hpp"

namespace hssbem::py_module {

namespace {

template <class T>
py::array view(const T *data, std::vector<py::ssize_t> shape, py::handle owner)
{
  // The storage outlives the array: `owner` (the Python object that holds it) is its base.
  return py::array(py::dtype::of<T>(), std::move(shape), {}, data, owner);
}

py::ssize_t size(std::size_t n) { return static_cast<py::ssize_t>(n); }

} // namespace

py::array view_vec3(const std::vector<Vec3> &v, py::handle owner) { return view(v.empty() ? nullptr : v[0].data(), {size(v.size()), 3}, owner); }
py::array view_voigt(const std::vector<Voigt> &v, py::handle owner) { return view(v.empty() ? nullptr : v[0].data(), {size(v.size()), 6}, owner); }
py::array view_doubles(const std::vector<double> &v, py::handle owner) { return view(v.data(), {size(v.size())}, owner); }
py::array view_mask(const std::vector<std::array<bool, 3>> &v, py::handle owner)
{
  static_assert(sizeof(std::array<bool, 3>) == 3, "a mask row is three bytes");
  return view(v.empty() ? nullptr : v[0].data(), {size(v.size()), 3}, owner);
}

py::array view_triangles(const std::vector<std::array<int, 3>> &t, py::handle owner) { return view(t.empty() ? nullptr : t[0].data(), {size(t.size()), 3}, owner); }

py::array copy_vec3(const Vec3 &v)
{
  py::array_t<double> a(3);
  std::copy(v.begin(), v.end(), a.mutable_data());
  return std::move(a);
}

py::dict fields_of(const ResultData &r, py::handle owner)
{
  py::dict d;
  if (!r.displacement.empty()) d["displacement"] = view_vec3(r.displacement, owner);
  if (!r.traction.empty()) d["traction"] = view_vec3(r.traction, owner);
  if (!r.traction_corner.empty())
    d["traction_corner"] = view(r.traction_corner[0][0].data(), {size(r.traction_corner.size()), 3, 3}, owner);
  if (!r.stress.stress.empty()) d["stress"] = view_voigt(r.stress.stress, owner);
  if (!r.stress.von_mises.empty()) d["von_mises"] = view_doubles(r.stress.von_mises, owner);
  if (!r.stress.principal.empty()) d["principal_stress"] = view_vec3(r.stress.principal, owner);
  if (!r.stress.corner.empty()) d["stress_corner"] = view(r.stress.corner[0][0].data(), {size(r.stress.corner.size()), 3, 6}, owner);
  return d;
}

py::dict contact_of(const ContactData &c, py::handle owner)
{
  py::dict d;
  if (!c.present()) return d;
  d["pressure"] = view_doubles(c.pressure, owner);
  d["gap"] = view_doubles(c.gap, owner);
  d["status"] = view(c.status.data(), {size(c.status.size())}, owner);
  py::dict forces;
  for (const auto &[name, f] : c.forces) forces[py::str(name)] = copy_vec3(f);
  d["forces"] = forces;
  d["iterations"] = c.iterations;
  d["active_vertices"] = c.active_vertices;
  return d;
}

} // namespace hssbem::py_module
