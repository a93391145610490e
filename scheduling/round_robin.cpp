#include "scheduling/round_robin.h"

namespace raycell {

std::optional<CellId> RoundRobinScheduler::Next(const QueueView& queues) {
  for (CellId i = 0; i < queues.cells; ++i) {
    const CellId c = static_cast<CellId>((std::uint64_t{start_} + i) % queues.cells);
    if (queues.has_work(c)) {
      start_ = static_cast<CellId>((std::uint64_t{c} + 1) % queues.cells);
      return c;
    }
  }
  return std::nullopt;
}

}  // namespace raycell
