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

// Hash64::AddBytes over bytes that come in pieces: Add(a), Add(b) then Finish() equals a
// Hash64 given AddBytes(a followed by b) then Finish(). The trace writer hashes each frame's
// bytes as it writes them this way (IndexEntry.storedHash in traces/trace.capnp).
class StreamHash64 {
 public:
  void Add(const void* data, std::size_t size);
  std::uint64_t Finish() const;

 private:
  Hash64 h_;
  std::uint64_t pending_ = 0;  // the bytes of an unfinished word, little-endian
  unsigned pending_bytes_ = 0;
  std::uint64_t size_ = 0;
};

}  // namespace raycell
