#include "scheduling/max_work.h"

namespace raycell {

constexpr SchedulerEntry kMaxWorkEntry = [] {
  SchedulerEntry e;
  e.name = "maxwork";
  e.meaning = "Max Work: the cell with the most queued rays";
  e.label = "Max Work";
  e.joins = false;  // stateless, and sees only the view
  e.history = 0;    // reads no earlier frame
  e.make = [](std::uint64_t) -> std::unique_ptr<Scheduler> {
    return std::make_unique<MaxWorkScheduler>();
  };
  return e;
}();

std::optional<CellId> MaxWorkScheduler::Next(const QueueView& queues) {
  return MostQueuedCell(queues);
}

}  // namespace raycell
