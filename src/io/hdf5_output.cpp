/// \file hdf5_output.cpp
/// The result writer. Serial HDF5 C API with default property lists: the caller gathers to one
/// rank, so MPI-IO would buy nothing. Every write goes to a temporary name and is renamed into
/// place only when complete, so a crash or an error never leaves a file that looks finished.
#include "hssbem/io/hdf5_output.hpp"

#include "file_commit.hpp"
#include "xdmf.hpp"

#include "hssbem/core/fault.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <system_error>
#include <utility>

#include <fcntl.h>
#include <unistd.h>

namespace hssbem {

namespace {

namespace fs = std::filesystem;
using detail::FileSetCommit;

/// Every error of the writer has this one form, naming the final (not the temporary) path.
[[noreturn]] void fail(const std::string &path, const std::string &reason)
{
  throw OutputError("cannot write output '" + path + "': " + reason);
}

std::string errno_text(int err) { return std::system_category().message(err); }

/// For a failed system call. Callers save errno in a statement of its own first: building the
/// message allocates, and argument evaluation order would let that run before errno is read.
[[noreturn]] void fail_sys(const std::string &path, int err, const std::string &what)
{
  fail(path, what + ": " + errno_text(err));
}

/// out.h5 -> out.xdmf; a dot in a directory name is not taken for an extension.
std::string xdmf_path(const std::string &path)
{
  return fs::path(path).replace_extension(".xdmf").string();
}

// --- temporary files ------------------------------------------------------------------------

/// Flushes `file` to disk, so that the rename that follows never exposes a file whose data is
/// still only in the page cache.
void sync_file(const std::string &file, const std::string &path)
{
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    fail_sys(path, err, "cannot open '" + file + "' to sync it");
  }
  const int status = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (status != 0)
    fail_sys(path, err, "cannot sync '" + file + "'");
}

/// write(2) may write less than asked; loops until all is out.
void write_all(int fd, const std::string &text, const std::string &file, const std::string &path)
{
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      fail_sys(path, err, "cannot write '" + file + "'");
    }
    done += static_cast<std::size_t>(n);
  }
}

/// Writes and fsyncs `file`, for the same reason as sync_file.
void write_text_file(const std::string &file, const std::string &text, const std::string &path)
{
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int err = errno;
    fail_sys(path, err, "cannot create '" + file + "'");
  }
  write_all(fd, text, file, path);
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    fail_sys(path, err, "cannot sync '" + file + "'");
  }
  if (::close(fd) != 0) {
    const int err = errno;
    fail_sys(path, err, "cannot close '" + file + "'");
  }
}

// --- HDF5 plumbing --------------------------------------------------------------------------

/// Turns off HDF5's automatic error-stack printing while the writer runs: failures are reported
/// through OutputError instead, and the previous handler is restored afterwards.
class H5ErrorSilencer {
public:
  H5ErrorSilencer()
  {
    saved_ = H5Eget_auto2(H5E_DEFAULT, &func_, &data_) >= 0;
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  H5ErrorSilencer(const H5ErrorSilencer &) = delete;
  H5ErrorSilencer &operator=(const H5ErrorSilencer &) = delete;
  ~H5ErrorSilencer()
  {
    if (saved_)
      H5Eset_auto2(H5E_DEFAULT, func_, data_);
  }

private:
  H5E_auto2_t func_ = nullptr;
  void *data_ = nullptr;
  bool saved_ = false;
};

/// H5Ewalk2 callback: with H5E_WALK_UPWARD, entry 0 is where the error was detected.
herr_t keep_innermost(unsigned n, const H5E_error2_t *err, void *out)
{
  if (n == 0 && err->desc)
    *static_cast<std::string *>(out) = err->desc;
  return 0;
}

/// The most specific message on HDF5's error stack (e.g. the errno text of a failed open).
/// Must run before the next HDF5 call, which clears the stack.
std::string h5_reason()
{
  std::string reason;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, keep_innermost, &reason);
  return reason;
}

/// Owns one HDF5 identifier, so error paths close everything they opened.
class H5Handle {
public:
  using Closer = herr_t (*)(hid_t);
  H5Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  H5Handle(const H5Handle &) = delete;
  H5Handle &operator=(const H5Handle &) = delete;
  ~H5Handle()
  {
    if (id_ >= 0)
      closer_(id_); // only reached on error paths, where a failed close changes nothing
  }
  hid_t get() const { return id_; }
  /// Closes now and reports the status, for the success path where it matters.
  herr_t close() { return closer_(std::exchange(id_, H5I_INVALID_HID)); }

private:
  hid_t id_;
  Closer closer_;
};

/// A contiguous array ready for H5Dwrite: memory layout `mem_type`, stored as `file_type`.
/// Borrows `data`: build it inside the call that writes it, so temporaries outlive the write.
struct H5Array {
  const void *data;
  std::vector<hsize_t> dims;
  hid_t file_type;
  hid_t mem_type;
};

/// A scalar attribute value; strings carry their own variable-length type.
struct H5Scalar {
  const void *data;
  hid_t file_type;
  hid_t mem_type;
};

/// One HDF5 file being written under a temporary name; errors name the final path.
class H5Writer {
public:
  H5Writer(const std::string &tmp_path, std::string path);
  /// Creates group `name` ("/mesh") and returns its handle.
  H5Handle group(const std::string &name);
  /// Closes group `name` opened by group(), checking the status.
  void end_group(H5Handle &g, const std::string &name);
  /// Writes dataset `group_name`/`name`.
  void dataset(hid_t group, const std::string &group_name, const std::string &name,
               const H5Array &a);
  /// Writes scalar attribute `name` on the object `owner` (named `owner_name`).
  void attribute(hid_t owner, const std::string &owner_name, const std::string &name,
                 const H5Scalar &v);
  /// Writes a variable-length UTF-8 string attribute, which h5py reads back as str.
  void string_attribute(hid_t owner, const std::string &owner_name, const std::string &name,
                        const std::string &value);
  hid_t root() const { return file_.get(); }
  /// Closes the file, checking the status: the final flush happens here.
  void close();

private:
  [[noreturn]] void h5_fail(const std::string &object, const char *call) const;
  hid_t create_file(const std::string &tmp_path) const;
  H5Handle open(hid_t id, H5Handle::Closer closer, const std::string &object,
                const char *call) const;
  void check(herr_t status, const std::string &object, const char *call) const;

  std::string path_; // initialised first: create_file's errors name it
  H5Handle file_;
};

void H5Writer::h5_fail(const std::string &object, const char *call) const
{
  const std::string reason = h5_reason();
  fail(path_, std::string(call) + " failed for " + object + (reason.empty() ? "" : ": " + reason));
}

H5Handle H5Writer::open(hid_t id, H5Handle::Closer closer, const std::string &object,
                        const char *call) const
{
  if (id < 0)
    h5_fail(object, call);
  return H5Handle(id, closer);
}

void H5Writer::check(herr_t status, const std::string &object, const char *call) const
{
  if (status < 0)
    h5_fail(object, call);
}

H5Writer::H5Writer(const std::string &tmp_path, std::string path)
    : path_(std::move(path)), file_(create_file(tmp_path), H5Fclose)
{
}

hid_t H5Writer::create_file(const std::string &tmp_path) const
{
  const hid_t id = H5Fcreate(tmp_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (id < 0)
    h5_fail("file '" + tmp_path + "'", "H5Fcreate");
  return id;
}

H5Handle H5Writer::group(const std::string &name)
{
  return open(H5Gcreate2(root(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
              "group '" + name + "'", "H5Gcreate2");
}

void H5Writer::dataset(hid_t group, const std::string &group_name, const std::string &name,
                       const H5Array &a)
{
  const std::string object = "dataset '" + group_name + "/" + name + "'";
  const int rank = static_cast<int>(a.dims.size());
  H5Handle space = open(H5Screate_simple(rank, a.dims.data(), nullptr), H5Sclose, object,
                        "H5Screate_simple");
  H5Handle set = open(H5Dcreate2(group, name.c_str(), a.file_type, space.get(), H5P_DEFAULT,
                                 H5P_DEFAULT, H5P_DEFAULT),
                      H5Dclose, object, "H5Dcreate2");
  check(H5Dwrite(set.get(), a.mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, a.data), object,
        "H5Dwrite");
  check(set.close(), object, "H5Dclose");
  check(space.close(), object, "H5Sclose");
}

void H5Writer::attribute(hid_t owner, const std::string &owner_name, const std::string &name,
                         const H5Scalar &v)
{
  const std::string object = "attribute '" + name + "' of '" + owner_name + "'";
  H5Handle space = open(H5Screate(H5S_SCALAR), H5Sclose, object, "H5Screate");
  H5Handle attr = open(H5Acreate2(owner, name.c_str(), v.file_type, space.get(), H5P_DEFAULT,
                                  H5P_DEFAULT),
                       H5Aclose, object, "H5Acreate2");
  check(H5Awrite(attr.get(), v.mem_type, v.data), object, "H5Awrite");
  check(attr.close(), object, "H5Aclose");
  check(space.close(), object, "H5Sclose");
}

void H5Writer::string_attribute(hid_t owner, const std::string &owner_name,
                                const std::string &name, const std::string &value)
{
  const std::string object = "attribute '" + name + "' of '" + owner_name + "'";
  H5Handle type = open(H5Tcopy(H5T_C_S1), H5Tclose, object, "H5Tcopy");
  check(H5Tset_size(type.get(), H5T_VARIABLE), object, "H5Tset_size");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), object, "H5Tset_cset");
  const char *text = value.c_str();
  attribute(owner, owner_name, name, {&text, type.get(), type.get()});
  check(type.close(), object, "H5Tclose");
}

void H5Writer::end_group(H5Handle &g, const std::string &name)
{
  check(g.close(), "group '" + name + "'", "H5Gclose");
}

void H5Writer::close() { check(file_.close(), "file", "H5Fclose"); }

// --- ResultData to flat arrays --------------------------------------------------------------

/// Row-major copy of fixed-size rows; copying (rather than aliasing std::array storage) keeps
/// the layout guarantee explicit at a cost far below that of the solve.
template <class T, std::size_t N>
std::vector<T> flatten(const std::vector<std::array<T, N>> &rows)
{
  std::vector<T> flat;
  flat.reserve(rows.size() * N);
  for (const auto &row : rows)
    flat.insert(flat.end(), row.begin(), row.end());
  return flat;
}

std::vector<std::int8_t> to_int8(const std::vector<std::array<bool, 3>> &mask)
{
  std::vector<std::int8_t> flat;
  flat.reserve(mask.size() * 3);
  for (const auto &row : mask)
    for (bool b : row)
      flat.push_back(b ? 1 : 0);
  return flat;
}

std::vector<std::int8_t> to_int8(const std::vector<int> &flags)
{
  return std::vector<std::int8_t>(flags.begin(), flags.end()); // validated 0/1
}

/// HDF5 extents from container sizes.
hsize_t count(std::size_t n) { return static_cast<hsize_t>(n); }

/// Arrays are stored little-endian whatever the machine, as most HDF5 files are.
H5Array doubles(const std::vector<double> &v, std::vector<hsize_t> dims)
{
  return {v.data(), std::move(dims), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE};
}

H5Array int32s(const std::vector<int> &v, std::vector<hsize_t> dims)
{
  return {v.data(), std::move(dims), H5T_STD_I32LE, H5T_NATIVE_INT};
}

H5Array int8s(const std::vector<std::int8_t> &v, std::vector<hsize_t> dims)
{
  return {v.data(), std::move(dims), H5T_STD_I8LE, H5T_NATIVE_INT8};
}

/// An nv x 3 (or m x 3) float64 dataset from a list of vectors.
void write_vec3s(H5Writer &w, const H5Handle &g, const std::string &group,
                 const std::string &name, const std::vector<Vec3> &v)
{
  w.dataset(g.get(), group, name, doubles(flatten(v), {count(v.size()), 3}));
}

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
  w.end_group(g, "/fields");
}

void write_bc(H5Writer &w, const ResultData &d)
{
  H5Handle g = w.group("/bc");
  const auto &mask = d.displacement_prescribed;
  if (!mask.empty())
    w.dataset(g.get(), "/bc", "displacement_prescribed",
              int8s(to_int8(mask), {count(mask.size()), 3}));
  w.end_group(g, "/bc");
}

void write_reactions(H5Writer &w, const ResultData &d)
{
  H5Handle g = w.group("/reactions");
  for (const auto &[region, force] : d.reactions)
    w.dataset(g.get(), "/reactions", region, doubles({force.begin(), force.end()}, {3}));
  w.end_group(g, "/reactions");
}

void write_interior(H5Writer &w, const ResultData &d)
{
  if (d.interior_points.empty())
    return;
  H5Handle g = w.group("/interior");
  write_vec3s(w, g, "/interior", "points", d.interior_points);
  if (!d.interior_displacement.empty())
    write_vec3s(w, g, "/interior", "displacement", d.interior_displacement);
  w.end_group(g, "/interior");
}

void write_root_attributes(H5Writer &w, const ResultData &d)
{
  for (const auto &[name, value] : d.attributes_real)
    w.attribute(w.root(), "/", name, {&value, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE});
  for (const auto &[name, value] : d.attributes_int)
    w.attribute(w.root(), "/", name, {&value, H5T_STD_I64LE, H5T_NATIVE_LLONG});
  for (const auto &[name, value] : d.attributes_str)
    w.string_attribute(w.root(), "/", name, value);
}

void write_timings(H5Writer &w, const ResultData &d)
{
  H5Handle g = w.group("/timings");
  for (const auto &[phase, seconds] : d.timings)
    w.attribute(g.get(), "/timings", phase, {&seconds, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE});
  w.end_group(g, "/timings");
}

/// The whole HDF5 file under `tmp_path`, closed (and so flushed) on return.
void write_h5(const std::string &tmp_path, const std::string &path, const ResultData &d)
{
  H5Writer w(tmp_path, path);
  write_mesh(w, d);
  write_fields(w, d);
  write_bc(w, d);
  write_reactions(w, d);
  write_interior(w, d);
  write_root_attributes(w, d);
  write_timings(w, d);
  w.close();
}

// --- the XDMF view of the same file ---------------------------------------------------------

detail::XdmfAttribute node_vectors(const std::string &name, const std::string &dataset,
                                   std::size_t nv, detail::XdmfNumber number)
{
  return {name, "Vector", "Node", {dataset, {nv, 3}, number}};
}

/// Lists exactly the datasets write_h5 wrote, so the sidecar never points at a missing one.
detail::XdmfGrid make_grid(const std::string &path, const ResultData &d)
{
  using detail::XdmfNumber;
  const std::size_t nv = d.vertices.size(), nt = d.triangles.size();
  detail::XdmfGrid grid{fs::path(path).filename().string(), nv, nt, {}};
  auto &attrs = grid.attributes;
  if (!d.displacement.empty())
    attrs.push_back(node_vectors("displacement", "/fields/displacement", nv, XdmfNumber::float64));
  if (!d.traction.empty())
    attrs.push_back(node_vectors("traction", "/fields/traction", nv, XdmfNumber::float64));
  if (!d.displacement_prescribed.empty())
    attrs.push_back(node_vectors("displacement_prescribed", "/bc/displacement_prescribed", nv,
                                 XdmfNumber::int8));
  attrs.push_back(
      {"sharp_vertex", "Scalar", "Node", {"/mesh/sharp_vertex", {nv}, XdmfNumber::int8}});
  attrs.push_back(
      {"triangle_region", "Scalar", "Cell", {"/mesh/triangle_region", {nt}, XdmfNumber::int32}});
  return grid;
}

// --- validation before any file is created --------------------------------------------------

/// Optional per-vertex or per-triangle arrays must be empty or complete.
void check_size(const std::string &path, const char *dataset, std::size_t size,
                std::size_t expected, const char *per, bool required)
{
  if ((required || size != 0) && size != expected)
    fail(path, std::string(dataset) + " has " + std::to_string(size) + " entries, expected " +
                   std::to_string(expected) + " (one per " + per + ")");
}

void check_mesh(const std::string &path, const ResultData &d)
{
  if (d.vertices.empty() || d.triangles.empty())
    fail(path, "the mesh is empty (" + std::to_string(d.vertices.size()) + " vertices, " +
                   std::to_string(d.triangles.size()) + " triangles)");
  const long long nv = static_cast<long long>(d.vertices.size());
  for (std::size_t t = 0; t < d.triangles.size(); ++t)
    for (int v : d.triangles[t])
      if (v < 0 || v >= nv)
        fail(path, "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                       " of " + std::to_string(nv));
  for (int flag : d.sharp_vertex)
    if (flag != 0 && flag != 1)
      fail(path, "/mesh/sharp_vertex holds " + std::to_string(flag) + ", expected 0 or 1");
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
}

/// A region name becomes an HDF5 link name, where '/' would nest and "." means the group.
void check_region_names(const std::string &path, const ResultData &d)
{
  for (const auto &entry : d.reactions) {
    const std::string &name = entry.first;
    if (name.empty() || name == "." || name.find('/') != std::string::npos)
      fail(path, "region name '" + name + "' cannot name the dataset /reactions/<region>");
  }
}

void validate(const std::string &path, const ResultData &d)
{
  check_mesh(path, d);
  check_sizes(path, d);
  check_region_names(path, d);
}

// --- output path ----------------------------------------------------------------------------

void check_target_names(const std::string &path)
{
  const fs::path p(path);
  std::error_code ec;
  if (path.empty())
    fail(path, "the path is empty");
  if (!p.has_filename() || fs::is_directory(p, ec))
    fail(path, "it is a directory");
  if (p.extension() == ".xdmf")
    fail(path, "the .xdmf name is taken by the XDMF sidecar; use .h5");
  // XDMF's "file.h5:/dataset" has no escape, and ParaView splits it at the first colon.
  if (p.filename().string().find(':') != std::string::npos)
    fail(path, "XDMF readers cannot refer to a file name that contains ':'");
  if (fs::is_directory(xdmf_path(path), ec))
    fail(path, "its XDMF sidecar '" + xdmf_path(path) + "' is a directory");
}

void check_parent_directory(const std::string &path)
{
  const fs::path parent = fs::path(path).parent_path();
  const fs::path dir = parent.empty() ? fs::path(".") : parent;
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (status.type() == fs::file_type::not_found)
    fail(path, "directory '" + dir.string() + "' does not exist");
  if (status.type() == fs::file_type::none)
    fail(path, "cannot inspect directory '" + dir.string() + "': " + ec.message());
  if (!fs::is_directory(status))
    fail(path, "'" + dir.string() + "' is not a directory");
  // X_OK as well: creating an entry needs search permission on the directory.
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    const int err = errno;
    fail_sys(path, err, "directory '" + dir.string() + "' is not writable");
  }
}

} // namespace

void check_output_path(const std::string &path)
{
  check_target_names(path);
  check_parent_directory(path);
}

void write_result(const std::string &path, const ResultData &data)
{
  check_output_path(path);
  validate(path, data);
  const H5ErrorSilencer quiet;
  const std::string xdmf = xdmf_path(path);
  FileSetCommit files(path); // removes the temporary files on error and on SIGINT/SIGTERM/SIGHUP
  const std::string h5_tmp = files.add(path), xdmf_tmp = files.add(xdmf);
  write_h5(h5_tmp, path, data);
  sync_file(h5_tmp, path);
  write_text_file(xdmf_tmp, detail::xdmf_document(make_grid(path, data)), path);
  fault_point("Write"); // tests: the temporary files are complete, nothing is renamed yet
  // The h5 goes first: a sidecar must never point at a file that is not there yet.
  files.commit();
}

} // namespace hssbem
