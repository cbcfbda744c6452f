/// \file saved_file_format.hpp
/// Private to io/: the header of a saved file (saved_file.hpp) and the checksum of what follows
/// it, shared by its writer and its reader.
#pragma once

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <sys/mman.h>
#include <unistd.h>

namespace hssbem::detail {

inline constexpr std::size_t kHeaderBytes = 512; // HDF5's smallest user block
inline constexpr const char *kMagic = "hssbem saved file";

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

/// The hash of bytes [kHeaderBytes, end) of the open file fd, read through a buffer; false on a
/// read error.
inline bool hash_body_read(int fd, std::uint64_t end, std::uint64_t &out)
{
  StreamHash h;
  std::vector<unsigned char> buf(8 << 20);
  for (std::uint64_t at = kHeaderBytes; at < end;) {
    const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(buf.size(), end - at));
    std::size_t have = 0; // a whole buffer (short reads joined): the stripes fall the same way every time
    while (have < want) {
      const ssize_t got = ::pread(fd, buf.data() + have, want - have, static_cast<off_t>(at + have));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      have += static_cast<std::size_t>(got);
    }
    h.add(buf.data(), want);
    at += want;
  }
  out = h.value();
  return true;
}

/// The same, from the file mapped into memory (no copy of its pages: the checksum pass of a
/// gigabyte file costs the hash alone when the file is in the page cache), in the same stripes;
/// through a buffer where the file cannot be mapped.
inline bool hash_body(int fd, std::uint64_t end, std::uint64_t &out)
{
  if (end <= kHeaderBytes) return hash_body_read(fd, end, out);
  void *map = ::mmap(nullptr, static_cast<std::size_t>(end), PROT_READ, MAP_PRIVATE, fd, 0);
  if (map == MAP_FAILED) return hash_body_read(fd, end, out);
  ::madvise(map, static_cast<std::size_t>(end), MADV_SEQUENTIAL);
  StreamHash h;
  const unsigned char *p = static_cast<const unsigned char *>(map);
  for (std::uint64_t at = kHeaderBytes; at < end; at += 8 << 20)
    h.add(p + at, static_cast<std::size_t>(std::min<std::uint64_t>(8 << 20, end - at)));
  ::munmap(map, static_cast<std::size_t>(end));
  out = h.value();
  return true;
}

inline std::string header_text(const std::string &kind, int format, std::uint64_t bytes, std::uint64_t checksum)
{
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(checksum));
  return std::string(kMagic) + "\nkind: " + kind + "\nformat: " + std::to_string(format) + "\nbytes: " + std::to_string(bytes) + "\nchecksum: " + hex + "\n";
}

} // namespace hssbem::detail
