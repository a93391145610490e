// The recommended online scheduler (issue 42; docs/design.md §5 "The recommended scheduler"):
// `auto`, one name for any processor count, that watches itself and falls back to Max Work.
//
//  - Its candidates: with one processor `celltree-adaptive` (issue 24's adaptive rule) alone,
//    falling back to Max Work only when the check shows Max Work saving
//    kOneProcessorFallbackPercent of its fetches (choosing among `celltree-union`,
//    `celltree-best` and `celltree` besides fetched more on the suite, and smaller savings of
//    Max Work on the frames seen did not hold); with several `balanced-critical` (load
//    balancing, critical path first, issue 22), `celltree-adaptive`, `celltree` and
//    `balanced`, judged by the check below.
//  - Its check, before each frame i >= 2: the replay's own board
//  (FrameInfo::seen: the
//    replay per Cell Tree node, from what the board's levels hold at frame i's start), or
//    outside a replay a model of the board (ModelFrame, linear in the tree but for the choices
//    it asks for), replays frame i-1's tree under each candidate as it would have run frame i-1
//    planned from frame i-2's tree alone, and frame i-2's planned from frame i-1's, and both
//    under Max Work. Frame i runs the candidate that fetched fewest over the two (then took
//    least time, then the first listed) among those that fetched fewer than Max Work by a
//    margin, kMarginPerProcessor per processor, and that took no longer than Max Work unless
//    they saved kTimeWaiverPercent of its fetches; when none did, Max Work. Its replays run at
//    once on the threads the replay gives (SeenFrameReplayer::threads), each on a scheduler of
//    its own; the choice is the same for any number.
//  - Frames 0 and 1 have no frame seen to judge by: Max Work with several processors (there the
//    candidates fetch 29-58% more in frame 0 on the development set).
// The decision is a function of the frame's FrameInfo (frames i-1 and i-2's trees, the
// processor count, the fetch costs), so the scheduler keeps no state across frames (frame
// shards and resumed sweeps give the whole replay's results). It watches the frame unfold
// (Scheduler::Watches), so it is never given the frame's own tree, and forwards what it sees
// to the candidate that runs.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "scheduling/scheduler.h"

namespace raycell {

// Its registry entry (SchedulerEntry), defined in auto_scheduler.cpp.
extern const SchedulerEntry kAutoEntry;

// With several processors, the fetches per processor a candidate must save over Max Work in
// the check's two frames (docs/design.md §5 "The recommended scheduler": chosen among 0-4 on
// the development set with the model, among 1-3 on the suite with the replay's board).
inline constexpr std::uint64_t kMarginPerProcessor = 2;
// With several processors, a candidate that took longer than Max Work in the check's two frames
// is taken only when it saved at least this share, in percent, of Max Work's fetches there
// (docs/design.md §5 "The recommended scheduler": chosen among 10-25 and never on the suite).
inline constexpr std::uint64_t kTimeWaiverPercent = 25;
// With one processor, the share, in percent, of celltree-adaptive's fetches in the check's two
// frames that Max Work must save there for the frame to fall back to Max Work (docs/design.md §5
// "The recommended scheduler": on the suite Max Work saved at most 14% in a frame seen, and ran
// worse in the frame each time; a quarter, as kTimeWaiverPercent, keeps the fallback for frames
// where the plans clearly fail).
inline constexpr std::uint64_t kOneProcessorFallbackPercent = 25;

// What a scheduler's choices cost on one frame's Cell Tree in the model of the board.
struct ModelResult {
  std::uint64_t fetches = 0;
  double time = 0;          // in sample times: fetches (FrameInfo::fetch_samples) and work
  std::uint64_t steps = 0;  // elementary steps of the model itself (views built, nodes moved)
  // "fetches 12, time 345.5".
  std::string ToString() const;
};

// Replays `tree` under `scheduler` (BeginFrame(info) first; info.current is not read) in a
// model of the board, near linear in the tree's size: info.processors processors, each with a
// cache of one cell; the unit of work is the tree's node (its rays enter together), queued in
// its cell when its parent's batch is done; a processor asks the scheduler with the busy cells
// masked out (no joins: QueueView::all_queued is not given), takes the cell's queue whole,
// fetches it unless its cache holds it (info.fetch_samples, 0 when null), works every node's
// samples, then takes what others released into the cell meanwhile, else frees it; a scheduler
// that watches is told each node as it is queued and each queue taken, as the replay tells it.
// With one processor it fetches exactly as the replay per node (a test).
ModelResult ModelFrame(const CellTree& tree, Scheduler& scheduler, const FrameInfo& info);

class AutoScheduler : public Scheduler {
 public:
  explicit AutoScheduler(std::uint64_t seed) : Scheduler(kAutoEntry), seed_(seed) {}

  void BeginFrame(const FrameInfo& frame) override;
  std::optional<CellId> Next(const QueueView& queues) override;
  std::optional<CellId> Peek(const QueueView& queues) const override {
    return active_->Peek(queues);
  }
  std::string Reason() const override;
  // As the candidate it runs this frame (Max Work does not): asked once the frame began.
  bool Watches() const override { return active_ == nullptr || active_->Watches(); }
  void Arrived(const Arrival& arrival) override;
  void Taken(CellId cell) override;
  DecisionCost Cost() const override;
  // The check reads the earlier trees in BeginFrame; the frame then runs one candidate.
  bool ReadsEarlierTrees() const override {
    return active_ == nullptr || active_->ReadsEarlierTrees();
  }
  std::uint64_t HeldBytes() const override { return active_ ? active_->HeldBytes() : 0; }

  // The candidates' registry entries for a board of `processors`, in order of preference.
  static std::vector<const SchedulerEntry*> CandidatesFor(std::uint32_t processors);
  static constexpr std::size_t kNone = ~std::size_t{0};
  // This frame: the candidate it runs (its index in CandidatesFor; kNone: Max Work), whether
  // the check ran (frames 0 and 1 have nothing to check on), and the check's results on frame
  // i-1's tree, Max Work's and each candidate's.
  std::size_t chosen() const { return chosen_; }
  bool checked() const { return checked_; }
  const ModelResult& max_work_model() const { return max_work_model_; }
  const std::vector<ModelResult>& candidate_models() const { return models_; }

 private:
  std::uint64_t seed_;
  std::vector<std::unique_ptr<Scheduler>> candidates_;
  std::unique_ptr<Scheduler> max_work_;
  Scheduler* active_ = nullptr;
  std::size_t chosen_ = kNone;
  bool checked_ = false;
  ModelResult max_work_model_;
  std::vector<ModelResult> models_;
  DecisionCost check_cost_;  // the check's steps and bytes this frame
  DecisionCost own_cost_;    // decisions this frame, and the scans of one that does not count
};

}  // namespace raycell
