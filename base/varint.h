// LEB128 varints in byte streams, 7 bits a byte, low bits first: the replay's compact work
// (replay/work.h) and parked Cell Trees (graph/cell_tree.h).
#pragma once

#include <cstdint>
#include <type_traits>
#include <vector>

namespace raycell {

// Appends x to `out`, a std::vector<std::uint8_t> or a MappedArray<std::uint8_t>.
template <typename Bytes>
inline void AppendVarint(Bytes& out, std::uint64_t x) {
  while (x >= 0x80) {
    out.push_back(std::uint8_t(x | 0x80));
    x >>= 7;
  }
  out.push_back(std::uint8_t(x));
}

// Reads the varint at stream[*at] as a U (the stream's writer put no larger value there) and
// moves *at past it. The replay's compact work names records by 32-bit offsets (U and Offset
// std::uint32_t: its hot path).
template <typename U = std::uint32_t, typename Offset>
U ReadVarint(const std::uint8_t* stream, Offset* at) {
  static_assert(std::is_unsigned_v<U> && std::is_unsigned_v<Offset>);
  U x = stream[(*at)++];
  if (x < 0x80) return x;
  x &= 0x7f;
  for (int shift = 7;; shift += 7) {
    const U b = stream[(*at)++];
    x |= (b & 0x7f) << shift;
    if (b < 0x80) return x;
  }
}

}  // namespace raycell
