/// \file fletcher32.hpp
/// Private to io/: HDF5's Fletcher-32 checksum of a chunk (H5_checksum_fletcher32: big-endian
/// 16-bit words, both sums folded after every 360 words and twice at the end), computed here so
/// that a saved file's large arrays are read straight into place (H5Dread_chunk) and still
/// checked against the checksum HDF5's filter stored after each chunk.
#pragma once

#include <cstddef>
#include <cstdint>

namespace hssbem::detail {

/// HDF5's Fletcher-32 of `bytes` bytes. The words of a block of m ≤ 360 are summed at once
/// (s1 += Σ wᵢ, s2 += m s1 + Σ (m − i) wᵢ: the same integers as HDF5's word-by-word loop, which
/// the compiler vectorises), so the value is HDF5's to the bit.
inline std::uint32_t fletcher32(const unsigned char *p, std::size_t bytes)
{
  std::uint32_t s1 = 0, s2 = 0;
  for (std::size_t words = bytes / 2; words > 0;) {
    const std::uint32_t m = static_cast<std::uint32_t>(words > 360 ? 360 : words);
    std::uint32_t sum = 0, weighted = 0;
    for (std::uint32_t i = 0; i < m; ++i) {
      const std::uint32_t w = (static_cast<std::uint32_t>(p[2 * i]) << 8) | p[2 * i + 1];
      sum += w, weighted += (m - i) * w;
    }
    s2 += m * s1 + weighted, s1 += sum;
    s1 = (s1 & 0xffff) + (s1 >> 16), s2 = (s2 & 0xffff) + (s2 >> 16);
    p += 2 * m, words -= m;
  }
  if (bytes % 2) {
    s1 += static_cast<std::uint32_t>(*p) << 8, s2 += s1;
    s1 = (s1 & 0xffff) + (s1 >> 16), s2 = (s2 & 0xffff) + (s2 >> 16);
  }
  s1 = (s1 & 0xffff) + (s1 >> 16), s2 = (s2 & 0xffff) + (s2 >> 16);
  return (s2 << 16) | s1;
}

} // namespace hssbem::detail
