// The Peel oracle: follows the Peel schedule of the frame's own Cell Tree (docs/design.md §1
// "Peel"), which a real machine cannot know before the frame is traced: an offline
// reference for how well Cell Tree scheduling could do. Entries whose cell has no queued
// work are skipped; when the schedule is used up, Max Work. With a one-cell cache the
// schedule is feasible, so the Max Work fallback is then never needed.
#pragma once

#include "scheduling/scheduler.h"

namespace raycell {

// Its registry entry (SchedulerEntry), defined in peel_oracle.cpp.
extern const SchedulerEntry kPeelEntry;

class PeelOracleScheduler : public FollowingScheduler {
 public:
  PeelOracleScheduler() : FollowingScheduler(kPeelEntry) {}
  // Computes Peel of frame.current, which must not be null.
  void BeginFrame(const FrameInfo& frame) override;
};

}  // namespace raycell
