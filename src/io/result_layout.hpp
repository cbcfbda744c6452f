/// \file result_layout.hpp
/// Private to the result writers: the parts of write_result's layout that FrameWriter shares
/// (validation, the groups of a ResultData, /timings, the sidecar's grid), defined in
/// hdf5_output.cpp.
#pragma once

#include "collective.hpp"
#include "h5_writer.hpp"
#include "xdmf.hpp"

#include "hssbem/io/hdf5_output.hpp"

#include <cmath>
#include <map>
#include <string>
#include <type_traits>

namespace hssbem::detail {

/// out.h5 -> out.xdmf; a dot in a directory name is not taken for an extension.
std::string xdmf_path(const std::string &path);

/// An array that is `required` (or not empty) must have `expected` entries, one per `per`
/// ("vertex"); throws OutputError naming `path` and `dataset` otherwise.
void check_size(const std::string &path, const std::string &dataset, std::size_t size,
                std::size_t expected, const char *per, bool required);

/// Throws OutputError naming `path`, `dataset`, the row and the value: a non-finite value in a
/// result is a failed solve, never written.
[[noreturn]] void fail_not_finite(const std::string &path, const std::string &dataset, std::size_t row, double value);

/// Every value of `rows` must be finite, in the rows where `only` (if given: one flag per row,
/// e.g. the interior grid's inside) is not 0; with `allow_nan` a NaN passes (a gap with no
/// obstacle within reach), an infinity does not.
template <class Row>
void check_finite(const std::string &path, const std::string &dataset, const std::vector<Row> &rows, const std::vector<int> *only = nullptr, bool allow_nan = false)
{
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (only && i < only->size() && (*only)[i] == 0) continue;
    const auto check = [&](double x) {
      if (!std::isfinite(x) && !(allow_nan && std::isnan(x))) fail_not_finite(path, dataset, i, x);
    };
    if constexpr (std::is_arithmetic_v<Row>) check(static_cast<double>(rows[i]));
    else
      for (double x : rows[i]) check(x);
  }
}

/// An HDF5 link name the layout can use for a user's name (an obstacle's, a region's): not
/// empty, ".", or "..", no '/', no control character.
bool link_name_ok(const std::string &name);

/// Refuses inconsistent data (empty mesh, bad indices, incomplete arrays, non-finite values,
/// unusable region names) before any file is created. Throws OutputError naming `path`.
void validate_result(const std::string &path, const ResultData &d);

/// The attributes, timings and reactions of `d`.
ResultMetadata metadata_of(const ResultData &d);

/// /mesh, /fields, /bc and /interior of `d`, /reactions, the root attributes and /options of
/// `meta`; not /timings.
void write_result_groups(H5Writer &w, const ResultData &d, const ResultMetadata &meta);

/// The group `name` (/contact or /frames/<i>/contact) of a contact's results.
void write_contact(H5Writer &w, const std::string &name, const ContactData &c);
/// Refuses contact arrays that are not one entry per vertex (nv) or names that cannot be datasets.
void check_contact(const std::string &path, const std::string &group, const ContactData &c, std::size_t nv);
/// The sidecar's contact fields (pressure, contact_status) read from `group`.
std::vector<XdmfAttribute> contact_attributes(const std::string &group, std::size_t nv);

// --- the obstacles' part of the layout (obstacle_output.cpp) -------------------------------

/// /obstacles/<name>/{vertices, triangles} and the attribute shape (nothing when empty).
void write_obstacles(H5Writer &w, const std::vector<ObstacleSurface> &obstacles);
/// <frame>/obstacles/<name>/vertices for each obstacle of `base` (nothing when `vertices` is empty).
void write_frame_obstacles(H5Writer &w, const std::string &frame, const std::vector<ObstacleSurface> &base, const std::vector<std::vector<Vec3>> &vertices);
/// Usable, distinct names; a surface each, triangles within it, finite vertices.
void check_obstacles(const std::string &path, const std::vector<ObstacleSurface> &obstacles);
/// A frame's obstacles: none, or one surface per obstacle of `base` with its vertex count, finite.
void check_frame_obstacles(const std::string &path, const std::string &frame, const std::vector<ObstacleSurface> &base, const std::vector<std::vector<Vec3>> &vertices);
/// The sidecar's grid of each obstacle, from /obstacles/<name>.
std::vector<XdmfGrid> obstacle_grids(const std::string &h5_name, const std::vector<ObstacleSurface> &obstacles);
/// A scene's sidecar: per obstacle a temporal collection, step i from /frames/<i>/obstacles/<name>
/// where placed[i], else from /obstacles/<name>.
std::vector<XdmfCollection> obstacle_collections(const std::string &h5_name, const std::vector<ObstacleSurface> &obstacles, const std::vector<bool> &placed);

/// /timings: one float64 attribute per phase (seconds).
void write_timings(H5Writer &w, const std::map<std::string, double> &timings);

/// A per-vertex 3-vector field of the sidecar, read from `dataset`.
XdmfAttribute node_vectors(const std::string &name, const std::string &dataset, std::size_t nv,
                           XdmfNumber number);

/// The sidecar's grid for the mesh of `d` with its per-mesh fields (sharp_vertex,
/// triangle_region) and no solution: each frame's grid starts from it.
XdmfGrid mesh_grid(const std::string &path, const ResultData &d);

/// The sidecar's grid of write_result: mesh_grid plus exactly the /fields and /bc datasets
/// written, so the sidecar never points at a missing one.
XdmfGrid result_grid(const std::string &path, const ResultData &d);

/// write_result's sidecar: result_grid, and the interior grid's rectilinear grid if any.
std::string result_sidecar(const std::string &path, const ResultData &d);

// --- the stress part of the layout (stress_output.cpp) -------------------------------------

/// <group>/{stress, von_mises, principal_stress, stress_corner}: those of f that are not empty.
void write_stress(H5Writer &w, const H5Handle &g, const std::string &group, const StressFields &f);
/// /interior/{stress, von_mises} into the open group /interior (g).
void write_interior_stress(H5Writer &w, const H5Handle &g, const ResultData &d);
/// /interior/grid (x, y, z, displacement, stress, von_mises, inside; origin, spacing and points
/// as attributes), when there is a grid; /interior must exist.
void write_interior_grid(H5Writer &w, const InteriorGridData &g);
/// Each non-empty field of f has one entry per vertex (nv) or triangle (nt), every value finite.
void check_stress_sizes(const std::string &path, const std::string &group, const StressFields &f, std::size_t nv, std::size_t nt);
/// One stress per interior point, and a consistent grid; finite values (the grid's inside its body).
void check_interior_stress(const std::string &path, const ResultData &d);
/// The sidecar's attributes of f in `group`: von_mises, principal_stress and stress_xx ... stress_xy.
std::vector<XdmfAttribute> stress_attributes(const std::string &group, const StressFields &f, std::size_t nv);
/// The sidecar's rectilinear grid of the interior grid (none when empty).
std::vector<XdmfRectGrid> interior_grid_view(const std::string &h5_name, const InteriorGridData &g);

} // namespace hssbem::detail
