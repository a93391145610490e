// Random frames for the replay tests: ray trees (a primary ray, then rays spawned at visits
// of earlier rays of its tree, each starting in its spawn visit's cell), walks without
// consecutive repeats, and sample counts that include zeros (units that take no time, so
// that events tie); and a frame's per-segment work in the Compact form, built batch by batch.
#pragma once

#include <algorithm>
#include <array>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "replay/work.h"
#include "traces/ray_batch.h"
#include "traces/trace_writer.h"

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

// `rays` cut into batches of 1 to `max` rays with frame-local ids, as TraceReader delivers
// them, fed to a RaySegmentWorkBuilder.
inline WorkGraph CompactWork(std::mt19937& rng, const RayBatch& rays, std::uint32_t cells,
                             std::size_t max) {
  RaySegmentWorkBuilder builder(cells);
  if (rng() % 2 == 0) {
    FrameSummary summary;
    summary.rays = rays.size();
    summary.visits = rays.visit_count();
    summary.rays_by_kind[0] = rays.size() / 2;  // a wrong hint must not matter
    builder.Reserve(summary);
  }
  for (std::size_t r = 0; r < rays.size();) {
    const std::size_t n = std::min(rays.size() - r, 1 + rng() % max);
    RayBatch batch(false);
    batch.set_first_id(RayId(r));
    for (std::size_t i = r; i < r + n; ++i) {
      const RayView ray = rays.ray(i);
      batch.BeginRay(ray.kind, ray.parent, ray.spawn, 0, 0);
      for (std::size_t v = 0; v < ray.visit_count; ++v) {
        batch.AddVisit(ray.cells[v], ray.samples[v], 0, 0);
      }
    }
    builder.AddBatch(batch);
    r += n;
  }
  return builder.Finish();
}

// Writes a capture of `frames` random frames (RandomReplayFrame with `max_rays` and
// `max_extra_visits`, drawn from `seed`) over `cells`, numbered from `first`, each cell
// `footprint(c)` bytes, for the scene `scene`; returns the frames' rays.
inline std::vector<RayBatch> WriteRandomCapture(
    const std::string& path, std::array<std::uint32_t, 3> cells, int frames, int first,
    std::uint32_t seed, int max_rays, int max_extra_visits,
    const std::function<std::uint64_t(std::uint32_t)>& footprint,
    const std::string& scene = "builtin:test") {
  TraceHeader h;
  h.producer = "raycell test";
  h.scene = scene;
  h.cells = cells;
  for (std::uint32_t c = 0; c < h.cell_count(); ++c) h.footprints.push_back(footprint(c));
  for (int f = 0; f < frames; ++f) {
    h.cameras.push_back({first + f, {1, 2, 3.0 + f}, {0, 0, 0}, {0, 1, 0}, 40});
  }
  h.settings.store_t = false;
  TraceWriter w = TraceWriter::Create(path, h, 3);
  std::mt19937 rng(seed);
  std::vector<RayBatch> out;
  for (int f = 0; f < frames; ++f) {
    w.BeginFrame(first + f);
    out.push_back(RandomReplayFrame(rng, h.cell_count(), max_rays, max_extra_visits));
    w.Append(out.back());
    w.EndFrame();
  }
  w.Finish();
  return out;
}

// What a replay must process once: counted from the rays themselves, the rays with a visit,
// the visits (segments) and the samples.
struct RayCounts {
  std::uint64_t rays = 0, segments = 0, samples = 0;
};
inline RayCounts CountRays(const RayBatch& rays) {
  RayCounts c;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (rays.visit_end(i) > rays.visit_begin(i)) ++c.rays;
  }
  c.segments = rays.cells().size();
  for (const std::uint32_t s : rays.samples()) c.samples += s;
  return c;
}

}  // namespace raycell::testing
