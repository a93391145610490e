// Cells of any shape from one fine capture (issue 23; docs/design.md §1 "Subdivisions"): a
// subdivision groups the cells of a fine uniform grid into coarse cells, each a box of whole
// fine cells, so that a capture recorded once on a fine grid can be replayed and analysed on
// any coarser subdivision whose boundaries are fine-cell boundaries.
//
// A subdivision is computed from what the fine capture knows of each fine cell: the footprint
// of any union of fine cells (each leaf node counted once, so it is not the sum of the fine
// footprints) and the work (samples) done in each. The SPEC texts, each parsed by
// ParseSubdivisionSpec and printed back by ToString:
//   NXxNYxNZ            uniform: every axis of the fine grid split evenly (NX must divide the
//                       fine grid's x count, and so on);
//   grid:NXxNYxNZ       a grid of any counts up to the fine grid's: along each axis the
//                       boundaries are the fine boundaries nearest to an even split (F fine
//                       cells in N: boundary i at round(i F / N), halves up), so that cells of
//                       any shape can be compared at one cell count (1x3x9 on a 12-cell fine
//                       axis); the uniform grid's boxes when the counts divide;
//   grid:N:crossings    the grid:NXxNYxNZ of N cells (NX NY NZ = N, each at most the fine
//                       grid's count) that the rays' steps cross least: the counts minimising
//                       sum over axes of crossings[a] (NA - 1) / (FA - 1), the steps across a
//                       fine boundary of axis a times the share of those boundaries that are
//                       cells' boundaries (ties: the lowest NX, then NY), so that cells are long
//                       along the axes rays travel (one fetch where the ray stays in its cell);
//   kd:N:footprint      a k-d tree of N cells, splitting the cell of largest footprint at the
//                       fine boundary that makes the larger half smallest (footprints as equal
//                       as possible);
//   kd:N:work           the same balancing samples (work) instead of footprints;
//   kd:N:sqrt           the same balancing footprint / sqrt(samples + 1): each cell's footprint
//                       in proportion to the square root of its work, so that cells where rays
//                       work much stay large (fewer crossings to fetch for) and cells of data
//                       that little work needs are cut small (fewer bytes for it);
//   kd:budget:BYTES     a k-d tree split until every cell's footprint is at most BYTES, or is
//                       one fine cell ("cell size set to memory size");
//   octree:BYTES        an octree: a box over BYTES splits in halves along every axis longer
//                       than one fine cell, until each is at most BYTES or one fine cell;
//   dynamic:N           kd:N:work on the previous frame's samples, recomputed per frame (frame 0:
//                       kd:N:footprint).
//   dynamic:N:sqrt      the same with kd:N:sqrt on the previous frame's samples.
//   auto:N              the recommended subdivision into N cells (traces/auto_cells.h): per
//                       frame, from the frames before it only, the uniform grid of N cells
//                       nearest a cube (CubicGrid) or an adaptive candidate when the frames
//                       seen show it cheaper by a margin; frame 0 (and Subdivide): that grid.
// Splits are deterministic (ties: the lowest cell, axis x before y before z, the lowest
// boundary), so the same fine data gives the same subdivision on every machine.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "traces/cell_id.h"

namespace raycell {

struct SubdivisionSpec {
  enum class Kind {
    kUniform,
    kGrid,
    kGridCrossings,
    kKdFootprint,
    kKdWork,
    kKdSqrt,
    kKdBudget,
    kOctree,
    kDynamic,
    kAuto
  };
  Kind kind = Kind::kUniform;
  std::array<std::uint32_t, 3> grid{1, 1, 1};  // kUniform, kGrid
  std::uint32_t cells = 0;                     // kd:N:*, dynamic:N, grid:N:crossings, auto:N
  std::uint64_t budget = 0;                    // kd:budget:BYTES, octree:BYTES (bytes, > 0)
  bool sqrt = false;  // kDynamic: dynamic:N:sqrt, each frame balanced as kd:N:sqrt

  // Whether each frame has its own cells (dynamic:N, auto:N).
  bool per_frame() const { return kind == Kind::kDynamic || kind == Kind::kAuto; }
  // The canonical SPEC ("3x3x3", "kd:27:footprint", "octree:256KiB"); parses back equal.
  std::string ToString() const;
  friend bool operator==(const SubdivisionSpec& a, const SubdivisionSpec& b) {
    return a.kind == b.kind && a.grid == b.grid && a.cells == b.cells && a.budget == b.budget &&
           a.sqrt == b.sqrt;
  }
};

// Most coarse cells a SPEC may ask for: the trace format's limit (traces/format.h).
inline constexpr std::uint32_t kMaxSubdivisionCells = 1u << 24;

// Parses a SPEC (above). InputError "WHAT: ..." naming what is wrong: an unknown kind, a
// missing or malformed count, a zero count or budget, a count over kMaxSubdivisionCells.
SubdivisionSpec ParseSubdivisionSpec(std::string_view text, const std::string& what);

// What a subdivision is computed from: the fine grid, and per fine cell (numbered x + nx*(y +
// ny*z)) what the capture knows.
struct FineCells {
  std::array<std::uint32_t, 3> grid{1, 1, 1};
  // The bytes a processor loads for the union of these fine cells, each leaf once. Called
  // with the fine cells of one box, in increasing order.
  std::function<std::uint64_t(const std::vector<std::uint32_t>&)> union_footprint;
  // Work per fine cell (samples): kd:N:work's and kd:N:sqrt's weights, and dynamic's (the
  // previous frame's; empty for frame 0, which then splits by footprint).
  std::vector<std::uint64_t> samples;
  // grid:N:crossings's weights: over every frame, the steps of each ray from one non-empty fine
  // cell to its next, by axis: |dx|, |dy| and |dz| of their fine coordinates (the boundaries
  // crossed along each axis). Empty (has_crossings false) when not counted.
  std::array<std::uint64_t, 3> crossings{};
  bool has_crossings = false;

  std::uint32_t count() const { return grid[0] * grid[1] * grid[2]; }
};

// A box of fine cells: [lo, hi) on each axis.
struct FineBox {
  std::array<std::uint32_t, 3> lo{}, hi{};
  std::uint64_t volume() const;
  friend bool operator==(const FineBox& a, const FineBox& b) {
    return a.lo == b.lo && a.hi == b.hi;
  }
};

// The fine cells of a box of a fine grid `g` (numbered x + nx*(y + ny*z)), in increasing order.
std::vector<std::uint32_t> FineCellsOf(const FineBox& b, const std::array<std::uint32_t, 3>& g);
// Per fine cell of `g`, the box of `boxes` holding it (its index), kNoCell where none does.
// The boxes must not overlap (a RAYCELL_CHECK).
std::vector<CellId> CellOfFine(const std::vector<FineBox>& boxes,
                               const std::array<std::uint32_t, 3>& g);

struct Subdivision {
  // Per coarse cell, its box, ordered by the box's lowest corner (z, then y, then x), so that
  // a uniform subdivision numbers its cells as a grid recorded directly (x + nx*(y + ny*z)).
  std::vector<FineBox> boxes;
  // Per fine cell, the coarse cell holding it.
  std::vector<CellId> coarse_of_fine;

  std::uint32_t cells() const { return std::uint32_t(boxes.size()); }
};

// auto:N's baseline: the counts NX NY NZ = n, each at most the fine grid's, nearest a cube
// (the smallest largest count, then the largest smallest; ties to the lowest NX, then NY):
// 3x3x3 for 27, 2x2x3 for 12. InputError "WHAT: ..." when no such counts fit the fine grid.
std::array<std::uint32_t, 3> CubicGrid(std::uint32_t n, const std::array<std::uint32_t, 3>& fine,
                                       const std::string& what);

// The subdivision `spec` gives on `fine` (auto:N: its frame 0's, the grid:CubicGrid). InputError
// when it cannot be made: a uniform grid whose counts do not divide the fine grid's, a grid: with
// more cells along an axis than the fine grid, a grid:N:crossings that no grid within the fine one
// makes or without crossings, more kd cells than fine cells, kd:N:work or dynamic beyond frame 0
// without samples.
Subdivision Subdivide(const SubdivisionSpec& spec, const FineCells& fine);

}  // namespace raycell
