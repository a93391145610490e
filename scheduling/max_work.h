// Max Work (docs/design.md §1 "Max Work"): the cell with the most queued rays, lowest number on
// ties. Stateless.
#pragma once

#include "scheduling/scheduler.h"

namespace raycell {

// Its registry entry (SchedulerEntry), defined in max_work.cpp.
extern const SchedulerEntry kMaxWorkEntry;

class MaxWorkScheduler : public Scheduler {
 public:
  MaxWorkScheduler() : Scheduler(kMaxWorkEntry) {}
  void BeginFrame(const FrameInfo&) override {}
  bool ReadsEarlierTrees() const override { return false; }
  std::optional<CellId> Next(const QueueView& queues) override;
};

}  // namespace raycell
