// The container of a saved precomputation (see saved_file.hpp), written: HDF5 behind a header of
// our own with the file's length and checksum (of all but the Fletcher-32 chunks, which the
// header lists), the result file's safe way.
#include "hssbem/io/saved_file.hpp"

#include "file_commit.hpp"
#include "fletcher32.hpp"
#include "h5_writer.hpp"
#include "saved_file_format.hpp"

#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/io/temp_files.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hssbem {

using detail::Fd;
using detail::ByteRange;
using detail::hash_kept;
using detail::header_text;
using detail::kHeaderBytes;

// --- writing --------------------------------------------------------------------------------

struct SavedFileWriter::Impl {
  std::string path, kind, tmp;
  int format = 0;
  detail::FileSetCommit files;
  std::optional<detail::H5ErrorSilencer> silence;
  hid_t file = H5I_INVALID_HID;
  std::vector<std::string> chunked; ///< the arrays stored in Fletcher-32 chunks

  Impl(const std::string &p) : path(p), files(p) {}
  ~Impl()
  {
    if (file >= 0) H5Fclose(file);
  }
  [[noreturn]] void fail(const std::string &object, const char *call) const
  {
    const std::string reason = detail::h5_reason();
    detail::fail_output(path, std::string(call) + " failed for " + object + (reason.empty() ? "" : ": " + reason));
  }
  void check(herr_t status, const std::string &object, const char *call) const
  {
    if (status < 0) fail(object, call);
  }
  void array(const std::string &name, const void *data, std::size_t n, hid_t file_type, hid_t mem_type);
  std::vector<ByteRange> chunk_ranges(int fd) const;
  std::uint64_t chunk_base(int fd, hid_t set) const;
  void header();
};

SavedFileWriter::SavedFileWriter(const std::string &path, const std::vector<std::string> &inputs, const std::string &kind, int format)
{
  check_not_an_input(path, inputs);
  m = std::make_unique<Impl>(path);
  m->kind = kind, m->format = format;
  m->tmp = m->files.add(path);
  m->silence.emplace();
  const detail::H5Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  m->check(fcpl.get() < 0 ? -1 : H5Pset_userblock(fcpl.get(), kHeaderBytes), "the file", "H5Pset_userblock");
  m->file = H5Fcreate(m->tmp.c_str(), H5F_ACC_TRUNC, fcpl.get(), H5P_DEFAULT);
  m->check(m->file < 0 ? -1 : 0, "the file", "H5Fcreate");
}

SavedFileWriter::~SavedFileWriter() = default;

void SavedFileWriter::text(const std::string &name, const std::string &value)
{
  const detail::H5Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  const std::string object = "attribute '" + name + "'";
  m->check(type.get() < 0 ? -1 : H5Tset_size(type.get(), H5T_VARIABLE), object, "H5Tset_size");
  m->check(H5Tset_cset(type.get(), H5T_CSET_UTF8), object, "H5Tset_cset");
  const detail::H5Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  detail::H5Handle attr(H5Acreate2(m->file, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  m->check(attr.get() < 0 ? -1 : 0, object, "H5Acreate2");
  const char *v = value.c_str();
  m->check(H5Awrite(attr.get(), type.get(), &v), object, "H5Awrite");
  m->check(attr.close(), object, "H5Aclose");
}

void SavedFileWriter::Impl::array(const std::string &name, const void *data, std::size_t n, hid_t file_type, hid_t mem_type)
{
  const std::string object = "array '" + name + "'";
  const hsize_t dims[1] = {static_cast<hsize_t>(n)};
  const detail::H5Handle space(H5Screate_simple(1, dims, nullptr), H5Sclose);
  const detail::H5Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose), dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  check(space.get() < 0 || lcpl.get() < 0 || dcpl.get() < 0 ? -1 : H5Pset_create_intermediate_group(lcpl.get(), 1), object, "H5Pcreate");
  if (n >= kChecksummedElements) { // chunks of at most 8 MB, each with its Fletcher-32 checksum
    // HDF5 stores the last chunk whole: chunks of equal size waste less than one element each
    const hsize_t most = (8u << 20) / H5Tget_size(file_type), count = (dims[0] + most - 1) / most;
    const hsize_t chunk[1] = {(dims[0] + count - 1) / count};
    check(H5Pset_chunk(dcpl.get(), 1, chunk), object, "H5Pset_chunk");
    check(H5Pset_fletcher32(dcpl.get()), object, "H5Pset_fletcher32");
    chunked.push_back(name);
  }
  detail::H5Handle set(H5Dcreate2(file, name.c_str(), file_type, space.get(), lcpl.get(), dcpl.get(), H5P_DEFAULT), H5Dclose);
  check(set.get() < 0 ? -1 : 0, object, "H5Dcreate2");
  if (n > 0) check(H5Dwrite(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), object, "H5Dwrite");
  check(set.close(), object, "H5Dclose");
}

void SavedFileWriter::doubles(const std::string &name, const double *data, std::size_t n) { m->array(name, data, n, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE); }
void SavedFileWriter::ints(const std::string &name, const int *data, std::size_t n) { m->array(name, data, n, H5T_STD_I32LE, H5T_NATIVE_INT); }
void SavedFileWriter::floats(const std::string &name, const float *data, std::size_t n) { m->array(name, data, n, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT); }
void SavedFileWriter::chars(const std::string &name, const char *data, std::size_t n) { m->array(name, data, n, H5T_STD_I8LE, H5T_NATIVE_SCHAR); }

/// Where HDF5's chunk addresses start in the file: after the user block (HDF5 1.10 reports
/// addresses relative to it) or at 0. Told by the first chunk of `set`, whose stored Fletcher-32
/// holds at exactly one of the two.
std::uint64_t SavedFileWriter::Impl::chunk_base(int fd, hid_t set) const
{
  const detail::H5Handle space(H5Dget_space(set), H5Sclose);
  hsize_t offset = 0, size = 0;
  haddr_t addr = HADDR_UNDEF;
  unsigned mask = 0;
  if (space.get() < 0 || H5Dget_chunk_info(set, space.get(), 0, &offset, &mask, &addr, &size) < 0 || size < 4) fail("a chunked array", "H5Dget_chunk_info");
  std::vector<unsigned char> chunk(size);
  for (std::uint64_t base : {static_cast<std::uint64_t>(kHeaderBytes), std::uint64_t{0}}) {
    if (::pread(fd, chunk.data(), size, static_cast<off_t>(base + addr)) != static_cast<ssize_t>(size)) continue;
    const unsigned char *c = chunk.data() + size - 4;
    if (detail::fletcher32(chunk.data(), size - 4) == (c[0] | c[1] << 8 | c[2] << 16 | static_cast<std::uint32_t>(c[3]) << 24)) return base;
  }
  detail::fail_output(path, "cannot locate the chunks HDF5 wrote in '" + tmp + "'");
}

/// The extents of every Fletcher-32 chunk in the file (reopened by HDF5), adjacent ones joined.
std::vector<ByteRange> SavedFileWriter::Impl::chunk_ranges(int fd) const
{
  std::vector<ByteRange> out;
  if (chunked.empty()) return out;
  const detail::H5Handle f(H5Fopen(tmp.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  check(f.get() < 0 ? -1 : 0, "the file", "H5Fopen");
  std::optional<std::uint64_t> base;
  for (const std::string &name : chunked) {
    const detail::H5Handle set(H5Dopen2(f.get(), name.c_str(), H5P_DEFAULT), H5Dclose), space(set.get() < 0 ? -1 : H5Dget_space(set.get()), H5Sclose);
    hsize_t count = 0;
    check(space.get() < 0 ? -1 : H5Dget_num_chunks(set.get(), space.get(), &count), "array '" + name + "'", "H5Dget_num_chunks");
    if (!base) base = chunk_base(fd, set.get());
    for (hsize_t k = 0; k < count; ++k) {
      hsize_t offset = 0, size = 0;
      haddr_t addr = HADDR_UNDEF;
      unsigned mask = 0;
      check(H5Dget_chunk_info(set.get(), space.get(), k, &offset, &mask, &addr, &size), "array '" + name + "'", "H5Dget_chunk_info");
      out.push_back({*base + addr, size});
    }
  }
  std::sort(out.begin(), out.end(), [](const ByteRange &a, const ByteRange &b) { return a.at < b.at; });
  std::vector<ByteRange> joined;
  for (const ByteRange &r : out) {
    if (!joined.empty() && joined.back().at + joined.back().bytes == r.at) joined.back().bytes += r.bytes;
    else joined.push_back(r);
  }
  return joined;
}

namespace {

/// The largest of `ranges` whose line fits the header beside `rest` bytes, in file order (the
/// others are hashed: slower to load, as safe).
std::vector<ByteRange> fitting(std::vector<ByteRange> ranges, std::size_t rest)
{
  std::sort(ranges.begin(), ranges.end(), [](const ByteRange &a, const ByteRange &b) { return a.bytes > b.bytes; });
  std::vector<ByteRange> kept;
  for (const ByteRange &r : ranges) {
    kept.push_back(r);
    if (rest + detail::unhashed_line(kept).size() + 2 > kHeaderBytes) kept.pop_back();
  }
  std::sort(kept.begin(), kept.end(), [](const ByteRange &a, const ByteRange &b) { return a.at < b.at; });
  return kept;
}

} // namespace

/// The header into the user block: the length, the ranges HDF5's Fletcher-32 checks, and the
/// hash of their line and of every other byte after the header.
void SavedFileWriter::Impl::header()
{
  const Fd f{::open(tmp.c_str(), O_RDWR | O_NOFOLLOW | O_CLOEXEC)};
  struct stat st {};
  if (f.fd < 0 || ::fstat(f.fd, &st) != 0) detail::fail_output(path, "cannot reopen '" + tmp + "': " + std::strerror(errno));
  const std::uint64_t bytes = static_cast<std::uint64_t>(st.st_size);
  const std::vector<ByteRange> skip = fitting(chunk_ranges(f.fd), header_text(kind, format, bytes, 0, "").size());
  const std::string unhashed = detail::unhashed_line(skip);
  std::uint64_t sum = 0;
  if (!hash_kept(f.fd, bytes, skip, unhashed, sum)) detail::fail_output(path, "cannot read back '" + tmp + "'");
  std::string h = header_text(kind, format, bytes, sum, unhashed);
  h.resize(kHeaderBytes, '\0');
  if (::pwrite(f.fd, h.data(), h.size(), 0) != static_cast<ssize_t>(h.size())) detail::fail_output(path, "cannot write the header of '" + tmp + "': " + std::strerror(errno));
}

void SavedFileWriter::commit()
{
  m->check(H5Fclose(std::exchange(m->file, H5I_INVALID_HID)), "the file", "H5Fclose");
  m->silence.reset();
  m->header();
  detail::sync_file(m->tmp, m->path);
  m->files.commit();
}

} // namespace hssbem
