// The per-segment replay as it was before the batch core (replay/replayer.cpp): a Board
// component on the engine's Simulator, one event per unit through the general event queue.
// Test-only: the reference the fast core must equal exactly (tests/replay/core_test.cpp).
#include "tests/oracle/reference_replayer.h"

#include <algorithm>
#include <deque>
#include <map>
#include <numeric>
#include <sstream>

#include "base/check.h"
#include "base/checked.h"
#include "replay/replayer.h"
#include "tests/oracle/simulator.h"

namespace raycell {
namespace {

enum EventKind : std::uint32_t { kIdle = 0, kFetched = 1, kUnitDone = 2 };

std::uint64_t Pack(std::uint32_t processor, UnitId unit) {
  return (std::uint64_t{processor} << 32) | unit;
}

struct ProcessorState {
  std::optional<CellId> cell;   // locked and loaded while working
  std::deque<UnitId> worklist;  // units of `cell` to work in this fetch
  bool waiting = false;         // idle, no cell had work
  bool holding = false;         // `cell` is locked by this processor
  SimTime work, stall;
};

// The board: queues, processors and memory as one component; the processors' requests,
// fetch completions and unit completions are its events.
class Board : public Component {
 public:
  Board(const WorkGraph& w, const std::vector<std::uint64_t>& footprints,
        const ReplayConfig& config, Scheduler& scheduler, const MemoryHierarchy::Requests& futures)
      : w_(w),
        config_(config),
        scheduler_(scheduler),
        memory_(config, footprints, futures),
        queues_(w.cells),
        queued_rays_(w.cells, 0),
        view_(w.cells, 0),
        locked_(w.cells, 0),
        processors_(config.processors.count) {
    if (scheduler_.Watches()) {
      // Each unit's Cell Tree node, named by its path of cells: a unit in its predecessor's
      // cell is in its node, any other in that node's child for its cell.
      path_.assign(w.size(), {});
      std::vector<UnitId> stack;
      for (UnitId u : w.roots) {
        path_[u] = {w.cell[u]};
        stack.push_back(u);
      }
      while (!stack.empty()) {
        const UnitId u = stack.back();
        stack.pop_back();
        for (UnitId i = w.succ_begin[u]; i < w.succ_begin[u + 1]; ++i) {
          const UnitId s = w.succ[i];
          path_[s] = path_[u];
          if (w.cell[s] != w.cell[u]) path_[s].push_back(w.cell[s]);
          stack.push_back(s);
        }
      }
      known_[{}] = 0;
    }
    for (UnitId u : w.roots) Enqueue(u);
  }

  void Start(Simulator& sim) {
    for (std::uint32_t p = 0; p < processors_.size(); ++p) {
      sim.Schedule(id_, SimTime::Zero(), kIdle, Pack(p, 0));
    }
  }
  void set_id(ComponentId id) { id_ = id; }

  void Handle(const Event& e, Simulator& sim) override {
    const auto p = std::uint32_t(e.payload >> 32);
    if (e.kind == kIdle) OnIdle(p, sim);
    if (e.kind == kFetched) OnFetched(p, sim);
    if (e.kind == kUnitDone) OnUnitDone(p, UnitId(e.payload & 0xffffffffu), sim);
  }
  std::string Name() const override { return "board"; }
  bool HasWork() const override { return done_ < w_.size(); }
  std::string DumpState() const override {
    std::ostringstream s;
    s << done_ << " of " << w_.size() << " units done; queued rays per cell:";
    for (std::uint64_t q : queued_rays_) s << ' ' << q;
    return s.str();
  }

  ReplayResult Result(SimTime end) const;
  const MemoryHierarchy& memory() const { return memory_; }

 private:
  void Enqueue(UnitId u) {
    const CellId c = w_.cell[u];
    if (scheduler_.Watches()) {  // the node of u as the rays entering it would carry it
      const std::vector<CellId>& path = path_[u];
      const auto it = known_.try_emplace(path, std::uint32_t(known_.size())).first;
      const std::vector<CellId> parent(path.begin(), path.end() - 1);
      RAYCELL_CHECK(known_.count(parent) == 1);
      scheduler_.Arrived({it->second, known_.at(parent), c, w_.queued_rays[u],
                          parent.empty() ? kNoCell : parent.back()});
    }
    queues_[c.value()].push_back(u);
    queued_rays_[c.value()] += w_.queued_rays[u];
    queued_total_ += w_.queued_rays[u];
    peak_queued_ = std::max(peak_queued_, queued_total_);
  }

  // The queues a scheduler may choose from: cells being worked are not available.
  QueueView View(std::uint32_t p) {
    open_.resize(w_.cells);
    for (std::uint32_t c = 0; c < w_.cells; ++c) {
      view_[c] = locked_[c] ? 0 : queued_rays_[c];
      open_[c] = locked_[c] ? 0 : 1;
    }
    QueueView v = QueueView::Of(view_, processors_[p].cell);
    v.processor = p;
    v.open = open_.data();
    v.working = std::accumulate(locked_.begin(), locked_.end(), 0u);
    v.all_queued = queued_rays_.data();
    return v;
  }

  void OnIdle(std::uint32_t p, Simulator& sim) {
    const std::optional<CellId> c = scheduler_.Next(View(p));
    if (!c) {
      processors_[p].waiting = true;  // woken when work is released
      return;
    }
    RAYCELL_CHECK(!queues_[c->value()].empty());
    ++locked_[c->value()];  // more than one when a scheduler joins a busy cell
    processors_[p].cell = *c;
    processors_[p].holding = true;
    const SimTime ready = memory_.Fetch(p, *c, sim.now());
    processors_[p].stall = processors_[p].stall + (ready - sim.now());
    sim.ScheduleAt(id_, ready, kFetched, Pack(p, 0));
  }

  void TakeQueue(ProcessorState& ps) {
    auto& q = queues_[ps.cell->value()];
    if (!q.empty() && scheduler_.Watches()) scheduler_.Taken(*ps.cell);
    for (UnitId u : q) {
      ps.worklist.push_back(u);
      queued_rays_[ps.cell->value()] -= w_.queued_rays[u];
      queued_total_ -= w_.queued_rays[u];
    }
    q.clear();
  }

  void OnFetched(std::uint32_t p, Simulator& sim) {
    TakeQueue(processors_[p]);
    if (config_.processors.prefetch) {  // double buffering: the predicted next cell
      const std::optional<CellId> next = scheduler_.Peek(View(p));
      if (next) memory_.Prefetch(p, *next, sim.now(), *processors_[p].cell);
    }
    StartNext(p, sim);
  }

  void StartNext(std::uint32_t p, Simulator& sim) {
    ProcessorState& ps = processors_[p];
    if (ps.worklist.empty()) TakeQueue(ps);  // units that arrived while the cell was loaded
    if (ps.worklist.empty() && locked_[ps.cell->value()] > 1) Split(p);
    if (ps.worklist.empty()) {
      ps.holding = false;
      --locked_[ps.cell->value()];
      sim.Schedule(id_, SimTime::Zero(), kIdle, Pack(p, 0));
      return;
    }
    const UnitId u = ps.worklist.front();
    ps.worklist.pop_front();
    const SimTime dt = config_.processors.time_per_sample * w_.samples[u];
    ps.work = ps.work + dt;
    sim.Schedule(id_, dt, kUnitDone, Pack(p, u));
  }

  // p shares its cell and has nothing left: the later half of the units not yet started of
  // the holder with the most (two or more; the lowest number on ties).
  void Split(std::uint32_t p) {
    ProcessorState& ps = processors_[p];
    std::optional<std::uint32_t> victim;
    for (std::uint32_t q = 0; q < processors_.size(); ++q) {
      const ProcessorState& qs = processors_[q];
      if (q == p || !qs.holding || qs.cell != ps.cell || qs.worklist.size() < 2) continue;
      if (!victim || qs.worklist.size() > processors_[*victim].worklist.size()) victim = q;
    }
    if (!victim) return;
    std::deque<UnitId>& from = processors_[*victim].worklist;
    const std::size_t n = from.size() / 2;
    ps.worklist.assign(from.end() - std::ptrdiff_t(n), from.end());
    from.resize(from.size() - n);
  }

  void OnUnitDone(std::uint32_t p, UnitId u, Simulator& sim) {
    sim.NoteProgress();
    ++done_;
    CheckedIncrement(rays_, w_.rays_started[u]);
    CheckedIncrement(segments_, w_.segments[u]);
    CheckedIncrement(samples_, w_.samples[u]);
    bool released = false;
    for (UnitId i = w_.succ_begin[u]; i < w_.succ_begin[u + 1]; ++i) {
      const UnitId s = w_.succ[i];
      if (w_.cell[s] == w_.cell[u]) {
        processors_[p].worklist.push_back(s);  // spawned in the loaded cell: worked now
      } else {
        Enqueue(s);
        released = true;
      }
    }
    if (released) WakeWaiting(sim);
    StartNext(p, sim);
  }

  // First the waiting processors whose last cell has queued rays, then the others (design §2).
  void WakeWaiting(Simulator& sim) {
    for (const bool holders_first : {true, false}) {
      for (std::uint32_t q = 0; q < processors_.size(); ++q) {
        ProcessorState& qs = processors_[q];
        if (!qs.waiting) continue;
        if (holders_first && (!qs.cell || queued_rays_[qs.cell->value()] == 0)) continue;
        qs.waiting = false;
        sim.Schedule(id_, SimTime::Zero(), kIdle, Pack(q, 0));
      }
    }
  }

  const WorkGraph& w_;
  const ReplayConfig& config_;
  Scheduler& scheduler_;
  MemoryHierarchy memory_;
  std::vector<std::vector<UnitId>> queues_;
  std::vector<std::uint64_t> queued_rays_, view_;
  std::vector<std::uint32_t> locked_;  // per cell: the processors working it
  std::vector<std::uint64_t> open_;    // the view's mask: 0 where locked
  std::vector<ProcessorState> processors_;
  ComponentId id_ = 0;
  std::uint64_t done_ = 0, queued_total_ = 0, peak_queued_ = 0;
  std::uint64_t rays_ = 0, segments_ = 0, samples_ = 0;
  // For a scheduler that watches the frame unfold: per unit its path of cells, and the paths
  // queued so far, numbered in that order from 1 (the root's, empty, is 0).
  std::vector<std::vector<CellId>> path_;
  std::map<std::vector<CellId>, std::uint32_t> known_;
};

ReplayResult Board::Result(SimTime end) const {
  RAYCELL_CHECK_EQ(done_, std::uint64_t(w_.size()));
  ReplayResult r;
  r.levels = memory_.stats();
  r.fetches = r.levels[0].fetches;
  r.time = end;
  for (const ProcessorState& ps : processors_) {
    r.work = r.work + ps.work;
    r.stall = r.stall + ps.stall;
    r.idle = r.idle + (end - ps.work - ps.stall);
  }
  const double capacity = double(end.picoseconds()) * double(processors_.size());
  r.utilisation = capacity > 0 ? double(r.work.picoseconds()) / capacity : 0.0;
  r.peak_queued_rays = peak_queued_;
  r.peak_queued_bytes = CheckedMul(peak_queued_, config_.processors.queue_record_bytes);
  r.rays = rays_, r.segments = segments_, r.samples = samples_;
  r.prefetches = memory_.prefetches();
  r.prefetch_hits = memory_.prefetch_hits();
  return r;
}

}  // namespace

namespace {

bool UsesMin(const ReplayConfig& config) {
  for (const LevelConfig& l : config.levels) {
    if (l.replacement == &kMinReplacement) return true;
  }
  return false;
}

}  // namespace

ReplayResult ReferenceReplayFrame(const WorkGraph& work,
                                  const std::vector<std::uint64_t>& footprints,
                                  const ReplayConfig& config, Scheduler& scheduler,
                                  const FrameTrees& frame, std::uint64_t bound) {
  RAYCELL_CHECK_EQ(footprints.size(), std::size_t(work.cells));
  CheckReplayable(config);
  const bool min = UsesMin(config);
  const std::uint32_t max_passes = min ? std::uint32_t(config.levels.size()) + 1 : 1;
  MemoryHierarchy::Requests futures;
  // What the core tells the schedulers a fetch costs (not what this reference checks).
  const std::vector<double> fetch_samples = FetchSamples(config, footprints);
  // What the scheduler is told, made here from the design (§5: the frame's trees, the fetch
  // costs, the processors; a scheduler that watches sees no current tree; every level holds
  // the cells), not by the core's MakeFrameInfo: the oracle stays a second implementation.
  FrameInfo info;
  info.frame_index = frame.frame_index;
  info.current = scheduler.Watches() ? nullptr : frame.current;
  info.previous = frame.previous;
  info.cells = frame.cells;
  info.before_previous = frame.before_previous;
  info.fetch_samples = &fetch_samples;
  info.processors = config.processors.count;
  for (std::uint32_t pass = 1;; ++pass) {
    scheduler.BeginFrame(info);
    Board board(work, footprints, config, scheduler, futures);
    Simulator sim;
    board.set_id(sim.Add(board));
    board.Start(sim);
    sim.Run();
    const bool converged = pass > 1 && !board.memory().diverged();
    if (!min || converged || pass == max_passes) {
      ReplayResult r = board.Result(sim.now());
      if (BoundHolds(config)) r.bound = bound;
      r.events = sim.events_handled();
      r.passes = pass;
      r.min_converged = !min || converged;
      const Scheduler::DecisionCost cost = scheduler.Cost();
      r.decisions = cost.decisions;
      r.decision_steps = cost.steps;
      r.scheduler_bytes = cost.peak_bytes;
      return r;
    }
    futures = board.memory().requests();
  }
}

}  // namespace raycell
