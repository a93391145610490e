#include "replay/replayer.h"

#include <algorithm>
#include <memory>
#include <sstream>

#include "base/check.h"
#include "base/checked.h"
#include "base/kept_room.h"
#include "base/mapped_array.h"
#include "engine/slot_queue.h"
#include "engine/watchdog.h"
#include "replay/time_bound.h"
#include "scheduling/plan_cache.h"

namespace raycell {

// The queues' and worklists' arrays (base/mapped_array.h).
template <typename T>
using ItemVector = MappedArray<T>;
namespace {

// ---- Units ----------------------------------------------------------------------------
// Queues and worklists hold entries, one per unit, carrying what working the unit reads:
// its samples and where its successors are. For the packed breadth-first records (the usual
// case) an entry copies them from the unit's record when its predecessor releases it (that
// record is then in cache, being read for the unit's cell), so working a unit reads only
// its successors' records, which lie together: one cache miss per unit, not three. Without
// packed records (values beyond 32 bits), an entry is the unit id and the columns are read.
// Either way ForEachChild(e, f) calls f(child entry, child's cell, child's queued rays) in the
// work graph's successor order.

struct PackedUnits {
  struct Entry {
    std::uint32_t first_child, end_child, samples;
  };
  const WorkGraph::Packed* p;
  UnitId roots;

  Entry MakeEntry(UnitId x) const { return {p[x].first_child, p[x + 1].first_child, p[x].samples}; }
  template <typename F>
  void ForEachRoot(F f) const {
    for (UnitId x = 0; x < roots; ++x) {
      f(MakeEntry(x), p[x].cell, std::uint64_t{p[x].queued_rays});
    }
  }
  template <typename F>
  void ForEachChild(const Entry& e, F f) const {
    for (UnitId x = e.first_child; x < e.end_child; ++x) {
      f(MakeEntry(x), p[x].cell, std::uint64_t{p[x].queued_rays});
    }
  }
  std::uint64_t samples(const Entry& e) const { return e.samples; }
  // Starts loading the successors' records of a unit about to be worked.
  void Prefetch(const Entry& e) const { __builtin_prefetch(p + e.first_child); }
};

struct ColumnUnits {
  using Entry = UnitId;
  const WorkGraph* w;

  template <typename F>
  void ForEachRoot(F f) const {
    for (UnitId u : w->roots) f(u, w->cell[u], w->queued_rays[u]);
  }
  template <typename F>
  void ForEachChild(UnitId u, F f) const {
    for (UnitId i = w->succ_begin[u]; i < w->succ_begin[u + 1]; ++i) {
      const UnitId s = w->succ[i];
      f(s, w->cell[s], w->queued_rays[s]);
    }
  }
  std::uint64_t samples(UnitId u) const { return w->samples[u]; }
  void Prefetch(UnitId) const {}
};

// The Compact form (work.h): a unit is its record's offset in the stream, its visit's
// number and a cursor into the spawned rays; what it holds is decoded from the stream when
// it is released (its cell) and worked (its samples). Slower than the packed records, but
// about 3 bytes a visit instead of 16 plus the columns.
struct CompactUnits {
  using Entry = WorkGraph::CompactUnit;
  const std::uint8_t* stream;
  const WorkGraph::Compact* c;

  std::uint32_t Read(std::uint32_t* at) const { return ReadVarint(stream, at); }
  CellId CellAt(std::uint32_t offset) const { return CellId(Read(&offset) >> 1); }

  template <typename F>
  void ForEachRoot(F f) const {
    for (const Entry& e : c->roots) f(e, CellAt(e.offset), std::uint64_t{1});
  }
  template <typename F>
  void ForEachChild(const Entry& e, F f) const {
    std::uint32_t at = e.offset;
    const bool last = (Read(&at) & 1) != 0;
    Read(&at);  // samples
    const WorkGraph::Spawned* s = c->spawned.data();
    const std::uint32_t n = std::uint32_t(c->spawned.size());
    std::uint32_t end = e.spawned;
    while (end < n && s[end].at == e.offset) ++end;
    if (!last) f(Entry{at, end}, CellAt(at), std::uint64_t{1});
    for (std::uint32_t k = e.spawned; k < end; ++k) {
      f(s[k].unit, CellAt(s[k].unit.offset), std::uint64_t{0});
    }
  }
  std::uint64_t samples(const Entry& e) const {
    std::uint32_t at = e.offset;
    Read(&at);
    return Read(&at);
  }
  void Prefetch(const Entry& e) const {
    __builtin_prefetch(stream + e.offset);
    __builtin_prefetch(c->spawned.data() + e.spawned);
  }
};

// ---- Paths, for schedulers that watch the frame unfold ---------------------------------
// What the board tells a scheduler that watches (Scheduler::Arrived, Taken). The board is a
// template on it: NoWatch, for every other scheduler, is empty and does nothing, and its queued
// items are the units' entries alone, so that their replay core is the same code as if
// watching did not exist.
struct NoWatch {
  template <typename Entry>
  struct Item {
    Entry e;
  };
  template <typename Entry>
  Item<Entry> Root(const Entry& e, CellId) {
    return {e};
  }
  template <typename Entry>
  Item<Entry> Child(const Item<Entry>&, CellId, const Entry& e, CellId) {
    return {e};
  }
  template <typename I>
  void Queued(const I&, CellId, std::uint64_t) {}
  void Taken(CellId) {}
};

// Each queued unit carries its Cell Tree node, named by its path: a unit in its predecessor's
// cell (a spawned ray's first visit) is in the predecessor's node, any other in the child of
// that node for its cell (docs/design.md §1 "Cell Tree"). The path is found when the unit is
// released, from its predecessor's (in hand then) and its cell: the predecessor's path's child
// for that cell, among its children kept most recently used first (ChildOf). A path is numbered
// when it is first met, 1, 2, ... (0 the root); only a unit entering another cell makes one, and it
// is queued at once, so the numbers are the order in which paths are first queued, as a scheduler
// is told them (Scheduler::Arrival). Work per node (WorkGraph::per_node) needs no lookup: each
// unit is a node of its own. Before (issue 43), a pass over the frame's units gave every unit
// its path in a table of 4 bytes a unit, read back when the unit was queued: a cache miss per
// unit, 180 MB and 13% of a watching replay's CPU at 1920x1080 and 4096 cells.
class Watch {
 public:
  template <typename Entry>
  struct Item {
    Entry e;
    std::uint32_t path;
  };

  // per_node: each unit is a node of its own (WorkGraph::per_node), so it makes a path, in the
  // order it is queued, without a lookup.
  Watch(Scheduler& scheduler, bool per_node, std::uint32_t cells)
      : scheduler_(&scheduler), per_node_(per_node), root_child_(per_node ? 0 : cells, 0) {
    parent_.push_back(0);
    if (per_node_) {
      node_cell_.push_back(kNoCell);
    } else {
      links_.push_back(Links{});
    }
  }

  template <typename Entry>
  Item<Entry> Root(const Entry& e, CellId c) {
    if (per_node_) return {e, NewNodePath(0, c)};
    std::uint32_t& k = root_child_[c.value()];
    if (k == 0) k = NewPath(0, c);
    return {e, k};
  }
  // A successor `e`, in cell c, of `from`, worked in `cell`.
  template <typename Entry>
  Item<Entry> Child(const Item<Entry>& from, CellId cell, const Entry& e, CellId c) {
    if (c != cell) return {e, per_node_ ? NewNodePath(from.path, c) : ChildOf(from.path, c)};
    RAYCELL_CHECK(!per_node_);  // a node's children lie in other cells than its own
    return {e, from.path};
  }
  template <typename I>
  void Queued(const I& item, CellId c, std::uint64_t q) {
    const std::uint32_t parent = parent_[item.path];
    scheduler_->Arrived({item.path, parent, c, q, CellOf(parent)});
  }
  void Taken(CellId c) { scheduler_->Taken(c); }

 private:
  // A path's cell and its children: `child` the child used last (0: none), whose `sibling` is
  // the one used before it, and so on (most recently used first).
  struct Links {
    std::uint32_t cell = 0, child = 0, sibling = 0;
  };

  std::uint32_t NewPath(std::uint32_t parent) {
    RAYCELL_CHECK_LT(parent_.size(), std::size_t{UINT32_MAX});
    parent_.push_back(parent);
    return std::uint32_t(parent_.size() - 1);
  }
  std::uint32_t NewPath(std::uint32_t parent, CellId c) {
    const std::uint32_t id = NewPath(parent);
    links_.push_back({c.value(), 0, 0});
    return id;
  }
  // Per node: a path and its cell.
  std::uint32_t NewNodePath(std::uint32_t parent, CellId c) {
    node_cell_.push_back(c);
    return NewPath(parent);
  }
  // The cell of `path` (kNoCell: the root), as the scheduler is told its arrivals' parents'.
  CellId CellOf(std::uint32_t path) const {
    if (path == 0) return kNoCell;
    return per_node_ ? node_cell_[path] : CellId(links_[path].cell);
  }

  // The child of path `parent` (not the root) for cell c, made if new. A new path's parent has
  // no child yet, so most paths are made without a search (issue 43: the table of (parent,
  // cell) this replaced missed the cache on every such lookup, 9% of a watching replay's CPU at
  // 4096 cells); rays leaving a node mostly enter the cell its last ray entered.
  std::uint32_t ChildOf(std::uint32_t parent, CellId c) {
    const std::uint32_t first = links_[parent].child;
    if (first != 0 && links_[first].cell == c.value()) return first;
    // The others, moved to the front when found.
    for (std::uint32_t before = first; before != 0;) {
      const std::uint32_t next = links_[before].sibling;
      if (next != 0 && links_[next].cell == c.value()) {
        links_[before].sibling = links_[next].sibling;
        links_[next].sibling = first;
        links_[parent].child = next;
        return next;
      }
      before = next;
    }
    const std::uint32_t id = NewPath(parent, c);
    links_[id].sibling = first;
    links_[parent].child = id;
    return id;
  }

  Scheduler* scheduler_;
  bool per_node_;
  // Per path, growing in place (MappedArray: a frame's millions of paths are never copied into
  // a larger array beside the old one).
  MappedArray<std::uint32_t> parent_;      // per path (the root's unused)
  MappedArray<Links> links_;               // per path, unless per node
  MappedArray<CellId> node_cell_;          // per path, per node only
  std::vector<std::uint32_t> root_child_;  // per cell, the root's child for it (0: none)
};

// ---- Pending events -------------------------------------------------------------------
// Each processor has at most one pending event: the end of its fetch, of its unit, or its
// call for a cell (and none while it waits for work). So the pending set is the engine's
// SlotQueue (engine/slot_queue.h), one slot per processor, which hands them out in the
// engine's order (time, then insertion order; every replay event has priority 0): ties fall
// exactly as on the Simulator.

enum class Kind : std::uint8_t { kNone, kIdle, kFetched, kUnitDone };

// ---- The board ------------------------------------------------------------------------

template <typename Item>
struct Processor {
  std::optional<CellId> cell;  // locked and loaded while working; the last one after
  ItemVector<Item> worklist;   // units of `cell` to work in this fetch, from `head` on
  std::size_t head = 0;
  Item unit{};           // the unit being worked
  bool holding = false;  // `cell` is locked by this processor (fetching or working it)
  SimTime work, stall;
};

// The board of docs/design.md §2: per-cell ray queues (flat arrays of unit ids), processors and
// memory, run as the engine would run the same events (see SlotQueue). A processor's unit is
// worked by its own loop iteration, without a queue push and pop: while a processor works
// the queued units of a cell, its next unit's end is compared with the other processors'
// pending events only.
template <typename Units, typename W>
class Board {
 public:
  using Entry = typename Units::Entry;
  using Item = typename W::template Item<Entry>;  // a queued unit

  Board(const WorkGraph& w, Units graph_units, const std::vector<std::uint64_t>& footprints,
        const ReplayConfig& config, Scheduler& scheduler, const MemoryHierarchy::Requests& futures,
        const MemoryState& start, ReplayObserver* observer, const MemoryUnits* units, W watch)
      : w_(w),
        u_(graph_units),
        config_(config),
        tps_(config.processors.time_per_sample),
        scheduler_(scheduler),
        memory_(config, footprints, futures, start, units),
        queues_(w.cells),
        kept_room_(KeptRoom(kKeptRoomBytes, sizeof(Item), w.cells, 64, kDropWorked)),
        queued_rays_(w.cells, 0),
        view_(w.cells, 0),
        open_(w.cells, kOpen),
        holders_(w.cells, 0),
        processors_(config.processors.count),
        slots_(config.processors.count),
        words_((config.processors.count + 63) / 64),
        waiting_mask_(words_, 0),
        holder_mask_(words_, 0),
        last_on_(std::size_t{w.cells} * words_, 0),
        ask_when_joinable_(scheduler.entry().joins),
        obs_(observer),
        watch_(std::move(watch)) {
    u_.ForEachRoot(
        [this](const Entry& e, CellId c, std::uint64_t q) { Enqueue(watch_.Root(e, c), c, q); });
    memory_.set_observer(obs_);
  }

  // Flattened: every call inside is inlined into this one loop, so that GCC's limits on a
  // function's growth never leave the core's small steps (SlotQueue::Update, WorkNext) out of
  // line, whatever surrounds the loop (they did by a few per cent when the board grew a
  // template parameter, 4% more instructions and 15-20% less speed).
  [[gnu::noinline, gnu::flatten]] void Run(std::size_t frame_index) {
    if (obs_) obs_->BeginRun(frame_index, queued_rays_);
    for (std::uint32_t p = 0; p < processors_.size(); ++p) {
      Schedule(p, SimTime::Zero(), Kind::kIdle);
      slots_.Update(p);
    }
    for (std::uint32_t p = slots_.top();;) {
      const auto& slot = slots_.at(p);
      // A woken processor's call comes first when its number is lower (its time is now_).
      if (batch_head_ != batch_end_ &&
          (slot.time != now_ || slot.seq > batches_[batch_head_].seq)) {
        p = HandleWoken();
        continue;
      }
      const Kind kind = slot.kind;
      if (kind == Kind::kNone) break;
      RAYCELL_CHECK_LE(now_, slot.time);  // time never goes backwards
      now_ = slot.time;
      slots_.Clear(p);  // handled; the handlers may schedule p's next event
      CheckedIncrement(events_);
      ++events_since_progress_;
      switch (kind) {
        case Kind::kIdle:
          OnIdle(p);
          break;
        case Kind::kFetched:
          OnFetched(p);
          break;
        case Kind::kUnitDone:
          OnUnitDone(p);
          break;
        case Kind::kNone:
          break;
      }
      p = updated_ ? top_ : slots_.Update(p);
      updated_ = false;
      if (events_since_progress_ >= kWatchdogEvents) Stall("events without progress");
    }
    if (done_ != w_.size()) Stall("no event pending while units remain");
    if (obs_) obs_->EndRun(now_);
  }

  ReplayResult Result() const;
  const MemoryHierarchy& memory() const { return memory_; }
  std::uint64_t events() const { return events_; }

 private:
  // How far ahead in a worklist the units' successors are prefetched.
  static constexpr std::size_t kPrefetch = 16;
  static constexpr std::size_t kPrefetchItems = 64;  // WorkNext: items read ahead
  // Worked units at the front of a worklist before they may be dropped.
  static constexpr std::size_t kDropWorked = std::size_t{1} << 16;

  // Schedules processor p's next event. p has none pending: it is the processor being
  // handled (its slot is brought up to date after the handler), or one that was waiting.
  void Schedule(std::uint32_t p, SimTime when, Kind kind) { slots_.Schedule(p, when, kind); }

  void Enqueue(const Item& item, CellId c, std::uint64_t q) {
    watch_.Queued(item, c, q);
    queues_[c.value()].push_back(item);
    const bool starts = (queued_rays_[c.value()] == 0) & (q != 0);
    available_ += starts & (open_[c.value()] != 0);
    joinable_ += starts & (open_[c.value()] == 0);
    if (starts) {  // the processors whose last cell this is now hold a cell with queued rays
      const std::uint64_t* on = &last_on_[std::size_t{c.value()} * words_];
      for (std::uint32_t k = 0; k < words_; ++k) holder_mask_[k] |= on[k];
    }
    queued_rays_[c.value()] += q;
    // Every cell's queue only grows here too: the most queued of all can change only to c.
    if (ask_when_joinable_ && all_most_known_ && q != 0) {
      const std::uint64_t a = queued_rays_[c.value()];
      if (all_most_ == kNoCell || a > queued_rays_[all_most_.value()] ||
          (a == queued_rays_[all_most_.value()] && c.value() < all_most_.value())) {
        all_most_ = c;
      }
    }
    queued_total_ += q;
    peak_queued_ = std::max(peak_queued_, queued_total_);
    // The view only grows here, so the cell with the most queued rays in view can change only
    // to c (lowest number on ties, as MostQueuedCell).
    const std::uint64_t v = queued_rays_[c.value()] & open_[c.value()];
    view_[c.value()] = v;
    if (most_known_ && v != 0 &&
        (most_ == kNoCell || v > view_[most_.value()] ||
         (v == view_[most_.value()] && c.value() < most_.value()))) {
      most_ = c;
    }
  }

  // The queues a scheduler may choose from: cells being worked are not available. view_ is
  // kept as the queues change (Enqueue, the lock in OnIdle), and with it the cell with the
  // most queued rays in view (QueueView::most), found again by a scan only when the lock took
  // it: with several processors most calls find every queued cell being worked, and cost
  // neither a pass over the cells nor Max Work's scan.
  QueueView View(std::uint32_t p) {
    if (!most_known_) {
      most_ = ScanMostQueued(view_.data(), w_.cells);
      most_known_ = true;
    }
    QueueView v = QueueView::Of(view_, processors_[p].cell);
    v.processor = p;
    v.open = open_.data();
    v.working = working_;
    v.all_queued = queued_rays_.data();
    if (ask_when_joinable_) {  // only a scheduler that may join reads every cell's queue
      if (!all_most_known_) {
        all_most_ = ScanMostQueued(queued_rays_.data(), w_.cells);
        all_most_known_ = true;
      }
      v.all_most_of = queued_rays_.data();
      v.all_most = all_most_;
    }
    v.most_of = view_.data();
    v.most_cells = w_.cells;
    v.most = most_;
    return v;
  }

  void OnIdle(std::uint32_t p) {
    // With no cell in view having work, every scheduler answers nothing and changes nothing
    // (Scheduler::Next), so it is not asked: with several processors most idle events are
    // of processors woken by work released into a cell that another one is working.
    // (A busy cell with queued rays may be joined: the scheduler is asked then too.)
    // (A busy cell with queued rays may be joined: the scheduler is asked then too, unless its
    // entry says it never joins, SchedulerEntry::joins.)
    const std::optional<CellId> c = NothingToAsk() ? std::nullopt : scheduler_.Next(View(p));
    if (!c) {
      // Next answers nothing only when nothing is in view, or postpones while others work.
      RAYCELL_CHECK(available_ == 0 || working_ > 0);
      waiting_mask_[p / 64] |= std::uint64_t{1} << (p % 64);  // woken when work is released
      ++waiting_;
      return;
    }
    RAYCELL_CHECK(!queues_[c->value()].empty() && queued_rays_[c->value()] != 0);
    if (holders_[c->value()] == 0) {  // lock it: its queued rays now wait for a holder
      open_[c->value()] = 0;
      view_[c->value()] = 0;
      if (*c == most_) most_known_ = false;
      --available_;
      ++joinable_;
    }
    ++holders_[c->value()];  // more than one: processors sharing a cell (Scheduler::Next)
    ++working_;
    const std::uint64_t bit = std::uint64_t{1} << (p % 64);
    if (processors_[p].cell)
      last_on_[std::size_t{processors_[p].cell->value()} * words_ + p / 64] &= ~bit;
    last_on_[std::size_t{c->value()} * words_ + p / 64] |= bit;
    holder_mask_[p / 64] |= bit;  // c has queued rays
    processors_[p].cell = *c;
    processors_[p].holding = true;
    const std::uint64_t fetches = obs_ ? memory_.stats()[0].fetches : 0;  // observed only
    const SimTime ready = memory_.Fetch(p, *c, now_);
    processors_[p].stall = processors_[p].stall + (ready - now_);
    if (obs_) {
      obs_->Fetch(p, *c, now_, ready, memory_.stats()[0].fetches != fetches, scheduler_.Reason());
    }
    Schedule(p, ready, Kind::kFetched);
  }

  // Moves the queue of p's cell to the end of its worklist: a swap of arrays when the
  // worklist is used up, as it is whenever a queue is taken.
  void TakeQueue(std::uint32_t p) {
    Processor<Item>& ps = processors_[p];
    const CellId c = *ps.cell;
    ItemVector<Item>& q = queues_[c.value()];
    if (q.empty()) return;
    if (obs_) obs_->QueueTaken(p, c, queued_rays_[c.value()], now_);
    watch_.Taken(c);

    joinable_ -= queued_rays_[c.value()] != 0;
    if (queued_rays_[c.value()] != 0) {
      const std::uint64_t* on = &last_on_[std::size_t{c.value()} * words_];
      for (std::uint32_t k = 0; k < words_; ++k) holder_mask_[k] &= ~on[k];
    }
    queued_total_ -= queued_rays_[c.value()];
    queued_rays_[c.value()] = 0;
    if (c == all_most_) all_most_known_ = false;
    if (ps.head == ps.worklist.size()) {
      ps.worklist.clear();
      ps.head = 0;
      ps.worklist.swap(q);
      // The cell's queue now has the old worklist's room; a long one is freed, else the
      // rooms of long worklists would pile up in the queues of every cell.
      ReleaseRoomAbove(q, kept_room_);
      // WorkNext prefetches kPrefetch units ahead: start the first ones here.
      const std::size_t n = std::min(kPrefetch, ps.worklist.size());
      for (std::size_t i = 0; i < n; ++i) u_.Prefetch(ps.worklist[i].e);
    } else {
      ps.worklist.append(q.begin(), q.end());
      q.clear();
      ReleaseRoomAbove(q, kept_room_);
    }
  }

  void OnFetched(std::uint32_t p) {
    TakeQueue(p);
    if (config_.processors.prefetch) {  // double buffering: the predicted next cell
      const std::optional<CellId> next = scheduler_.Peek(View(p));
      if (next) memory_.Prefetch(p, *next, now_, *processors_[p].cell);
    }
    StartNext(p);
  }

  void StartNext(std::uint32_t p) {
    Processor<Item>& ps = processors_[p];
    if (ps.head == ps.worklist.size()) TakeQueue(p);  // units that arrived meanwhile
    if (ps.head == ps.worklist.size() && holders_[ps.cell->value()] > 1) Split(p);
    if (ps.head == ps.worklist.size()) {
      ps.holding = false;
      if (obs_) obs_->BatchEnd(p, *ps.cell, now_);
      RAYCELL_CHECK_EQ(queued_rays_[ps.cell->value()],
                       0u);  // so unlocking leaves available_ as it is
      if (--holders_[ps.cell->value()] == 0) open_[ps.cell->value()] = kOpen;
      --working_;
      Schedule(p, now_, Kind::kIdle);
      return;
    }
    WorkNext(p);
  }

  // p shares its cell and has nothing left: it takes the later half of the units not yet
  // started of the holder with the most (lowest number on ties), if it has two or more.
  void Split(std::uint32_t p) {
    Processor<Item>& ps = processors_[p];
    std::uint32_t victim = p;
    std::size_t most = 1;
    for (std::uint32_t q = 0; q < processors_.size(); ++q) {
      const Processor<Item>& qs = processors_[q];
      if (q == p || !qs.holding || qs.cell != ps.cell) continue;
      const std::size_t left = qs.worklist.size() - qs.head;
      if (left > most) victim = q, most = left;
    }
    if (victim == p) return;
    ItemVector<Item>& from = processors_[victim].worklist;
    const std::size_t n = most / 2;
    ps.worklist.clear();
    ps.head = 0;
    ps.worklist.append(from.end() - n, from.end());
    from.truncate(from.size() - n);
  }

  // Starts working the unit at the head of p's worklist.
  void WorkNext(std::uint32_t p) {
    Processor<Item>& ps = processors_[p];
    // Units worked are dropped from the front once they are half of a long worklist, so
    // that a batch that keeps spawning units in its cell (millions in a large frame) holds
    // those still to work, not every unit of the batch; the order is unchanged.
    if (ps.head >= kDropWorked && 2 * ps.head >= ps.worklist.size()) {
      ps.worklist.erase_front(ps.head);
      ps.head = 0;
    }
    // The units a few places ahead are known: load their successors while this one is
    // worked (the records are scattered over the frame, so each would be a cache miss).
    if (ps.head + kPrefetch < ps.worklist.size()) u_.Prefetch(ps.worklist[ps.head + kPrefetch].e);
    // And the worklist's own items further on: a queue taken whole was written while its
    // units were released, long before, and is read one item per unit worked.
    if (ps.head + kPrefetchItems < ps.worklist.size()) {
      __builtin_prefetch(ps.worklist.data() + ps.head + kPrefetchItems);
    }
    ps.unit = ps.worklist[ps.head++];
    const SimTime dt = tps_ * u_.samples(ps.unit.e);
    ps.work = ps.work + dt;
    Schedule(p, now_ + dt, Kind::kUnitDone);
  }

  void OnUnitDone(std::uint32_t p) {
    events_since_progress_ = 0;
    ++done_;
    Processor<Item>& ps = processors_[p];
    const CellId cell = *ps.cell;  // the unit's, as every unit of the worklist
    const Item unit = ps.unit;
    // When the next unit is already in the worklist and no processor waits (so releasing
    // successors schedules no event and takes no seq), p's next event is the same whether it
    // is scheduled before or after the successors are released. Scheduling it first lets the
    // choice of the next event (slots_, an unpredictable branch with several processors)
    // resolve without waiting for the successors' records, which are often cache misses.
    const bool early = waiting_ == 0 && ps.head < ps.worklist.size();
    if (early) {
      WorkNext(p);
      top_ = slots_.Update(p);
      updated_ = true;
    }
    bool released = false;
    u_.ForEachChild(unit.e, [&](const Entry& e, CellId c, std::uint64_t q) {
      const Item child = watch_.Child(unit, cell, e, c);
      if (c == cell) {
        ps.worklist.push_back(child);  // spawned in the loaded cell: worked now
      } else {
        Enqueue(child, c, q);
        released = true;
      }
    });
    if (early) return;
    if (released && waiting_ > 0) WakeWaiting();
    StartNext(p);
  }

  // Wakes every waiting processor: first, in processor order, those whose last cell (the one
  // in their cache, QueueView::loaded) now has queued rays, so that such a cell goes to a
  // processor that holds it rather than to one that would fetch it; then the others.
  //
  // Each gets a call at now_, numbered in that order (as if scheduled), but the calls are kept
  // as one batch outside the slots: with tens of processors a release wakes dozens, and most
  // find nothing. Nothing comes between a batch's calls (later events have higher numbers),
  // and a call that finds nothing changes nothing but the event count, so once one does, every
  // call left in its batch would too: HandleWoken puts them back to waiting at once, each
  // counted as an event as before.
  void WakeWaiting() {
    if (batch_end_ == batches_.size()) batches_.emplace_back();
    Batch& b = batches_[batch_end_++];
    b.seq = slots_.TakeSeqs(waiting_);
    b.left = waiting_;
    b.bits.resize(2 * std::size_t{words_});
    for (std::uint32_t k = 0; k < words_; ++k) {
      b.bits[k] = waiting_mask_[k] & holder_mask_[k];
      b.bits[words_ + k] = waiting_mask_[k] & ~holder_mask_[k];
      waiting_mask_[k] = 0;
    }
    waiting_ = 0;
  }

  // Whether a call now would find nothing without asking the scheduler (OnIdle).
  bool NothingToAsk() const { return available_ == 0 && (joinable_ == 0 || !ask_when_joinable_); }

  // Handles the first batch's next call (WakeWaiting); returns the next slot to look at.
  std::uint32_t HandleWoken() {
    Batch& b = batches_[batch_head_];
    if (NothingToAsk()) {
      // This call and every one left in the batch find nothing: back to waiting, each an event
      // (up to the watchdog's limit, where the replay stops as it would have).
      const std::uint64_t n =
          std::min<std::uint64_t>(b.left, kWatchdogEvents - events_since_progress_);
      events_ = CheckedAdd(events_, n);
      events_since_progress_ += n;
      if (events_since_progress_ >= kWatchdogEvents) Stall("events without progress");
      for (std::uint32_t k = 0; k < words_; ++k) waiting_mask_[k] |= b.bits[k] | b.bits[words_ + k];
      waiting_ += b.left;
      PopBatch();
      return slots_.top();
    }
    // The next in order: the lowest bit of the holders, then of the others.
    std::uint32_t q = 0;
    for (std::uint32_t k = 0; k < 2 * words_; ++k) {
      if (b.bits[k] != 0) {
        q = (k % words_) * 64 + std::uint32_t(__builtin_ctzll(b.bits[k]));
        b.bits[k] &= b.bits[k] - 1;
        break;
      }
    }
    ++b.seq;
    const bool last = --b.left == 0;
    if (last) PopBatch();
    CheckedIncrement(events_);
    ++events_since_progress_;
    OnIdle(q);
    const std::uint32_t top = slots_.at(q).kind != Kind::kNone ? slots_.Update(q) : slots_.top();
    if (events_since_progress_ >= kWatchdogEvents) Stall("events without progress");
    return top;
  }

  void PopBatch() {
    if (++batch_head_ == batch_end_) batch_head_ = batch_end_ = 0;
  }

  [[noreturn]] void Stall(const std::string& reason) const {
    std::ostringstream s;
    s << "replay stalled: " << reason << " at " << now_ << " after " << events_ << " events; "
      << done_ << " of " << w_.size() << " units done; queued rays per cell:";
    for (std::uint64_t q : queued_rays_) s << ' ' << q;
    throw SimulationStalled(s.str());
  }

  const WorkGraph& w_;
  Units u_;
  const ReplayConfig& config_;
  SimTime tps_;
  Scheduler& scheduler_;
  MemoryHierarchy memory_;
  std::vector<ItemVector<Item>> queues_;
  // The room in items an emptied queue may keep (base/kept_room.h): a queue taken leaves its cell
  // the old worklist's room, or its own when appended to a worklist.
  std::size_t kept_room_;
  // view_[c] = queued_rays_[c] & open_[c], kept so (the queues in a scheduler's view).
  std::vector<std::uint64_t> queued_rays_, view_;
  // The cell with the most queued rays in view_, lowest number on ties (kNoCell: none), when
  // most_known_; found again by a scan at the next View when not.
  CellId most_ = kNoCell;
  bool most_known_ = true;
  // The same for queued_rays_ (every cell's queue, QueueView::all_most), kept only for a
  // scheduler that may join (ask_when_joinable_): found again by a scan when the take emptied it.
  CellId all_most_ = kNoCell;
  bool all_most_known_ = true;
  // Per cell: all ones, or 0 while a processor works it (locked: not in the view).
  static constexpr std::uint64_t kOpen = ~std::uint64_t{0};
  std::vector<std::uint64_t> open_;
  // Cells in view: with queued rays and open. A queue is taken only by the processor that
  // locked its cell, and a cell is unlocked only with an empty queue, so only Enqueue and
  // the lock in OnIdle change it.
  std::uint32_t available_ = 0;
  std::uint32_t working_ = 0;  // processors working a cell
  // Per cell: the processors working it (more than one only when a scheduler joins it);
  // busy cells with queued rays, which a scheduler may join.
  std::vector<std::uint32_t> holders_;
  std::uint32_t joinable_ = 0;
  std::vector<Processor<Item>> processors_;
  SlotQueue<Kind> slots_;
  // Bit sets of processors, words_ 64-bit words each: waiting (idle, no cell had work), and
  // whose last cell has queued rays; per cell, the processors whose last cell it is.
  std::uint32_t words_;
  std::vector<std::uint64_t> waiting_mask_, holder_mask_, last_on_;
  std::uint32_t waiting_ = 0;
  // Woken processors' calls not yet handled (WakeWaiting): batches_[batch_head_, batch_end_),
  // in order; each the number of its next call, the calls left, and the processors, holders
  // first (bits[0, words_)) then the others.
  struct Batch {
    std::uint64_t seq = 0;
    std::uint32_t left = 0;
    std::vector<std::uint64_t> bits;
  };
  std::vector<Batch> batches_;
  std::size_t batch_head_ = 0, batch_end_ = 0;
  // Whether the scheduler is asked when only busy cells have work (SchedulerEntry::joins).
  bool ask_when_joinable_;
  // OnUnitDone brought its processor's slot up to date itself; top_ is then the next.
  bool updated_ = false;
  std::uint32_t top_ = 0;
  SimTime now_;
  std::uint64_t events_ = 0, events_since_progress_ = 0;
  std::uint64_t done_ = 0, queued_total_ = 0, peak_queued_ = 0;
  ReplayObserver* obs_;            // null: nothing observes (replay/observer.h)
  [[no_unique_address]] W watch_;  // NoWatch, or what a watching scheduler is told
};

template <typename Units, typename W>
ReplayResult Board<Units, W>::Result() const {
  RAYCELL_CHECK_EQ(done_, std::uint64_t(w_.size()));
  ReplayResult r;
  r.levels = memory_.stats();
  r.fetches = r.levels[0].fetches;
  r.time = now_;
  for (const Processor<Item>& ps : processors_) {
    r.work = r.work + ps.work;
    r.stall = r.stall + ps.stall;
    r.idle = r.idle + (now_ - ps.work - ps.stall);
  }
  const double capacity = double(now_.picoseconds()) * double(processors_.size());
  r.utilisation = capacity > 0 ? double(r.work.picoseconds()) / capacity : 0.0;
  r.peak_queued_rays = peak_queued_;
  r.peak_queued_bytes = CheckedMul(peak_queued_, config_.processors.queue_record_bytes);
  r.rays = w_.total_rays(), r.segments = w_.total_segments(), r.samples = w_.total_samples();
  r.prefetches = memory_.prefetches();
  r.prefetch_hits = memory_.prefetch_hits();
  r.events = events_;
  return r;
}

// Whether some level's policy needs its future requests (Belady's MIN).
bool NeedsFuture(const ReplayConfig& config) {
  for (const LevelConfig& l : config.levels) {
    if (l.replacement->needs_future) return true;
  }
  return false;
}

// ReplayFrame of a seen frame's work per node, without what only a frame's own result reports
// (its lower bound on the time).
ReplayResult SeenReplay(const WorkGraph& work, const std::vector<std::uint64_t>& footprints,
                        const ReplayConfig& config, Scheduler& scheduler, const FrameTrees& frame,
                        MemoryState* memory, const MemoryUnits* units);

// Earlier frames' trees replayed per node on a frame's board (FrameInfo::seen): its
// configuration, footprints and what its levels hold at the frame's start.
class SeenReplayer : public SeenFrameReplayer {
 public:
  SeenReplayer(const std::vector<std::uint64_t>& footprints, const ReplayConfig& config,
               const MemoryState& start, const MemoryUnits* units, PlanCache* plans,
               unsigned threads)
      : footprints_(footprints),
        config_(config),
        start_(start),
        units_(units),
        plans_(plans),
        threads_(std::max(1u, threads)) {
    config_.granularity = ReplayConfig::Granularity::kNode;
  }
  SeenOutcome Replay(const CellTree& tree, Scheduler& scheduler, std::size_t frame_index,
                     const CellTree* previous, const CellTree* before_previous) const override {
    const std::uint32_t cells = std::uint32_t(footprints_.size());
    // The frame's plan cache: what the scheduler makes from the earlier trees is shared with
    // the replay's own frame, the other seen replays and the other configurations, and so is
    // the tree's work per node, as the walker's packed records (docs/design.md §5 "Sharing
    // plans").
    const FrameTrees frame{frame_index, &tree, previous, cells, before_previous, plans_};
    const std::shared_ptr<const WorkGraph> work =
        Shared<WorkGraph>(plans_, PlanKey(kSeenWork, {TreeKey(tree), cells}),
                          [&] { return PackedNodeWork(tree, cells); });
    MemoryState memory = start_;
    const ReplayResult r = SeenReplay(*work, footprints_, config_, scheduler, frame,
                                      start_.empty() ? nullptr : &memory, units_);
    SeenOutcome o;
    o.fetches = r.fetches;
    o.time =
        double(r.time.picoseconds()) / double(config_.processors.time_per_sample.picoseconds());
    o.steps = r.events;
    return o;
  }
  unsigned threads() const override { return threads_; }

 private:
  const std::vector<std::uint64_t>& footprints_;
  ReplayConfig config_;
  const MemoryState& start_;
  const MemoryUnits* units_;
  PlanCache* plans_;
  unsigned threads_;
};

// `make_watch()` gives each run's W (NoWatch, or Watch for a scheduler that watches).
// `time_bound`: false within a replay of a frame seen, which reports no lower bound (0).
// `frame_start`: begun (by the Replay below, which asks whether the scheduler watches only
// then); MIN's later passes begin it again.
template <typename Units, typename W, typename MakeWatch>
ReplayResult Replay(const WorkGraph& work, Units graph_units,
                    const std::vector<std::uint64_t>& footprints, const ReplayConfig& config,
                    Scheduler& scheduler, const FrameTrees& frame, std::uint64_t bound,
                    ReplayObserver* observer, MemoryState* memory, const MemoryUnits* units,
                    MakeWatch make_watch, bool time_bound, FrameStart& frame_start) {
  static const MemoryState kEmpty;
  const MemoryState& start = memory ? *memory : kEmpty;
  const bool min = NeedsFuture(config);
  const std::uint32_t max_passes = min ? std::uint32_t(config.levels.size()) + 1 : 1;
  MemoryHierarchy::Requests futures;
  for (std::uint32_t pass = 1;; ++pass) {
    if (pass > 1 || !frame_start.begun()) frame_start.Begin(scheduler);
    Board<Units, W> board(work, graph_units, footprints, config, scheduler, futures, start,
                          observer, units, make_watch());
    board.Run(frame.frame_index);
    const bool converged = pass > 1 && !board.memory().diverged();
    if (!min || converged || pass == max_passes) {
      ReplayResult r = board.Result();
      if (BoundHolds(config)) {
        // A cell warm in the one-cell cache may save the frame's first fetch, no more.
        const bool warm_cache = !start.empty() && !start.held[0][0].empty();
        r.bound = warm_cache && bound > 0 ? bound - 1 : bound;
      }
      if (time_bound) {
        const std::vector<std::vector<bool>> held = start.empty()
                                                        ? std::vector<std::vector<bool>>()
                                                        : HeldAnywhere(start, work.cells, units);
        r.time_bound =
            TimeLowerBound(work, footprints, config, start.empty() ? nullptr : &held, units);
      }
      r.passes = pass;
      r.min_converged = !min || converged;
      const Scheduler::DecisionCost cost = scheduler.Cost();
      r.decisions = cost.decisions;
      r.decision_steps = cost.steps;
      r.scheduler_bytes = cost.peak_bytes;
      if (memory) *memory = board.memory().State();
      return r;
    }
    futures = board.memory().requests();
  }
}

// Replay with the board's W chosen by whether the scheduler watches.
template <typename Units>
ReplayResult Replay(const WorkGraph& work, Units graph_units,
                    const std::vector<std::uint64_t>& footprints, const ReplayConfig& config,
                    Scheduler& scheduler, const FrameTrees& frame, std::uint64_t bound,
                    ReplayObserver* observer, MemoryState* memory, const MemoryUnits* units,
                    bool seen, bool time_bound, FrameStart* begun) {
  // The scheduler begins the frame first: whether it watches may depend on the frame (auto
  // watches where the candidate it runs does).
  std::optional<FrameStart> own;
  FrameStart& start = begun != nullptr
                          ? *begun
                          : own.emplace(footprints, config, scheduler, frame, memory, units, seen);
  if (!start.begun()) start.Begin(scheduler);
  if (!scheduler.Watches()) {
    return Replay<Units, NoWatch>(
        work, graph_units, footprints, config, scheduler, frame, bound, observer, memory, units,
        [] { return NoWatch{}; }, time_bound, start);
  }
  return Replay<Units, Watch>(
      work, graph_units, footprints, config, scheduler, frame, bound, observer, memory, units,
      [&] { return Watch(scheduler, work.per_node, work.cells); }, time_bound, start);
}

// The replay of `work` in its form: the compact stream, the packed records or the columns.
ReplayResult ReplayWork(const WorkGraph& work, const std::vector<std::uint64_t>& footprints,
                        const ReplayConfig& config, Scheduler& scheduler, const FrameTrees& frame,
                        std::uint64_t bound, ReplayObserver* observer, MemoryState* memory,
                        const MemoryUnits* units, bool seen, bool time_bound,
                        FrameStart* begun = nullptr) {
  RAYCELL_CHECK_EQ(footprints.size(), std::size_t(work.cells));
  if (work.compact.units != 0) {
    return Replay(work, CompactUnits{work.compact.stream.data(), &work.compact}, footprints, config,
                  scheduler, frame, bound, observer, memory, units, seen, time_bound, begun);
  }
  if (!work.packed.empty()) {
    return Replay(work, PackedUnits{work.packed.data(), UnitId(work.roots.size())}, footprints,
                  config, scheduler, frame, bound, observer, memory, units, seen, time_bound,
                  begun);
  }
  return Replay(work, ColumnUnits{&work}, footprints, config, scheduler, frame, bound, observer,
                memory, units, seen, time_bound, begun);
}

ReplayResult SeenReplay(const WorkGraph& work, const std::vector<std::uint64_t>& footprints,
                        const ReplayConfig& config, Scheduler& scheduler, const FrameTrees& frame,
                        MemoryState* memory, const MemoryUnits* units) {
  RAYCELL_CHECK(work.compact.units == 0);  // per node: packed records or columns
  return ReplayWork(work, footprints, config, scheduler, frame, 0, nullptr, memory, units,
                    /*seen=*/false, /*time_bound=*/false);
}

}  // namespace

FrameStart::FrameStart(const std::vector<std::uint64_t>& footprints, const ReplayConfig& config,
                       const Scheduler& scheduler, const FrameTrees& frame,
                       const MemoryState* memory, const MemoryUnits* units, bool seen)
    : fetch_samples_(FetchSamples(config, footprints)) {
  static const MemoryState kEmpty;
  info_ = MakeFrameInfo(frame, config, fetch_samples_, units, scheduler);
  if (seen) {
    seen_ = std::make_unique<SeenReplayer>(footprints, config, memory ? *memory : kEmpty, units,
                                           frame.plans, frame.threads);
    info_.seen = seen_.get();
  }
}

FrameStart::~FrameStart() = default;

void FrameStart::Begin(Scheduler& scheduler) {
  scheduler.BeginFrame(info_);
  begun_ = true;
}

FrameInfo MakeFrameInfo(const FrameTrees& frame, const ReplayConfig& config,
                        const std::vector<double>& fetch_samples, const MemoryUnits* units,
                        const Scheduler& scheduler) {
  FrameInfo info;
  info.frame_index = frame.frame_index;
  // Only an oracle is given the frame's own tree: every other scheduler learns the frame from
  // what is queued, and begins it before its tree is built (FrameStart).
  info.current = scheduler.entry().oracle ? frame.current : nullptr;
  info.previous = frame.previous;
  info.cells = frame.cells;
  info.before_previous = frame.before_previous;
  info.plans = frame.plans;
  info.fetch_samples = &fetch_samples;
  info.processors = config.processors.count;
  if (units != nullptr) {
    for (const LevelUnits& level : *units) {
      if (!level.identity()) {
        info.board_cell_of = &level.unit_of_cell;
        break;
      }
    }
  }
  return info;
}

std::vector<double> FetchSamples(const ReplayConfig& config,
                                 const std::vector<std::uint64_t>& footprints) {
  std::vector<double> samples(footprints.size());
  const LevelConfig& l0 = config.levels.front();
  const double tps = double(config.processors.time_per_sample.picoseconds());
  for (std::size_t c = 0; c < footprints.size(); ++c) {
    const SimTime t = l0.latency_below + l0.bandwidth_below.TransferTime(footprints[c]);
    samples[c] = double(t.picoseconds()) / tps;
  }
  return samples;
}

bool BoundHolds(const ReplayConfig& config) {
  const LevelConfig& l0 = config.levels.front();
  return config.processors.count == 1 && l0.capacity_unit == LevelConfig::CapacityUnit::kCells &&
         l0.capacity == 1;
}

void CheckReplayable(const ReplayConfig& config) {
  const LevelConfig& cache = config.levels.front();
  if (config.processors.prefetch && cache.capacity_unit == LevelConfig::CapacityUnit::kCells &&
      cache.capacity < 2) {
    throw InputError(
        "processors.prefetch = true needs a cache that holds two cells (double "
        "buffering), but level '" +
        cache.name + "' holds " + FormatCapacity(cache));
  }
}

void CheckModelSize(const ReplayConfig& config, std::uint64_t cells) {
  const std::uint64_t n = std::uint64_t{config.processors.count} * cells;
  if (n > kMaxProcessorCells) {
    throw InputError("processors.count " + std::to_string(config.processors.count) + " x " +
                     std::to_string(cells) + " cells of the trace = " + std::to_string(n) +
                     " exceeds the limit of " + std::to_string(kMaxProcessorCells) +
                     " processor-cells (the memory model keeps 8 bytes per processor and cell)");
  }
}

void CheckReplay(const ReplayConfig& config, std::uint64_t cells) {
  CheckReplayable(config);
  CheckModelSize(config, cells);
}

ReplayResult ReplayFrame(const WorkGraph& work, const std::vector<std::uint64_t>& footprints,
                         const ReplayConfig& config, Scheduler& scheduler, const FrameTrees& frame,
                         std::uint64_t bound, ReplayObserver* observer, MemoryState* memory,
                         const MemoryUnits* units, bool seen, FrameStart* start) {
  // The caller ran CheckReplay (its bound on the memory model's size, as an invariant here).
  RAYCELL_CHECK_LE(std::uint64_t{config.processors.count} * work.cells, kMaxProcessorCells);
  return ReplayWork(work, footprints, config, scheduler, frame, bound, observer, memory, units,
                    seen, /*time_bound=*/true, start);
}

}  // namespace raycell
