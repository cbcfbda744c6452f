/// \file h5_writer.cpp
/// HDF5 plumbing of the result writers (see h5_writer.hpp). Serial HDF5 C API with default
/// property lists: the caller gathers to one rank, so MPI-IO would buy nothing.
#include "h5_writer.hpp"

#include "hssbem/io/hdf5_output.hpp"

namespace hssbem::detail {

void fail_output(const std::string &path, const std::string &reason)
{
  throw OutputError("cannot write output '" + path + "': " + reason);
}

H5ErrorSilencer::H5ErrorSilencer()
{
  m_saved = H5Eget_auto2(H5E_DEFAULT, &m_func, &m_data) >= 0;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

H5ErrorSilencer::~H5ErrorSilencer()
{
  if (m_saved)
    H5Eset_auto2(H5E_DEFAULT, m_func, m_data);
}

namespace {

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

} // namespace

void H5Writer::h5_fail(const std::string &object, const char *call) const
{
  const std::string reason = h5_reason();
  fail_output(m_path, std::string(call) + " failed for " + object + (reason.empty() ? "" : ": " + reason));
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
    : m_path(std::move(path)), m_file(create_file(tmp_path), H5Fclose)
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

void H5Writer::close() { check(m_file.close(), "file", "H5Fclose"); }

void H5Writer::flush() { check(H5Fflush(root(), H5F_SCOPE_LOCAL), "file", "H5Fflush"); }

void write_attributes(H5Writer &w, hid_t owner, const std::string &owner_name,
                      const H5Attributes &a)
{
  for (const auto &[name, value] : a.real)
    w.attribute(owner, owner_name, name, {&value, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE});
  for (const auto &[name, value] : a.integer)
    w.attribute(owner, owner_name, name, {&value, H5T_STD_I64LE, H5T_NATIVE_LLONG});
  for (const auto &[name, value] : a.text)
    w.string_attribute(owner, owner_name, name, value);
}

// --- flat arrays ------------------------------------------------------------------------------

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

void write_vec3s(H5Writer &w, const H5Handle &g, const std::string &group,
                 const std::string &name, const std::vector<Vec3> &v)
{
  w.dataset(g.get(), group, name, doubles(flatten(v), {count(v.size()), 3}));
}

void write_mask(H5Writer &w, const H5Handle &g, const std::string &group,
                const std::string &name, const std::vector<std::array<bool, 3>> &mask)
{
  w.dataset(g.get(), group, name, int8s(to_int8(mask), {count(mask.size()), 3}));
}

} // namespace hssbem::detail
