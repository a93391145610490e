// The recording renderer: front-to-back volume ray marching with OpenVDB (fog volumes lit by
// shadow rays as in vdb_render; level-set surfaces with reflection, refraction and shadow
// rays) that records every ray's visits to the non-empty cells. OpenVDB stays inside
// renderer.cpp.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "record/cell_grid.h"
#include "record/image.h"
#include "record/scene.h"
#include "traces/ray_batch.h"
#include "traces/trace_header.h"

namespace raycell {

struct FrameStats {
  std::uint64_t rays = 0, visits = 0, samples = 0;
  std::array<std::uint64_t, kRayKindCount> rays_by_kind{};
  std::uint64_t primary_missed = 0;  // primary rays that met no non-empty cell (not recorded)
};

// One fog sample of the marcher, for checks (RenderJob::sample_probe): the ray's optical
// depth over the step and its transmittance after it.
struct MarchSample {
  std::uint32_t px, py;  // the pixel
  std::uint32_t ray;     // the ray's index among the pixel's rays, in start order
  RayKind kind;
  std::uint32_t depth;  // 0 for a primary ray, +1 per spawn
  double t;             // world units along the ray
  std::array<double, 3> tau, transmittance;
};

struct RenderJob {
  const Scene* scene = nullptr;
  const CellGrid* cells = nullptr;
  // This frame's footprints, one per cell (0 = empty, never visited); not copied, so they
  // must outlive the call.
  const std::vector<std::uint64_t>* footprints = nullptr;
  // A regroupable capture (TraceHeader::regroupable): rays also visit the empty cells they
  // cross, with no samples, and a primary ray crossing only empty cells is recorded.
  bool all_cells = false;
  CameraKey camera;
  RenderSettings settings;
  int threads = 0;  // 0: all cores
  // Receives the frame's rays in id order, one batch at a time, from one thread at a time
  // (not necessarily the calling one: it runs while the next rows are traced).
  std::function<void(const RayBatch&)> sink;
  // Called with the fraction of the frame done, one call at a time, from a tracing thread.
  std::function<void(double)> progress;
  const std::atomic<bool>* cancel = nullptr;  // stop early (the frame is then incomplete)
  // For checks: called for every fog sample that attenuates a ray (primary, secondary or
  // shadow), in order along each ray, from the tracing threads (concurrently unless threads
  // is 1). Empty: never called, at no cost.
  std::function<void(const MarchSample&)> sample_probe;
};

// Renders one frame into `image` (linear RGB) and streams its rays to job.sink. The rays
// and the image are the same whatever the thread count. Returns false if cancelled (the
// sink has then had the rays of the rows finished so far, in order). An exception from the
// sink stops the frame and is rethrown here, once the tracing threads have stopped.
bool RenderFrame(const RenderJob& job, Image* image, FrameStats* stats);

}  // namespace raycell
