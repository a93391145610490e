// Schedulers that follow the best schedule found for a Cell Tree (search/best_schedule.h)
// instead of Peel's (docs/design.md §1 "Cell Tree scheduling"):
//  - `best`: each frame follows its own tree's best schedule, an offline oracle (as `peel`
//    is for Peel);
//  - `celltree-best`: frame i+1 follows the best schedule of frame i's tree, the paper's
//    scheme with a better plan (frame 0 runs Max Work);
//  - `celltree-union`: frame i+1 follows the best schedule of the union of frames i and
//    i-1's trees (graph/cell_tree.h UnionTree; FrameInfo::before_previous): feasible for
//    both, so a plan that holds whichever of the two the next frame resembles (frame 0 runs
//    Max Work, frame 1 follows frame 0's tree alone).
// Entries with no queued work are skipped; when the plan is used up, Max Work.
//
// The plans use PlanEffort, a small budget (a plan must be ready while the frame before it
// is replayed: BENCHMARKS.md states the time per frame). BestSchedule is deterministic, so
// plans are memoised by the tree's contents (PlanFor): sweeps whose configurations share a
// scheduler compute each frame's plan once, with the same result.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "scheduling/plan_cache.h"
#include "scheduling/scheduler.h"
#include "search/best_schedule.h"

namespace raycell {

// Its registry entries (SchedulerEntry), defined in best_scheduler.cpp.
extern const SchedulerEntry kBestEntry;
extern const SchedulerEntry kCellTreeBestEntry;
extern const SchedulerEntry kCellTreeUnionEntry;
extern const SchedulerEntry kCellTree2LevelBestEntry;

// The schedule search budget of the following schedulers, before it is fitted to a tree.
BestScheduleOptions PlanEffort(std::uint64_t seed);

// PlanEffort(seed) fitted to `tree` (docs/design.md §5 "Planners and PlanEffort"): the beam
// search only when its full width fits in its work limit (64 x nodes x the maxGen bound, its
// moves, within beam_max_node_visits; else it would run narrowed, and a narrow beam plans worse
// than Peel on large trees), and the local search's re-timings of the whole schedule (a pass
// over every node after each change and each deletion of an idle entry:
// LocalSearchOptions::max_retimes) within 1/kPlanRetimeShare of its work limit. Trees of up to
// a few thousand nodes plan as with PlanEffort(seed).
BestScheduleOptions PlanEffort(std::uint64_t seed, const CellTree& tree);
// The local search's re-timings: 1/50 of its work limit, in node visits (see PlanEffort).
inline constexpr std::uint64_t kPlanRetimeShare = 50;

// The effort for small forests planned many times a frame: the beam search alone (width 64).
BestScheduleOptions FinePlanEffort(std::uint64_t seed);

// The best schedule BestSchedule(tree, PlanEffort(seed, tree)) finds, memoised (thread-safe).
std::vector<CellId> PlanFor(const CellTree& tree, std::uint64_t seed);
// The same plan, shared through `cache` (scheduling/plan_cache.h; null: PlanFor's own): made
// by PlanFor, or searched again when the cache's memo is off.
std::shared_ptr<const std::vector<CellId>> SharedPlan(PlanCache* cache, const CellTree& tree,
                                                      std::uint64_t seed);

class BestOracleScheduler : public FollowingScheduler {
 public:
  explicit BestOracleScheduler(std::uint64_t seed) : FollowingScheduler(kBestEntry), seed_(seed) {}
  // Plans frame.current, which must not be null.
  void BeginFrame(const FrameInfo& frame) override;

 private:
  std::uint64_t seed_;
};

class CellTreeBestScheduler : public FollowingScheduler {
 public:
  // union_frames: plan the union of the last two frames' trees rather than the last alone.
  CellTreeBestScheduler(std::uint64_t seed, bool union_frames)
      : FollowingScheduler(union_frames ? kCellTreeUnionEntry : kCellTreeBestEntry),
        seed_(seed),
        union_frames_(union_frames) {}
  void BeginFrame(const FrameInfo& frame) override;
  // celltree-union with frames i-2 and i-1: their union, from which alone it then plans.
  bool Prepare(const FrameInfo& frame) override;

 private:
  // Whether it plans from the union of frames i-2 and i-1 (celltree-union, both trees given):
  // what Prepare makes and BeginFrame reads.
  bool PlansUnion(const FrameInfo& frame) const;

  std::uint64_t seed_;
  bool union_frames_;
};

// Two-level scheduling with the best-schedule search at both levels (issue 23; docs/design.md
// §5 "Two-level scheduling"): frame i+1 follows TwoLevelSchedule of frame i's tree, the board's
// cells (FrameInfo::board_cell_of) ordered by the plan for the contracted tree (PlanFor), the
// cells within each by the plan for each forest (PlanEffort). Frame 0: Max Work.
class TwoLevelBestScheduler : public FollowingScheduler {
 public:
  explicit TwoLevelBestScheduler(std::uint64_t seed)
      : FollowingScheduler(kCellTree2LevelBestEntry), seed_(seed) {}
  void BeginFrame(const FrameInfo& frame) override;

 private:
  std::uint64_t seed_;
};

}  // namespace raycell
