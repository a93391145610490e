// The study's depth section (issue 23, "Limited depth recursion"): what the renderer's maximum
// depth of reflection and refraction rays (`raycell record --max-depth`) costs and saves, for
// max depth 0 to kDeepestMaxDepth. It makes no capture of its own: it reads the run time
// against error section's max depth captures (study/accuracy.h: the same scene, resolution,
// frames and 3x3x3 cells, the default step) and replays each under Max Work and Cell Tree
// scheduling, the default configuration otherwise, per Cell Tree node (exact with one
// processor).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/time.h"
#include "study/accuracy.h"
#include "traces/ray_batch.h"

namespace raycell {

// One max depth, summed over the capture's frames.
struct DepthRow {
  std::uint32_t max_depth = 0;
  bool is_default = false;                                  // record's default max depth
  std::array<std::uint64_t, kRayKindCount> rays_by_kind{};  // indexed by RayKind
  std::uint64_t rays = 0;                                   // of every kind
  std::uint64_t nodes = 0;                                  // Cell Tree nodes (the root left out)
  std::uint64_t fetches_maxwork = 0, fetches_celltree = 0;  // into the one-cell cache
  SimTime time_maxwork, time_celltree;                      // simulated
  double rmse = 0;  // the run time against error row's image RMSE vs max depth 5
  std::uint64_t spawned() const { return rays - rays_by_kind[0]; }
};

struct DepthStudy {
  AccuracyOptions options;  // the run time against error section's, whose captures it reads
  bool measured = false;
  // Why not, when not measured: the run time against error section was skipped (its frames 0)
  // or could not be measured (its reason).
  std::string not_measured;
  std::vector<DepthRow> rows;  // when measured: max depth 0 to kDeepestMaxDepth
};

// The depth section from a run time against error study and the captures it left in
// accuracy.options.out. InputError if a capture cannot be read or replayed.
DepthStudy MeasureDepth(const AccuracyStudy& accuracy);

}  // namespace raycell
