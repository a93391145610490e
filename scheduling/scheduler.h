// Ray schedulers (docs/design.md §1 "Max Work", "Cell Tree scheduling"; §2 "scheduler"): the
// policy that picks which cell a processor fetches next. The replay model keeps per-cell ray
// queues and asks its Scheduler whenever a processor needs a cell; policies plug in through
// this small interface (CONTRIBUTING.md, after ChampSim's replacement modules).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

// What a scheduler may see when asked for a cell: the rays waiting to enter each cell
// (0 = no work) and the cell in the cache, if any. Does not own the counts.
struct QueueView {
  const std::uint64_t* queued_rays = nullptr;  // queued_rays[c] for c < cells
  std::uint32_t cells = 0;
  std::optional<CellId> loaded;
  // Several processors (docs/design.md §2): the one asking (their number is
  // FrameInfo::processors), and the cells the others are working (open[c] == 0: busy, its
  // queued rays masked out of queued_rays; null: none is).
  std::uint32_t processor = 0;
  const std::uint64_t* open = nullptr;
  // Processors other than the one asking that are working a cell now. While some are, a
  // scheduler may postpone (Scheduler::Next).
  std::uint32_t working = 0;
  // Queued rays of every cell, busy ones included (null: not given). A scheduler may choose a
  // busy cell with queued rays: the processor then *joins* it, working it beside the others
  // (a cell is read-only volume data, so each holds a copy); every queue the holders take is
  // taken whole by the first that asks. Only the `share` schedulers do.
  const std::uint64_t* all_queued = nullptr;
  // The replay's answer of MostQueuedCell for this view, kept as its queues change so that a
  // decision need not scan every cell (docs/design.md §2 "Several processors"): `most`
  // (kNoCell: no cell has work), for these queued_rays and cells only. MostQueuedCell uses it
  // when most_of == queued_rays and most_cells == cells, so a view a scheduler copies with other
  // counts (or made by QueueView::Of) is scanned. Null: none given.
  const std::uint64_t* most_of = nullptr;
  std::uint32_t most_cells = 0;
  CellId most = kNoCell;
  // The same for all_queued: the replay's answer of ScanMostQueued(all_queued, cells), used by
  // MostQueuedAll when all_most_of == all_queued (null: none given, scanned).
  const std::uint64_t* all_most_of = nullptr;
  CellId all_most = kNoCell;

  std::uint64_t queued(CellId c) const { return queued_rays[c.value()]; }
  // Whether another processor is working `c` (work released there is done by that one).
  bool busy(CellId c) const { return open != nullptr && open[c.value()] == 0; }
  bool has_work(CellId c) const { return c.value() < cells && queued_rays[c.value()] > 0; }
  // True when no cell has queued work.
  bool empty() const;
  // A view of `queued` (which must outlive the view); cells = queued.size().
  static QueueView Of(const std::vector<std::uint64_t>& queued,
                      std::optional<CellId> loaded = std::nullopt);
};

class PlanCache;  // scheduling/plan_cache.h
class Scheduler;

// A frame seen, replayed on this replay's board (replay/replayer.cpp SeenReplayer): for a
// scheduler that judges candidates on earlier frames (auto, scheduling/auto_scheduler.h).
struct SeenOutcome {
  std::uint64_t fetches = 0;
  double time = 0;          // in sample times
  std::uint64_t steps = 0;  // the replay's events
};
class SeenFrameReplayer {
 public:
  virtual ~SeenFrameReplayer() = default;
  // Replays `tree` as frame `frame_index` with `previous` and `before_previous` as its earlier
  // frames, under `scheduler` (told BeginFrame by the replay), per Cell Tree node, on the board
  // of the replay asking (configuration, footprints, what its levels hold at the frame's start).
  // Calls on different schedulers may run at once, on different threads.
  virtual SeenOutcome Replay(const CellTree& tree, Scheduler& scheduler, std::size_t frame_index,
                             const CellTree* previous, const CellTree* before_previous) const = 0;
  // How many Replay calls the asker may run at once (threads it is given for them, >= 1: the
  // caller's among them); the outcomes are the same for any number.
  virtual unsigned threads() const { return 1; }
};

// What a scheduler is told at the start of each frame.
struct FrameInfo {
  std::size_t frame_index = 0;
  const CellTree* current = nullptr;   // this frame's tree (the Peel oracle needs it)
  const CellTree* previous = nullptr;  // the previous frame's tree; null for frame 0
  std::uint32_t cells = 0;             // cells of the grid; every tree's cell_count() <= cells
  // Frame i-2's tree, for schedulers whose registry entry has history 2; else null.
  const CellTree* before_previous = nullptr;
  // Per cell: how long bringing it into a processor's cache from the level below takes (the
  // first link's latency + footprint / bandwidth), in units of one sample's work; null when
  // unknown (a scheduler asked outside a replay).
  const std::vector<double>* fetch_samples = nullptr;
  // Block processors of the replay (1..kMaxProcessors, replay/config.h): told once per frame,
  // here; a scheduler that needs the count while choosing keeps it from BeginFrame.
  std::uint32_t processors = 1;
  // The board's cells, when a shared memory level holds coarser cells than the replay's
  // (level.NAME.cells; the nearest such level): per cell of the grid, the board cell holding
  // it; null when every level holds the grid's cells.
  const std::vector<CellId>* board_cell_of = nullptr;
  // Where what BeginFrame computes from earlier trees is shared with the other configurations
  // replayed on this frame (scheduling/plan_cache.h; docs/design.md §5 "Sharing plans"); null:
  // the scheduler computes it alone.
  PlanCache* plans = nullptr;
  // Replays earlier frames' trees on this replay's board; null outside a replay (and within
  // such a replay of a frame seen).
  const SeenFrameReplayer* seen = nullptr;
};
// The board cell of every cell of frame.previous (not null): FrameInfo::board_cell_of, or
// each cell its own when every level holds the grid's cells.
std::vector<CellId> BoardCellOf(const FrameInfo& frame);

class Scheduler;

// A scheduler's registry entry (ChampSim-style, CONTRIBUTING.md): each scheduler's own file
// defines its entry (or entries, one per name) with each field it sets named (a flag left out keeps
// the default stated here), and declares it in its header (kMaxWorkEntry in max_work.h, ...);
// SchedulerRegistry() lists them. The entry is where a scheduler's name is written:
// Scheduler::Name() reads it. A name is looked up once (SchedulerByName, where a configuration is
// read); configurations then hold the entry.
struct SchedulerEntry {
  const char* name = nullptr;     // as in configs and --scheduler: "maxwork"
  const char* meaning = nullptr;  // one line for --help and the configuration's comments
  const char* label = nullptr;    // as raycell study's tables name it: "Max Work"
  // A new scheduler of this kind; `seed` matters to the seeded ones.
  std::unique_ptr<Scheduler> (*make)(std::uint64_t seed) = nullptr;
  // Earlier frames' trees it reads: 0 (none: the replay keeps no earlier tree for it), 1
  // (FrameInfo::previous) or 2 (also before_previous).
  std::uint32_t history = 1;
  // Whether its choices depend on the seed (random, and the planners' seeded searches).
  bool seeded = false;
  // Whether Peek predicts its next choice (what prefetch fetches); without a prediction,
  // prefetch changes nothing.
  bool predicts = true;
  // An oracle knows the frame being replayed (its own tree); the others only earlier frames.
  bool oracle = false;
  // Whether raycell study replays it: all but the naive baselines (Round Robin, Random).
  bool studied = true;
  // Whether it may choose a busy cell (QueueView::all_queued: join it) or otherwise answer
  // anything but nothing when no cell in view has work. false promises that Next then returns
  // nullopt and changes nothing, so the replay does not ask it (with tens of processors most
  // calls are such). true, the default, is always safe.
  bool joins = true;
};

// A scheduling policy. Per frame: BeginFrame once, then Next once per fetch.
//
// A frame's choices depend only on the frame's FrameInfo and queues, never on what earlier
// frames did: a replay of frames A..B then gives each frame what a replay of the whole trace
// gives it (frame shards and resumed sweeps rely on this).
//
// Next returns a cell with queued work, or nullopt when no cell has any. It may also return
// nullopt with work in view while another processor is working (QueueView::working > 0):
// it *postpones*, the processor waiting until work is released somewhere (Aila and Karras's
// postponing of small batches); it then changes nothing, as with no work. With no other
// processor working it must choose, so a replay always progresses. A scheduler may keep
// state between calls (a cursor into a schedule), so the caller must call Next again only
// after it has processed the returned cell's queue (fetched it and worked its rays). When no
// cell has work, Next changes nothing that a later Next, Peek or Reason could show (no
// random draw, no cursor moved), so that a caller may skip asking then: the replay does, for
// the idle processors woken by work released into cells that others are working.
class Scheduler {
 public:
  // `entry`: the registry entry this scheduler is made by (static storage, outlives it).
  explicit Scheduler(const SchedulerEntry& entry) : entry_(&entry) {}
  virtual ~Scheduler() = default;
  const SchedulerEntry& entry() const { return *entry_; }
  // The name MakeScheduler knows it by, its entry's: "maxwork", "roundrobin", ...
  std::string Name() const { return entry_->name; }
  virtual void BeginFrame(const FrameInfo& frame) = 0;
  virtual std::optional<CellId> Next(const QueueView& queues) = 0;
  // What Next would choose for these queues, without choosing it (no state changes): the
  // cell a processor prefetches while it works the current one. nullopt: no prediction.
  // Default: Max Work's choice.
  virtual std::optional<CellId> Peek(const QueueView& queues) const;
  // Why the last Next chose its cell, in a few words for people reading a replay's timeline
  // (runner/timeline.h): "followed", "max work (skipped 2)". Empty (the default) when the
  // policy has nothing to say beyond its name. Read only when asked: never on the replay's
  // path unless a timeline is written.
  virtual std::string Reason() const { return {}; }

  // Watching the frame unfold (docs/design.md §5 "Adaptive scheduling"). A scheduler that
  // watches is told, as the replay queues it, each unit of work released into a cell with the
  // Cell Tree node it belongs to, as a ray packet carrying its node would tell the board; and
  // each time a processor takes a cell's queue. Unless its entry is an oracle
  // (celltree-dag-oracle), it is not given the frame's own tree (FrameInfo::current is null for
  // it): what it knows of the frame is what was queued so far. The replay asks Watches() once
  // the scheduler began the frame (BeginFrame), so the answer may differ from frame to frame.
  // Nodes are numbered in the order they are first queued, from 1; 0 is the root.
  struct Arrival {
    std::uint32_t node = 0;        // the node the unit's rays enter
    std::uint32_t parent = 0;      // its parent, queued before it (0: the root)
    CellId cell{0};                // the node's cell, where the unit is queued
    std::uint64_t rays = 0;        // rays the unit adds to the cell's queue
    CellId parent_cell = kNoCell;  // the parent's cell (kNoCell: the root)
  };
  virtual bool Watches() const { return false; }
  virtual void Arrived(const Arrival& /*arrival*/) {}
  // A processor took `cell`'s queue: every unit queued there so far is being worked.
  virtual void Taken(CellId /*cell*/) {}

  // What deciding has cost so far this frame (docs/design.md §5 "The cost of deciding"): calls
  // of Next that chose a cell, and the elementary steps spent planning and choosing (tree nodes
  // and schedule entries visited, search states), and the most bytes of state the scheduler
  // kept. A scheduler that does not count reports zeros.
  struct DecisionCost {
    std::uint64_t decisions = 0, steps = 0, peak_bytes = 0;
  };
  virtual DecisionCost Cost() const { return {}; }

  // Whether, once BeginFrame returned, the frame may still read an earlier frame's tree it was
  // given (FrameInfo::previous, before_previous) through a pointer kept: true, the default,
  // unless the scheduler says otherwise. Where no replay of a frame does, the previous frame's
  // tree waits parked (CellTree::Park) while the frame is built and replayed
  // (runner/driver.cpp; docs/design.md §2 "What a replay holds").
  virtual bool ReadsEarlierTrees() const { return true; }

  // Makes in frame.plans, before BeginFrame(frame), what BeginFrame would make of the earlier
  // frames' trees (a union of frames i-2 and i-1), and says whether BeginFrame and the replay
  // then read nothing of those trees but their size and ContentKey: where every configuration
  // of a frame says so, the runner parks them and begins the frame while it is built (a spare
  // thread; runner/driver.cpp, docs/design.md §2 "What a replay holds"). false, the default
  // (nothing made), is always safe.
  virtual bool Prepare(const FrameInfo& frame) {
    (void)frame;
    return false;
  }

  // The bytes of what BeginFrame made or took from the frame's plan cache and the scheduler
  // holds until its replay of the frame ends (a union of trees, a plan's due entry per node,
  // per-node heights); 0 where that is small. A sweep's runner frees the cache once every
  // configuration of the frame began and replays those holding most first, so that each such
  // state goes before the others replay (runner/driver.cpp; docs/design.md §5 "Sharing plans").
  virtual std::uint64_t HeldBytes() const { return 0; }

 private:
  const SchedulerEntry* entry_;
};

// Max Work's choice: the cell with the most queued rays, lowest number on ties; nullopt when
// no cell has work. O(1) with the replay's answer (QueueView::most), else a scan of the cells
// (ScanMostQueued).
std::optional<CellId> MostQueuedCell(const QueueView& queues);
// The same by a scan of queued[0 .. cells): kNoCell when no cell has work.
CellId ScanMostQueued(const std::uint64_t* queued, std::uint32_t cells);
// The cell with the most queued rays of all (QueueView::all_queued, busy cells included), lowest
// number on ties; kNoCell when none has any or all_queued is not given. O(1) with the replay's
// answer (QueueView::all_most), else a scan.
CellId MostQueuedAll(const QueueView& queues);

// Of `cells`, the one with the most queued rays (queued[c] > 0), lowest number on ties; none
// when none has work.
std::optional<CellId> MostQueuedOf(const std::vector<std::uint32_t>& cells,
                                   const std::uint64_t* queued);

// Cells kept in one list per key (a depth, a level), each cell in at most one list, in any
// order: a cell moves in O(1), the last cell of its old list taking its place. A scheduler
// looks at the lists of a few keys instead of at every cell (issue 43).
class CellLists {
 public:
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};  // a key: in no list
  // Every list empty, for cells 0 .. cells-1.
  void Reset(std::uint32_t cells) {
    pos_.assign(cells, 0);
    for (auto& l : lists_) l.clear();
  }
  // Moves `cell` from list `from` to list `to` (either kNone).
  void Move(std::uint32_t cell, std::uint32_t from, std::uint32_t to) {
    if (from == to) return;
    if (from != kNone) {
      std::vector<std::uint32_t>& l = lists_[from];
      l[pos_[cell]] = l.back();
      pos_[l.back()] = pos_[cell];
      l.pop_back();
    }
    if (to != kNone) {
      if (to >= lists_.size()) lists_.resize(std::size_t{to} + 1);
      pos_[cell] = std::uint32_t(lists_[to].size());
      lists_[to].push_back(cell);
    }
  }
  // The keys that have had a list (every key at or above it has an empty one).
  std::uint32_t keys() const { return std::uint32_t(lists_.size()); }
  const std::vector<std::uint32_t>& at(std::uint32_t key) const { return lists_[key]; }

 private:
  std::vector<std::vector<std::uint32_t>> lists_;
  std::vector<std::uint32_t> pos_;  // per cell: its place in its list
};

// Entries 0 .. n-1 of a schedule, some used up: the first entry from i on that is not, in
// amortised near-constant time (a union-find over the used entries, paths halved as they are
// walked), so that a follower walking past entries taken out of order does not visit them
// again at every decision.
class UnusedEntries {
 public:
  void Reset(std::size_t n) {
    next_.resize(n + 1);
    for (std::size_t i = 0; i <= n; ++i) next_[i] = i;
  }
  // The first entry >= i not used up; n when none.
  std::size_t From(std::size_t i) const {
    while (next_[i] != i) {
      next_[i] = next_[next_[i]];
      i = next_[i];
    }
    return i;
  }
  void Use(std::size_t i) { next_[i] = i + 1; }
  bool used(std::size_t i) const { return next_[i] != i; }

 private:
  mutable std::vector<std::size_t> next_;
};

// Walks a fixed schedule with a cursor, skipping (using up) entries whose cell has no queued
// work (no fetch); once the schedule is used up, Max Work. With several processors an entry
// whose cell another processor is working (QueueView::busy) is deferred, not used up: Next
// takes the first entry after it whose cell has work in view, and the deferred entry stays
// first in line for when its cell is free; when every entry left is deferred, Max Work
// chooses and the entries stay. When no cell has work in view (a processor woken while the
// others work every cell that has some), Next returns nullopt without skipping anything.
// Shared by the Peel oracle, Cell Tree scheduling and the planners.
class ScheduleFollower {
 public:
  struct Stats {
    std::size_t followed = 0;  // entries fetched
    std::size_t skipped = 0;   // entries skipped, their cell having no work
    std::size_t deferred = 0;  // times an entry was passed over, its cell busy
    std::size_t max_work = 0;  // fetches chosen by Max Work (schedule used up, or all deferred)
    // "followed 5, skipped 2, deferred 0, max work 1".
    std::string ToString() const;
  };

  // Starts over on `schedule`; every entry must be < cells.
  void Reset(std::vector<CellId> schedule, std::uint32_t cells);
  std::optional<CellId> Next(const QueueView& queues);
  // Next's choice without moving the cursor or counting.
  std::optional<CellId> Peek(const QueueView& queues) const;
  // Why the last Next chose its cell: "followed" (the next schedule entry with work) or "max
  // work" (the schedule was used up), with " (skipped N)" when that Next skipped N entries
  // whose cell had no work; empty before any Next, or when the last found no work.
  std::string Reason() const;
  const std::vector<CellId>& schedule() const { return schedule_; }
  std::size_t cursor() const { return cursor_; }
  const Stats& stats() const { return stats_; }

 private:
  // The entry Next would take, from cursor_ on, and whether it would use up the entries
  // before it that are not deferred; schedule_.size() when none has work in view.
  std::size_t Find(const QueueView& queues) const;

  std::vector<CellId> schedule_;
  std::size_t cursor_ = 0;  // entries before it are used up
  UnusedEntries used_;      // per entry: used up (those from cursor_ on, taken out of order)
  Stats stats_;
  // The last Next: how it chose (0 none, 1 followed, 2 max work) and the entries it skipped.
  std::uint8_t last_how_ = 0;
  std::size_t last_skipped_ = 0;
};

// Every scheduler, in the order of --help, sweeps and raycell study's tables: the one list that
// MakeScheduler, the configuration's validation and messages, --help and the study's tables
// are derived from. A new scheduler is an entry in its own file and a line here
// (scheduling/scheduler.cpp lists the entries by reference, so no linker drops one).
const std::vector<std::reference_wrapper<const SchedulerEntry>>& SchedulerRegistry();
// The registry's names, in its order; and joined by `separator` ("maxwork | roundrobin ...").
const std::vector<std::string>& SchedulerNames();
std::string SchedulerNameList(const char* separator);
// The names of the entries whose choices depend on the seed (SchedulerEntry::seeded), in the
// registry's order, joined by `separator`.
std::string SeededSchedulerList(const char* separator);
// The entry named `name`: the one lookup by name. InputError "WHAT: unknown scheduler 'x'
// (expected maxwork, roundrobin, ... or celltree-union)" for any other name.
const SchedulerEntry& SchedulerByName(std::string_view name, const std::string& what);
// A new scheduler of the entry's kind.
std::unique_ptr<Scheduler> MakeScheduler(const SchedulerEntry& entry, std::uint64_t seed);
// The same by name (SchedulerByName with what "scheduler"), for tests and tools that name one.
std::unique_ptr<Scheduler> MakeScheduler(std::string_view name, std::uint64_t seed);

// A scheduler that follows a schedule chosen in BeginFrame (ScheduleFollower: entries with no
// work skipped, then Max Work). The Peel oracle and Cell Tree scheduling differ only in which
// tree's Peel schedule they follow.
class FollowingScheduler : public Scheduler {
 public:
  explicit FollowingScheduler(const SchedulerEntry& entry) : Scheduler(entry) {}
  std::optional<CellId> Next(const QueueView& queues) override { return follower_.Next(queues); }
  std::optional<CellId> Peek(const QueueView& queues) const override {
    return follower_.Peek(queues);
  }
  std::string Reason() const override { return follower_.Reason(); }
  // The schedule is copied in BeginFrame: no tree is read after it.
  bool ReadsEarlierTrees() const override { return false; }
  const ScheduleFollower& follower() const { return follower_; }

 protected:
  ScheduleFollower follower_;
};

}  // namespace raycell
