// Round Robin (a baseline, docs/design.md §2): the next cell with queued work after the last one
// chosen, cyclically; each frame starts the search at cell 0.
#pragma once

#include "scheduling/scheduler.h"

namespace raycell {

// Its registry entry (SchedulerEntry), defined in round_robin.cpp.
extern const SchedulerEntry kRoundRobinEntry;

class RoundRobinScheduler : public Scheduler {
 public:
  RoundRobinScheduler() : Scheduler(kRoundRobinEntry) {}
  void BeginFrame(const FrameInfo&) override { start_ = 0; }
  std::optional<CellId> Next(const QueueView& queues) override;
  std::optional<CellId> Peek(const QueueView& queues) const override;

 private:
  std::uint32_t start_ = 0;  // the cell where the next search begins: one past the last choice
};

}  // namespace raycell
