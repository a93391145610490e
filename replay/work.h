// A frame's work as the replay schedules it (docs/design.md §2 "granularity"): units, each done in
// one cell, that become ready when their predecessor is done.
//  - Per ray segment (exact): one unit per visit of every ray. A visit's successors are the
//    ray's next visit and the first visits of the rays spawned at it.
//  - Per Cell Tree node (aggregated): one unit per node, its successors its children.
// A successor in the same cell as its unit (a spawned ray's first visit) is worked in the
// same fetch, never queued (docs/design.md §1 "Max Work").
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "base/mapped_allocator.h"
#include "base/varint.h"  // the Compact stream's records
#include "graph/cell_tree.h"
#include "traces/ray_batch.h"
#include "traces/trace_header.h"

namespace raycell {

using UnitId = std::uint32_t;

struct WorkGraph {
  std::uint32_t cells = 0;                  // of the grid
  std::vector<CellId> cell;                 // per unit
  std::vector<std::uint64_t> samples;       // volume samples worked in the unit
  std::vector<std::uint64_t> queued_rays;   // rays it stands for in a queue (0: in place)
  std::vector<std::uint64_t> segments;      // ray visits it covers
  std::vector<std::uint64_t> rays_started;  // rays whose first visit it holds
  std::vector<UnitId> succ_begin;           // successors of u: succ[succ_begin[u] ..
  std::vector<UnitId> succ;                 //   succ_begin[u + 1])
  std::vector<UnitId> roots;                // ready when the frame starts
  // Each unit a Cell Tree node (NodeWork, PackedNodeWork): its successors are other nodes, in
  // other cells than its own. A watching replay then names each unit's node by the unit alone.
  bool per_node = false;

  // What the replay core reads of a unit, packed in 16 bytes and laid out breadth first from
  // the roots, so that a unit's successors are adjacent records: entry x's successors are
  // entries first_child[x] .. first_child[x + 1], in succ's order, and the roots are entries
  // 0 .. roots.size(). The core works on these entries; the unit ids they stand for do not
  // matter to any result. size() + 1 entries (the last ends the successors of the one
  // before); empty when some unit's samples or queued rays exceed 32 bits or some unit
  // cannot be reached from the roots, and the core then reads the columns.
  struct Packed {
    CellId cell;
    std::uint32_t samples;
    std::uint32_t queued_rays;
    std::uint32_t first_child;
  };
  std::vector<Packed, HugePageAllocator<Packed>> packed;

  // Per ray segment for large frames (RaySegmentWorkBuilder): the visits as a byte stream
  // instead of columns, about 3 bytes a visit and 8-12 bytes a ray, so that a frame of tens
  // of millions of visits fits (BENCHMARKS.md "Capture at scale"). When `compact.units` is
  // not zero it is the only form: the columns and `packed` are empty.
  //  - stream: each visit of each ray with visits, in ray order, as a record of two LEB128
  //    varints: cell * 2 + (1 on the ray's last visit), then samples. Visits are numbered
  //    0, 1, ... in that order, so a ray's visits have consecutive numbers, and a record's
  //    offset increases with its visit's number.
  //  - A unit is named by a CompactUnit: its record's offset and where the rays spawned at it
  //    (or at the ray's later visits) begin in `spawned` (8 bytes a queued unit, not 12 with
  //    the visit's number beside: issue 43).
  //  - roots: the primary rays' first units, in ray order. spawned: the other rays' first
  //    units, ordered by (`at`, the offset of the parent's visit they are spawned at; ray
  //    order), so that the rays spawned at one visit are one run, in ray order, as in
  //    RaySegmentWork.
  struct CompactUnit {
    std::uint32_t offset, spawned;
  };
  struct Spawned {
    std::uint32_t at;
    CompactUnit unit;
  };
  struct Compact {
    std::vector<std::uint8_t, HugePageAllocator<std::uint8_t>> stream;  // read at random
    std::vector<CompactUnit> roots;
    std::vector<Spawned, HugePageAllocator<Spawned>> spawned;
    std::size_t units = 0;  // visits
  } compact;

  // Sums over the units.
  struct Totals {
    std::uint64_t samples = 0, segments = 0, rays = 0;
  } totals;

  // What the time bound (replay/time_bound.h) reads of the graph, whatever the configuration:
  // computed once where the graph is built (ShapeOf), so that the replays of many
  // configurations on one frame do not walk it again; empty for a graph assembled by hand.
  struct Shape {
    std::uint64_t chain_samples = 0;  // the longest path from a root, in samples
    std::vector<std::uint8_t> used;   // per cell: 1 if some unit is in it
  };
  std::optional<Shape> shape;

  std::size_t size() const {
    return compact.units != 0 ? compact.units : !packed.empty() ? packed.size() - 1 : cell.size();
  }
  std::uint64_t total_samples() const { return totals.samples; }
  std::uint64_t total_segments() const { return totals.segments; }
  std::uint64_t total_rays() const { return totals.rays; }
};

// Per ray segment, built from a frame's batches as TraceReader::ForEachBatch delivers them
// (frame-local ray ids, in order, parents in earlier batches or the same), without holding
// the frame: the Compact form above. The same units, successors in the same order and the
// same totals as RaySegmentWork on the whole frame, so a replay gives the same results.
class RaySegmentWorkBuilder {
 public:
  explicit RaySegmentWorkBuilder(std::uint32_t cells) { w_.cells = cells; }
  // Room for the frame `summary` describes, so that the arrays are not copied as they grow
  // (pages reserved but never written are not resident).
  void Reserve(const FrameSummary& summary);
  // InputError on a parent or spawn outside the rays and visits seen so far.
  void AddBatch(const RayBatch& batch);
  WorkGraph Finish();

 private:
  WorkGraph w_;
  std::vector<std::uint32_t> visit_begin_;  // per ray so far: its first visit's number
  std::uint64_t visits_ = 0;
  std::size_t rays_ = 0;
};

// Frames of more visits than this are replayed per ray segment in the Compact form when they
// are read for that alone (FrameWalker): about 3 bytes a visit instead of ~100.
inline constexpr std::uint64_t kCompactAboveVisits = std::uint64_t{1} << 22;

// Per ray segment: `frame` holds a whole frame (first_id 0), as TraceReader::LoadFrame
// returns it. Rays without visits do no work and are not counted.
WorkGraph RaySegmentWork(const RayBatch& frame, std::uint32_t cells);
// Per Cell Tree node.
WorkGraph NodeWork(const CellTree& tree, std::uint32_t cells);
// The same units as NodeWork, in the packed records alone (no columns: what the replay reads),
// made straight from the tree: 16 bytes a node (and 4 per root) instead of about 60, and no
// column copy on the way, so that a frame replayed per node holds about its tree and the
// records (docs/design.md §2 "What a replay holds"). The same `packed`, `roots`, `totals` and
// `shape` as NodeWork, so a replay gives the same results; NodeWork itself when some node's
// samples or entering rays exceed 32 bits (the records cannot hold them).
WorkGraph PackedNodeWork(const CellTree& tree, std::uint32_t cells);

// Sampling: the ray trees (a primary ray and its descendants) whose order in the frame is a
// multiple of k, renumbered from 0. k = 1 returns the frame as it is.
RayBatch SampleRayTrees(const RayBatch& frame, std::uint32_t k);

}  // namespace raycell
