// Cell Tree scheduling, the paper's scheme (docs/design.md §1 "Cell Tree scheduling"): frame 0
// runs Max Work; frame i+1 follows the Peel schedule of frame i's Cell Tree, skipping
// entries whose cell has no queued work (no fetch), then Max Work once the schedule is used
// up. Peel runs once per frame, in BeginFrame.
#pragma once

#include "scheduling/scheduler.h"

namespace raycell {

class CellTreeScheduler : public FollowingScheduler {
 public:
  std::string Name() const override { return "celltree"; }
  // Computes Peel of frame.previous; a null previous (frame 0) means Max Work all frame.
  void BeginFrame(const FrameInfo& frame) override;
};

}  // namespace raycell
