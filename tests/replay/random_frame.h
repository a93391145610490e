// Random frames for the replay tests: ray trees (a primary ray, then rays spawned at visits
// of earlier rays of its tree, each starting in its spawn visit's cell), walks without
// consecutive repeats, and sample counts that include zeros (units that take no time, so
// that events tie).
#pragma once

#include <random>

#include "traces/ray_batch.h"

namespace raycell::testing {

inline RayBatch RandomReplayFrame(std::mt19937& rng, std::uint32_t cells, int max_rays = 40,
                                  int max_extra_visits = 4) {
  RayBatch b(false);
  std::uniform_int_distribution<std::uint32_t> cell_number(0, cells - 1);
  const auto cell = [&](auto& r) { return CellId(cell_number(r)); };
  const int rays = 2 + int(rng() % std::uint32_t(max_rays));
  int tree_start = 0;
  for (int i = 0; i < rays; ++i) {
    const bool primary = i == 0 || rng() % 3 == 0;
    if (primary) tree_start = i;
    const RayId parent = primary ? kNoParent : tree_start + rng() % (i - tree_start);
    const std::uint32_t spawn =
        primary ? 0 : std::uint32_t(rng() % (b.visit_end(parent) - b.visit_begin(parent)));
    CellId prev = primary ? cell(rng) : b.cells()[b.visit_begin(parent) + spawn];
    b.BeginRay(primary ? RayKind::kPrimary : RayKind::kReflection, parent, spawn, 0, 0);
    b.AddVisit(prev, std::uint32_t(rng() % 20), 0, 0);
    for (int v = int(rng() % std::uint32_t(max_extra_visits + 1)); v > 0; --v) {
      CellId next;
      do next = cell(rng);
      while (next == prev);
      b.AddVisit(prev = next, std::uint32_t(rng() % 20), 0, 0);
    }
  }
  return b;
}

}  // namespace raycell::testing
