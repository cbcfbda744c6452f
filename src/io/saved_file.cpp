// The container of a saved precomputation (see saved_file.hpp): HDF5 behind a header of our own
// with the file's length and checksum, written the result file's safe way.
#include "hssbem/io/saved_file.hpp"

#include "file_commit.hpp"
#include "h5_writer.hpp"

#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/io/temp_files.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <sstream>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hssbem {

namespace {

constexpr std::size_t kHeaderBytes = 512; // HDF5's smallest user block
constexpr const char *kMagic = "hssbem saved file";

/// A file descriptor closed on every path.
struct Fd {
  int fd;
  ~Fd()
  {
    if (fd >= 0) ::close(fd);
  }
};

/// A 64-bit hash of a byte stream in 32-byte stripes on four lanes (xxHash64's round), fast
/// enough to check gigabytes at the rate they are read.
class StreamHash {
public:
  /// Bytes in any amount; only the last call may leave a part of a stripe.
  void add(const unsigned char *p, std::size_t n)
  {
    m_bytes += n;
    std::size_t i = 0;
    for (; i + 32 <= n; i += 32)
      for (int l = 0; l < 4; ++l) m_lane[l] = round(m_lane[l], word(p + i + 8 * l));
    for (; i < n; ++i) m_lane[0] = round(m_lane[0], p[i] + 1);
  }
  std::uint64_t value() const
  {
    std::uint64_t h = m_bytes * kP1;
    for (std::uint64_t l : m_lane) h = (h ^ round(0, l)) * kP1 + kP4;
    h ^= h >> 33, h *= kP2, h ^= h >> 29, h *= kP3, h ^= h >> 32;
    return h;
  }

private:
  static constexpr std::uint64_t kP1 = 11400714785074694791ULL, kP2 = 14029467366897019727ULL, kP3 = 1609587929392839161ULL, kP4 = 9650029242287828579ULL;
  static std::uint64_t word(const unsigned char *p)
  {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    return w;
  }
  static std::uint64_t round(std::uint64_t acc, std::uint64_t w)
  {
    acc += w * kP2;
    acc = (acc << 31) | (acc >> 33);
    return acc * kP1;
  }
  std::uint64_t m_lane[4] = {kP1 + kP2, kP2, 0, 0 - kP1};
  std::uint64_t m_bytes = 0;
};

/// The hash of bytes [kHeaderBytes, end) of the open file fd; false on a read error.
bool hash_body(int fd, std::uint64_t end, std::uint64_t &out)
{
  StreamHash h;
  std::vector<unsigned char> buf(8 << 20);
  std::uint64_t at = kHeaderBytes;
  while (at < end) {
    const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(buf.size(), end - at));
    const ssize_t got = ::pread(fd, buf.data(), want, static_cast<off_t>(at));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    h.add(buf.data(), static_cast<std::size_t>(got));
    at += static_cast<std::uint64_t>(got);
  }
  out = h.value();
  return true;
}

std::string header_text(const std::string &kind, int format, std::uint64_t bytes, std::uint64_t checksum)
{
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(checksum));
  return std::string(kMagic) + "\nkind: " + kind + "\nformat: " + std::to_string(format) + "\nbytes: " + std::to_string(bytes) + "\nchecksum: " + hex + "\n";
}

/// The innermost message of HDF5's error stack (before the next HDF5 call clears it).
herr_t innermost(unsigned n, const H5E_error2_t *err, void *out)
{
  if (n == 0 && err->desc) *static_cast<std::string *>(out) = err->desc;
  return 0;
}

std::string h5_reason()
{
  std::string r;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost, &r);
  return r;
}

} // namespace

// --- writing --------------------------------------------------------------------------------

struct SavedFileWriter::Impl {
  std::string path, kind, tmp;
  int format = 0;
  detail::FileSetCommit files;
  std::optional<detail::H5ErrorSilencer> silence;
  hid_t file = H5I_INVALID_HID;

  Impl(const std::string &p) : path(p), files(p) {}
  ~Impl()
  {
    if (file >= 0) H5Fclose(file);
  }
  [[noreturn]] void fail(const std::string &object, const char *call) const
  {
    const std::string reason = h5_reason();
    detail::fail_output(path, std::string(call) + " failed for " + object + (reason.empty() ? "" : ": " + reason));
  }
  void check(herr_t status, const std::string &object, const char *call) const
  {
    if (status < 0) fail(object, call);
  }
  void array(const std::string &name, const void *data, std::size_t n, hid_t file_type, hid_t mem_type);
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
  }
  detail::H5Handle set(H5Dcreate2(file, name.c_str(), file_type, space.get(), lcpl.get(), dcpl.get(), H5P_DEFAULT), H5Dclose);
  check(set.get() < 0 ? -1 : 0, object, "H5Dcreate2");
  if (n > 0) check(H5Dwrite(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), object, "H5Dwrite");
  check(set.close(), object, "H5Dclose");
}

void SavedFileWriter::doubles(const std::string &name, const double *data, std::size_t n) { m->array(name, data, n, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE); }
void SavedFileWriter::ints(const std::string &name, const int *data, std::size_t n) { m->array(name, data, n, H5T_STD_I32LE, H5T_NATIVE_INT); }
void SavedFileWriter::chars(const std::string &name, const char *data, std::size_t n) { m->array(name, data, n, H5T_STD_I8LE, H5T_NATIVE_SCHAR); }

/// The header into the user block: the length and the hash of what HDF5 wrote after it.
void SavedFileWriter::Impl::header()
{
  const Fd f{::open(tmp.c_str(), O_RDWR | O_NOFOLLOW | O_CLOEXEC)};
  struct stat st {};
  if (f.fd < 0 || ::fstat(f.fd, &st) != 0) detail::fail_output(path, "cannot reopen '" + tmp + "': " + std::strerror(errno));
  const std::uint64_t bytes = static_cast<std::uint64_t>(st.st_size);
  std::uint64_t sum = 0;
  if (!hash_body(f.fd, bytes, sum)) detail::fail_output(path, "cannot read back '" + tmp + "'");
  std::string h = header_text(kind, format, bytes, sum);
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

// --- reading --------------------------------------------------------------------------------

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

/// The header's "key: value" lines into their values, in order; false when it is not ours.
bool parse_header(const std::string &h, std::vector<std::string> &values)
{
  static const char *keys[] = {"kind", "format", "bytes", "checksum"};
  std::istringstream in(h.substr(0, h.find('\0')));
  std::string line;
  if (!std::getline(in, line) || line != kMagic) return false;
  for (const char *k : keys) {
    if (!std::getline(in, line) || line.rfind(std::string(k) + ": ", 0) != 0) return false;
    values.push_back(line.substr(std::strlen(k) + 2));
  }
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

} // namespace

void SavedFileReader::fail(const std::string &reason) const { throw SavedFileError("cannot load '" + m->path + "': " + reason); }

SavedFileReader::SavedFileReader(const std::string &path, const std::string &kind, int format) : m(std::make_unique<Impl>())
{
  m->path = path;
  const Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  struct stat st {};
  if (f.fd < 0 || ::fstat(f.fd, &st) != 0) fail(std::strerror(errno));
  if (!S_ISREG(st.st_mode)) fail("not a regular file");
  std::string h(kHeaderBytes, '\0');
  std::vector<std::string> v;
  if (st.st_size < static_cast<off_t>(kHeaderBytes) || ::pread(f.fd, h.data(), h.size(), 0) != static_cast<ssize_t>(h.size()) || !parse_header(h, v))
    fail("not a file hssbem saved (no hssbem header)");
  std::uint64_t fmt = 0, bytes = 0, sum = 0, actual = 0;
  if (v[0] != kind) fail("it holds a " + v[0] + ", not a " + kind);
  if (!digits(v[1], fmt) || !digits(v[2], bytes) || !digits(v[3], sum, 16)) fail("its header is damaged");
  if (fmt != static_cast<std::uint64_t>(format))
    fail("its format is version " + v[1] + "; this hssbem reads version " + std::to_string(format) + " (save it again with this hssbem)");
  if (bytes != static_cast<std::uint64_t>(st.st_size))
    fail("the file is truncated or extended: " + std::to_string(st.st_size) + " bytes, its header says " + v[2]);
  if (!hash_body(f.fd, bytes, actual)) fail("read error");
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

template <class T> std::vector<T> read_array(const SavedFileReader &r, hid_t file, const std::string &name, hid_t file_type, hid_t mem_type)
{
  std::size_t n = 0;
  const detail::H5Handle set(open_array(r, file, name, file_type, n), H5Dclose);
  std::vector<T> out(n);
  if (n > 0 && H5Dread(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) r.fail("cannot read its array '" + name + "': " + h5_reason());
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
  if (n > 0 && H5Dread(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) fail("cannot read its array '" + name + "': " + h5_reason());
}

std::vector<double> SavedFileReader::doubles(const std::string &name) const { return read_array<double>(*this, m->file, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE); }
std::vector<int> SavedFileReader::ints(const std::string &name) const { return read_array<int>(*this, m->file, name, H5T_STD_I32LE, H5T_NATIVE_INT); }
std::vector<char> SavedFileReader::chars(const std::string &name) const { return read_array<char>(*this, m->file, name, H5T_STD_I8LE, H5T_NATIVE_SCHAR); }

} // namespace hssbem
