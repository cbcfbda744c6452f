/// \file h5_writer.hpp
/// Private to the result writers (write_result and FrameWriter): the HDF5 C API behind owners
/// that close what they open, and errors that name the final path of the result.
#pragma once

#include "h5_handle.hpp"

#include "hssbem/core/geometry.hpp"

#include <hdf5.h>
#include <mpi.h>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace hssbem::detail {

/// Every error of the writers has this one form: "cannot write output '<path>': <reason>",
/// naming the final (not the temporary) path. Throws OutputError.
[[noreturn]] void fail_output(const std::string &path, const std::string &reason);

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
///
/// Serial (comm = MPI_COMM_NULL): this process writes everything with HDF5's default driver.
/// Collective (a communicator): every rank of `comm` opens the file with the MPI-IO driver and
/// makes every call, in the same order and with the same arguments; each rank writes its own
/// contiguous block of rows (the first dimension, split evenly in rank order) of each dataset
/// from the whole array it passes. Every HDF5 status is agreed on by all ranks, so a failure on
/// one rank throws the same OutputError on all of them at the same call.
class H5Writer {
public:
  H5Writer(const std::string &tmp_path, std::string path, MPI_Comm comm = MPI_COMM_NULL);
  /// Creates group `name` (an absolute path such as "/mesh" or "/frames/3", whose parent
  /// exists) and returns its handle.
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
  hid_t root() const { return m_file.get(); }
  /// Hands what has been written so far to the operating system (H5Fflush), so that HDF5's
  /// caches do not grow with the file.
  void flush();
  /// Closes the file, checking the status: the final flush happens here.
  void close();

private:
  [[noreturn]] void h5_fail(const std::string &object, const char *call) const;
  hid_t create_file(const std::string &tmp_path) const;
  H5Handle open(hid_t id, H5Handle::Closer closer, const std::string &object,
                const char *call) const;
  void check(herr_t status, const std::string &object, const char *call) const;
  bool parallel() const { return m_comm != MPI_COMM_NULL; }
  /// Writes this rank's rows of `a` into the open dataset `set` (collective).
  void write_rows(hid_t set, const std::string &object, const H5Array &a);

  std::string m_path; // initialised first: create_file's errors name it
  MPI_Comm m_comm;
  int m_rank = 0, m_size = 1;
  H5Handle m_file;
};

/// Scalar attributes of three kinds on `owner` (named `owner_name`): float64, int64, UTF-8.
struct H5Attributes {
  const std::map<std::string, double> &real;
  const std::map<std::string, long long> &integer;
  const std::map<std::string, std::string> &text;
};
void write_attributes(H5Writer &w, hid_t owner, const std::string &owner_name,
                      const H5Attributes &a);

// --- flat arrays ------------------------------------------------------------------------------

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

std::vector<std::int8_t> to_int8(const std::vector<std::array<bool, 3>> &mask);
std::vector<std::int8_t> to_int8(const std::vector<int> &flags);

/// HDF5 extents from container sizes.
inline hsize_t count(std::size_t n) { return static_cast<hsize_t>(n); }

/// Arrays are stored little-endian whatever the machine, as most HDF5 files are.
H5Array doubles(const std::vector<double> &v, std::vector<hsize_t> dims);
H5Array int32s(const std::vector<int> &v, std::vector<hsize_t> dims);
H5Array int8s(const std::vector<std::int8_t> &v, std::vector<hsize_t> dims);

/// An n x 3 float64 dataset `group`/`name` from a list of vectors.
void write_vec3s(H5Writer &w, const H5Handle &g, const std::string &group,
                 const std::string &name, const std::vector<Vec3> &v);
/// An n x 3 int8 (0/1) dataset `group`/`name` from a mask.
void write_mask(H5Writer &w, const H5Handle &g, const std::string &group,
                const std::string &name, const std::vector<std::array<bool, 3>> &mask);

} // namespace hssbem::detail
