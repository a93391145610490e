#include "scheduling/cell_tree_scheduler.h"

#include "graph/peel.h"

namespace raycell {

void CellTreeScheduler::BeginFrame(const FrameInfo& frame) {
  follower_.Reset(frame.previous ? Peel(*frame.previous).schedule : std::vector<CellId>{},
                  frame.cells);
}

void TwoLevelScheduler::BeginFrame(const FrameInfo& frame) {
  std::vector<CellId> plan;
  if (frame.previous != nullptr) {
    if (frame.board_cell_of != nullptr) {
      plan = TwoLevelPeel(*frame.previous, *frame.board_cell_of);
    } else {
      std::vector<CellId> own(frame.previous->cell_count());
      for (const CellId c : CellRange(frame.previous->cell_count())) own[c.value()] = c;
      plan = TwoLevelPeel(*frame.previous, own);
    }
  }
  follower_.Reset(std::move(plan), frame.cells);
}

}  // namespace raycell
