#include "scheduling/best_scheduler.h"

#include <algorithm>
#include <deque>
#include <map>
#include <mutex>

#include "base/check.h"
#include "base/hash.h"
#include "graph/peel.h"

namespace raycell {

constexpr SchedulerEntry kBestEntry = [] {
  SchedulerEntry e;
  e.name = "best";
  e.meaning = "the best-schedule oracle: each frame follows the best schedule found for its tree";
  e.label = "best-schedule oracle (the frame's own best schedule)";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<BestOracleScheduler>(seed);
  };
  e.seeded = true;
  e.oracle = true;
  return e;
}();

constexpr SchedulerEntry kCellTreeBestEntry = [] {
  SchedulerEntry e;
  e.name = "celltree-best";
  e.meaning = "frame i+1 follows the best schedule found for frame i's tree";
  e.label = "Cell Tree, best schedule of frame i's tree";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<CellTreeBestScheduler>(seed, false);
  };
  e.seeded = true;
  return e;
}();

constexpr SchedulerEntry kCellTreeUnionEntry = [] {
  SchedulerEntry e;
  e.name = "celltree-union";
  e.meaning = "frame i+1 follows the best schedule found for the union of frames i and i-1's trees";
  e.label = "Cell Tree, best schedule of frames i-1 and i together";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<CellTreeBestScheduler>(seed, true);
  };
  e.history = 2;
  e.seeded = true;
  return e;
}();

constexpr SchedulerEntry kCellTree2LevelBestEntry = [] {
  SchedulerEntry e;
  e.name = "celltree-2level-best";
  e.meaning =
      "celltree-2level with the best-schedule search at both levels: the plan for the tree "
      "contracted to the board's cells, then the plan for each board cell's part";
  e.label = "Cell Tree, two levels, best schedules";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<TwoLevelBestScheduler>(seed);
  };
  e.seeded = true;
  e.studied = false;
  return e;
}();

BestScheduleOptions PlanEffort(std::uint64_t seed) {
  BestScheduleOptions o;
  o.seed = seed;
  o.beam_width = 64;
  o.chains = 1;
  // The one chain has the large windows (LocalSearchOptions::large_every) that the portfolio
  // gives only to odd chains: they shorten the plans more than they cost. 2000 windows within
  // 2*10^8 node visits (the work limit binds first): about 0.4 s of planning per 27-cell frame,
  // so that a plan is ready while the frame before it is replayed (BENCHMARKS.md "Online:
  // fetches against Max Work" has the plans' fetches and times).
  o.vary_windows = false;
  o.threads = 1;
  o.local.max_windows = 2000;
  o.local.max_work = 200'000'000;
  o.exact_states = 20000;
  o.exact_max_nodes = 1000;
  return o;
}

BestScheduleOptions PlanEffort(std::uint64_t seed, const CellTree& tree) {
  BestScheduleOptions o = PlanEffort(seed);
  const std::uint64_t nodes = std::max<std::uint64_t>(tree.node_count(), 1);
  // The beam's first layer alone would narrow it below its width: no beam.
  if (o.beam_width * nodes > o.beam_max_node_visits / std::max<std::uint64_t>(Bound(tree), 1)) {
    o.beam_width = 0;
  }
  // The local search's re-timings, a pass over every node each: a share of its work limit.
  o.local.max_retimes = std::max<std::uint64_t>(o.local.max_work / kPlanRetimeShare / nodes, 1);
  // One re-timing is the local search's first (of its start): no idle entry can be deleted nor
  // window tried after it, so it returns its start unchanged. No chain, and no forest built for
  // it (issue 43: a tree of millions of nodes planned in Peel's memory, not the search's).
  if (o.local.max_retimes <= 1) o.chains = 0;
  return o;
}

namespace {

// The tree's contents (cells and parents of every node) and the seed. Four hashes of every
// fourth node, then of them: one chain of multiplications over the union of millions of nodes
// took 2% of a replay's CPU (the key lives only in this process's memo).
std::uint64_t MemoKey(const CellTree& tree, std::uint64_t seed) {
  Hash64 lanes[4];
  const std::uint32_t n = std::uint32_t(tree.size());
  const auto word = [&](std::uint32_t i) {
    const NodeId id(i);
    return std::uint64_t{tree.cell(id).value()} << 32 | tree.parent(id).index();
  };
  std::uint32_t i = 1;
  for (; i + 4 <= n; i += 4) {
    for (std::uint32_t k = 0; k < 4; ++k) lanes[k].Add(word(i + k));
  }
  for (; i < n; ++i) lanes[0].Add(word(i));
  Hash64 h;
  h.Add(seed);
  h.Add(tree.size());
  for (const Hash64& lane : lanes) h.Add(lane.Finish());
  return h.Finish();
}

// The plan searched again, without the memo (BestSchedule checks that it is feasible).
std::vector<CellId> SearchPlan(const CellTree& tree, std::uint64_t seed) {
  return BestSchedule(tree, PlanEffort(seed, tree)).schedule;
}

// PlanFor, or the plan searched again when `cache`'s memo is off.
std::vector<CellId> PlanOf(const PlanCache* cache, const CellTree& tree, std::uint64_t seed) {
  return cache == nullptr || cache->memo() ? PlanFor(tree, seed) : SearchPlan(tree, seed);
}

// A bounded memo of plans: the oldest is dropped past kCapacity entries.
class PlanMemo {
 public:
  std::optional<std::vector<CellId>> Find(std::uint64_t key) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = plans_.find(key);
    if (it == plans_.end()) return std::nullopt;
    return it->second;
  }
  void Add(std::uint64_t key, const std::vector<CellId>& plan) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!plans_.emplace(key, plan).second) return;
    order_.push_back(key);
    if (order_.size() > kCapacity) {
      plans_.erase(order_.front());
      order_.pop_front();
    }
  }

 private:
  static constexpr std::size_t kCapacity = 256;
  std::mutex mutex_;
  std::map<std::uint64_t, std::vector<CellId>> plans_;
  std::deque<std::uint64_t> order_;
};

PlanMemo& Memo() {
  static PlanMemo memo;
  return memo;
}

}  // namespace

std::vector<CellId> PlanFor(const CellTree& tree, std::uint64_t seed) {
  const std::uint64_t key = MemoKey(tree, seed);
  if (auto plan = Memo().Find(key)) return *plan;
  std::vector<CellId> plan = SearchPlan(tree, seed);
  Memo().Add(key, plan);
  return plan;
}

std::shared_ptr<const std::vector<CellId>> SharedPlan(PlanCache* cache, const CellTree& tree,
                                                      std::uint64_t seed) {
  return Shared<std::vector<CellId>>(cache, PlanKey(kBestPlan, {TreeKey(tree), seed}),
                                     [&] { return PlanOf(cache, tree, seed); });
}

void BestOracleScheduler::BeginFrame(const FrameInfo& frame) {
  RAYCELL_CHECK(frame.current != nullptr);
  follower_.Reset(*SharedPlan(frame.plans, *frame.current, seed_), frame.cells);
}

bool CellTreeBestScheduler::PlansUnion(const FrameInfo& frame) const {
  return union_frames_ && frame.previous != nullptr && frame.before_previous != nullptr;
}

bool CellTreeBestScheduler::Prepare(const FrameInfo& frame) {
  if (!PlansUnion(frame)) return false;
  SharedUnion(frame.plans, *frame.before_previous, *frame.previous);
  return true;
}

void CellTreeBestScheduler::BeginFrame(const FrameInfo& frame) {
  std::vector<CellId> plan;
  if (frame.previous != nullptr) {
    if (PlansUnion(frame)) {
      const std::shared_ptr<const CellTree> both =
          SharedUnion(frame.plans, *frame.before_previous, *frame.previous);
      plan = *SharedPlan(frame.plans, *both, seed_);
    } else {
      plan = *SharedPlan(frame.plans, *frame.previous, seed_);
    }
  }
  follower_.Reset(std::move(plan), frame.cells);
}

// The effort for the forests inside one board cell, a hundred or more a frame: the beam search
// alone (width 64). On the study scene's 6x6x6 cells under 3x3x3 board cells it plans as well
// as adding PlanEffort's local search and exact search to it (26,548 against 26,496 fetches over
// 24 frames) at an eighth of the time (BENCHMARKS.md "Two memory levels").
BestScheduleOptions FinePlanEffort(std::uint64_t seed) {
  BestScheduleOptions o = PlanEffort(seed);
  o.chains = 0;
  o.exact_states = 0;
  return o;
}

void TwoLevelBestScheduler::BeginFrame(const FrameInfo& frame) {
  std::vector<CellId> plan;
  if (frame.previous != nullptr) {
    const std::uint64_t seed = seed_;
    const std::vector<CellId> board = BoardCellOf(frame);
    PlanCache* cache = frame.plans;
    const std::uint64_t key =
        PlanKey(kTwoLevelBestPlan, {TreeKey(*frame.previous), BoardKey(board), seed});
    plan = *Shared<std::vector<CellId>>(cache, key, [&] {
      return TwoLevelSchedule(
          *frame.previous, board, [&](const CellTree& t) { return PlanOf(cache, t, seed); },
          [seed](const CellTree& t) { return BestSchedule(t, FinePlanEffort(seed)).schedule; });
    });
  }
  follower_.Reset(std::move(plan), frame.cells);
}

}  // namespace raycell
