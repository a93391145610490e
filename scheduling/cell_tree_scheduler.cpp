#include "scheduling/cell_tree_scheduler.h"

#include "graph/peel.h"

namespace raycell {

void CellTreeScheduler::BeginFrame(const FrameInfo& frame) {
  follower_.Reset(frame.previous ? Peel(*frame.previous).schedule : std::vector<CellId>{},
                  frame.cells);
}

void TwoLevelScheduler::BeginFrame(const FrameInfo& frame) {
  follower_.Reset(
      frame.previous ? TwoLevelPeel(*frame.previous, BoardCellOf(frame)) : std::vector<CellId>{},
      frame.cells);
}

}  // namespace raycell
