#include "scheduling/scheduler.h"

#include <sstream>
#include <utility>

#include "base/check.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/max_work.h"
#include "scheduling/peel_oracle.h"
#include "scheduling/random_scheduler.h"
#include "scheduling/round_robin.h"

namespace raycell {

bool QueueView::empty() const { return !MostQueuedCell(*this).has_value(); }

QueueView QueueView::Of(const std::vector<std::uint64_t>& queued, std::optional<CellId> loaded) {
  RAYCELL_CHECK_LE(queued.size(), std::size_t{kNoCell});
  return {queued.data(), static_cast<CellId>(queued.size()), loaded};
}

std::optional<CellId> MostQueuedCell(const QueueView& queues) {
  std::optional<CellId> best;
  for (CellId c = 0; c < queues.cells; ++c) {
    if (queues.queued(c) > (best ? queues.queued(*best) : 0)) best = c;
  }
  return best;
}

std::string ScheduleFollower::Stats::ToString() const {
  std::ostringstream s;
  s << "followed " << followed << ", skipped " << skipped << ", max work " << max_work;
  return s.str();
}

void ScheduleFollower::Reset(std::vector<CellId> schedule, CellId cells) {
  for (CellId c : schedule) RAYCELL_CHECK_LT(c, cells);
  schedule_ = std::move(schedule);
  cursor_ = 0;
  stats_ = {};
}

std::optional<CellId> Scheduler::Peek(const QueueView& queues) const {
  return MostQueuedCell(queues);
}

std::optional<CellId> ScheduleFollower::Peek(const QueueView& queues) const {
  for (std::size_t i = cursor_; i < schedule_.size(); ++i) {
    if (queues.has_work(schedule_[i])) return schedule_[i];
  }
  return MostQueuedCell(queues);
}

std::optional<CellId> ScheduleFollower::Next(const QueueView& queues) {
  while (cursor_ < schedule_.size()) {
    const CellId c = schedule_[cursor_++];
    if (queues.has_work(c)) {
      ++stats_.followed;
      return c;
    }
    ++stats_.skipped;
  }
  const std::optional<CellId> c = MostQueuedCell(queues);
  stats_.max_work += c ? 1 : 0;
  return c;
}

const std::vector<std::string>& SchedulerNames() {
  static const std::vector<std::string> names = {"maxwork", "roundrobin", "random", "peel",
                                                 "celltree"};
  return names;
}

std::unique_ptr<Scheduler> MakeScheduler(const std::string& name, std::uint64_t seed) {
  if (name == "maxwork") return std::make_unique<MaxWorkScheduler>();
  if (name == "roundrobin") return std::make_unique<RoundRobinScheduler>();
  if (name == "random") return std::make_unique<RandomScheduler>(seed);
  if (name == "peel") return std::make_unique<PeelOracleScheduler>();
  if (name == "celltree") return std::make_unique<CellTreeScheduler>();
  std::string valid;
  for (const std::string& n : SchedulerNames()) valid += (valid.empty() ? "" : ", ") + n;
  throw InputError("unknown scheduler '" + name + "' (expected one of: " + valid + ")");
}

}  // namespace raycell
