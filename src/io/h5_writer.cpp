/// \file h5_writer.cpp
/// HDF5 plumbing of the result writers (see h5_writer.hpp): the HDF5 C API, serial with default
/// property lists, or collective over the MPI-IO driver with each rank writing its rows.
#include "h5_writer.hpp"

#include "collective.hpp"

#include "hssbem/io/hdf5_output.hpp"

#include <algorithm>

namespace hssbem::detail {

void fail_output(const std::string &path, const std::string &reason)
{
  throw OutputError("cannot write output '" + path + "': " + reason);
}

namespace {

/// Rows [first, last) of `rows` for `rank` of `size`: an even split in rank order when every
/// rank gets a row, else all of them on rank 0. (HDF5 1.10 lets a rank with an empty selection
/// leave a collective H5Dwrite early while the others wait in it: no rank may have none.)
std::pair<hsize_t, hsize_t> row_block(hsize_t rows, int rank, int size)
{
  const auto r = static_cast<hsize_t>(rank), n = static_cast<hsize_t>(size);
  if (rows < n)
    return rank == 0 ? std::make_pair(hsize_t{0}, rows) : std::make_pair(hsize_t{0}, hsize_t{0});
  return {rows * r / n, rows * (r + 1) / n};
}

/// Writes `block` rows from `data` at `start` of `set`; returns the first failing status. Local:
/// the caller agrees on the status with the other ranks.
herr_t write_block(hid_t set, hid_t xfer, const H5Array &a, const std::vector<hsize_t> &start,
                   const std::vector<hsize_t> &block, const void *data)
{
  const int rank = static_cast<int>(block.size());
  const hid_t file_space = H5Dget_space(set);
  const hid_t mem_space = H5Screate_simple(rank, block.data(), nullptr);
  herr_t status = file_space < 0 || mem_space < 0 ? -1 : 0;
  if (status >= 0)
    status = H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start.data(), nullptr, block.data(),
                                 nullptr);
  if (status >= 0)
    status = H5Dwrite(set, a.mem_type, mem_space, file_space, xfer, data);
  if (mem_space >= 0 && H5Sclose(mem_space) < 0)
    status = -1;
  if (file_space >= 0 && H5Sclose(file_space) < 0)
    status = -1;
  return status;
}

std::string failure_message(const std::string &path, const std::string &object, const char *call)
{
  const std::string reason = h5_reason();
  return "cannot write output '" + path + "': " + call + " failed for " + object +
         (reason.empty() ? "" : ": " + reason);
}

} // namespace

void H5Writer::h5_fail(const std::string &object, const char *call) const
{
  throw OutputError(failure_message(m_path, object, call));
}

/// A handle the ranks failed to agree on is not closed (closing is collective for some objects,
/// and the ranks that failed would not join): the library releases it at exit.
H5Handle H5Writer::open(hid_t id, H5Handle::Closer closer, const std::string &object,
                        const char *call) const
{
  check(id < 0 ? -1 : 0, object, call);
  return H5Handle(id, closer);
}

void H5Writer::check(herr_t status, const std::string &object, const char *call) const
{
  if (!parallel()) {
    if (status < 0)
      h5_fail(object, call);
    return;
  }
  const std::string failure = status < 0 ? failure_message(m_path, object, call) : std::string();
  agree_on_failure(m_comm, status < 0 ? &failure : nullptr);
}

H5Writer::H5Writer(const std::string &tmp_path, std::string path, MPI_Comm comm)
    : m_path(std::move(path)), m_comm(comm), m_rank(comm_rank(comm)), m_size(comm_size(comm)),
      m_file(create_file(tmp_path), H5Fclose)
{
}

hid_t H5Writer::create_file(const std::string &tmp_path) const
{
  const std::string object = "file '" + tmp_path + "'";
  if (!parallel())
    return open(H5Fcreate(tmp_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose,
                object, "H5Fcreate")
        .release();
  H5Handle fapl = open(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, object, "H5Pcreate");
  check(H5Pset_fapl_mpio(fapl.get(), m_comm, MPI_INFO_NULL), object, "H5Pset_fapl_mpio");
  // Every rank makes every metadata call anyway: let HDF5 do them collectively too.
  check(H5Pset_all_coll_metadata_ops(fapl.get(), true), object, "H5Pset_all_coll_metadata_ops");
  check(H5Pset_coll_metadata_write(fapl.get(), true), object, "H5Pset_coll_metadata_write");
  H5Handle file = open(H5Fcreate(tmp_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
                       H5Fclose, object, "H5Fcreate");
  check(fapl.close(), object, "H5Pclose");
  return file.release();
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
  H5Handle create = open(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, object, "H5Pcreate");
  // Every element is written below: filling the dataset first would write it twice.
  check(H5Pset_fill_time(create.get(), H5D_FILL_TIME_NEVER), object, "H5Pset_fill_time");
  H5Handle set = open(H5Dcreate2(group, name.c_str(), a.file_type, space.get(), H5P_DEFAULT,
                                 create.get(), H5P_DEFAULT),
                      H5Dclose, object, "H5Dcreate2");
  if (parallel())
    write_rows(set.get(), object, a);
  else
    check(H5Dwrite(set.get(), a.mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, a.data), object,
          "H5Dwrite");
  check(set.close(), object, "H5Dclose");
  check(create.close(), object, "H5Pclose");
  check(space.close(), object, "H5Sclose");
}

void H5Writer::write_rows(hid_t set, const std::string &object, const H5Array &a)
{
  const auto [first, last] = row_block(a.dims[0], m_rank, m_size);
  const bool collective = a.dims[0] >= static_cast<hsize_t>(m_size);
  H5Handle xfer = open(H5Pcreate(H5P_DATASET_XFER), H5Pclose, object, "H5Pcreate");
  check(H5Pset_dxpl_mpio(xfer.get(), collective ? H5FD_MPIO_COLLECTIVE : H5FD_MPIO_INDEPENDENT),
        object, "H5Pset_dxpl_mpio");
  herr_t status = 0;
  if (last > first) {
    std::vector<hsize_t> start(a.dims.size(), 0), block = a.dims;
    start[0] = first;
    block[0] = last - first;
    hsize_t row_size = H5Tget_size(a.mem_type);
    for (std::size_t d = 1; d < a.dims.size(); ++d)
      row_size *= a.dims[d];
    status = write_block(set, xfer.get(), a, start, block,
                         static_cast<const char *>(a.data) + first * row_size);
  }
  check(status, object, "H5Dwrite"); // agreed by all ranks, also those that wrote nothing
  check(xfer.close(), object, "H5Pclose");
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
