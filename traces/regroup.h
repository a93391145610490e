// Regrouping a fine capture's rays into the cells of a coarser subdivision (issue 23;
// docs/design.md §1 "Subdivisions"): each visit's fine cell becomes the coarse cell holding
// it, consecutive visits in one coarse cell merge into one visit (samples added, t_enter of
// the first, t_exit of the last), and a spawned ray's spawn visit becomes the merged visit
// that holds it. A visit to a coarse cell that is empty (kNoCell) is dropped; its samples,
// and the rays spawned there, go to the merged visit before it, or the first one when there
// is none before (a capture's rule for a sample between its visits). A spawned ray whose
// first merged visit is not its spawn visit's cell starts with a zero-length visit there (a
// capture's rule for a start point outside the spawn cell). A primary ray left with no visit
// is dropped, as a capture of the subdivision would not record it; the rays are renumbered to
// stay consecutive. Kinds and pixels are kept. Rays come as a capture stores
// them: one ray tree at a time (a primary ray, then its descendants), so only the current
// tree's visits are remembered (4 bytes each).
#pragma once

#include <cstdint>
#include <vector>

#include "traces/cell_id.h"
#include "traces/ray_batch.h"

namespace raycell {

class RayRegrouper {
 public:
  // coarse_of_fine[f]: the coarse cell of fine cell f (Subdivision::coarse_of_fine), kNoCell
  // when that coarse cell is empty (footprint 0).
  explicit RayRegrouper(std::vector<CellId> coarse_of_fine);

  // The batch's rays regrouped; its first_id is the number of rays regrouped before it in
  // the frame. Batches of one frame must come in ray order; Reset() between frames.
  // InputError when a visit's cell is not a fine cell, a spawned ray's parent is not in the
  // current ray tree or was dropped, its spawn visit is past the parent's visits, a dropped
  // primary ray has samples, or merged samples exceed 32 bits.
  RayBatch Regroup(const RayBatch& fine);
  void Reset();

 private:
  std::vector<CellId> coarse_of_fine_;
  // The current ray tree: its first ray id, and per ray where its visits' merged indices
  // start in merged_.
  RayId tree_first_ = 0;
  RayId next_id_ = 0;  // the id of the next ray regrouped
  std::vector<std::uint64_t> tree_offset_;
  std::vector<RayId> tree_out_;  // per ray of the tree: its new id, kNoParent if dropped
  // Per fine visit of the tree: the merged visit a ray spawned there starts from, and its cell.
  std::vector<std::uint32_t> merged_;
  std::vector<CellId> merged_cell_;
  // The current ray's merged visits, and per fine visit its merged visit (scratch).
  struct Kept {
    CellId cell;
    std::uint64_t samples;
    float t_enter, t_exit;
  };
  std::vector<Kept> kept_;
  std::vector<std::uint32_t> fine_to_kept_;
};

}  // namespace raycell
