#include "traces/frame_checksum.h"

#include <cstring>

namespace raycell {

FrameAccumulator::FrameAccumulator(std::int32_t frame, bool store_t) : store_t_(store_t) {
  summary_.frame = frame;
}

namespace {
std::uint64_t FloatBits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}
}  // namespace

void FrameAccumulator::AddRay(const RayView& r) {
  hash_.Add(static_cast<std::uint64_t>(r.kind));
  hash_.Add(r.parent);
  hash_.Add(r.spawn);
  hash_.Add(r.pixel_x);
  hash_.Add(r.pixel_y);
  hash_.Add(r.visit_count);
  for (std::size_t i = 0; i < r.visit_count; ++i) {
    hash_.Add(r.cells[i].value());
    hash_.Add(r.samples[i]);
    if (store_t_) hash_.Add(FloatBits(r.t_enter[i]) << 32 | FloatBits(r.t_exit[i]));
    summary_.samples += r.samples[i];
  }
  ++summary_.rays;
  ++summary_.rays_by_kind[static_cast<int>(r.kind)];
  summary_.visits += r.visit_count;
}

FrameSummary FrameAccumulator::Summary() const {
  FrameSummary s = summary_;
  s.checksum = hash_.Finish();
  return s;
}

}  // namespace raycell
