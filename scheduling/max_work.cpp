#include "scheduling/max_work.h"

namespace raycell {

std::optional<CellId> MaxWorkScheduler::Next(const QueueView& queues) {
  return MostQueuedCell(queues);
}

}  // namespace raycell
