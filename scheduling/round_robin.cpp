#include "scheduling/round_robin.h"

namespace raycell {

constexpr SchedulerEntry kRoundRobinEntry = [] {
  SchedulerEntry e;
  e.name = "roundrobin";
  e.meaning = "Round Robin: the next cell with work after the last one (a baseline)";
  e.label = "Round Robin";
  e.history = 0;  // reads no earlier frame
  e.make = [](std::uint64_t) -> std::unique_ptr<Scheduler> {
    return std::make_unique<RoundRobinScheduler>();
  };
  e.studied = false;
  return e;
}();

std::optional<CellId> RoundRobinScheduler::Peek(const QueueView& queues) const {
  for (std::uint32_t i = 0; i < queues.cells; ++i) {
    const CellId c(static_cast<std::uint32_t>((std::uint64_t{start_} + i) % queues.cells));
    if (queues.has_work(c)) return c;
  }
  return std::nullopt;
}

std::optional<CellId> RoundRobinScheduler::Next(const QueueView& queues) {
  const std::optional<CellId> c = Peek(queues);
  if (c) start_ = static_cast<std::uint32_t>((std::uint64_t{c->value()} + 1) % queues.cells);
  return c;
}

}  // namespace raycell
