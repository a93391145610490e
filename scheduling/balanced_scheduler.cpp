#include "scheduling/balanced_scheduler.h"

#include <algorithm>
#include <numeric>
#include <utility>

#include "base/check.h"
#include "scheduling/best_scheduler.h"

namespace raycell {

constexpr SchedulerEntry kAffinityEntry = [] {
  SchedulerEntry e;
  e.name = "affinity";
  e.meaning =
      "cell affinity: the cell in the processor's cache if it has work, else Max Work weighted "
      "to the cells its last cell sends rays to (frame i's tree)";
  e.label = "cell affinity";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<BalancedScheduler>(
        kAffinityEntry, BalanceOptions{false, false, false, true, false, false}, seed);
  };
  e.studied = false;
  return e;
}();

constexpr SchedulerEntry kPartitionEntry = [] {
  SchedulerEntry e;
  e.name = "partition";
  e.meaning =
      "frame i's best schedule split over the processors by list scheduling (each cell on one "
      "processor), each following its part; Max Work when its cells have no work";
  e.label = "partitioned plan";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<BalancedScheduler>(
        kPartitionEntry, BalanceOptions{true, true, false, false, false, false}, seed);
  };
  e.seeded = true;
  e.studied = false;
  return e;
}();

constexpr SchedulerEntry kStealEntry = [] {
  SchedulerEntry e;
  e.name = "steal";
  e.meaning =
      "cells split over the processors by list scheduling, Max Work on one's own; with none "
      "ready, the largest queue of the processor with the most queued rays (work stealing)";
  e.label = "work stealing";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<BalancedScheduler>(
        kStealEntry, BalanceOptions{false, true, true, false, false, false}, seed);
  };
  e.studied = false;
  return e;
}();

constexpr SchedulerEntry kPartitionStealEntry = [] {
  SchedulerEntry e;
  e.name = "partition-steal";
  e.meaning = "the partitioned plan, stealing when a processor's own cells have no work";
  e.label = "partitioned plan with stealing";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<BalancedScheduler>(
        kPartitionStealEntry, BalanceOptions{true, true, true, false, false, false}, seed);
  };
  e.seeded = true;
  e.studied = false;
  return e;
}();

constexpr SchedulerEntry kShareEntry = [] {
  SchedulerEntry e;
  e.name = "share";
  e.meaning =
      "Max Work; with no free cell ready, the busy cell with the most queued rays (a "
      "processor joins a cell another works)";
  e.label = "Max Work with shared cells";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<BalancedScheduler>(
        kShareEntry, BalanceOptions{false, false, false, false, false, true}, seed);
  };
  e.studied = false;
  return e;
}();

constexpr SchedulerEntry kBalancedEntry = [] {
  SchedulerEntry e;
  e.name = "balanced";
  e.meaning =
      "the cached cell if it has work, else celltree-best's plan shared by the processors (busy "
      "entries deferred, then Max Work); no free cell ready: joins a busy one (affinity-"
      "weighted; not for under 3 fetches' worth of queued work); on 8+ processors, while all "
      "others work, a batch under 3 fetches' worth waits";
  e.label = "balanced (plan, affinity, shared cells, postponing)";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<BalancedScheduler>(
        kBalancedEntry, BalanceOptions{true, false, false, true, true, true}, seed);
  };
  e.seeded = true;
  e.studied = false;
  return e;
}();

constexpr SchedulerEntry kBalancedCriticalEntry = [] {
  SchedulerEntry e;
  e.name = "balanced-critical";
  e.meaning =
      "balanced, with the free cell whose queued rays start the longest chain in frame i's "
      "tree first (highest level first, each queued node matched by its cell path) when it is "
      "longer than the plan's";
  e.label = "Balanced, critical path first";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    BalanceOptions o{true, false, false, true, true, true};
    o.critical = true;
    return std::make_unique<BalancedScheduler>(kBalancedCriticalEntry, o, seed);
  };
  e.seeded = true;
  e.studied = false;
  return e;
}();

constexpr SchedulerEntry kBalancedAdaptiveEntry = [] {
  SchedulerEntry e;
  e.name = "balanced-adaptive";
  e.meaning =
      "balanced with celltree-adaptive's rule in place of celltree-best's plan: the cached "
      "cell first, then the adaptive choice, joining busy cells and postponing small batches "
      "as balanced does";
  e.label = "Balanced, adaptive";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<BalancedScheduler>(
        kBalancedAdaptiveEntry, BalanceOptions{false, false, false, true, true, true, true}, seed);
  };
  e.history = 2;
  e.seeded = true;
  e.studied = false;
  return e;
}();

BalancedScheduler::BalancedScheduler(const SchedulerEntry& entry, BalanceOptions options,
                                     std::uint64_t seed)
    : Scheduler(entry), options_(options), seed_(seed) {
  if (options_.adaptive) adaptive_ = std::make_unique<AdaptiveScheduler>(seed);
}

std::shared_ptr<const BalancedScheduler::TreeStats> BalancedScheduler::SharedStats(
    const FrameInfo& frame) const {
  const bool affinity = options_.affinity;
  const std::uint32_t cells = frame.cells;
  return Shared<TreeStats>(frame.plans,
                           PlanKey(kTreeStats, {frame.previous ? TreeKey(*frame.previous) : 0,
                                                frame.previous != nullptr, cells, affinity}),
                           [&] { return StatsOf(frame.previous, cells, affinity); });
}

bool BalancedScheduler::Prepare(const FrameInfo& frame) {
  if (adaptive_ == nullptr || options_.plan || options_.critical) return false;
  if (!adaptive_->Prepare(frame)) return false;
  SharedStats(frame);  // kept in the frame's plan cache until every configuration began
  return true;
}

void BalancedScheduler::BeginFrame(const FrameInfo& frame) {
  cells_ = frame.cells;
  processors_ = std::max<std::uint32_t>(frame.processors, 1);
  fetch_samples_ = frame.fetch_samples;
  why_ = Why::kNone;
  plan_.clear();
  if (options_.plan && frame.previous != nullptr) {
    plan_ = *SharedPlan(frame.plans, *frame.previous, seed_);
  }
  if (adaptive_) adaptive_->BeginFrame(frame);
  // What frame i-1's tree says of each cell: its work, samples per visit, where rays go next.
  stats_ = SharedStats(frame);
  const std::vector<double>& work = stats_->work;
  // The cells over the processors: list scheduling, largest work first, each to the
  // processor with the least work so far (then the fewest cells, then the lowest number).
  const std::uint32_t p = options_.partition ? processors_ : 1;
  owner_.assign(cells_, 0);
  if (p > 1) {
    std::vector<std::uint32_t> order(cells_);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return work[a] > work[b]; });
    std::vector<double> load(p, 0.0);
    std::vector<std::uint32_t> count(p, 0);
    for (const std::uint32_t c : order) {
      std::uint32_t best = 0;
      for (std::uint32_t k = 1; k < p; ++k) {
        if (load[k] < load[best] || (load[k] == load[best] && count[k] < count[best])) best = k;
      }
      owner_[c] = best;
      load[best] += work[c];
      ++count[best];
    }
  }
  followers_.assign(p, ScheduleFollower());
  std::vector<std::vector<CellId>> parts(p);
  for (const CellId c : plan_) parts[owner_[c.value()]].push_back(c);
  for (std::uint32_t k = 0; k < p; ++k) followers_[k].Reset(std::move(parts[k]), cells_);
  if (options_.critical) {
    previous_ = frame.previous;
    match_.assign(1, previous_ != nullptr ? kRootNode : kNoNode);
    level_.assign(cells_, 0);
    at_level_.Reset(cells_);
    top_level_ = 0;
    level_best_.clear();
    touched_.clear();
    touched_at_.assign(cells_, 0);
    cost_ = {};
    heights_.reset();
    if (previous_ != nullptr) SetHeights(frame);
  }
}

BalancedScheduler::TreeStats BalancedScheduler::StatsOf(const CellTree* previous,
                                                        std::uint32_t cells, bool affinity) {
  TreeStats s;
  s.work.assign(cells, 0.0);
  s.samples_per_visit.assign(cells, 0.0);
  s.flow_begin.assign(std::size_t{cells} + 1, 0);
  if (previous == nullptr) return s;
  const CellTree& t = *previous;
  std::vector<double> visits(cells, 0.0);
  // at[from + 1]: the nodes whose parent is not the root and lies in cell `from`.
  std::vector<std::uint32_t> at(std::size_t{cells} + 1, 0);
  for (const NodeId n : t.nodes()) {
    const std::uint32_t c = t.cell(n).value();
    s.work[c] += double(t.samples(n));
    visits[c] += double(t.visits(n));
    const NodeId parent = t.parent(n);
    if (affinity && parent != kRootNode) ++at[t.cell(parent).value() + 1];
  }
  for (std::uint32_t c = 0; c < cells; ++c) {
    if (visits[c] > 0) s.samples_per_visit[c] = s.work[c] / visits[c];
  }
  if (!affinity) return s;
  // Those nodes bucketed by their parent's cell, in node order: 4 bytes a node, counted before
  // they are placed, so that no array grows by copies (the (from, to, rays) entries sorted
  // twice that this replaced held up to 48 bytes a node at once, about 200 MB for a 1920x1080
  // frame at 4096 cells, and `auto`'s check makes two at once).
  for (std::uint32_t c = 0; c < cells; ++c) at[c + 1] += at[c];
  std::vector<NodeId> entering(at[cells]);
  {
    std::vector<std::uint32_t> next(at.begin(), at.end() - 1);
    for (const NodeId n : t.nodes()) {
      const NodeId parent = t.parent(n);
      if (parent != kRootNode) entering[next[t.cell(parent).value()]++] = n;
    }
  }
  // Row `from`: the rays into each cell `to` it sends rays to, each (from, to) summed in node
  // order, listed by increasing `to`, and the row's total over increasing `to`: the sums a dense
  // cells x cells table would hold, so the shares are the same doubles.
  std::vector<double> sum(cells, 0.0);
  std::vector<std::uint32_t> row_of(cells, std::uint32_t(-1));  // the last row `to` was in
  std::vector<std::uint32_t> tos;
  for (std::uint32_t from = 0; from < cells; ++from) {
    tos.clear();
    for (std::uint32_t k = at[from]; k < at[from + 1]; ++k) {
      const NodeId n = entering[k];
      const std::uint32_t to = t.cell(n).value();
      if (row_of[to] != from) {
        row_of[to] = from;
        sum[to] = 0.0;
        tos.push_back(to);
      }
      sum[to] += double(t.enter(n));
    }
    std::sort(tos.begin(), tos.end());
    for (const std::uint32_t to : tos) s.flow.emplace_back(to, sum[to]);
    s.flow_begin[from + 1] = s.flow_begin[from] + std::uint32_t(tos.size());
  }
  for (std::uint32_t from = 0; from < cells; ++from) {
    const auto row = s.flow.begin() + s.flow_begin[from];
    const auto end = s.flow.begin() + s.flow_begin[from + 1];
    double out = 0.0;
    for (auto it = row; it != end; ++it) out += it->second;
    if (out > 0) {
      for (auto it = row; it != end; ++it) it->second /= out;
    }
  }
  return s;
}

void BalancedScheduler::SetHeights(const FrameInfo& frame) {
  const CellTree& t = *frame.previous;
  PlanCache* cache = frame.plans;
  heights_ = Shared<Heights>(cache, PlanKey(kHeights, {TreeKey(t)}), [&] {
    Heights h;
    // A node's children are numbered after it, so one pass from the last node up.
    h.height.assign(t.size(), 0);
    for (std::size_t i = t.size(); i-- > 1;) {
      const NodeId n(static_cast<std::uint32_t>(i));
      h.height[i] += 1;
      const NodeId parent = t.parent(n);
      h.height[parent.index()] = std::max(h.height[parent.index()], h.height[i]);
    }
    h.stand_in = SharedStandIns(cache, t);
    return h;
  });
  cost_.steps += 2 * t.size();
}

void BalancedScheduler::Arrived(const Arrival& a) {
  if (adaptive_) adaptive_->Arrived(a);
  if (!options_.critical) return;
  cost_.steps += 1;
  if (a.node == match_.size()) {  // first queued: match it
    NodeId m = kNoNode;
    if (previous_ != nullptr) {
      bool stand_in = false;
      m = MatchNode(*previous_, *heights_->stand_in, match_[a.parent], a.parent_cell, a.cell,
                    &stand_in);
    }
    match_.push_back(m);
    cost_.peak_bytes = std::max(cost_.peak_bytes, Bytes());
  }
  RAYCELL_CHECK_LT(a.node, match_.size());
  const NodeId m = match_[a.node];
  if (m != kNoNode && heights_->height[m.index()] > level_[a.cell.value()]) {
    SetLevel(a.cell, heights_->height[m.index()]);
  }
  // Its queued rays grow: a candidate for its level's most queued cell (LevelBest).
  const std::uint32_t l = level_[a.cell.value()];
  if (l > 0 && touched_at_[a.cell.value()] != l) {
    touched_at_[a.cell.value()] = l;
    touched_[l].push_back(a.cell.value());
  }
}

void BalancedScheduler::Taken(CellId cell) {
  if (adaptive_) adaptive_->Taken(cell);
  if (options_.critical) SetLevel(cell, 0);
}

void BalancedScheduler::SetLevel(CellId cell, std::uint32_t level) {
  const std::uint32_t c = cell.value();
  // Level 0 (no queued node) is in no list.
  const auto key = [](std::uint32_t l) { return l > 0 ? l : CellLists::kNone; };
  at_level_.Move(c, key(level_[c]), key(level));
  Forget(cell);
  level_[c] = level;
  if (level >= touched_.size()) {
    touched_.resize(std::size_t{level} + 1);
    level_best_.resize(std::size_t{level} + 1, kUnknownBest);
  }
  top_level_ = std::max(top_level_, level);
  // The highest level with a cell: Critical looks down from it, and levels emptied by takes
  // would otherwise be looked at by every decision until the frame ends.
  while (top_level_ > 0 && at_level_.at(top_level_).empty()) --top_level_;
}

void BalancedScheduler::Forget(CellId cell) {
  const std::uint32_t l = level_[cell.value()];
  if (l > 0 && level_best_[l] == cell.value()) level_best_[l] = kUnknownBest;
}

std::uint32_t BalancedScheduler::LevelBest(std::uint32_t l, const QueueView& queues) const {
  const std::uint64_t* q = queues.queued_rays;
  // Only the board's own view changes as this scheduler is told (a view made otherwise, the
  // model's or a test's, is scanned).
  if (queues.most_of != q) {
    const std::optional<CellId> b = MostQueuedOf(at_level_.at(l), q);
    return b ? b->value() : kNoBest;
  }
  std::uint32_t best = level_best_[l];
  if (best == kUnknownBest) {
    const std::optional<CellId> b = MostQueuedOf(at_level_.at(l), q);
    best = b ? b->value() : kNoBest;
  } else {
    for (const std::uint32_t c : touched_[l]) {
      if (touched_at_[c] != l || level_[c] != l || q[c] == 0) continue;
      if (best == kNoBest || q[c] > q[best] || (q[c] == q[best] && c < best)) best = c;
    }
  }
  for (const std::uint32_t c : touched_[l]) {
    if (touched_at_[c] == l) touched_at_[c] = 0;
  }
  touched_[l].clear();
  level_best_[l] = best;
  return best;
}

std::uint64_t BalancedScheduler::Bytes() const {
  // As a hardware block would keep it: per node of frame i-1's tree its height (4 bytes), per
  // queued node its match and cell (8), per cell its level (4).
  return 4 * std::uint64_t{heights_ ? heights_->height.size() : 0} +
         8 * std::uint64_t{match_.size()} + 4 * std::uint64_t{level_.size()};
}

Scheduler::DecisionCost BalancedScheduler::Cost() const {
  if (adaptive_) return adaptive_->Cost();
  return cost_;
}

std::optional<CellId> BalancedScheduler::Critical(const QueueView& queues,
                                                  std::optional<CellId> plan) const {
  // Counted as the hardware's pass over the cells (docs/design.md §5 "Load balancing").
  cost_.steps += queues.cells;
  // No plan entry: the follower found no cell in view with work (then no cell has a level in
  // view either; with several processors most calls find only busy cells with work).
  if (!plan && queues.empty()) return std::nullopt;
  // The highest level above the plan entry's (above 0 without one) with a cell in view, the
  // most queued rays there (lowest number on ties): what a scan of the cells by level, then
  // queued rays, then number gives, found from the top level down (a scan of the cells each
  // time was the cost of this rule at thousands of cells). A cell of a level has queued nodes;
  // only the busy ones (at most the other processors) have none in view.
  const std::uint32_t lowest = plan ? level_[plan->value()] : 0;
  for (std::uint32_t l = top_level_; l > lowest; --l) {
    // A cell number, not an optional: Critical tries every level down from the top, most
    // of them with no cell in view, and an optional returned there went through the stack
    // as two stores read back as one (a stalled load: 2% of balanced-critical's CPU).
    if (const std::uint32_t best = LevelBest(l, queues); best != kNoBest) return CellId(best);
  }
  // Without a plan entry and no level in view, the most queued cell in view.
  return plan ? std::nullopt : MostQueuedCell(queues);
}

const std::uint64_t* BalancedScheduler::Queued(const QueueView& queues) const {
  return options_.share && queues.all_queued != nullptr ? queues.all_queued : queues.queued_rays;
}

QueueView BalancedScheduler::Own(const QueueView& queues) const {
  if (followers_.size() <= 1) return queues;
  own_.assign(queues.queued_rays, queues.queued_rays + queues.cells);
  for (std::uint32_t c = 0; c < queues.cells; ++c) {
    if (owner_[c] != queues.processor) own_[c] = 0;
  }
  QueueView v = queues;
  v.queued_rays = own_.data();
  return v;
}

std::optional<CellId> BalancedScheduler::BestOfAll(const QueueView& queues,
                                                   const std::uint64_t* queued) const {
  // The scan of Best scores each cell q x (1 + its share) and keeps the first of the highest.
  // Off the loaded cell's row the share is 0 and the score q, so the highest there is the
  // most queued cell (lowest number on ties); that cell's score q is at most its own in the
  // row (shares are >= 0). So the answer is the highest of that cell (at q) and the row's cells
  // (at their scores), the lowest number on ties, as the scan gives it.
  CellId most = kNoCell;
  if (queued == queues.all_queued) {
    most = MostQueuedAll(queues);
  } else if (queued == queues.queued_rays) {
    most = MostQueuedCell(queues).value_or(kNoCell);
  } else {
    most = ScanMostQueued(queued, queues.cells);
  }
  if (most == kNoCell) return std::nullopt;
  CellId best = most;
  double best_score = double(queued[most.value()]);
  if (options_.affinity && stats_ && queues.loaded && queues.loaded->value() < cells_) {
    const auto* flow = stats_->flow.data() + stats_->flow_begin[queues.loaded->value()];
    const auto* flow_end = stats_->flow.data() + stats_->flow_begin[queues.loaded->value() + 1];
    for (; flow != flow_end && flow->first < queues.cells; ++flow) {
      const std::uint64_t q = queued[flow->first];
      if (q == 0) continue;
      const double score = double(q) * (1.0 + flow->second);
      if (score > best_score || (score == best_score && flow->first < best.value())) {
        best = CellId(flow->first), best_score = score;
      }
    }
  }
  return best;
}

template <typename Take>
std::optional<CellId> BalancedScheduler::Best(const QueueView& queues, const std::uint64_t* queued,
                                              Take take) const {
  // The loaded cell's row of shares (empty: no affinity), read in step with c.
  const std::pair<std::uint32_t, double>* flow = nullptr;
  const std::pair<std::uint32_t, double>* flow_end = nullptr;
  if (options_.affinity && stats_ && queues.loaded && queues.loaded->value() < cells_) {
    flow = stats_->flow.data() + stats_->flow_begin[queues.loaded->value()];
    flow_end = stats_->flow.data() + stats_->flow_begin[queues.loaded->value() + 1];
  }
  std::optional<CellId> best;
  double best_score = 0;
  for (std::uint32_t c = 0; c < queues.cells; ++c) {
    const std::uint64_t q = queued[c];
    if (q == 0 || !take(c)) continue;
    while (flow != flow_end && flow->first < c) ++flow;
    const double share = flow != flow_end && flow->first == c ? flow->second : 0.0;
    const double score = double(q) * (1.0 + share);
    if (!best || score > best_score) best = CellId(c), best_score = score;
  }
  return best;
}

std::optional<CellId> BalancedScheduler::Choose(const QueueView& queues,
                                                ScheduleFollower** follower, bool* adaptive,
                                                bool* critical) const {
  *follower = nullptr;
  *adaptive = false;
  *critical = false;
  // Affinity: the cell in the processor's cache, when it has work, costs no fetch.
  if (options_.affinity && queues.loaded) {
    if (Queued(queues)[queues.loaded->value()] > 0) return queues.loaded;
  }
  const std::uint32_t k =
      followers_.size() > 1 ? std::min<std::uint32_t>(queues.processor, followers_.size() - 1) : 0;
  const QueueView own = Own(queues);
  const auto mine = [&](std::uint32_t c) { return followers_.size() <= 1 || owner_[c] == k; };
  if (adaptive_) {
    // The adaptive rule's choice among the cells in view.
    if (const std::optional<CellId> c = adaptive_->Peek(queues)) {
      *adaptive = true;
      return c;
    }
  } else if (options_.plan) {
    // Follower k's next entry with work in view, or Max Work over k's cells.
    const std::optional<CellId> c = followers_[k].Peek(own);
    if (options_.critical && processors_ > 1 && previous_ != nullptr) {
      if (const std::optional<CellId> first = Critical(queues, c)) {
        *critical = true;
        return first;
      }
    }
    if (c) {
      *follower = const_cast<ScheduleFollower*>(&followers_[k]);
      return c;
    }
  } else if (const std::optional<CellId> c = Best(queues, queues.queued_rays, mine)) {
    return c;
  }
  if (options_.steal && followers_.size() > 1) {
    // The processor with the most queued rays gives up its largest queue.
    std::vector<std::uint64_t> load(followers_.size(), 0);
    for (std::uint32_t c = 0; c < queues.cells; ++c) load[owner_[c]] += queues.queued_rays[c];
    load[k] = 0;
    const std::uint32_t victim =
        std::uint32_t(std::max_element(load.begin(), load.end()) - load.begin());
    if (load[victim] > 0) {
      return Best(queues, queues.queued_rays, [&](std::uint32_t c) { return owner_[c] == victim; });
    }
  }
  // Sharing: busy cells' queues count too (the processor joins the cell).
  return BestOfAll(queues, Queued(queues));
}

bool BalancedScheduler::TooSmall(const QueueView& queues, CellId c) const {
  const double per_visit = stats_->samples_per_visit[c.value()];
  if (fetch_samples_ == nullptr || per_visit <= 0) return false;
  if (queues.loaded == c) return false;  // in the cache: no fetch
  const double work = double(Queued(queues)[c.value()]) * per_visit;
  return work < kPostponeFactor * (*fetch_samples_)[c.value()];
}

bool BalancedScheduler::NoWork(const QueueView& queues) const {
  if (!queues.empty()) return false;
  if (!options_.share || queues.all_queued == nullptr) return true;
  return MostQueuedAll(queues) == kNoCell;
}

std::optional<CellId> BalancedScheduler::Peek(const QueueView& queues) const {
  if (NoWork(queues)) return std::nullopt;
  ScheduleFollower* follower = nullptr;
  bool adaptive = false, critical = false;
  return Choose(queues, &follower, &adaptive, &critical);
}

std::optional<CellId> BalancedScheduler::Next(const QueueView& queues) {
  if (NoWork(queues)) return std::nullopt;
  ScheduleFollower* follower = nullptr;
  bool adaptive = false, critical = false;
  std::optional<CellId> c = Choose(queues, &follower, &adaptive, &critical);
  RAYCELL_CHECK(c.has_value());
  why_ = critical ? Why::kCritical : Why::kMaxWork;
  // Postpone only while every other processor is working (at most one waits by choice), and
  // only on boards of kPostponeMinProcessors or more, where one waiting processor is a small
  // part of the whole.
  if (options_.postpone && processors_ >= kPostponeMinProcessors &&
      queues.working + 1 >= processors_ && TooSmall(queues, *c)) {
    const std::optional<CellId> largest = BestOfAll(queues, Queued(queues));
    if (largest && !TooSmall(queues, *largest)) {
      why_ = Why::kPlanSmall;
      Locked(*largest);
      return largest;  // the plan keeps its place
    }
    why_ = Why::kNone;
    return std::nullopt;  // postponed: wait for released work
  }
  // A join (a busy cell: its holder takes released work when its worklist runs out) costs a
  // fetch for at most the rays queued there; too few, and the largest batch worth a fetch is
  // taken instead, or the processor waits (the holder is working, so the replay progresses).
  if (options_.postpone && queues.busy(*c) && TooSmall(queues, *c)) {
    const std::optional<CellId> largest =
        Best(queues, Queued(queues), [&](std::uint32_t x) { return !TooSmall(queues, CellId(x)); });
    if (largest) {
      why_ = Why::kJoinSmall;
      Locked(*largest);
      return largest;
    }
    why_ = Why::kNone;
    return std::nullopt;
  }
  if (options_.critical) ++cost_.decisions;
  if (adaptive) {
    // The rule decides now (it may plan the rest again when its plan is used up, and then
    // choose otherwise than it peeked): its choice is taken.
    c = adaptive_->Next(queues);
    RAYCELL_CHECK(c.has_value());
    why_ = Why::kAdaptive;
  } else if (follower) {
    const std::optional<CellId> taken = follower->Next(Own(queues));
    RAYCELL_CHECK(taken == c);
    why_ = Why::kFollower;
    why_follower_ = follower;
  }
  Locked(*c);
  return c;
}

std::string BalancedScheduler::Reason() const {
  switch (why_) {
    case Why::kFollower:
      return why_follower_->Reason();
    case Why::kAdaptive:
      return adaptive_->Reason();
    case Why::kCritical:
      return "critical path first";
    case Why::kMaxWork:
      return "max work";
    case Why::kPlanSmall:
      return "largest (plan's batch too small)";
    case Why::kJoinSmall:
      return "largest (join too small)";
    case Why::kNone:
      break;
  }
  return {};
}

}  // namespace raycell
