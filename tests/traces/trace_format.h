// The trace format as the tests spell it out, independently of the writer and reader.
#pragma once

#include <cstdint>

#include "traces/ray_batch.h"

namespace raycell::testing {

// A ray's head byte (see "Ray heads" in traces/trace.capnp).
constexpr std::uint8_t Head(RayKind kind, unsigned parent_code, unsigned spawn_code, bool new_path,
                            bool new_pixel) {
  return static_cast<std::uint8_t>(static_cast<unsigned>(kind) | parent_code << 2 |
                                   spawn_code << 4 | (new_path ? 0x40 : 0) |
                                   (new_pixel ? 0x80 : 0));
}

}  // namespace raycell::testing
