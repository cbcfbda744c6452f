/// \file hdf5_output.cpp
/// The result writer's layout and write_result(). Every write goes to a temporary name and is
/// renamed into place only when complete, so a crash or an error never leaves a file that looks
/// finished. The HDF5 plumbing is in h5_writer.cpp, the renaming in file_commit.cpp.
#include "hssbem/io/hdf5_output.hpp"

#include "collective.hpp"
#include "file_commit.hpp"
#include "result_layout.hpp"

#include "hssbem/core/fault.hpp"
#include "hssbem/io/temp_files.hpp"

#include <cerrno>
#include <cmath>
#include <filesystem>
#include <optional>
#include <system_error>

#include <unistd.h>

namespace hssbem {

namespace detail {

namespace fs = std::filesystem;

std::string xdmf_path(const std::string &path)
{
  return fs::path(path).replace_extension(".xdmf").string();
}

namespace {

// --- the file layout ------------------------------------------------------------------------

void write_mesh(H5Writer &w, const ResultData &d)
{
  H5Handle g = w.group("/mesh");
  const hsize_t nv = count(d.vertices.size());
  const hsize_t nt = count(d.triangles.size());
  write_vec3s(w, g, "/mesh", "vertices", d.vertices);
  w.dataset(g.get(), "/mesh", "triangles", int32s(flatten(d.triangles), {nt, 3}));
  w.dataset(g.get(), "/mesh", "triangle_region", int32s(d.triangle_region, {nt}));
  w.dataset(g.get(), "/mesh", "sharp_vertex", int8s(to_int8(d.sharp_vertex), {nv}));
  w.end_group(g, "/mesh");
}

void write_fields(H5Writer &w, const ResultData &d)
{
  H5Handle g = w.group("/fields");
  if (!d.displacement.empty())
    write_vec3s(w, g, "/fields", "displacement", d.displacement);
  if (!d.traction.empty())
    write_vec3s(w, g, "/fields", "traction", d.traction);
  if (!d.traction_corner.empty()) {
    const std::vector<double> flat = flatten(flatten(d.traction_corner));
    w.dataset(g.get(), "/fields", "traction_corner",
              doubles(flat, {count(d.traction_corner.size()), 3, 3}));
  }
  write_stress(w, g, "/fields", d.stress);
  w.end_group(g, "/fields");
}

void write_bc(H5Writer &w, const ResultData &d)
{
  H5Handle g = w.group("/bc");
  if (!d.displacement_prescribed.empty())
    write_mask(w, g, "/bc", "displacement_prescribed", d.displacement_prescribed);
  w.end_group(g, "/bc");
}

void write_reactions(H5Writer &w, const std::map<std::string, Vec3> &reactions)
{
  H5Handle g = w.group("/reactions");
  for (const auto &[region, force] : reactions)
    w.dataset(g.get(), "/reactions", region, doubles({force.begin(), force.end()}, {3}));
  w.end_group(g, "/reactions");
}

void write_interior(H5Writer &w, const ResultData &d)
{
  if (d.interior_points.empty() && d.interior_grid.empty())
    return;
  H5Handle g = w.group("/interior");
  if (!d.interior_points.empty())
    write_vec3s(w, g, "/interior", "points", d.interior_points);
  if (!d.interior_displacement.empty())
    write_vec3s(w, g, "/interior", "displacement", d.interior_displacement);
  write_interior_stress(w, g, d);
  write_interior_grid(w, d.interior_grid);
  w.end_group(g, "/interior");
}

} // namespace

void write_contact(H5Writer &w, const std::string &name, const ContactData &c)
{
  H5Handle g = w.group(name);
  const hsize_t nv = count(c.pressure.size());
  w.dataset(g.get(), name, "pressure", doubles(c.pressure, {nv}));
  w.dataset(g.get(), name, "gap", doubles(c.gap, {nv}));
  w.dataset(g.get(), name, "status", int8s(c.status, {nv}));
  const std::string fname = name + "/forces";
  H5Handle f = w.group(fname);
  for (const auto &[who, force] : c.forces)
    w.dataset(f.get(), fname, who, doubles({force.begin(), force.end()}, {3}));
  w.end_group(f, fname);
  if (!c.body_motion.empty()) {
    const std::string bname = name + "/bodies";
    H5Handle b = w.group(bname);
    for (const auto &[k, motion] : c.body_motion) {
      const std::string kname = bname + "/" + std::to_string(k);
      H5Handle kg = w.group(kname);
      w.dataset(kg.get(), kname, "translation", doubles({motion[0].begin(), motion[0].end()}, {3}));
      w.dataset(kg.get(), kname, "rotation", doubles({motion[1].begin(), motion[1].end()}, {3}));
      w.end_group(kg, kname);
    }
    w.end_group(b, bname);
  }
  const std::map<std::string, double> no_real;
  const std::map<std::string, long long> counts{{"iterations", c.iterations}, {"active_vertices", c.active_vertices}};
  const std::map<std::string, std::string> no_text;
  write_attributes(w, g.get(), name, {no_real, counts, no_text});
  w.end_group(g, name);
}

void check_contact(const std::string &path, const std::string &group, const ContactData &c, std::size_t nv)
{
  if (!c.present())
    return;
  check_size(path, group + "/pressure", c.pressure.size(), nv, "vertex", true);
  check_size(path, group + "/gap", c.gap.size(), nv, "vertex", true);
  check_size(path, group + "/status", c.status.size(), nv, "vertex", true);
  check_finite(path, group + "/pressure", c.pressure);
  check_finite(path, group + "/gap", c.gap, nullptr, true); // NaN: no obstacle within reach
  for (const auto &entry : c.forces) {
    if (!link_name_ok(entry.first))
      fail_output(path, "obstacle name '" + entry.first + "' cannot name the dataset " + group + "/forces/<name>");
    check_finite(path, group + "/forces/" + entry.first, std::vector<Vec3>{entry.second});
  }
  for (const auto &[k, motion] : c.body_motion) check_finite(path, group + "/bodies/" + std::to_string(k), std::vector<Vec3>{motion[0], motion[1]});
}

std::vector<XdmfAttribute> contact_attributes(const std::string &group, std::size_t nv)
{
  return {{"pressure", "Scalar", "Node", {group + "/pressure", {nv}, XdmfNumber::float64}},
          {"contact_status", "Scalar", "Node", {group + "/status", {nv}, XdmfNumber::int8}}};
}

ResultMetadata metadata_of(const ResultData &d)
{
  return {d.attributes_real, d.attributes_int, d.attributes_str, d.timings, d.reactions, d.options_real, d.options_int, d.options_str};
}

void write_result_groups(H5Writer &w, const ResultData &d, const ResultMetadata &meta)
{
  write_mesh(w, d);
  write_fields(w, d);
  write_bc(w, d);
  write_reactions(w, meta.reactions);
  write_interior(w, d);
  if (d.contact.present())
    write_contact(w, "/contact", d.contact);
  write_obstacles(w, d.obstacles);
  write_attributes(w, w.root(), "/", {meta.attributes_real, meta.attributes_int, meta.attributes_str});
  if (!meta.options_real.empty() || !meta.options_int.empty() || !meta.options_str.empty()) {
    H5Handle g = w.group("/options");
    write_attributes(w, g.get(), "/options", {meta.options_real, meta.options_int, meta.options_str});
    w.end_group(g, "/options");
  }
}

void write_timings(H5Writer &w, const std::map<std::string, double> &timings)
{
  H5Handle g = w.group("/timings");
  for (const auto &[phase, seconds] : timings)
    w.attribute(g.get(), "/timings", phase, {&seconds, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE});
  w.end_group(g, "/timings");
}

// --- the XDMF view of the same file ---------------------------------------------------------

XdmfAttribute node_vectors(const std::string &name, const std::string &dataset, std::size_t nv,
                           XdmfNumber number)
{
  return {name, "Vector", "Node", {dataset, {nv, 3}, number}};
}

XdmfGrid mesh_grid(const std::string &path, const ResultData &d)
{
  const std::size_t nv = d.vertices.size(), nt = d.triangles.size();
  XdmfGrid grid;
  grid.h5_name = fs::path(path).filename().string();
  grid.num_vertices = nv;
  grid.num_triangles = nt;
  grid.attributes = {
      {"sharp_vertex", "Scalar", "Node", {"/mesh/sharp_vertex", {nv}, XdmfNumber::int8}},
      {"triangle_region", "Scalar", "Cell", {"/mesh/triangle_region", {nt}, XdmfNumber::int32}}};
  return grid;
}

std::string result_sidecar(const std::string &path, const ResultData &d)
{
  const std::string h5_name = fs::path(path).filename().string();
  return xdmf_document(result_grid(path, d), interior_grid_view(h5_name, d.interior_grid), obstacle_grids(h5_name, d.obstacles));
}

XdmfGrid result_grid(const std::string &path, const ResultData &d)
{
  const std::size_t nv = d.vertices.size();
  std::vector<XdmfAttribute> fields;
  if (!d.displacement.empty())
    fields.push_back(node_vectors("displacement", "/fields/displacement", nv, XdmfNumber::float64));
  if (!d.traction.empty())
    fields.push_back(node_vectors("traction", "/fields/traction", nv, XdmfNumber::float64));
  if (!d.displacement_prescribed.empty())
    fields.push_back(node_vectors("displacement_prescribed", "/bc/displacement_prescribed", nv,
                                  XdmfNumber::int8));
  const std::vector<XdmfAttribute> stress = stress_attributes("/fields", d.stress, nv);
  fields.insert(fields.end(), stress.begin(), stress.end());
  if (d.contact.present())
    for (const XdmfAttribute &a : contact_attributes("/contact", nv))
      fields.push_back(a);
  XdmfGrid grid = mesh_grid(path, d);
  grid.attributes.insert(grid.attributes.begin(), fields.begin(), fields.end());
  return grid;
}

// --- validation before any file is created --------------------------------------------------

void check_size(const std::string &path, const std::string &dataset, std::size_t size,
                std::size_t expected, const char *per, bool required)
{
  if ((required || size != 0) && size != expected)
    fail_output(path, dataset + " has " + std::to_string(size) + " entries, expected " +
                          std::to_string(expected) + " (one per " + per + ")");
}

void fail_not_finite(const std::string &path, const std::string &dataset, std::size_t row, double value)
{
  fail_output(path, dataset + " row " + std::to_string(row) + " holds a non-finite value (" + std::to_string(value) + "); a failed solve is not written");
}

namespace {

void check_mesh(const std::string &path, const ResultData &d)
{
  if (d.vertices.empty() || d.triangles.empty())
    fail_output(path, "the mesh is empty (" + std::to_string(d.vertices.size()) + " vertices, " +
                   std::to_string(d.triangles.size()) + " triangles)");
  const long long nv = static_cast<long long>(d.vertices.size());
  for (std::size_t t = 0; t < d.triangles.size(); ++t)
    for (int v : d.triangles[t])
      if (v < 0 || v >= nv)
        fail_output(path, "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                       " of " + std::to_string(nv));
  for (int flag : d.sharp_vertex)
    if (flag != 0 && flag != 1)
      fail_output(path, "/mesh/sharp_vertex holds " + std::to_string(flag) + ", expected 0 or 1");
}

void check_sizes(const std::string &path, const ResultData &d)
{
  const std::size_t nv = d.vertices.size(), nt = d.triangles.size();
  check_size(path, "/mesh/triangle_region", d.triangle_region.size(), nt, "triangle", true);
  check_size(path, "/mesh/sharp_vertex", d.sharp_vertex.size(), nv, "vertex", true);
  check_size(path, "/fields/displacement", d.displacement.size(), nv, "vertex", false);
  check_size(path, "/fields/traction", d.traction.size(), nv, "vertex", false);
  check_size(path, "/fields/traction_corner", d.traction_corner.size(), nt, "triangle", false);
  check_size(path, "/bc/displacement_prescribed", d.displacement_prescribed.size(), nv, "vertex",
             false);
  check_size(path, "/interior/displacement", d.interior_displacement.size(),
             d.interior_points.size(), "interior point", false);
  check_stress_sizes(path, "/fields", d.stress, nv, nt);
  check_interior_stress(path, d);
}

void check_values(const std::string &path, const ResultData &d)
{
  check_finite(path, "/mesh/vertices", d.vertices);
  check_finite(path, "/fields/displacement", d.displacement);
  check_finite(path, "/fields/traction", d.traction);
  for (std::size_t t = 0; t < d.traction_corner.size(); ++t)
    check_finite(path, "/fields/traction_corner[" + std::to_string(t) + "]", std::vector<Vec3>(d.traction_corner[t].begin(), d.traction_corner[t].end()));
  check_finite(path, "/interior/displacement", d.interior_displacement);
  for (const auto &[region, force] : d.reactions)
    check_finite(path, "/reactions/" + region, std::vector<Vec3>{force});
}

/// A region name becomes an HDF5 link name, where '/' would nest and "." means the group.
void check_region_names(const std::string &path, const ResultData &d)
{
  for (const auto &entry : d.reactions) {
    const std::string &name = entry.first;
    if (!link_name_ok(name))
      fail_output(path, "region name '" + name + "' cannot name the dataset /reactions/<region>");
  }
}

} // namespace

void validate_result(const std::string &path, const ResultData &d)
{
  check_mesh(path, d);
  check_sizes(path, d);
  check_values(path, d);
  check_region_names(path, d);
  check_contact(path, "/contact", d.contact, d.vertices.size());
  check_obstacles(path, d.obstacles);
}

namespace {

// --- output path ----------------------------------------------------------------------------

void check_target_names(const std::string &path)
{
  const fs::path p(path);
  std::error_code ec;
  if (path.empty())
    fail_output(path, "the path is empty");
  if (!p.has_filename() || fs::is_directory(p, ec))
    fail_output(path, "it is a directory");
  if (p.extension() == ".xdmf")
    fail_output(path, "the .xdmf name is taken by the XDMF sidecar; use .h5");
  // XDMF's "file.h5:/dataset" has no escape, and ParaView splits it at the first colon.
  if (p.filename().string().find(':') != std::string::npos)
    fail_output(path, "XDMF readers cannot refer to a file name that contains ':'");
  if (fs::is_directory(xdmf_path(path), ec))
    fail_output(path, "its XDMF sidecar '" + xdmf_path(path) + "' is a directory");
}

void check_parent_directory(const std::string &path)
{
  const fs::path parent = fs::path(path).parent_path();
  const fs::path dir = parent.empty() ? fs::path(".") : parent;
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (status.type() == fs::file_type::not_found)
    fail_output(path, "directory '" + dir.string() + "' does not exist");
  if (status.type() == fs::file_type::none)
    fail_output(path, "cannot inspect directory '" + dir.string() + "': " + ec.message());
  if (!fs::is_directory(status))
    fail_output(path, "'" + dir.string() + "' is not a directory");
  // X_OK as well: creating an entry needs search permission on the directory.
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    const int err = errno;
    fail_output(path, "directory '" + dir.string() + "' is not writable: " + std::system_category().message(err));
  }
}

/// The whole HDF5 file under `tmp_path`, closed (and so flushed) on return.
/// Collective over `comm` when it is not MPI_COMM_NULL: see H5Writer.
void write_h5(const std::string &tmp_path, const std::string &path, const ResultData &d,
              const ResultMetadata &meta, MPI_Comm comm)
{
  H5Writer w(tmp_path, path, comm);
  write_result_groups(w, d, meta);
  write_timings(w, meta.timings);
  w.close();
}

/// Rank 0 creates the temporary files (its host and process id in their names) and owns their
/// removal and the renaming; every rank learns the HDF5 file's temporary name.
std::string register_files(MPI_Comm comm, const std::string &path, const ResultData &d,
                           std::optional<FileSetCommit> &files, std::string &xdmf_tmp)
{
  std::string h5_tmp;
  run_agreed(comm, [&] {
    if (comm_rank(comm) != 0)
      return;
    check_output_path(path, d.input_files);
    files.emplace(path); // removes the temporary files on error and on SIGINT/SIGTERM/SIGHUP
    h5_tmp = files->add(path);
    xdmf_tmp = files->add(xdmf_path(path));
  });
  return broadcast_from_root(comm, h5_tmp);
}

/// The collective write_result: every rank writes its rows into one file, rank 0 renames it.
void write_result_collectively(MPI_Comm comm, const std::string &path, const ResultData &d)
{
  const bool root = comm_rank(comm) == 0;
  run_agreed(comm, [&] { validate_result(path, d); });
  check_same_shape(comm, path, d);
  const ResultMetadata meta = broadcast_metadata(comm, d);
  const H5ErrorSilencer quiet;
  std::optional<FileSetCommit> files; // rank 0's
  std::string xdmf_tmp;
  const std::string h5_tmp = register_files(comm, path, d, files, xdmf_tmp);
  write_h5(h5_tmp, path, d, meta, comm); // every rank has closed the file on return
  run_agreed(comm, [&] {
    if (root) {
      sync_file(h5_tmp, path);
      write_text_file(xdmf_tmp, result_sidecar(path, d), path);
    }
    fault_point("Write"); // tests: the temporary files are complete, nothing is renamed yet
  });
  run_agreed(comm, [&] {
    if (root)
      files->commit(); // the h5 first, as in write_result
  });
}

} // namespace

} // namespace detail

void check_output_path(const std::string &path, const std::vector<std::string> &inputs)
{
  detail::check_target_names(path);
  detail::check_parent_directory(path);
  check_not_an_input(path, inputs);
}

void write_result(const std::string &path, const ResultData &data)
{
  using namespace detail;
  check_output_path(path, data.input_files);
  validate_result(path, data);
  const H5ErrorSilencer quiet;
  FileSetCommit files(path); // removes the temporary files on error and on SIGINT/SIGTERM/SIGHUP
  const std::string h5_tmp = files.add(path), xdmf_tmp = files.add(xdmf_path(path));
  write_h5(h5_tmp, path, data, metadata_of(data), MPI_COMM_NULL);
  sync_file(h5_tmp, path);
  write_text_file(xdmf_tmp, result_sidecar(path, data), path);
  fault_point("Write"); // tests: the temporary files are complete, nothing is renamed yet
  // The h5 goes first: a sidecar must never point at a file that is not there yet.
  files.commit();
}

void write_result(MPI_Comm comm, const std::string &path, const ResultData &data)
{
  if (detail::comm_size(comm) == 1)
    write_result(path, data);
  else
    detail::write_result_collectively(comm, path, data);
}

} // namespace hssbem
