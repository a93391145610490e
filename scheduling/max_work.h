// Max Work (docs/design.md §1 "Max Work"): the cell with the most queued rays, lowest number on
// ties. Stateless.
#pragma once

#include "scheduling/scheduler.h"

namespace raycell {

class MaxWorkScheduler : public Scheduler {
 public:
  std::string Name() const override { return "maxwork"; }
  void BeginFrame(const FrameInfo&) override {}
  std::optional<CellId> Next(const QueueView& queues) override;
};

}  // namespace raycell
