/// \file saved_file.hpp
/// The container of a saved precomputation (session/precomputation_file.hpp): one HDF5 file of
/// named one-dimensional arrays and text attributes, behind a header of its own in the file's
/// first 512 bytes (HDF5's user block, which HDF5 leaves alone):
///
///   hssbem saved file
///   kind: contact precomputation
///   format: 1
///   bytes: 1834567168
///   checksum: 5f0c2a9d3e71b460
///
/// (then zero bytes up to 512). `bytes` is the whole file's length and `checksum` a 64-bit hash
/// of every byte after the header, so a truncated, extended or altered file is refused before
/// HDF5 reads any of it; the arrays of at least kChecksummedElements elements are also chunked
/// with HDF5's Fletcher-32 filter, which HDF5 checks as it reads them. Writing goes the result
/// file's safe way (a temporary file created exclusively beside the final name, fsync, rename;
/// never over an input: temp_files.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem {

/// A saved file that cannot be read: "cannot load '<path>': <reason>".
class SavedFileError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// Arrays at least this long are chunked and checksummed by HDF5 (Fletcher-32) as well.
inline constexpr std::size_t kChecksummedElements = 4096;

class SavedFileWriter {
public:
  /// Starts `path` under a temporary name. `kind` and `format` go into the header; `inputs`
  /// (the problem's files, a file loaded) may not be `path`. Throws OutputError.
  SavedFileWriter(const std::string &path, const std::vector<std::string> &inputs, const std::string &kind, int format);
  ~SavedFileWriter();
  SavedFileWriter(const SavedFileWriter &) = delete;
  SavedFileWriter &operator=(const SavedFileWriter &) = delete;

  /// A text attribute of the file.
  void text(const std::string &name, const std::string &value);
  /// Array `name` (a path such as "body0/lu"; its groups are made as needed).
  void doubles(const std::string &name, const double *data, std::size_t n);
  void ints(const std::string &name, const int *data, std::size_t n);
  void chars(const std::string &name, const char *data, std::size_t n);
  void floats(const std::string &name, const float *data, std::size_t n);
  /// Closes the file, writes the header, syncs and renames it into place. Throws OutputError.
  void commit();

private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

class SavedFileReader {
public:
  /// Opens `path` after checking its header (this kind, this format), its length and its
  /// checksum. Throws SavedFileError naming what is wrong.
  SavedFileReader(const std::string &path, const std::string &kind, int format);
  ~SavedFileReader();
  SavedFileReader(const SavedFileReader &) = delete;
  SavedFileReader &operator=(const SavedFileReader &) = delete;

  std::string text(const std::string &name) const;
  bool has(const std::string &name) const;
  /// The number of elements of array `name`.
  std::size_t size(const std::string &name) const;
  /// Array `name`, which must hold `n` elements of its type, into `out`.
  void doubles(const std::string &name, double *out, std::size_t n) const;
  std::vector<double> doubles(const std::string &name) const;
  std::vector<int> ints(const std::string &name) const;
  std::vector<char> chars(const std::string &name) const;
  std::vector<float> floats(const std::string &name) const;
  /// Throws SavedFileError "cannot load '<path>': <reason>".
  [[noreturn]] void fail(const std::string &reason) const;

private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

} // namespace hssbem
