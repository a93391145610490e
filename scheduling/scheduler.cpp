#include "scheduling/scheduler.h"

#include <sstream>
#include <utility>

#include "base/check.h"
#include "base/parse.h"
#include "scheduling/adaptive_scheduler.h"
#include "scheduling/balanced_scheduler.h"
#include "scheduling/best_scheduler.h"
#include "scheduling/cell_tree_scheduler.h"
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

std::optional<CellId> MostQueuedCell(const QueueView& queues) {
  std::optional<CellId> best;
  for (CellId c : CellRange(queues.cells)) {
    if (queues.queued(c) > (best ? queues.queued(*best) : 0)) best = c;
  }
  return best;
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
  used_.assign(schedule_.size(), false);
  stats_ = {};
  last_how_ = 0;
  last_skipped_ = 0;
}

std::optional<CellId> Scheduler::Peek(const QueueView& queues) const {
  return MostQueuedCell(queues);
}

std::size_t ScheduleFollower::Find(const QueueView& queues) const {
  for (std::size_t i = cursor_; i < schedule_.size(); ++i) {
    if (!used_[i] && queues.has_work(schedule_[i])) return i;
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
  for (std::size_t i = cursor_; i < found; ++i) {
    if (used_[i]) continue;
    if (queues.busy(schedule_[i])) {
      ++stats_.deferred;
      continue;
    }
    used_[i] = true;
    ++stats_.skipped;
    ++last_skipped_;
  }
  if (found < schedule_.size()) used_[found] = true;
  while (cursor_ < schedule_.size() && used_[cursor_]) ++cursor_;
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

template <bool kPlan, bool kPartition, bool kSteal, bool kAffinity, bool kPostpone, bool kShare>
std::unique_ptr<Scheduler> MakeBalanced(std::uint64_t seed);

const std::vector<SchedulerEntry>& SchedulerRegistry() {
  static const std::vector<SchedulerEntry> registry = {
      {"maxwork", "Max Work: the cell with the most queued rays", "Max Work",
       [](std::uint64_t) -> std::unique_ptr<Scheduler> {
         return std::make_unique<MaxWorkScheduler>();
       }},
      {"roundrobin", "Round Robin: the next cell with work after the last one (a baseline)",
       "Round Robin",
       [](std::uint64_t) -> std::unique_ptr<Scheduler> {
         return std::make_unique<RoundRobinScheduler>();
       },
       1, false, true, false, false},
      {"random", "a seeded random cell with work (a baseline)", "Random",
       [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
         return std::make_unique<RandomScheduler>(seed);
       },
       1, true, false, false, false},
      {"peel", "the Peel oracle: each frame follows its own tree's Peel schedule",
       "Peel oracle (the frame's own Peel schedule)",
       [](std::uint64_t) -> std::unique_ptr<Scheduler> {
         return std::make_unique<PeelOracleScheduler>();
       },
       1, false, true, true},
      {"celltree", "the paper's Cell Tree scheduling: frame i+1 follows frame i's Peel schedule",
       "Cell Tree scheduling (Peel of frame i's tree)",
       [](std::uint64_t) -> std::unique_ptr<Scheduler> {
         return std::make_unique<CellTreeScheduler>();
       }},
      {"best", "the best-schedule oracle: each frame follows the best schedule found for its tree",
       "best-schedule oracle (the frame's own best schedule)",
       [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
         return std::make_unique<BestOracleScheduler>(seed);
       },
       1, true, true, true},
      {"celltree-best", "frame i+1 follows the best schedule found for frame i's tree",
       "Cell Tree, best schedule of frame i's tree",
       [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
         return std::make_unique<CellTreeBestScheduler>(seed, false);
       },
       1, true},
      {"celltree-union",
       "frame i+1 follows the best schedule found for the union of frames i and i-1's trees",
       "Cell Tree, best schedule of frames i-1 and i together",
       [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
         return std::make_unique<CellTreeBestScheduler>(seed, true);
       },
       2, true},
      // Several processors (balanced_scheduler.h): (a) cell affinity, (b) a partitioned plan,
      // (c) work stealing, (d) combinations. With one processor `partition`,
      // `partition-steal` and `balanced` choose exactly as celltree-best.
      {"affinity",
       "cell affinity: the cell in the processor's cache if it has work, else Max Work weighted "
       "to the cells its last cell sends rays to (frame i's tree)",
       "cell affinity", MakeBalanced<false, false, false, true, false, false>, 1, false, true,
       false, false},
      {"partition",
       "frame i's best schedule split over the processors by list scheduling (each cell on one "
       "processor), each following its part; Max Work when its cells have no work",
       "partitioned plan", MakeBalanced<true, true, false, false, false, false>, 1, true, true,
       false, false},
      {"steal",
       "cells split over the processors by list scheduling, Max Work on one's own; with none "
       "ready, the largest queue of the processor with the most queued rays (work stealing)",
       "work stealing", MakeBalanced<false, true, true, false, false, false>, 1, false, true, false,
       false},
      {"partition-steal",
       "the partitioned plan, stealing when a processor's own cells have no work",
       "partitioned plan with stealing", MakeBalanced<true, true, true, false, false, false>, 1,
       true, true, false, false},
      {"share",
       "Max Work; with no free cell ready, the busy cell with the most queued rays (a "
       "processor joins a cell another works)",
       "Max Work with shared cells", MakeBalanced<false, false, false, false, false, true>, 1,
       false, true, false, false},
      {"balanced",
       "the cached cell if it has work, else celltree-best's plan shared by the processors (busy "
       "entries deferred, then Max Work); no free cell ready: joins a busy one (affinity-"
       "weighted; not for under 3 fetches' worth of queued work); on 8+ processors, while all "
       "others work, a batch under 3 fetches' worth waits",
       "balanced (plan, affinity, shared cells, postponing)",
       MakeBalanced<true, false, false, true, true, true>, 1, true, true, false, false},
      // Two memory levels (issue 23): a board of coarser cells (level.NAME.cells).
      {"celltree-2level",
       "frame i+1 follows a two-level plan of frame i's tree: Peel of the tree contracted to "
       "the board's cells (level.NAME.cells) orders them, Peel orders the cells within each",
       "Cell Tree, two levels (board cells, then cache cells)",
       [](std::uint64_t) -> std::unique_ptr<Scheduler> {
         return std::make_unique<TwoLevelScheduler>();
       },
       1, false, true, false, false},
      {"celltree-2level-best",
       "celltree-2level with the best-schedule search at both levels: the plan for the tree "
       "contracted to the board's cells, then the plan for each board cell's part",
       "Cell Tree, two levels, best schedules",
       [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
         return std::make_unique<TwoLevelBestScheduler>(seed);
       },
       1, true, true, false, false},
      // Adaptive scheduling (adaptive_scheduler.h): they watch the frame unfold.
      {"balanced-critical",
       "balanced, with the free cell whose queued rays start the longest chain in frame i's "
       "tree first (highest level first, each queued node matched by its cell path) when it is "
       "longer than the plan's",
       "Balanced, critical path first",
       [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
         BalanceOptions o{true, false, false, true, true, true};
         o.critical = true;
         return std::make_unique<BalancedScheduler>("balanced-critical", o, seed);
       },
       1, true, true, false, false},
      {"balanced-adaptive",
       "balanced with celltree-adaptive's rule in place of celltree-best's plan: the cached "
       "cell first, then the adaptive choice, joining busy cells and postponing small batches "
       "as balanced does",
       "Balanced, adaptive",
       [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
         return std::make_unique<BalancedScheduler>(
             "balanced-adaptive", BalanceOptions{false, false, false, true, true, true, true},
             seed);
       },
       2, true, true, false, false},
      {"celltree-adaptive",
       "celltree-union followed node by node as the frame unfolds: work waits for the entry "
       "its predicted node is due at, work the plan is done with is fetched at once, and the "
       "rest is planned again by Peel when the plan runs out",
       "Cell Tree, adaptive",
       [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
         return std::make_unique<AdaptiveScheduler>(seed);
       },
       2, true},
  };
  return registry;
}

std::vector<CellId> BoardCellOf(const FrameInfo& frame) {
  if (frame.board_cell_of != nullptr) return *frame.board_cell_of;
  std::vector<CellId> own;
  for (const CellId c : CellRange(frame.previous->cell_count())) own.push_back(c);
  return own;
}

// The entry's name, found by its factory (each registry entry has its own).
template <bool kPlan, bool kPartition, bool kSteal, bool kAffinity, bool kPostpone, bool kShare>
std::unique_ptr<Scheduler> MakeBalanced(std::uint64_t seed) {
  const auto make = &MakeBalanced<kPlan, kPartition, kSteal, kAffinity, kPostpone, kShare>;
  for (const SchedulerEntry& e : SchedulerRegistry()) {
    if (e.make == make) {
      return std::make_unique<BalancedScheduler>(
          e.name, BalanceOptions{kPlan, kPartition, kSteal, kAffinity, kPostpone, kShare}, seed);
    }
  }
  RAYCELL_CHECK(false);  // only the registry names these factories
  return nullptr;
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
