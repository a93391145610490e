// A capture's character (issue 42): what kind of workload its frames are, in the figures a
// suite of scenes is compared by. `raycell trace info` prints it and `raycell suite` tabulates
// it per scene (docs/design.md §6 "A capture's character").
#pragma once

#include <array>
#include <cstdint>
#include <ostream>
#include <vector>

#include "traces/ray_batch.h"
#include "traces/trace_reader.h"

namespace raycell {

struct CaptureCharacter {
  std::uint64_t frames = 0, pixels = 0;  // pixels of one frame
  std::uint64_t rays = 0, visits = 0, samples = 0;
  std::array<std::uint64_t, kRayKindCount> rays_by_kind{};
  // Over every frame, the cells with at least one Cell Tree node in that frame: how many
  // (frame, cell) pairs, the sum of their maxGen (the maxGen bound of the frames summed) and
  // the largest maxGen of any.
  std::uint64_t busy_cells = 0, max_gen_sum = 0;
  std::uint32_t max_gen_largest = 0;

  // Rays (of every kind) per pixel per frame.
  double rays_per_pixel() const;
  // Reflection, refraction and shadow rays over all rays.
  double secondary_share() const;
  double visits_per_ray() const;
  // The mean over busy (frame, cell) pairs of maxGen: how often, at least, each such cell must
  // be fetched in a frame with a one-cell cache.
  double mean_max_gen() const;
};

// Reads every frame of `reader` once, building its Cell Tree (frames on up to `threads`
// threads; the result does not depend on their number).
CaptureCharacter Characterize(const TraceReader& reader, unsigned threads);

// The lines `raycell trace info` prints under "character:".
void PrintCharacter(const CaptureCharacter& c, std::ostream& out);

}  // namespace raycell
