// The container of a saved precomputation (see saved_file.hpp), read: the header, the length and
// the checksum first, then HDF5; the large arrays chunk by chunk straight into place, each
// chunk's Fletcher-32 checked here. No MPI, no result writer: the fuzzer (tests/fuzz/) builds it alone.
#include "hssbem/io/saved_file.hpp"

#include "fletcher32.hpp"
#include "h5_handle.hpp"
#include "saved_file_format.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <optional>
#include <sstream>
#include <vector>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hssbem {

using detail::h5_reason;
using detail::ByteRange;
using detail::hash_kept;
using detail::kHeaderBytes;
using detail::kMagic;
using detail::Fd;

struct SavedFileReader::Impl {
  std::string path;
  std::optional<detail::H5ErrorSilencer> silence;
  hid_t file = H5I_INVALID_HID;
  ~Impl()
  {
    if (file >= 0) H5Fclose(file);
  }
};

namespace {

/// The header's "key: value" lines into their values, in order, then its line of unhashed
/// ranges (empty when it has none: a file of format 1); false when it is not ours.
bool parse_header(const std::string &h, std::vector<std::string> &values, std::string &unhashed)
{
  static const char *keys[] = {"kind", "format", "bytes", "checksum"};
  std::istringstream in(h.substr(0, h.find('\0')));
  std::string line;
  if (!std::getline(in, line) || line != kMagic) return false;
  for (const char *k : keys) {
    if (!std::getline(in, line) || line.rfind(std::string(k) + ": ", 0) != 0) return false;
    values.push_back(line.substr(std::strlen(k) + 2));
  }
  if (std::getline(in, line) && line.rfind("unhashed:", 0) == 0) unhashed = line;
  return true;
}

/// The header is all text, then zero bytes to its end.
bool zero_tail(const std::string &h)
{
  const std::size_t end = h.find('\0');
  return end != std::string::npos && std::all_of(h.begin() + static_cast<long>(end), h.end(), [](char c) { return c == '\0'; });
}

/// The digits of s as a number; false unless s is all digits (at most 19).
bool digits(const std::string &s, std::uint64_t &v, int base = 10)
{
  if (s.empty() || s.size() > (base == 10 ? 19u : 16u)) return false;
  v = 0;
  for (char c : s) {
    const int d = c >= '0' && c <= '9' ? c - '0' : base == 16 && c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
    if (d < 0) return false;
    v = v * base + d;
  }
  return true;
}

/// The ranges of an "unhashed:" line: sorted, disjoint, inside [kHeaderBytes, bytes); false
/// otherwise.
bool parse_ranges(const std::string &line, std::uint64_t bytes, std::vector<ByteRange> &out)
{
  std::istringstream in(line.substr(std::strlen("unhashed:")));
  std::uint64_t end = kHeaderBytes;
  for (std::string item; in >> item;) {
    const std::size_t plus = item.find('+');
    ByteRange r{};
    if (plus == std::string::npos || !digits(item.substr(0, plus), r.at, 16) || !digits(item.substr(plus + 1), r.bytes, 16)) return false;
    if (r.bytes == 0 || r.at < end || r.at > bytes || r.bytes > bytes - r.at) return false;
    out.push_back(r), end = r.at + r.bytes;
  }
  return detail::unhashed_line(out) == line; // one spelling: the line hashed is the one parsed
}

} // namespace

void SavedFileReader::fail(const std::string &reason) const { throw SavedFileError("cannot load '" + m->path + "': " + reason); }

SavedFileReader::SavedFileReader(const std::string &path, const std::string &kind, int format) : m(std::make_unique<Impl>())
{
  m->path = path;
  const Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  struct stat st {};
  if (f.fd < 0 || ::fstat(f.fd, &st) != 0) fail(std::strerror(errno));
  if (!S_ISREG(st.st_mode)) fail("not a regular file");
  std::string h(kHeaderBytes, '\0'), unhashed;
  std::vector<std::string> v;
  if (st.st_size < 64 || ::pread(f.fd, h.data(), h.size(), 0) < 64 || !parse_header(h, v, unhashed)) fail("not a file hssbem saved (no hssbem header)");
  std::uint64_t fmt = 0, bytes = 0, sum = 0, actual = 0;
  if (v[0] != kind) fail("it holds a " + v[0] + ", not a " + kind);
  if (!digits(v[1], fmt) || !digits(v[2], bytes) || !digits(v[3], sum, 16)) fail("its header is damaged");
  if (fmt != static_cast<std::uint64_t>(format))
    fail("its format is version " + v[1] + "; this hssbem reads version " + std::to_string(format) + " (save it again with this hssbem)");
  if (bytes != static_cast<std::uint64_t>(st.st_size))
    fail("the file is truncated or extended: " + std::to_string(st.st_size) + " bytes, its header says " + v[2]);
  std::vector<ByteRange> skip;
  if (bytes < kHeaderBytes || !zero_tail(h) || unhashed.empty() || !parse_ranges(unhashed, bytes, skip)) fail("its header is damaged");
  if (!hash_kept(f.fd, bytes, skip, unhashed, actual)) fail("read error");
  if (actual != sum) fail("the file is damaged: its checksum does not match its contents");
  m->silence.emplace();
  m->file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (m->file < 0) fail("HDF5 cannot open it: " + h5_reason());
}

SavedFileReader::~SavedFileReader() = default;

bool SavedFileReader::has(const std::string &name) const
{
  return H5Lexists(m->file, name.c_str(), H5P_DEFAULT) > 0 || H5Aexists(m->file, name.c_str()) > 0;
}

std::string SavedFileReader::text(const std::string &name) const
{
  if (H5Aexists(m->file, name.c_str()) <= 0) fail("it has no attribute '" + name + "'");
  const detail::H5Handle attr(H5Aopen(m->file, name.c_str(), H5P_DEFAULT), H5Aclose);
  const detail::H5Handle type(attr.get() < 0 ? -1 : H5Aget_type(attr.get()), H5Tclose);
  if (type.get() < 0 || H5Tget_class(type.get()) != H5T_STRING || H5Tis_variable_str(type.get()) <= 0) fail("its attribute '" + name + "' is no text");
  char *value = nullptr;
  if (H5Aread(attr.get(), type.get(), &value) < 0 || !value) fail("cannot read its attribute '" + name + "': " + h5_reason());
  const std::string out(value);
  H5free_memory(value);
  return out;
}

namespace {

/// Opens array `name` of `file_type` (checked: one dimension, that type); its length into n.
hid_t open_array(const SavedFileReader &r, hid_t file, const std::string &name, hid_t file_type, std::size_t &n)
{
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) <= 0) r.fail("it has no array '" + name + "'");
  detail::H5Handle set(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  const detail::H5Handle type(set.get() < 0 ? -1 : H5Dget_type(set.get()), H5Tclose), space(set.get() < 0 ? -1 : H5Dget_space(set.get()), H5Sclose);
  hsize_t dims[1] = {0};
  if (type.get() < 0 || space.get() < 0 || H5Tequal(type.get(), file_type) <= 0 || H5Sget_simple_extent_ndims(space.get()) != 1 ||
      H5Sget_simple_extent_dims(space.get(), dims, nullptr) != 1)
    r.fail("its array '" + name + "' is not what hssbem wrote");
  n = static_cast<std::size_t>(dims[0]);
  return set.release();
}

/// Asks for huge pages under [p, p + bytes) before it is first written (transparent huge pages
/// in "madvise" mode): a gigabyte array then faults in 2 MB at a time, not 4 kB.
void advise_huge_pages(void *p, std::size_t bytes)
{
  constexpr std::uintptr_t huge = 2u << 20;
  const std::uintptr_t from = (reinterpret_cast<std::uintptr_t>(p) + huge - 1) & ~(huge - 1), to = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(huge - 1);
  if (to > from) ::madvise(reinterpret_cast<void *>(from), to - from, MADV_HUGEPAGE); // advice: its failure changes nothing
}

/// Whether `set` is stored as the writer stores large arrays: one-dimensional chunks, Fletcher-32
/// alone, the file's type the memory's; its chunk length into chunk.
bool plain_fletcher_chunks(hid_t set, hid_t file_type, hid_t mem_type, hsize_t &chunk)
{
  const detail::H5Handle dcpl(H5Dget_create_plist(set), H5Pclose);
  unsigned flags = 0, config = 0;
  std::size_t values = 0;
  return dcpl.get() >= 0 && H5Pget_layout(dcpl.get()) == H5D_CHUNKED && H5Pget_chunk(dcpl.get(), 1, &chunk) == 1 && chunk > 0 && H5Pget_nfilters(dcpl.get()) == 1 &&
         H5Pget_filter2(dcpl.get(), 0, &flags, &values, nullptr, 0, nullptr, &config) == H5Z_FILTER_FLETCHER32 && H5Tequal(file_type, mem_type) > 0;
}

/// Array `name` (`set`, n elements) into `out`: chunk by chunk straight into place
/// (H5Dread_chunk: one copy from the file, no filter buffer), each chunk's Fletcher-32 (stored
/// after its values) checked here; a chunk whose 4 checksum bytes would land past the array goes
/// through a spare buffer. Arrays stored otherwise are read by H5Dread.
void read_into(const SavedFileReader &r, const std::string &name, hid_t set, hid_t file_type, hid_t mem_type, void *out, std::size_t n)
{
  hsize_t chunk = 0;
  if (n == 0) return;
  if (!plain_fletcher_chunks(set, file_type, mem_type, chunk)) {
    if (H5Dread(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) r.fail("cannot read its array '" + name + "': " + h5_reason());
    return;
  }
  const std::size_t elem = H5Tget_size(mem_type), bytes = chunk * elem;
  unsigned char *const to = static_cast<unsigned char *>(out);
  std::vector<unsigned char> spare;
  for (hsize_t at = 0; at < n; at += chunk) {
    hsize_t stored = 0;
    std::uint32_t mask = 0;
    if (H5Dget_chunk_storage_size(set, &at, &stored) < 0 || stored != bytes + 4) r.fail("its array '" + name + "' is damaged (the size of a chunk)");
    const bool in_place = (at + chunk) * elem + 4 <= n * elem;
    unsigned char *dst = in_place ? to + at * elem : (spare.resize(bytes + 4), spare.data());
    if (H5Dread_chunk(set, H5P_DEFAULT, &at, &mask, dst) < 0 || mask != 0) r.fail("cannot read its array '" + name + "': " + h5_reason());
    const unsigned char *c = dst + bytes;
    if (detail::fletcher32(dst, bytes) != (c[0] | c[1] << 8 | c[2] << 16 | static_cast<std::uint32_t>(c[3]) << 24))
      r.fail("its array '" + name + "' is damaged: the checksum of a chunk does not match");
    if (!in_place) std::memcpy(to + at * elem, dst, std::min<std::size_t>(chunk, n - at) * elem);
  }
}

template <class T> std::vector<T> read_array(const SavedFileReader &r, hid_t file, const std::string &name, hid_t file_type, hid_t mem_type)
{
  std::size_t n = 0;
  const detail::H5Handle set(open_array(r, file, name, file_type, n), H5Dclose);
  std::vector<T> out(n);
  read_into(r, name, set.get(), file_type, mem_type, out.data(), n);
  return out;
}

} // namespace

std::size_t SavedFileReader::size(const std::string &name) const
{
  if (H5Lexists(m->file, name.c_str(), H5P_DEFAULT) <= 0) fail("it has no array '" + name + "'");
  const detail::H5Handle set(H5Dopen2(m->file, name.c_str(), H5P_DEFAULT), H5Dclose);
  const detail::H5Handle space(set.get() < 0 ? -1 : H5Dget_space(set.get()), H5Sclose);
  const hssize_t n = space.get() < 0 ? -1 : H5Sget_simple_extent_npoints(space.get());
  if (n < 0) fail("its array '" + name + "' is not what hssbem wrote");
  return static_cast<std::size_t>(n);
}

void SavedFileReader::doubles(const std::string &name, double *out, std::size_t n) const
{
  std::size_t have = 0;
  const detail::H5Handle set(open_array(*this, m->file, name, H5T_IEEE_F64LE, have), H5Dclose);
  if (have != n) fail("its array '" + name + "' holds " + std::to_string(have) + " values, not " + std::to_string(n));
  advise_huge_pages(out, n * sizeof(double));
  read_into(*this, name, set.get(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, out, n);
}

std::vector<double> SavedFileReader::doubles(const std::string &name) const { return read_array<double>(*this, m->file, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE); }
std::vector<int> SavedFileReader::ints(const std::string &name) const { return read_array<int>(*this, m->file, name, H5T_STD_I32LE, H5T_NATIVE_INT); }
std::vector<float> SavedFileReader::floats(const std::string &name) const { return read_array<float>(*this, m->file, name, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT); }
std::vector<char> SavedFileReader::chars(const std::string &name) const { return read_array<char>(*this, m->file, name, H5T_STD_I8LE, H5T_NATIVE_SCHAR); }

} // namespace hssbem
