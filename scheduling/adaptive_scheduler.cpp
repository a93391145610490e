#include "scheduling/adaptive_scheduler.h"

#include <algorithm>

#include "base/check.h"
#include "base/kept_room.h"
#include "graph/peel.h"
#include "scheduling/best_scheduler.h"

namespace raycell {

constexpr SchedulerEntry kCellTreeAdaptiveEntry = [] {
  SchedulerEntry e;
  e.name = "celltree-adaptive";
  e.meaning =
      "celltree-union (one processor: celltree-best) followed node by node as the frame "
      "unfolds: work waits for the entry its predicted node is due at, work the plan is done "
      "with is fetched at once (while such fetches are no more than the plan's), and the rest is "
      "planned again by Peel when the plan runs out";
  e.label = "Cell Tree, adaptive";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<AdaptiveScheduler>(seed);
  };
  e.history = 2;
  e.seeded = true;
  return e;
}();

StandIns StandInsOf(const CellTree& tree) {
  StandIns s;
  for (NodeId n : tree.nodes()) {
    const NodeId parent = tree.parent(n);
    s.try_emplace(StandInKey(parent == kRootNode ? kNoCell : tree.cell(parent), tree.cell(n)), n);
  }
  return s;
}

std::shared_ptr<const StandIns> SharedStandIns(PlanCache* cache, const CellTree& tree) {
  return Shared<StandIns>(cache, PlanKey(kStandIns, {TreeKey(tree)}),
                          [&] { return StandInsOf(tree); });
}

NodeId MatchNode(const CellTree& tree, const StandIns& stand_ins, NodeId parent, CellId parent_cell,
                 CellId cell, bool* stand_in) {
  if (parent != kNoNode) {
    const NodeId m = tree.FindChild(parent, cell);
    if (m != kNoNode) return m;
  }
  *stand_in = true;
  const auto it = stand_ins.find(StandInKey(parent_cell, cell));
  return it == stand_ins.end() ? kNoNode : it->second;
}

bool AdaptiveScheduler::PredictsByUnion(const FrameInfo& frame) {
  return frame.processors > 1 && frame.previous != nullptr && frame.before_previous != nullptr;
}

bool AdaptiveScheduler::Prepare(const FrameInfo& frame) {
  if (!PredictsByUnion(frame)) return false;  // one processor plans from frame i-1's tree itself
  SharedUnion(frame.plans, *frame.before_previous, *frame.previous);
  return true;
}

void AdaptiveScheduler::BeginFrame(const FrameInfo& frame) {
  cells_ = frame.cells;
  // The last frame's per-node state freed before this frame's union and plan are made (issue
  // 43; assign would keep its capacity).
  own_.reset();
  own_start_.reset();
  start_bytes_ = 0;
  due_ = nullptr;
  FreeRoom(own_due_);
  FreeRoom(match_);
  FreeRoom(guess_);
  FreeRoom(depth_);
  predicted_ = frame.previous;
  one_processor_ = frame.processors <= 1;
  // Several processors predict by the union of frames i-2 and i-1, one by frame i-1 alone
  // (docs/design.md §5 "Adaptive scheduling" has the measurements).
  if (PredictsByUnion(frame)) {
    std::shared_ptr<const CellTree> both =
        SharedUnion(frame.plans, *frame.before_previous, *frame.previous);
    predicted_ = both.get();
    // Held here, not by the frame's plan cache, which the runner frees once every
    // configuration of the frame began: it goes with this scheduler (the runner makes a fresh
    // one after each frame's replay) or at the next BeginFrame.
    own_ = std::move(both);
  }
  reads_previous_ = predicted_ != nullptr && predicted_ == frame.previous;
  match_.assign(1, predicted_ != nullptr ? kRootNode : kNoNode);
  guess_.assign(1, false);
  queued_.assign(cells_, {});
  kept_room_ = KeptRoom(kKeptRoomBytes, sizeof(std::uint32_t), cells_, 16, std::size_t{1} << 16);
  min_due_.assign(cells_, kNever);
  depth_.assign(1, 0);
  min_depth_.assign(cells_, kNever);
  at_depth_.Reset(cells_);
  low_depth_ = 0;
  done_cells_.clear();
  told_.assign(cells_, 0);
  orphans_.clear();
  touched_.clear();
  touched_at_.assign(cells_, 0);
  replans_ = 0;
  plan_fetches_ = orphan_fetches_ = 0;
  last_how_ = 0;
  cost_ = {};
  stand_in_.reset();
  plan_.clear();
  used_.Reset(0);
  cursor_ = 0;
  if (predicted_ == nullptr) return;
  const CellTree& t = *predicted_;
  stand_in_ = SharedStandIns(frame.plans, t);
  cost_.steps += t.size();
  // The plan and its run on the predicted tree: the same for every configuration of the frame.
  struct Start {
    std::shared_ptr<const std::vector<CellId>> plan;
    std::vector<std::uint32_t> due;
    std::uint64_t steps = 0;
  };
  const std::uint32_t cells = cells_;
  const std::uint64_t seed = seed_;
  const std::shared_ptr<const Start> start =
      Shared<Start>(frame.plans, PlanKey(kAdaptiveStart, {TreeKey(t), seed, cells}), [&] {
        Start s;
        s.plan = SharedPlan(frame.plans, t, seed);
        s.due = DueOf(*s.plan, &t, nullptr, t.size(), cells, &s.steps);
        return s;
      });
  cost_.steps += start->steps;
  own_start_ = start;  // held as the union is
  start_bytes_ = 4 * (start->due.capacity() + start->plan->capacity());
  Install(*start->plan, &start->due);
}

std::vector<std::uint32_t> AdaptiveScheduler::DueOf(const std::vector<CellId>& plan,
                                                    const CellTree* planned,
                                                    const std::vector<NodeId>* nodes,
                                                    std::size_t predicted, std::uint32_t cells,
                                                    std::uint64_t* steps) {
  std::vector<std::uint32_t> due(predicted, kNever);
  if (planned != nullptr) {
    // The run of docs/design.md §1 on `planned`: each entry processes every node of its cell
    // whose parent is done.
    const CellTree& f = *planned;
    std::vector<std::vector<NodeId>> ready(cells);
    for (NodeId c = f.first_child(kRootNode); c != kNoNode; c = f.next_sibling(c)) {
      ready[f.cell(c).value()].push_back(c);
    }
    for (std::size_t i = 0; i < plan.size(); ++i) {
      std::vector<NodeId> now;
      now.swap(ready[plan[i].value()]);
      for (NodeId n : now) {
        due[nodes == nullptr ? n.index() : (*nodes)[n.index() - 1].index()] = std::uint32_t(i);
        for (NodeId c = f.first_child(n); c != kNoNode; c = f.next_sibling(c)) {
          ready[f.cell(c).value()].push_back(c);
        }
      }
      *steps += 1 + now.size();
    }
  }
  return due;
}

void AdaptiveScheduler::SetPlan(std::vector<CellId> plan, const CellTree* planned,
                                const std::vector<NodeId>* nodes) {
  FreeRoom(own_due_);  // the last re-plan's, freed first
  own_due_ = DueOf(plan, planned, nodes, predicted_->size(), cells_, &cost_.steps);
  Install(std::move(plan), &own_due_);
}

void AdaptiveScheduler::Install(std::vector<CellId> plan, const std::vector<std::uint32_t>* due) {
  due_ = due;
  plan_ = std::move(plan);
  used_.Reset(plan_.size());
  cursor_ = 0;
  remaining_.assign(cells_, 0);
  for (CellId c : plan_) ++remaining_[c.value()];
  done_cells_.clear();
  for (std::uint32_t c = 0; c < cells_; ++c) {
    if (remaining_[c] == 0) done_cells_.push_back(c);
  }
  for (std::uint32_t c = 0; c < cells_; ++c) RecomputeDue(CellId(c));
  RebuildOrphans();
  CountBytes();
}

namespace {
// Whether orphan key a comes after b: the least depth, then the most rays, then the lowest cell
// first (a max-heap under this order has the first orphan on top).
template <typename Key>
bool After(const Key& a, const Key& b) {
  if (a.depth != b.depth) return a.depth > b.depth;
  if (a.rays != b.rays) return a.rays < b.rays;
  return a.cell > b.cell;
}
}  // namespace

bool AdaptiveScheduler::Stale(const OrphanKey& k) const {
  const OrphanKey now = KeyOf(k.cell);
  return remaining_[k.cell] != 0 || now.rays == 0 || now.rays != k.rays || now.depth != k.depth;
}

void AdaptiveScheduler::Touch(std::uint32_t c) {
  if (touched_at_[c] != 0 || remaining_[c] != 0) return;
  touched_at_[c] = 1;
  touched_.push_back(c);
}

void AdaptiveScheduler::PushOrphan(std::uint32_t c) const {
  if (remaining_[c] != 0 || told_[c] == 0) return;
  if (orphans_.size() >= 2 * std::size_t{cells_} + 64) {
    RebuildOrphans();  // pushes c's key too
    return;
  }
  orphans_.push_back(KeyOf(c));
  std::push_heap(orphans_.begin(), orphans_.end(), After<OrphanKey>);
}

void AdaptiveScheduler::RebuildOrphans() const {
  // (Cells touched stay listed: their keys pushed again at the next look are duplicates.)
  orphans_.clear();
  for (const std::uint32_t c : done_cells_) {
    if (told_[c] > 0) orphans_.push_back(KeyOf(c));
  }
  std::make_heap(orphans_.begin(), orphans_.end(), After<OrphanKey>);
}

std::optional<CellId> AdaptiveScheduler::TopOrphan(const QueueView& queues) const {
  // The cells touched since the last look, each pushed once with its key now.
  for (const std::uint32_t c : touched_) {
    touched_at_[c] = 0;
    PushOrphan(c);
  }
  touched_.clear();
  std::optional<CellId> found;
  std::vector<OrphanKey>& busy = passed_;  // passed over: at most the other processors' cells
  busy.clear();
  while (!orphans_.empty()) {
    const OrphanKey k = orphans_.front();
    std::pop_heap(orphans_.begin(), orphans_.end(), After<OrphanKey>);
    orphans_.pop_back();
    if (Stale(k)) continue;
    busy.push_back(k);  // kept, found or not
    if (queues.queued(CellId(k.cell)) > 0) {
      found = CellId(k.cell);
      break;
    }
  }
  for (const OrphanKey& k : busy) {
    orphans_.push_back(k);
    std::push_heap(orphans_.begin(), orphans_.end(), After<OrphanKey>);
  }
  return found;
}

void AdaptiveScheduler::RecomputeDue(CellId c) {
  std::uint32_t d = kNever;
  for (std::uint32_t r : queued_[c.value()]) {
    const NodeId m = match_[r];
    d = std::min(d, m == kNoNode ? 0 : (*due_)[m.index()] == kNever ? 0 : (*due_)[m.index()]);
  }
  min_due_[c.value()] = d;
  cost_.steps += queued_[c.value()].size();
}

std::uint64_t AdaptiveScheduler::HeldBytes() const {
  return (own_ ? own_->Bytes() : 0) + start_bytes_;
}

void AdaptiveScheduler::Arrived(const Arrival& a) {
  cost_.steps += 1;
  if (a.node == match_.size()) {  // first queued: match it
    NodeId m = kNoNode;
    bool guess = guess_[a.parent];  // a match below a stand-in is a guess too
    if (predicted_ != nullptr) {
      bool stand_in = false;
      m = MatchNode(*predicted_, *stand_in_, match_[a.parent], a.parent_cell, a.cell, &stand_in);
      guess = guess || stand_in;
    }
    guess_.push_back(guess);
    // Depths for Shallowest (no prediction) and the one-processor orphans (ShallowestOrphan).
    if (KeepsDepths()) depth_.push_back(depth_[a.parent] + 1);
    match_.push_back(m);
  }
  RAYCELL_CHECK_LT(a.node, match_.size());
  queued_[a.cell.value()].push_back(a.node);
  told_[a.cell.value()] += a.rays;
  const NodeId m = match_[a.node];
  const std::uint32_t d =
      m == kNoNode || due_ == nullptr || (*due_)[m.index()] == kNever ? 0 : (*due_)[m.index()];
  min_due_[a.cell.value()] = std::min(min_due_[a.cell.value()], d);
  if (KeepsDepths() && depth_[a.node] < min_depth_[a.cell.value()]) {
    SetMinDepth(a.cell, depth_[a.node]);
  }
  if (predicted_ != nullptr) Touch(a.cell.value());
}

void AdaptiveScheduler::Taken(CellId cell) {
  queued_[cell.value()].clear();
  ReleaseRoomAbove(queued_[cell.value()], kept_room_);
  told_[cell.value()] = 0;
  min_due_[cell.value()] = kNever;
  SetMinDepth(cell, kNever);
}

void AdaptiveScheduler::SetMinDepth(CellId cell, std::uint32_t depth) {
  static_assert(kNever == CellLists::kNone, "kNever is in no list");
  const std::uint32_t c = cell.value();
  at_depth_.Move(c, min_depth_[c], depth);
  min_depth_[c] = depth;
  if (depth != kNever) low_depth_ = std::min(low_depth_, depth);
  while (low_depth_ < at_depth_.keys() && at_depth_.at(low_depth_).empty()) ++low_depth_;
}

std::uint32_t AdaptiveScheduler::DueAt(CellId c) const {
  // Work with no queued node known (a replay that does not tell) is due now.
  return min_due_[c.value()] == kNever ? 0 : min_due_[c.value()];
}

std::size_t AdaptiveScheduler::Find(const QueueView& queues) const {
  // Entries used up are passed without a look (UnusedEntries); each entry looked at is a step.
  for (std::size_t i = used_.From(cursor_); i < plan_.size(); i = used_.From(i + 1)) {
    ++cost_.steps;
    if (queues.has_work(plan_[i]) && DueAt(plan_[i]) <= i) return i;
  }
  return plan_.size();
}

bool AdaptiveScheduler::PlanAgain(const QueueView& queues) {
  if (predicted_ == nullptr) return false;
  // The forest: the queued nodes' matches and their predicted subtrees.
  const CellTree& t = *predicted_;
  std::vector<bool> in(t.size(), false);
  std::vector<NodeId> stack;
  std::vector<bool> outside(cells_, false);  // cells with work outside the forest
  for (std::uint32_t c = 0; c < cells_; ++c) {
    for (std::uint32_t r : queued_[c]) {
      const NodeId m = match_[r];
      if (m == kNoNode || guess_[r]) {  // a guessed subtree is not worth planning for
        outside[c] = true;
      } else if (!in[m.index()]) {
        in[m.index()] = true;
        stack.push_back(m);
      }
    }
    if (queued_[c].empty() && queues.has_work(CellId(c))) outside[c] = true;
  }
  while (!stack.empty()) {
    const NodeId n = stack.back();
    stack.pop_back();
    ++cost_.steps;
    for (NodeId c = t.first_child(n); c != kNoNode; c = t.next_sibling(c)) {
      if (!in[c.index()]) {
        in[c.index()] = true;
        stack.push_back(c);
      }
    }
  }
  std::vector<NodeId> nodes;
  for (NodeId n : t.nodes()) {
    if (in[n.index()]) nodes.push_back(n);
  }
  std::vector<CellId> plan;
  std::optional<CellTree> forest;
  if (!nodes.empty()) {
    forest = SubTree(t, nodes);
    plan = Peel(*forest).schedule;
    cost_.steps += forest->size();
  }
  for (std::uint32_t c = 0; c < cells_; ++c) {
    if (outside[c]) plan.push_back(CellId(c));
  }
  if (plan.empty()) return false;
  ++replans_;
  SetPlan(std::move(plan), forest ? &*forest : nullptr, &nodes);
  return true;
}

std::optional<CellId> AdaptiveScheduler::Next(const QueueView& queues) {
  if (queues.empty()) {
    last_how_ = 0;
    return std::nullopt;
  }
  ++cost_.decisions;
  if (predicted_ == nullptr) {  // no earlier frame
    last_how_ = 5;
    return Shallowest(queues);
  }
  // An orphan first: work in a cell that no entry left in the plan fetches, while orphans have
  // taken no more of the frame's fetches than the plan has (OrphansFirst).
  if (OrphansFirst()) {
    if (const std::optional<CellId> orphan = Orphan(queues)) {
      last_how_ = 4;
      ++orphan_fetches_;
      return orphan;
    }
  }
  last_how_ = 1;
  std::size_t found = Find(queues);
  if (found == plan_.size() && PlanAgain(queues)) {
    last_how_ = 2;
    found = Find(queues);
  }
  // Entries before the one taken: used up, unless another processor works their cell.
  for (std::size_t i = used_.From(cursor_); i < found; i = used_.From(i + 1)) {
    if (!queues.busy(plan_[i])) Use(i);
  }
  if (found < plan_.size()) Use(found);
  cursor_ = used_.From(cursor_);
  if (found < plan_.size()) {
    ++plan_fetches_;
    return plan_[found];
  }
  last_how_ = 3;
  return MostQueuedCell(queues);
}

std::optional<CellId> AdaptiveScheduler::Shallowest(const QueueView& queues) const {
  // Counted as the hardware's pass over the cells.
  cost_.steps += cells_;
  // The loop below's answer from the shallowest lists up: the first depth with a cell in view,
  // the most queued rays there (lowest number on ties). Only a cell with work of no known node
  // (none in a replay, which tells every node) is in no list: then the loop.
  for (std::uint32_t d = low_depth_; d < at_depth_.keys(); ++d) {
    if (const std::optional<CellId> best = MostQueuedOf(at_depth_.at(d), queues.queued_rays)) {
      return best;
    }
  }
  std::optional<CellId> best;
  for (std::uint32_t c = 0; c < cells_; ++c) {
    const std::uint64_t q = queues.queued(CellId(c));
    if (q == 0) continue;
    if (!best || min_depth_[c] < min_depth_[best->value()] ||
        (min_depth_[c] == min_depth_[best->value()] && q > queues.queued(*best))) {
      best = CellId(c);
    }
  }
  return best;
}

void AdaptiveScheduler::Use(std::size_t i) {
  used_.Use(i);
  if (--remaining_[plan_[i].value()] == 0) {
    done_cells_.push_back(plan_[i].value());
    Touch(plan_[i].value());
  }
}

std::optional<CellId> AdaptiveScheduler::Orphan(const QueueView& queues) const {
  if (cursor_ == plan_.size()) return std::nullopt;  // the plan is used up: planned again
  // Counted as the hardware's mask of the cells with work and no entry left.
  cost_.steps += cells_;
  // The board's own view shows every free cell's told rays: the heap answers (the loops below
  // are its reference, for any other view).
  const bool own_view = queues.most_of != nullptr && queues.most_of == queues.queued_rays;
  if (one_processor_) return own_view ? TopOrphan(queues) : ShallowestOrphan(queues);
  // Several processors: the most queued cell in view with no entry left (lowest number on ties):
  // the most queued of all when the plan is done with it (the replay keeps it,
  // QueueView::most), else the most queued of the cells the plan is done with.
  const std::optional<CellId> top = MostQueuedCell(queues);
  if (!top) return std::nullopt;
  if (top->value() < cells_ && remaining_[top->value()] == 0) return top;
  if (own_view) return TopOrphan(queues);
  std::optional<CellId> orphan;
  std::uint64_t most = 0;
  for (const std::uint32_t c : done_cells_) {
    const std::uint64_t q = queues.queued(CellId(c));
    if (q > most || (q == most && q > 0 && c < orphan->value())) {
      most = q;
      orphan = CellId(c);
    }
  }
  return orphan;
}

std::optional<CellId> AdaptiveScheduler::ShallowestOrphan(const QueueView& queues) const {
  std::optional<CellId> orphan;
  for (const std::uint32_t c : done_cells_) {
    const std::uint64_t q = queues.queued_rays[c];
    if (q == 0) continue;
    const std::uint32_t o = orphan ? orphan->value() : c;
    if (!orphan || min_depth_[c] < min_depth_[o] ||
        (min_depth_[c] == min_depth_[o] &&
         (q > queues.queued_rays[o] || (q == queues.queued_rays[o] && c < o)))) {
      orphan = CellId(c);
    }
  }
  return orphan;
}

std::optional<CellId> AdaptiveScheduler::Peek(const QueueView& queues) const {
  if (predicted_ == nullptr) return Shallowest(queues);
  if (OrphansFirst()) {
    if (const std::optional<CellId> orphan = Orphan(queues)) return orphan;
  }
  const std::size_t i = Find(queues);
  return i < plan_.size() ? std::optional<CellId>(plan_[i]) : MostQueuedCell(queues);
}

std::string AdaptiveScheduler::Reason() const {
  switch (last_how_) {
    case 1:
      return "followed";
    case 2:
      return "re-planned";
    case 3:
      return "max work";
    case 5:
      return "shallowest first (no earlier frame)";
    case 4:
      return "orphan";
    default:
      return {};
  }
}

std::uint64_t AdaptiveScheduler::StateBytes() const {
  // What a hardware block would keep: per predicted node its cell, parent and due entry (12
  // bytes); per queued node its match, cell and depth (12); per plan entry its cell (4); per
  // entry of a cell's list of queued nodes 4.
  std::uint64_t queued = 0;
  for (const auto& q : queued_) queued += q.size();
  return 12 * std::uint64_t(predicted_ ? predicted_->size() : 0) +
         12 * std::uint64_t(match_.size()) + 4 * std::uint64_t(plan_.size()) + 4 * queued;
}

void AdaptiveScheduler::CountBytes() {
  cost_.peak_bytes = std::max(cost_.peak_bytes, StateBytes());
}

Scheduler::DecisionCost AdaptiveScheduler::Cost() const {
  DecisionCost c = cost_;
  c.peak_bytes = std::max(c.peak_bytes, StateBytes());
  return c;
}

}  // namespace raycell
