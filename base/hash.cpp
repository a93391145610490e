#include "base/hash.h"

#include <cstring>

namespace raycell {
namespace {

// The 8 bytes at p as a little-endian word.
std::uint64_t LoadLittleEndian(const unsigned char* p) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  std::uint64_t w;
  std::memcpy(&w, p, 8);
  return w;
#else
  std::uint64_t w = 0;
  for (unsigned b = 0; b < 8; ++b) w |= std::uint64_t{p[b]} << (8 * b);
  return w;
#endif
}

}  // namespace

void Hash64::AddBytes(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) Add(LoadLittleEndian(p + i));
  if (i < size) {  // the last word, zero-padded
    std::uint64_t w = 0;
    for (std::size_t b = 0; i + b < size; ++b) w |= std::uint64_t{p[i + b]} << (8 * b);
    Add(w);
  }
  Add(size);
}

std::uint64_t Hash64::Finish() const {
  std::uint64_t h = h_;
  h ^= h >> 33;
  h *= kP2;
  h ^= h >> 29;
  h *= kP3;
  h ^= h >> 32;
  return h;
}

void StreamHash64::Add(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  size_ += size;
  std::size_t i = 0;
  while (i < size && pending_bytes_ != 0) {  // finish the word begun by an earlier piece
    pending_ |= std::uint64_t{p[i++]} << (8 * pending_bytes_);
    if (++pending_bytes_ == 8) h_.Add(pending_), pending_ = 0, pending_bytes_ = 0;
  }
  for (; i + 8 <= size; i += 8) h_.Add(LoadLittleEndian(p + i));
  for (; i < size; ++i) pending_ |= std::uint64_t{p[i]} << (8 * pending_bytes_++);
}

std::uint64_t StreamHash64::Finish() const {
  Hash64 h = h_;
  if (pending_bytes_ != 0) h.Add(pending_);  // zero-padded, as AddBytes pads its last word
  h.Add(size_);
  return h.Finish();
}

}  // namespace raycell
