/// \file stress_output.cpp
/// The stress part of the result layout (see hdf5_output.hpp): the surface's stress fields
/// (/fields or a frame's group), the interior points' stress and the interior grid, their size
/// checks and their XDMF view. The Voigt stress appears in the sidecar as one 6-component
/// "Matrix" attribute `stress` (xx, yy, zz, yz, xz, xy), the dataset as it is: XDMF's Tensor6
/// orders its entries differently, and a column taken by a HyperSlab item is more than some
/// readers take (meshio reads plain HDF items only).
#include "result_layout.hpp"

#include <cmath>

namespace hssbem::detail {

namespace {

std::vector<double> flat_voigt(const std::vector<Voigt> &v) { return flatten(v); }

/// Coordinates of the grid's points along axis a.
std::vector<double> axis_coordinates(const InteriorGridData &g, int a)
{
  std::vector<double> x(static_cast<std::size_t>(g.points[a]));
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = g.origin[a] + static_cast<double>(i) * g.spacing[a];
  return x;
}

/// Dimensions of a grid dataset: points along z, y, x, then `components` (none when 0).
std::vector<hsize_t> grid_dims(const InteriorGridData &g, int components)
{
  if (components > 0)
    return {count(g.points[2]), count(g.points[1]), count(g.points[0]), static_cast<hsize_t>(components)};
  return {count(g.points[2]), count(g.points[1]), count(g.points[0])};
}

} // namespace

void write_stress(H5Writer &w, const H5Handle &g, const std::string &group, const StressFields &f)
{
  if (!f.stress.empty())
    w.dataset(g.get(), group, "stress", doubles(flat_voigt(f.stress), {count(f.stress.size()), 6}));
  if (!f.von_mises.empty())
    w.dataset(g.get(), group, "von_mises", doubles(f.von_mises, {count(f.von_mises.size())}));
  if (!f.principal.empty())
    write_vec3s(w, g, group, "principal_stress", f.principal);
  if (!f.corner.empty())
    w.dataset(g.get(), group, "stress_corner", doubles(flatten(flatten(f.corner)), {count(f.corner.size()), 3, 6}));
}

void write_interior_stress(H5Writer &w, const H5Handle &g, const ResultData &d)
{
  if (!d.interior_stress.empty())
    w.dataset(g.get(), "/interior", "stress", doubles(flat_voigt(d.interior_stress), {count(d.interior_stress.size()), 6}));
  if (!d.interior_von_mises.empty())
    w.dataset(g.get(), "/interior", "von_mises", doubles(d.interior_von_mises, {count(d.interior_von_mises.size())}));
}

void write_interior_grid(H5Writer &w, const InteriorGridData &g)
{
  if (g.empty())
    return;
  const std::string name = "/interior/grid";
  H5Handle h = w.group(name);
  const char *axes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    const std::vector<double> x = axis_coordinates(g, a);
    w.dataset(h.get(), name, axes[a], doubles(x, {count(x.size())}));
  }
  w.dataset(h.get(), name, "displacement", doubles(flatten(g.displacement), grid_dims(g, 3)));
  if (!g.stress.empty())
    w.dataset(h.get(), name, "stress", doubles(flat_voigt(g.stress), grid_dims(g, 6)));
  if (!g.von_mises.empty())
    w.dataset(h.get(), name, "von_mises", doubles(g.von_mises, grid_dims(g, 0)));
  w.dataset(h.get(), name, "inside", int8s(to_int8(g.inside), grid_dims(g, 0)));
  const std::map<std::string, double> real{{"origin_x", g.origin[0]}, {"origin_y", g.origin[1]}, {"origin_z", g.origin[2]},
                                           {"spacing_x", g.spacing[0]}, {"spacing_y", g.spacing[1]}, {"spacing_z", g.spacing[2]}};
  const std::map<std::string, long long> integer{{"points_x", g.points[0]}, {"points_y", g.points[1]}, {"points_z", g.points[2]}};
  const std::map<std::string, std::string> text;
  write_attributes(w, h.get(), name, {real, integer, text});
  w.end_group(h, name);
}

void check_stress_sizes(const std::string &path, const std::string &group, const StressFields &f, std::size_t nv, std::size_t nt)
{
  check_size(path, group + "/stress", f.stress.size(), nv, "vertex", false);
  check_size(path, group + "/von_mises", f.von_mises.size(), nv, "vertex", false);
  check_size(path, group + "/principal_stress", f.principal.size(), nv, "vertex", false);
  check_size(path, group + "/stress_corner", f.corner.size(), nt, "triangle", false);
  check_finite(path, group + "/stress", f.stress);
  check_finite(path, group + "/von_mises", f.von_mises);
  check_finite(path, group + "/principal_stress", f.principal);
  for (std::size_t t = 0; t < f.corner.size(); ++t) check_finite(path, group + "/stress_corner[" + std::to_string(t) + "]", std::vector<Voigt>(f.corner[t].begin(), f.corner[t].end()));
}

void check_interior_stress(const std::string &path, const ResultData &d)
{
  check_size(path, "/interior/stress", d.interior_stress.size(), d.interior_points.size(), "interior point", false);
  check_size(path, "/interior/von_mises", d.interior_von_mises.size(), d.interior_points.size(), "interior point", false);
  check_finite(path, "/interior/stress", d.interior_stress);
  check_finite(path, "/interior/von_mises", d.interior_von_mises);
  const InteriorGridData &g = d.interior_grid;
  if (g.empty())
    return;
  for (int a = 0; a < 3; ++a)
    if (g.points[a] < 2 || !(g.spacing[a] > 0) || !std::isfinite(g.origin[a]))
      fail_output(path, "/interior/grid needs at least 2 points and a positive spacing along each axis");
  const std::size_t n = g.size();
  check_size(path, "/interior/grid/displacement", g.displacement.size(), n, "grid point", true);
  check_size(path, "/interior/grid/stress", g.stress.size(), n, "grid point", false);
  check_size(path, "/interior/grid/von_mises", g.von_mises.size(), n, "grid point", false);
  check_size(path, "/interior/grid/inside", g.inside.size(), n, "grid point", true);
  for (int flag : g.inside)
    if (flag != 0 && flag != 1)
      fail_output(path, "/interior/grid/inside holds " + std::to_string(flag) + ", expected 0 or 1");
  check_finite(path, "/interior/grid/displacement", g.displacement, &g.inside); // NaN outside the body
  check_finite(path, "/interior/grid/stress", g.stress, &g.inside);
  check_finite(path, "/interior/grid/von_mises", g.von_mises, &g.inside);
}

std::vector<XdmfAttribute> stress_attributes(const std::string &group, const StressFields &f, std::size_t nv)
{
  std::vector<XdmfAttribute> out;
  if (!f.von_mises.empty())
    out.push_back({"von_mises", "Scalar", "Node", {group + "/von_mises", {nv}, XdmfNumber::float64}});
  if (!f.principal.empty())
    out.push_back(node_vectors("principal_stress", group + "/principal_stress", nv, XdmfNumber::float64));
  if (!f.stress.empty())
    out.push_back({"stress", "Matrix", "Node", {group + "/stress", {nv, 6}, XdmfNumber::float64}});
  return out;
}

std::vector<XdmfRectGrid> interior_grid_view(const std::string &h5_name, const InteriorGridData &g)
{
  if (g.empty())
    return {};
  const std::string name = "/interior/grid";
  XdmfRectGrid r;
  r.h5_name = h5_name;
  r.name = "interior_grid";
  r.points = {static_cast<std::size_t>(g.points[0]), static_cast<std::size_t>(g.points[1]), static_cast<std::size_t>(g.points[2])};
  r.axes = {name + "/x", name + "/y", name + "/z"};
  const std::vector<std::size_t> dims{r.points[2], r.points[1], r.points[0]};
  auto with = [&](std::size_t c) { return std::vector<std::size_t>{r.points[2], r.points[1], r.points[0], c}; };
  r.attributes.push_back({"displacement", "Vector", "Node", {name + "/displacement", with(3), XdmfNumber::float64}});
  if (!g.von_mises.empty())
    r.attributes.push_back({"von_mises", "Scalar", "Node", {name + "/von_mises", dims, XdmfNumber::float64}});
  if (!g.stress.empty())
    r.attributes.push_back({"stress", "Matrix", "Node", {name + "/stress", with(6), XdmfNumber::float64}});
  r.attributes.push_back({"inside", "Scalar", "Node", {name + "/inside", dims, XdmfNumber::int8}});
  return {r};
}

} // namespace hssbem::detail
