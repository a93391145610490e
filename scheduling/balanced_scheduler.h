// Schedulers for several block processors (docs/design.md §5 "Load balancing"): the paper
// schedules one processor; with P of them the question is also which processor takes which
// cell, and when a processor should rather wait than fetch a cell for a handful of rays.
// One class, its parts switched by BalanceOptions, each combination a registry entry:
//  - plan: follow the best schedule of frame i-1's tree (celltree-best's plan, entries of
//    busy cells deferred); without it, Max Work's order.
//  - partition: the plan's cells split over the processors before the frame, by list
//    scheduling (Graham): cells in order of their work in frame i-1's tree, each to the
//    processor with the least work so far, so every cell stays on one processor; a
//    processor follows the entries of its own cells (or Max Work over them).
//  - steal: a processor with none of its own cells ready takes a whole cell's queue from the
//    processor with the most queued rays (its largest queue); without steal it takes Max
//    Work's choice among the other cells.
//  - affinity: the cell in the processor's cache first when it has work (no fetch); else,
//    among the cells with work, those the processor's last cell sends its rays to (by frame
//    i-1's tree: rays entering a node of cell c from a node of the last cell): Max Work on
//    queued rays x (1 + the share of the last cell's rays going there).
//  - share: when no free cell has work in view, the busy cell with the most queued rays
//    (QueueView::all_queued): the processor joins a cell another one works, so the hot cells
//    of a frame do not leave the other processors idle. The holders take the cell's queue
//    whole, whoever asks first; one that finds it empty takes half of the units another
//    holder has not started (docs/design.md §2), so a joiner shares the work already taken.
//  - postpone: on boards of kPostponeMinProcessors or more, while every other processor is
//    working, a cell whose queued work (queued rays
//    x the cell's samples per ray visit in frame i-1's tree) is less than kPostponeFactor
//    fetches (FrameInfo::fetch_samples) is not fetched: the largest queue is taken instead if
//    it is large enough, else the processor waits for released work (Scheduler::Next).
//    Aila and Karras's postponing of rays until queues fill, as a rule on batch size; at
//    most one processor waits by choice, so the tails of frames are not serialised. On any
//    board, a join (share) whose busy cell has less than kPostponeFactor fetches of work
//    queued is not made: the largest batch worth a fetch is taken instead, else the processor
//    waits; the holder takes those rays when its worklist runs out, and in a frame's tail a
//    joiner would pay a fetch to find the queue already taken.
//  - adaptive: instead of following celltree-best's plan, ask celltree-adaptive
//    (adaptive_scheduler.h), which watches the frame unfold: issue 24's adaptive rule with
//    this class's affinity, sharing and postponing around it (`balanced-adaptive`).
//  - critical: with several processors, the free cell whose queued work starts the longest
//    predicted chain first (Hu's highest-level-first list scheduling): the scheduler watches
//    the frame (Scheduler::Watches), matches each queued node to frame i-1's node of the same
//    cell path (else the first node with the same parent's cell and cell, as
//    celltree-adaptive's stand-ins), and a cell's level is the largest height (nodes on the
//    longest path down to a leaf, itself included) of its queued nodes' matches. The plan's
//    entry is taken when no free cell's level is higher. The tails of frames are chains of
//    fetches for a few rays on deep paths; started earlier, they overlap the bulk of the work
//    (`balanced-critical`).
// With one processor nothing is busy, shared, stolen or postponed, the cached cell never has
// work when the processor asks, and the one partition is the whole plan: `partition`,
// `partition-steal` and `balanced` then choose exactly as celltree-best (a test).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/mapped_array.h"
#include "scheduling/adaptive_scheduler.h"
#include "scheduling/scheduler.h"

namespace raycell {

struct BalanceOptions {
  bool plan = false;
  bool partition = false;
  bool steal = false;
  bool affinity = false;
  bool postpone = false;
  bool share = false;
  bool adaptive = false;
  bool critical = false;
};

// A batch is postponed when its estimated work is below this many fetch times.
// Chosen on the study's capture (BENCHMARKS.md "Several processors": 0.5 to 4 tried).
inline constexpr double kPostponeFactor = 3.0;
// Processors a board needs for postponing: with fewer, the one that waits is too large a share
// (on the study's capture postponing costs 60% at 2 processors and 17% at 4, saves 16% at 8).
inline constexpr std::uint32_t kPostponeMinProcessors = 8;

// The registry's entries of this class, one per combination of options (balanced_scheduler.cpp).
extern const SchedulerEntry kAffinityEntry;
extern const SchedulerEntry kPartitionEntry;
extern const SchedulerEntry kStealEntry;
extern const SchedulerEntry kPartitionStealEntry;
extern const SchedulerEntry kShareEntry;
extern const SchedulerEntry kBalancedEntry;
extern const SchedulerEntry kBalancedCriticalEntry;
extern const SchedulerEntry kBalancedAdaptiveEntry;

class BalancedScheduler : public Scheduler {
 public:
  // `entry`: the registry entry naming this combination of options.
  BalancedScheduler(const SchedulerEntry& entry, BalanceOptions options, std::uint64_t seed);
  void BeginFrame(const FrameInfo& frame) override;
  std::optional<CellId> Next(const QueueView& queues) override;
  std::optional<CellId> Peek(const QueueView& queues) const override;
  std::string Reason() const override;
  bool Watches() const override { return adaptive_ != nullptr || options_.critical; }
  void Arrived(const Arrival& arrival) override;
  void Taken(CellId cell) override;
  DecisionCost Cost() const override;
  // `critical` matches arrivals in the previous tree; the adaptive one as it says.
  bool ReadsEarlierTrees() const override {
    return previous_ != nullptr || (adaptive_ != nullptr && adaptive_->ReadsEarlierTrees());
  }
  // The adaptive rule's union, and frame i-1's statistics (StatsOf), where it neither plans from
  // frame i-1's tree nor matches arrivals in it (balanced-adaptive with several processors).
  bool Prepare(const FrameInfo& frame) override;
  // The adaptive rule's, and `critical`'s heights of frame i-1's nodes.
  std::uint64_t HeldBytes() const override {
    return (adaptive_ ? adaptive_->HeldBytes() : 0) +
           (heights_ ? 4 * std::uint64_t{heights_->height.capacity()} : 0);
  }

  // What frame i-1's tree says of each cell (shared by the configurations of a frame,
  // FrameInfo::plans): per cell its samples and samples per visit (0: unknown); for affinity,
  // per cell `from` the cells `to` its rays enter, with the share of what leaves `from` that
  // enters nodes of `to` (a sparse row, increasing `to`: at most one entry per node).
  struct TreeStats {
    std::vector<double> work, samples_per_visit;
    std::vector<std::uint32_t> flow_begin;  // row `from`: flow[flow_begin[from] .. [from + 1])
    std::vector<std::pair<std::uint32_t, double>> flow;
  };
  // (public for its test)
  static TreeStats StatsOf(const CellTree* previous, std::uint32_t cells, bool affinity);
  // StatsOf(frame.previous), through the frame's plan cache.
  std::shared_ptr<const TreeStats> SharedStats(const FrameInfo& frame) const;

 private:
  // The choice for `queues` without the postponing rule, and the follower it came from (null:
  // not a plan entry) or whether the adaptive rule or the critical rule chose it.
  std::optional<CellId> Choose(const QueueView& queues, ScheduleFollower** follower, bool* adaptive,
                               bool* critical) const;
  // The queued rays this scheduler may choose from: every cell's with share, else the view's.
  const std::uint64_t* Queued(const QueueView& queues) const;
  // `queues` with the cells of other processors masked out (partition), in own_.
  QueueView Own(const QueueView& queues) const;
  // Max Work over the cells with work in view that `take` accepts, weighted by affinity.
  // `queued`: per cell (queues.queued_rays, or all_queued to count busy cells too).
  template <typename Take>
  std::optional<CellId> Best(const QueueView& queues, const std::uint64_t* queued, Take take) const;
  // Best taking every cell, without a scan of the cells: the replay's most queued cell
  // (MostQueuedAll, MostQueuedCell) against the loaded cell's row of shares (O(row)).
  std::optional<CellId> BestOfAll(const QueueView& queues, const std::uint64_t* queued) const;
  // Whether no cell has queued rays this scheduler may take.
  bool NoWork(const QueueView& queues) const;
  // Whether a batch of `c` is too small to fetch while others work.
  bool TooSmall(const QueueView& queues, CellId c) const;
  // Critical: the free cell in view with the highest level, when it is higher than the level
  // of `plan` (the plan's choice; none: any); ties to the most queued rays, then the lowest
  // number.
  std::optional<CellId> Critical(const QueueView& queues, std::optional<CellId> plan) const;
  void SetHeights(const FrameInfo& frame);
  // The bytes of the critical rule's state now (DecisionCost::bytes keeps the largest).
  std::uint64_t Bytes() const;

  BalanceOptions options_;
  std::uint64_t seed_;
  std::uint32_t cells_ = 0;
  std::uint32_t processors_ = 1;  // FrameInfo::processors
  std::vector<CellId> plan_;
  const std::vector<double>* fetch_samples_ = nullptr;
  std::shared_ptr<const TreeStats> stats_;  // frame i-1's (StatsOf), shared
  // Critical: per node of frame i-1's tree its height, and the tree's stand-ins (shared).
  struct Heights {
    std::vector<std::uint32_t> height;
    std::shared_ptr<const StandIns> stand_in;
  };
  // Critical: sets `cell`'s level, keeping the cells of each level (at_level_).
  void SetLevel(CellId cell, std::uint32_t level);
  // Critical: the most queued cell in view of level l (kNoBest: none; lowest number on ties), as
  // MostQueuedOf over its list gives it, from the level's last answer and the cells that had
  // arrivals there since (level_best_, touched_), when `queues` is the board's own view: it changes
  // only by arrivals (told), takes (told) and the locks of the cells this scheduler returns.
  std::uint32_t LevelBest(std::uint32_t l, const QueueView& queues) const;
  // Critical: `cell` leaves its level's answer (moved, taken or locked).
  void Forget(CellId cell);
  // Critical: `cell` was returned by Next, so its queue leaves the view.
  void Locked(CellId cell) {
    if (options_.critical) Forget(cell);
  }
  // Each cell's processor and one follower per processor over the plan's entries of its
  // cells (one follower, owner 0 everywhere, without partition).
  std::vector<std::uint32_t> owner_;
  std::vector<ScheduleFollower> followers_;
  mutable std::vector<std::uint64_t> own_;  // scratch for Own()
  // Why the last Next chose its cell, kept as which rule chose (its words made only when Reason
  // asks, for a timeline: with tens of processors Next runs millions of times a frame, and a
  // string a decision was a heap allocation each, 30M in a replay at 4096 cells).
  enum class Why : std::uint8_t {
    kNone,
    kFollower,
    kAdaptive,
    kCritical,
    kMaxWork,
    kPlanSmall,
    kJoinSmall
  };
  Why why_ = Why::kNone;
  const ScheduleFollower* why_follower_ = nullptr;  // Why::kFollower's
  std::unique_ptr<AdaptiveScheduler> adaptive_;     // options_.adaptive
  // Critical (options_.critical): per node of frame i-1's tree its height; per (parent's cell,
  // cell) the first node with those cells (StandInKey); per queued node (Arrival::node) its
  // match (kNoNode: none); per cell the highest level of its queued nodes (0: none).
  const CellTree* previous_ = nullptr;
  std::shared_ptr<const Heights> heights_;
  MappedArray<NodeId> match_;
  std::vector<std::uint32_t> level_;
  // Per level >= 1 the cells of that level, and the highest level that may have cells. Critical
  // looks at the levels above the plan's entry's, from the top, not at every cell.
  CellLists at_level_;
  std::uint32_t top_level_ = 0;
  // Per level its last answer of LevelBest (a cell, kNoBest: none in view, kUnknownBest: to be
  // found by a scan), and the cells with arrivals at that level since (each once: per cell the
  // level it was last listed at, 0: none).
  static constexpr std::uint32_t kNoBest = ~std::uint32_t{0};
  static constexpr std::uint32_t kUnknownBest = ~std::uint32_t{0} - 1;
  mutable std::vector<std::uint32_t> level_best_;
  mutable std::vector<std::vector<std::uint32_t>> touched_;
  mutable std::vector<std::uint32_t> touched_at_;
  mutable DecisionCost cost_;  // the critical rule's own
};

}  // namespace raycell
