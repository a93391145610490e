// Helpers shared by the trace suites (and the fuzz seed generator): a test header and valid
// random rays.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <random>

#include "traces/ray_batch.h"
#include "traces/trace_header.h"

namespace raycell::testing {

// A header with every field set to something distinct (so a round trip that drops or swaps
// one is caught): two grids, a box, footprints 1000 * cell + 7, `frames` cameras.
inline TraceHeader TestHeader(std::array<std::uint32_t, 3> cells = {3, 3, 3}, bool store_t = false,
                              int frames = 4) {
  TraceHeader h;
  h.producer = "raycell test";
  h.scene = "builtin:smoke";
  h.grids = {{"density", "fog", "builtin", 0.5, 1234}, {"surface", "surface", "a.vdb", 0.25, 77}};
  h.box_min = {-1, -2, -3};
  h.box_max = {4, 5, 6.5};
  h.cells = cells;
  for (std::uint32_t c = 0; c < h.cell_count(); ++c) h.footprints.push_back(1000 * c + 7);
  h.footprint_mode = "sparse";
  for (int f = 0; f < frames; ++f) {
    h.cameras.push_back({10 + f, {1, 2, 3.0 + f}, {0, 0, 0}, {0, 1, 0}, 40});
  }
  h.settings.store_t = store_t;
  h.settings.single_precision = !store_t;  // both values round-trip
  h.settings.width = 320;
  h.settings.height = 200;
  return h;
}

// Valid random rays of one frame over `cell_count` >= 2 cells: parents earlier (mostly close,
// sometimes far) and with visits, spawns inside the parent's visits, a spawned ray's first
// visit in the cell of its spawn visit, consecutive visits in different cells, 0 to
// `max_visits` visits per ray, and some values big enough to need escapes (pixels beyond
// 100000, samples up to 2^32 - 1).
inline RayBatch RandomFrame(std::mt19937_64& rng, std::size_t rays, bool store_t,
                            std::uint32_t cell_count, int max_visits = 5) {
  RayBatch b(store_t);
  std::uniform_real_distribution<float> t(0.f, 100.f);
  for (std::size_t i = 0; i < rays; ++i) {
    RayId parent = kNoParent;
    std::uint32_t spawn = 0;
    if (i > 0 && rng() % 5 != 0) {
      parent = rng() % 10 == 0 ? rng() % i : i - 1 - rng() % std::min<std::size_t>(i, 40);
      const std::size_t n = b.ray(parent).visit_count;
      if (n == 0) parent = kNoParent;
      if (n > 0) spawn = static_cast<std::uint32_t>(rng() % n);
    }
    const RayKind kind = parent == kNoParent ? RayKind::kPrimary : RayKind(1 + rng() % 3);
    const std::uint32_t big = rng() % 50 == 0 ? 100000 : 0;
    b.BeginRay(kind, parent, spawn, big + rng() % 320, rng() % 200);
    std::uint32_t cell =
        parent == kNoParent ? rng() % cell_count : b.ray(parent).cells[spawn].value();
    const int n = static_cast<int>(rng() % (max_visits + 1));
    for (int v = 0; v < std::max(n, parent == kNoParent ? 0 : 1); ++v) {
      const std::uint32_t samples =
          rng() % 20 == 0 ? static_cast<std::uint32_t>(rng()) : rng() % 200;
      b.AddVisit(CellId(cell), samples, t(rng), t(rng));
      cell = (cell + 1 + rng() % (cell_count - 1)) % cell_count;
    }
  }
  return b;
}

}  // namespace raycell::testing
