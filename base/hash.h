// A 64-bit non-cryptographic hash (an xxHash64-style mix): trace checksums (see "Checksums"
// in traces/trace.capnp) and sweep fingerprints. Its values are part of the trace format,
// so it must never change.
#pragma once

#include <cstddef>
#include <cstdint>

namespace raycell {

class Hash64 {
 public:
  void Add(std::uint64_t word) {
    h_ ^= word * kP2;
    h_ = ((h_ << 31) | (h_ >> 33)) * kP1;
  }
  // Adds `size` bytes (a whole number of words read little-endian, else zero-padded) and
  // their length.
  void AddBytes(const void* data, std::size_t size);
  std::uint64_t Finish() const;

  static constexpr std::uint64_t kP1 = 0x9E3779B185EBCA87ull;
  static constexpr std::uint64_t kP2 = 0xC2B2AE3D27D4EB4Full;
  static constexpr std::uint64_t kP3 = 0x165667B19E3779F9ull;
  static constexpr std::uint64_t kSeed = 0x52435431ull;

 private:
  std::uint64_t h_ = kSeed;
};

}  // namespace raycell
