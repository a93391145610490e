// The study's subdivision section (issue 23; docs/design.md §1 "Subdivisions"): one fine
// capture of the scene recorded with --regroupable, replayed regrouped into cells of several
// shapes at about 27 cells (uniform 3x3x3, k-d trees by footprint and by work, a byte budget,
// an octree, a dynamic subdivision) under Max Work and Cell Tree scheduling, with the on-chip
// cache sized in bytes to the median footprint of the uniform grid, so that the cells' shapes,
// not their count, make the difference. Replays as `raycell replay FINE --cells SPEC --set
// level.cache.capacity=MEDIANB` makes them, in this process.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace raycell {

struct SubdivisionOptions {
  std::string scene = "builtin", res = "128x128";
  int frames = 8;  // 0: not measured; an orbit of 3.75 degrees a frame
  std::string fine = "12x12x12";
  std::string out;    // the fine capture goes to OUT/fine.rct
  bool quiet = true;  // false: a line on stderr when the measurement starts
};

struct SubdivisionRow {
  std::string spec, scheduler;  // "kd:27:footprint", "maxwork"
  std::uint32_t cells = 0;      // non-empty cells
  // The non-empty cells' footprints (for dynamic:N, each cell's largest over the frames).
  std::uint64_t footprint_min = 0, footprint_median = 0, footprint_max = 0;
  std::uint64_t fetches = 0;
  std::uint64_t cache_bytes = 0, board_bytes = 0;  // into the cache and into the board
  std::uint64_t stall_ps = 0, time_ps = 0;
};

struct SubdivisionStudy {
  SubdivisionOptions options;
  bool measured = false;
  std::string not_measured;          // why, when asked for and not measured
  std::uint64_t cache_bytes = 0;     // the cache's capacity: the median footprint of 3x3x3
  std::vector<SubdivisionRow> rows;  // SubdivisionSpecs() x {maxwork, celltree}, in order
};

// The non-empty cells' footprints, sorted; and the median of such a list (not empty), the
// cache's capacity of the subdivision section and of `raycell suite`.
std::vector<std::uint64_t> NonEmptyFootprints(const std::vector<std::uint64_t>& footprints);
std::uint64_t MedianFootprint(const std::vector<std::uint64_t>& sorted);

// The SPECs studied, given the cache's capacity in bytes: 3x3x3, kd:27:footprint, kd:27:work,
// kd:budget:CACHE B, octree:CACHE B, dynamic:27.
std::vector<std::string> SubdivisionSpecs(std::uint64_t cache_bytes);

// Records the fine capture and replays it regrouped into every SPEC (nothing when
// options.frames is 0; not_measured says why when the scene cannot be loaded here).
SubdivisionStudy MeasureSubdivisions(const SubdivisionOptions& options);

}  // namespace raycell
