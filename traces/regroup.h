// Regrouping a fine capture's rays into the cells of a coarser subdivision (issue 23;
// docs/design.md §1 "Subdivisions"): each visit's fine cell becomes the coarse cell holding
// it, consecutive visits in one coarse cell merge into one visit (samples added, t_enter of
// the first, t_exit of the last), and a spawned ray's spawn visit becomes the merged visit
// that holds it. Ray ids, parents, kinds and pixels are kept. Rays come as a capture stores
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
  // coarse_of_fine[f]: the coarse cell of fine cell f (Subdivision::coarse_of_fine).
  explicit RayRegrouper(std::vector<CellId> coarse_of_fine);

  // The batch's rays regrouped, with the batch's first_id. Batches of one frame must come in
  // ray order; Reset() between frames. InputError when a visit's cell is not a fine cell, a
  // spawned ray's parent is not in the current ray tree or its spawn visit is past the
  // parent's visits, or merged samples exceed 32 bits.
  RayBatch Regroup(const RayBatch& fine);
  void Reset();

 private:
  std::vector<CellId> coarse_of_fine_;
  // The current ray tree: its first ray id, and per ray where its visits' merged indices
  // start in merged_.
  RayId tree_first_ = 0;
  std::vector<std::uint64_t> tree_offset_;
  std::vector<std::uint32_t> merged_;  // per fine visit of the tree: its merged visit
};

}  // namespace raycell
