/// \file result_layout.hpp
/// Private to the result writers: the parts of write_result's layout that FrameWriter shares
/// (validation, the groups of a ResultData, /timings, the sidecar's grid), defined in
/// hdf5_output.cpp.
#pragma once

#include "collective.hpp"
#include "h5_writer.hpp"
#include "xdmf.hpp"

#include "hssbem/io/hdf5_output.hpp"

#include <map>
#include <string>

namespace hssbem::detail {

/// out.h5 -> out.xdmf; a dot in a directory name is not taken for an extension.
std::string xdmf_path(const std::string &path);

/// An array that is `required` (or not empty) must have `expected` entries, one per `per`
/// ("vertex"); throws OutputError naming `path` and `dataset` otherwise.
void check_size(const std::string &path, const std::string &dataset, std::size_t size,
                std::size_t expected, const char *per, bool required);

/// Every value of `rows` must be finite (a NaN or an infinity is a failed solve, never written);
/// throws OutputError naming `path`, `dataset` and the row otherwise.
void check_finite(const std::string &path, const std::string &dataset, const std::vector<Vec3> &rows);

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
/// Each non-empty field of f has one entry per vertex (nv) or triangle (nt).
void check_stress_sizes(const std::string &path, const std::string &group, const StressFields &f, std::size_t nv, std::size_t nt);
/// One stress per interior point, and a consistent grid.
void check_interior_stress(const std::string &path, const ResultData &d);
/// The sidecar's attributes of f in `group`: von_mises, principal_stress and stress_xx ... stress_xy.
std::vector<XdmfAttribute> stress_attributes(const std::string &group, const StressFields &f, std::size_t nv);
/// The sidecar's rectilinear grid of the interior grid (none when empty).
std::vector<XdmfRectGrid> interior_grid_view(const std::string &h5_name, const InteriorGridData &g);

} // namespace hssbem::detail
