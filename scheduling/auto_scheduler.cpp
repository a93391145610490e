#include "scheduling/auto_scheduler.h"

#include <algorithm>
#include <sstream>
#include <vector>

#include "base/check.h"
#include "base/format.h"
#include "base/parallel.h"
#include "scheduling/adaptive_scheduler.h"
#include "scheduling/balanced_scheduler.h"
#include "scheduling/best_scheduler.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/max_work.h"

namespace raycell {

constexpr SchedulerEntry kAutoEntry = [] {
  SchedulerEntry e;
  e.name = "auto";
  e.meaning =
      "the recommended online scheduler: with one processor celltree-adaptive (Max Work when "
      "Max Work saved a quarter of its fetches on the two previous frames); with several, "
      "per frame, of balanced-critical, celltree-adaptive, celltree and balanced, the one that "
      "fetched fewest on the two previous frames' trees (each planned from the other) replayed "
      "on the board; Max Work when none fetched fewer than Max Work there by 2 per processor "
      "(and, when it took longer, by 25% of Max Work's fetches), and in frames 0 and 1, with "
      "nothing to judge by";
  e.label = "auto (recommended, falls back to Max Work)";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<AutoScheduler>(seed);
  };
  e.history = 2;
  e.seeded = true;
  e.studied = false;
  return e;
}();

std::string ModelResult::ToString() const {
  std::ostringstream s;
  s << "fetches " << fetches << ", time " << FormatReal(time);
  return s.str();
}

namespace {

// The model's state: per cell its queue of nodes and queued rays, open (1) or busy (0); per
// node its number in the order queued (0: the root); per processor its batch.
class BoardModel {
 public:
  BoardModel(const CellTree& tree, Scheduler& scheduler, const FrameInfo& info)
      : tree_(tree),
        s_(scheduler),
        cells_(info.cells),
        watch_(scheduler.Watches()),
        fetch_samples_(info.fetch_samples),
        queue_(cells_),
        queued_(cells_, 0),
        view_(cells_, 0),
        open_(cells_, 1),
        number_(tree.size(), 0),
        procs_(std::max<std::uint32_t>(info.processors, 1)) {
    RAYCELL_CHECK_LE(tree.cell_count(), cells_);
  }

  ModelResult Run() {
    for (NodeId c = tree_.first_child(kRootNode); c != kNoNode; c = tree_.next_sibling(c)) {
      Release(c);
    }
    double now = 0;
    for (;;) {
      // The idle processors ask again only when the queues or the busy cells changed since they
      // last asked (a node done inside a batch with no child changes neither): a scheduler
      // answers the same view the same (Scheduler::Next: no work, or postponing, changes
      // nothing).
      if (changed_) {
        changed_ = false;
        for (std::uint32_t k = 0; k < procs_.size(); ++k) {
          if (!procs_[k].working) Ask(k, now);
        }
      }
      // The next node done: its children are queued, and its processor goes on with its batch,
      // then with what others released into its cell meanwhile (no fetch), else frees the cell.
      Proc* next = nullptr;
      for (Proc& p : procs_) {
        if (p.working && (next == nullptr || p.end < next->end)) next = &p;
      }
      if (next == nullptr) break;
      now = next->end;
      const NodeId done = next->batch[next->done++];
      for (NodeId c = tree_.first_child(done); c != kNoNode; c = tree_.next_sibling(c)) Release(c);
      if (next->done == next->batch.size() && !queue_[next->cell.value()].empty()) {
        Take(*next, next->cell);
      }
      if (next->done < next->batch.size()) {
        next->end = now + double(tree_.samples(next->batch[next->done]));
        continue;
      }
      open_[next->cell.value()] = 1;
      next->working = false;
      changed_ = true;
    }
    RAYCELL_CHECK_EQ(taken_, tree_.node_count());
    result_.time = now;
    return result_;
  }

 private:
  struct Proc {
    bool working = false;
    double end = 0;  // when batch[done] is done
    std::optional<CellId> loaded;
    CellId cell{0};
    std::vector<NodeId> batch;
    std::size_t done = 0;
  };

  void Release(NodeId n) {
    const CellId c = tree_.cell(n);
    number_[n.index()] = next_number_++;
    const std::uint64_t rays = std::max<std::uint64_t>(tree_.enter(n), 1);
    queue_[c.value()].push_back(n);
    queued_[c.value()] += rays;
    changed_ = true;
    ++result_.steps;
    if (watch_) {
      const NodeId parent = tree_.parent(n);
      s_.Arrived({number_[n.index()], number_[parent.index()], c, rays,
                  parent == kRootNode ? kNoCell : tree_.cell(parent)});
    }
  }

  // Takes `c`'s queue whole as p's batch.
  void Take(Proc& p, CellId c) {
    if (watch_) s_.Taken(c);
    p.batch.swap(queue_[c.value()]);
    queue_[c.value()].clear();
    p.done = 0;
    taken_ += p.batch.size();
    result_.steps += p.batch.size();
    queued_[c.value()] = 0;
  }

  void Ask(std::uint32_t k, double now) {
    Proc& p = procs_[k];
    std::uint32_t working = 0;
    for (const Proc& o : procs_) working += o.working ? 1 : 0;
    for (std::uint32_t c = 0; c < cells_; ++c) view_[c] = open_[c] != 0 ? queued_[c] : 0;
    result_.steps += cells_;
    QueueView v{view_.data(), cells_, p.loaded};
    v.processor = k;
    v.open = open_.data();
    v.working = working;
    if (v.empty()) return;
    const std::optional<CellId> c = s_.Next(v);
    if (!c) return;  // postponed: waits for released work
    RAYCELL_CHECK(v.has_work(*c));
    double fetch = 0;
    if (p.loaded != c) {
      ++result_.fetches;
      if (fetch_samples_ != nullptr) fetch = (*fetch_samples_)[c->value()];
    }
    p.loaded = c;
    p.cell = *c;
    p.working = true;
    open_[c->value()] = 0;
    Take(p, *c);
    p.end = now + fetch + double(tree_.samples(p.batch[0]));
  }

  const CellTree& tree_;
  Scheduler& s_;
  std::uint32_t cells_;
  bool watch_;
  const std::vector<double>* fetch_samples_;
  std::vector<std::vector<NodeId>> queue_;
  std::vector<std::uint64_t> queued_, view_, open_;
  std::vector<std::uint32_t> number_;
  std::uint32_t next_number_ = 1;
  std::vector<Proc> procs_;
  std::size_t taken_ = 0;
  bool changed_ = true;  // since the idle processors last asked
  ModelResult result_;
};

}  // namespace

ModelResult ModelFrame(const CellTree& tree, Scheduler& scheduler, const FrameInfo& info) {
  scheduler.BeginFrame(info);
  return BoardModel(tree, scheduler, info).Run();
}

std::vector<const SchedulerEntry*> AutoScheduler::CandidatesFor(std::uint32_t processors) {
  if (processors <= 1) return {&kCellTreeAdaptiveEntry};
  return {&kBalancedCriticalEntry, &kCellTreeAdaptiveEntry, &kCellTreeEntry, &kBalancedEntry};
}

void AutoScheduler::BeginFrame(const FrameInfo& frame) {
  const std::vector<const SchedulerEntry*> entries = CandidatesFor(frame.processors);
  if (candidates_.size() != entries.size() || &candidates_[0]->entry() != entries[0]) {
    candidates_.clear();
    for (const SchedulerEntry* e : entries) candidates_.push_back(MakeScheduler(*e, seed_));
  }
  if (!max_work_) max_work_ = MakeScheduler(kMaxWorkEntry, seed_);
  models_.assign(candidates_.size(), {});
  max_work_model_ = {};
  check_cost_ = own_cost_ = {};
  // No frame seen to judge by (frames 0 and 1): the candidate with one processor, Max Work with
  // several (docs/design.md §5 "The recommended scheduler" has the evidence).
  chosen_ = frame.processors <= 1 ? 0 : kNone;
  checked_ = frame.previous != nullptr && frame.before_previous != nullptr;
  if (checked_) {
    // Frame i-1 as each candidate would have run it planned from frame i-2 (alone: frame i-3
    // is not told), and frame i-2 planned from frame i-1, and the same frames under Max Work:
    // two frames' worth of evidence of how the plans of one frame serve the next.
    FrameInfo seen = frame;
    seen.frame_index = frame.frame_index > 0 ? frame.frame_index - 1 : 0;
    seen.current = nullptr;
    seen.previous = frame.before_previous;
    seen.before_previous = nullptr;
    FrameInfo back = seen;
    back.previous = frame.previous;
    // On the replay's own board when it offers one (FrameInfo::seen: per node, with its links,
    // levels and joins, from what its levels hold at this frame's start), else in the model.
    const auto one = [&](const CellTree& tree, Scheduler& s, const FrameInfo& f) {
      if (frame.seen == nullptr) return ModelFrame(tree, s, f);
      const SeenOutcome o =
          frame.seen->Replay(tree, s, f.frame_index, f.previous, f.before_previous);
      ModelResult m;
      m.fetches = o.fetches;
      m.time = o.time;
      m.steps = o.steps;
      return m;
    };
    // The 2 (1 + candidates) replays, each on a scheduler of its own, run on the threads the
    // replay gives (FrameInfo::seen's threads()); their outcomes do not depend on the order.
    const std::size_t runs = 1 + candidates_.size();
    std::vector<ModelResult> outcome(2 * runs);
    std::vector<DecisionCost> cost(2 * runs);
    const auto replay = [&](std::size_t t) {
      const SchedulerEntry& e = t < 2 ? kMaxWorkEntry : candidates_[t / 2 - 1]->entry();
      const std::unique_ptr<Scheduler> s = MakeScheduler(e, seed_);
      outcome[t] =
          t % 2 == 0 ? one(*frame.previous, *s, seen) : one(*frame.before_previous, *s, back);
      cost[t] = s->Cost();
    };
    ParallelFor(outcome.size(), frame.seen != nullptr ? frame.seen->threads() : 1, replay);
    const auto run = [&](std::size_t r) {
      ModelResult m;
      for (std::size_t t = 2 * r; t < 2 * r + 2; ++t) {
        check_cost_.steps += outcome[t].steps + cost[t].steps;
        check_cost_.peak_bytes = std::max(check_cost_.peak_bytes, cost[t].peak_bytes);
        m.fetches += outcome[t].fetches;
        m.time += outcome[t].time;
        m.steps += outcome[t].steps;
      }
      return m;
    };
    max_work_model_ = run(0);
    // With several processors a frame's choices serve the next only roughly: a candidate must
    // save kMarginPerProcessor fetches per processor over the two frames.
    const std::uint64_t margin = frame.processors > 1 ? kMarginPerProcessor * frame.processors : 0;
    chosen_ = kNone;
    for (std::size_t k = 0; k < candidates_.size(); ++k) {
      models_[k] = run(k + 1);
      // Fewer fetches than Max Work by the margin; the fewest, then the least time, then the
      // first listed.
      const ModelResult& m = models_[k];
      if (frame.processors <= 1) {
        // One processor: the candidate unless Max Work saved kOneProcessorFallbackPercent of its
        // fetches (a safety net: smaller savings of Max Work there did not hold in the frame).
        if (max_work_model_.fetches * 100 < m.fetches * (100 - kOneProcessorFallbackPercent)) {
          continue;
        }
        chosen_ = k;
        continue;
      }
      if (m.fetches + margin > max_work_model_.fetches) continue;
      // With several processors, one that took longer than Max Work must save at least
      // kTimeWaiverPercent of Max Work's fetches (fewer fetches saved do not pay for the time).
      if (frame.processors > 1 && m.time > max_work_model_.time &&
          (max_work_model_.fetches - m.fetches) * 100 <
              max_work_model_.fetches * kTimeWaiverPercent) {
        continue;
      }
      if (chosen_ == kNone || m.fetches < models_[chosen_].fetches ||
          (m.fetches == models_[chosen_].fetches && m.time < models_[chosen_].time)) {
        chosen_ = k;
      }
    }
    // The model's state: per node its number and queue slot (8 bytes), per cell its queued
    // rays and state (16), beside what the candidates kept.
    check_cost_.peak_bytes +=
        8 * std::uint64_t{std::max(frame.previous->size(), frame.before_previous->size())} +
        16 * std::uint64_t{frame.cells};
  }
  // What a candidate kept of the frame it last ran (a watching one's state, per node) is not
  // kept through this frame: they begin afresh, as a scheduler keeps no state across frames
  // (issue 43: on the orbit's largest frames at 4096 cells, 8 processors, 1037 -> 952 MB, when
  // the check still ran on them).
  if (checked_) {
    for (auto& c : candidates_) c = MakeScheduler(c->entry(), seed_);
  }
  active_ = chosen_ == kNone ? max_work_.get() : candidates_[chosen_].get();
  active_->BeginFrame(frame);
}

std::string AutoScheduler::Reason() const {
  const std::string r = active_->Reason();
  if (chosen_ != kNone) return r;
  return "max work (fallback)";
}

void AutoScheduler::Arrived(const Arrival& arrival) {
  if (active_->Watches()) active_->Arrived(arrival);
}

void AutoScheduler::Taken(CellId cell) {
  if (active_->Watches()) active_->Taken(cell);
}

std::optional<CellId> AutoScheduler::Next(const QueueView& queues) {
  const std::optional<CellId> c = active_->Next(queues);
  if (c) {
    ++own_cost_.decisions;
    // Max Work and the plain followers count nothing themselves: a scan of the cells (Max Work's,
    // or a follower's skipped entries at worst, one per cell).
    if (!active_->Watches()) own_cost_.steps += queues.cells;
  }
  return c;
}

Scheduler::DecisionCost AutoScheduler::Cost() const {
  // Decisions counted here, whoever runs the frame; the steps of the one that runs it (its own
  // count when it watches, else one scan per decision) and the check's; the most bytes of either.
  DecisionCost c = own_cost_;
  if (active_->Watches()) {
    const DecisionCost a = active_->Cost();
    c.steps += a.steps;
    c.peak_bytes = a.peak_bytes;
  }
  c.steps += check_cost_.steps;
  c.peak_bytes = std::max(c.peak_bytes, check_cost_.peak_bytes);
  return c;
}

}  // namespace raycell
