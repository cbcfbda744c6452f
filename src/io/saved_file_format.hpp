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

#include <unistd.h>

namespace hssbem::detail {

inline constexpr std::size_t kHeaderBytes = 4096; // HDF5's user block: room for the unhashed ranges
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

/// A byte range [at, at + bytes) of a file.
struct ByteRange {
  std::uint64_t at, bytes;
};

/// The hash of `prefix`, then of the bytes [kHeaderBytes, end) of the open file fd outside
/// `skip` (sorted, disjoint, inside that span), read through one buffer: the kept pieces are
/// joined so that the stripes fall the same way whatever the pieces. False on a read error.
inline bool hash_kept(int fd, std::uint64_t end, const std::vector<ByteRange> &skip, const std::string &prefix, std::uint64_t &out)
{
  StreamHash h;
  std::vector<unsigned char> buf(8 << 20);
  std::size_t fill = std::min(prefix.size(), buf.size());
  std::memcpy(buf.data(), prefix.data(), fill);
  std::uint64_t at = kHeaderBytes;
  for (std::size_t r = 0; r <= skip.size(); ++r) {
    const std::uint64_t stop = r < skip.size() ? skip[r].at : end;
    while (at < stop) {
      const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(buf.size() - fill, stop - at));
      const ssize_t got = ::pread(fd, buf.data() + fill, want, static_cast<off_t>(at));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      fill += static_cast<std::size_t>(got), at += static_cast<std::uint64_t>(got);
      if (fill == buf.size()) h.add(buf.data(), fill), fill = 0;
    }
    if (r < skip.size()) at = skip[r].at + skip[r].bytes;
  }
  h.add(buf.data(), fill);
  out = h.value();
  return true;
}

/// The header's line of the ranges left out of the checksum (each checked by HDF5's Fletcher-32
/// as it is read): "unhashed:" then " <at>+<bytes>" per range, in hexadecimal.
inline std::string unhashed_line(const std::vector<ByteRange> &skip)
{
  std::string line = "unhashed:";
  char b[40];
  for (const ByteRange &r : skip) {
    std::snprintf(b, sizeof b, " %llx+%llx", static_cast<unsigned long long>(r.at), static_cast<unsigned long long>(r.bytes));
    line += b;
  }
  return line;
}

inline std::string header_text(const std::string &kind, int format, std::uint64_t bytes, std::uint64_t checksum, const std::string &unhashed)
{
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(checksum));
  return std::string(kMagic) + "\nkind: " + kind + "\nformat: " + std::to_string(format) + "\nbytes: " + std::to_string(bytes) + "\nchecksum: " + hex + "\n" + unhashed + "\n";
}

} // namespace hssbem::detail
