// Cell Tree scheduling, the paper's scheme (docs/design.md §1 "Cell Tree scheduling"): frame 0
// runs Max Work; frame i+1 follows the Peel schedule of frame i's Cell Tree, skipping
// entries whose cell has no queued work (no fetch), then Max Work once the schedule is used
// up. Peel runs once per frame, in BeginFrame.
#pragma once

#include "scheduling/scheduler.h"

namespace raycell {

// Its registry entries (SchedulerEntry), defined in cell_tree_scheduler.cpp.
extern const SchedulerEntry kCellTreeEntry;
extern const SchedulerEntry kCellTree2LevelEntry;

class CellTreeScheduler : public FollowingScheduler {
 public:
  CellTreeScheduler() : FollowingScheduler(kCellTreeEntry) {}
  // Computes Peel of frame.previous; a null previous (frame 0) means Max Work all frame.
  void BeginFrame(const FrameInfo& frame) override;
};

// Two-level Cell Tree scheduling (issue 23; docs/design.md §5 "Two-level scheduling"): frame
// i+1 follows TwoLevelPeel of frame i's tree with the board's cells (FrameInfo::board_cell_of,
// a shared level's level.NAME.cells): the board's cells in the order Peel gives the tree
// contracted to them, the cells within each by Peel. Without board cells it plans as celltree
// (Peel), but for entries that process nothing. Frame 0: Max Work.
class TwoLevelScheduler : public FollowingScheduler {
 public:
  TwoLevelScheduler() : FollowingScheduler(kCellTree2LevelEntry) {}
  void BeginFrame(const FrameInfo& frame) override;
};

}  // namespace raycell
