// A frame's totals and checksum (see "Checksums" in traces/trace.capnp), accumulated ray by
// ray in id order. Writer and reader both use it, so the checksum does not depend on how the
// rays were split into batches.
#pragma once

#include <cstdint>

#include "base/hash.h"
#include "traces/ray_batch.h"
#include "traces/trace_header.h"

namespace raycell {

class FrameAccumulator {
 public:
  FrameAccumulator(std::int32_t frame, bool store_t);
  void AddRay(const RayView& ray);
  // Totals so far; offset and length are left 0.
  FrameSummary Summary() const;
  std::uint64_t rays() const { return summary_.rays; }
  std::uint64_t visits() const { return summary_.visits; }

 private:
  FrameSummary summary_;
  bool store_t_;
  Hash64 hash_;
};

}  // namespace raycell
