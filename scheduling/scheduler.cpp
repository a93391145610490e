#include "scheduling/scheduler.h"

#include <sstream>
#include <utility>

#include "base/check.h"
#include "base/parse.h"
#include "scheduling/adaptive_scheduler.h"
#include "scheduling/auto_scheduler.h"
#include "scheduling/balanced_scheduler.h"
#include "scheduling/best_scheduler.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/dag_scheduler.h"
#include "scheduling/max_work.h"
#include "scheduling/peel_oracle.h"
#include "scheduling/random_scheduler.h"
#include "scheduling/round_robin.h"

namespace raycell {

bool QueueView::empty() const { return !MostQueuedCell(*this).has_value(); }

QueueView QueueView::Of(const std::vector<std::uint64_t>& queued, std::optional<CellId> loaded) {
  RAYCELL_CHECK_LE(queued.size(), std::size_t{kNoCell.value()});
  return {queued.data(), static_cast<std::uint32_t>(queued.size()), loaded};
}

CellId ScanMostQueued(const std::uint64_t* queued, std::uint32_t cells) {
  std::uint32_t best = kNoCell.value();
  std::uint64_t most = 0;
  for (std::uint32_t c = 0; c < cells; ++c) {
    if (queued[c] > most) best = c, most = queued[c];
  }
  return CellId(best);
}

std::optional<CellId> MostQueuedOf(const std::vector<std::uint32_t>& cells,
                                   const std::uint64_t* queued) {
  std::optional<CellId> best;
  for (const std::uint32_t c : cells) {
    const std::uint64_t q = queued[c];
    if (q == 0) continue;
    if (!best || q > queued[best->value()] || (q == queued[best->value()] && c < best->value())) {
      best = CellId(c);
    }
  }
  return best;
}

std::optional<CellId> MostQueuedCell(const QueueView& queues) {
  const CellId c = queues.most_of != nullptr && queues.most_of == queues.queued_rays &&
                           queues.most_cells == queues.cells
                       ? queues.most
                       : ScanMostQueued(queues.queued_rays, queues.cells);
  return c == kNoCell ? std::nullopt : std::optional<CellId>(c);
}

CellId MostQueuedAll(const QueueView& queues) {
  if (queues.all_queued == nullptr) return kNoCell;
  if (queues.all_most_of != nullptr && queues.all_most_of == queues.all_queued) {
    return queues.all_most;
  }
  return ScanMostQueued(queues.all_queued, queues.cells);
}

std::string ScheduleFollower::Stats::ToString() const {
  std::ostringstream s;
  s << "followed " << followed << ", skipped " << skipped << ", deferred " << deferred
    << ", max work " << max_work;
  return s.str();
}

void ScheduleFollower::Reset(std::vector<CellId> schedule, std::uint32_t cells) {
  for (CellId c : schedule) RAYCELL_CHECK_LT(c.value(), cells);
  schedule_ = std::move(schedule);
  cursor_ = 0;
  used_.Reset(schedule_.size());
  stats_ = {};
  last_how_ = 0;
  last_skipped_ = 0;
}

std::optional<CellId> Scheduler::Peek(const QueueView& queues) const {
  return MostQueuedCell(queues);
}

std::size_t ScheduleFollower::Find(const QueueView& queues) const {
  // Entries used up are passed without a look; those left are free cells without work (Next
  // uses them up) or busy cells (deferred).
  for (std::size_t i = used_.From(cursor_); i < schedule_.size(); i = used_.From(i + 1)) {
    if (queues.has_work(schedule_[i])) return i;
  }
  return schedule_.size();
}

std::optional<CellId> ScheduleFollower::Peek(const QueueView& queues) const {
  const std::size_t i = Find(queues);
  return i < schedule_.size() ? std::optional<CellId>(schedule_[i]) : MostQueuedCell(queues);
}

std::optional<CellId> ScheduleFollower::Next(const QueueView& queues) {
  last_skipped_ = 0;
  // No work anywhere in view (with several processors: the cells with work are all being
  // worked): nothing to choose, and the schedule keeps its place. Walking on would skip
  // every entry left and hand the rest of the frame to Max Work.
  if (queues.empty()) {
    last_how_ = 0;
    return std::nullopt;
  }
  const std::size_t found = Find(queues);
  // Entries before the one taken: used up when their cell has no work and is free, deferred
  // (kept) when another processor is working it.
  for (std::size_t i = used_.From(cursor_); i < found; i = used_.From(i + 1)) {
    if (queues.busy(schedule_[i])) {
      ++stats_.deferred;
      continue;
    }
    used_.Use(i);
    ++stats_.skipped;
    ++last_skipped_;
  }
  if (found < schedule_.size()) used_.Use(found);
  cursor_ = used_.From(cursor_);
  if (found < schedule_.size()) {
    ++stats_.followed;
    last_how_ = 1;
    return schedule_[found];
  }
  const std::optional<CellId> c = MostQueuedCell(queues);
  stats_.max_work += c ? 1 : 0;
  last_how_ = c ? 2 : 0;
  return c;
}

std::string ScheduleFollower::Reason() const {
  if (last_how_ == 0) return {};
  std::string r = last_how_ == 1 ? "followed" : "max work";
  if (last_skipped_ > 0) r += " (skipped " + std::to_string(last_skipped_) + ")";
  return r;
}

const std::vector<std::reference_wrapper<const SchedulerEntry>>& SchedulerRegistry() {
  // Each entry is defined in its scheduler's file; the order here is the order of --help, sweeps
  // and the study's tables.
  static const std::vector<std::reference_wrapper<const SchedulerEntry>> registry = {
      kMaxWorkEntry,
      kRoundRobinEntry,
      kRandomEntry,
      kPeelEntry,
      kCellTreeEntry,
      kBestEntry,
      kCellTreeBestEntry,
      kCellTreeUnionEntry,
      // Several processors (balanced_scheduler.h).
      kAffinityEntry,
      kPartitionEntry,
      kStealEntry,
      kPartitionStealEntry,
      kShareEntry,
      kBalancedEntry,
      // Two memory levels (cell_tree_scheduler.h, best_scheduler.h).
      kCellTree2LevelEntry,
      kCellTree2LevelBestEntry,
      // Adaptive scheduling: they watch the frame unfold.
      kBalancedCriticalEntry,
      kBalancedAdaptiveEntry,
      kCellTreeAdaptiveEntry,
      kCellTreeDagEntry,
      kCellTreeDagOracleEntry,
      // The recommended one (auto_scheduler.h).
      kAutoEntry,
  };
  return registry;
}

std::vector<CellId> BoardCellOf(const FrameInfo& frame) {
  if (frame.board_cell_of != nullptr) return *frame.board_cell_of;
  std::vector<CellId> own;
  for (const CellId c : CellRange(frame.previous->cell_count())) own.push_back(c);
  return own;
}

const std::vector<std::string>& SchedulerNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const SchedulerEntry& e : SchedulerRegistry()) n.push_back(e.name);
    return n;
  }();
  return names;
}

std::string SchedulerNameList(const char* separator) {
  std::string out;
  for (const std::string& n : SchedulerNames()) out += (out.empty() ? "" : separator) + n;
  return out;
}

std::string SeededSchedulerList(const char* separator) {
  std::string out;
  for (const SchedulerEntry& e : SchedulerRegistry()) {
    if (e.seeded) out += (out.empty() ? "" : separator) + std::string(e.name);
  }
  return out;
}

const SchedulerEntry& SchedulerByName(std::string_view name, const std::string& what) {
  for (const SchedulerEntry& e : SchedulerRegistry()) {
    if (name == e.name) return e;
  }
  throw InputError(what + ": unknown scheduler '" + std::string(name) + "' (expected " +
                   JoinOr(SchedulerNames()) + ")");
}

std::unique_ptr<Scheduler> MakeScheduler(const SchedulerEntry& entry, std::uint64_t seed) {
  return entry.make(seed);
}

std::unique_ptr<Scheduler> MakeScheduler(std::string_view name, std::uint64_t seed) {
  return MakeScheduler(SchedulerByName(name, "scheduler"), seed);
}

}  // namespace raycell
