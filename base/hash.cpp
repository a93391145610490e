#include "base/hash.h"

namespace raycell {

void Hash64::AddBytes(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; i += 8) {
    std::uint64_t w = 0;
    for (std::size_t b = 0; b < 8 && i + b < size; ++b) w |= std::uint64_t{p[i + b]} << (8 * b);
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

}  // namespace raycell
