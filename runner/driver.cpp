#include "runner/driver.h"

#include <algorithm>
#include <atomic>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "base/check.h"
#include "base/checked.h"
#include "base/parallel.h"
#include "graph/frame_tree.h"
#include "replay/level_units.h"
#include "replay/replacement.h"
#include "scheduling/scheduler.h"

namespace raycell {
namespace {

// Gives the pages of the heap's free chunks back to the system (glibc; elsewhere nothing): the
// large arrays of one frame, freed, leave holes that the next frame's, of other sizes, do not
// fill exactly, and a process walking many frames would otherwise keep them all resident
// (issue 43: the peak grew with the frames walked).
void ReturnFreedMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

std::unique_ptr<CellTree> TreeOf(const RayBatch& rays) {
  CellTreeBuilder builder;
  builder.AddBatch(rays);
  return std::make_unique<CellTree>(builder.Finish());
}

// Frame i's tree alone, of 1 in k ray trees: streamed batch by batch when k = 1.
std::unique_ptr<CellTree> LoadTree(const TraceReader& reader, std::size_t i, std::uint32_t k) {
  if (k == 1) return std::make_unique<CellTree>(BuildFrameTree(reader, i));
  return TreeOf(SampleRayTrees(reader.LoadFrame(i), k));
}

void ScaleBack(ReplayResult& r, std::uint32_t k, std::uint32_t processors) {
  if (k == 1) return;
  const SimTime extra = r.work * (k - 1);
  r.rays = CheckedMul(r.rays, k);
  r.segments = CheckedMul(r.segments, k);
  r.samples = CheckedMul(r.samples, k);
  r.work = r.work * k;
  // The added work spread over the processors, in the time and its bound alike.
  const SimTime spread = SimTime::Picoseconds(extra.picoseconds() / processors);
  r.time = r.time + spread;
  r.time_bound = r.time_bound + spread;
}

// `inner`, told `begun()` after its first BeginFrame of the frame (where schedulers read frame
// i-2's tree and the frames seen), forwarding every call unchanged.
class BeginSignal final : public Scheduler {
 public:
  BeginSignal(Scheduler& inner, std::function<void()> begun)
      : Scheduler(inner.entry()), inner_(inner), begun_(std::move(begun)) {}
  void BeginFrame(const FrameInfo& frame) override {
    inner_.BeginFrame(frame);
    if (begun_) std::exchange(begun_, nullptr)();
  }
  std::optional<CellId> Next(const QueueView& queues) override { return inner_.Next(queues); }
  std::optional<CellId> Peek(const QueueView& queues) const override { return inner_.Peek(queues); }
  std::string Reason() const override { return inner_.Reason(); }
  bool Watches() const override { return inner_.Watches(); }
  void Arrived(const Arrival& arrival) override { inner_.Arrived(arrival); }
  void Taken(CellId cell) override { inner_.Taken(cell); }
  DecisionCost Cost() const override { return inner_.Cost(); }
  bool ReadsEarlierTrees() const override { return inner_.ReadsEarlierTrees(); }
  bool Prepare(const FrameInfo& frame) override { return inner_.Prepare(frame); }

 private:
  Scheduler& inner_;
  std::function<void()> begun_;
};

}  // namespace

void Accumulate(const ReplayResult& f, ReplayResult* t) {
  if (t->levels.empty()) t->levels.assign(f.levels.size(), {});
  for (std::size_t i = 0; i < f.levels.size(); ++i) {
    t->levels[i].name = f.levels[i].name;
    CheckedIncrement(t->levels[i].fetches, f.levels[i].fetches);
    CheckedIncrement(t->levels[i].bytes, f.levels[i].bytes);
  }
  CheckedIncrement(t->fetches, f.fetches);
  if (f.bound) t->bound = CheckedAdd(t->bound.value_or(0), *f.bound);
  t->time = t->time + f.time;
  t->time_bound = t->time_bound + f.time_bound;  // every frame starts at time 0
  t->work = t->work + f.work;
  t->stall = t->stall + f.stall;
  t->idle = t->idle + f.idle;
  t->peak_queued_rays = std::max(t->peak_queued_rays, f.peak_queued_rays);
  t->peak_queued_bytes = std::max(t->peak_queued_bytes, f.peak_queued_bytes);
  CheckedIncrement(t->rays, f.rays);
  CheckedIncrement(t->segments, f.segments);
  CheckedIncrement(t->samples, f.samples);
  CheckedIncrement(t->events, f.events);
  CheckedIncrement(t->prefetches, f.prefetches);
  CheckedIncrement(t->prefetch_hits, f.prefetch_hits);
  CheckedIncrement(t->decisions, f.decisions);
  CheckedIncrement(t->decision_steps, f.decision_steps);
  t->scheduler_bytes = std::max(t->scheduler_bytes, f.scheduler_bytes);
  t->passes = std::max(t->passes, f.passes);
  t->min_converged = t->min_converged && f.min_converged;
}

void FinishTotal(std::uint32_t processors, ReplayResult* t) {
  const double capacity = double(t->time.picoseconds()) * processors;
  t->utilisation = capacity > 0 ? double(t->work.picoseconds()) / capacity : 0.0;
}

// ---- Frames ------------------------------------------------------------------------------

FrameWalker::FrameWalker(const TraceReader& reader, std::vector<std::size_t> frame_indices,
                         bool need_segments, bool need_nodes, std::uint32_t sample_every,
                         std::uint32_t history, std::uint64_t compact_above_visits, bool warm_up,
                         bool keep_tree)
    : reader_(reader),
      indices_(std::move(frame_indices)),
      need_segments_(need_segments),
      need_nodes_(need_nodes),
      k_(sample_every),
      history_(history),
      own_tree_(keep_tree),
      compact_above_(compact_above_visits) {
  if (k_ < 1) throw InputError("sampling: 1 in k ray trees needs k >= 1");
  for (std::size_t p = 1; p < indices_.size(); ++p) RAYCELL_CHECK_LT(indices_[p - 1], indices_[p]);
  asked_ = indices_.size();
  if (warm_up && !indices_.empty()) {
    std::vector<std::size_t> all(indices_.back() + 1);
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    asked_for_.assign(all.size(), false);
    for (std::size_t i : indices_) asked_for_[i] = true;
    indices_ = std::move(all);
  } else {
    asked_for_.assign(indices_.size(), true);
  }
}

LoadedFrame* FrameWalker::Advance() {
  if (position_ == indices_.size()) return nullptr;
  const std::size_t i = indices_[position_];
  LoadedFrame& f = frame_;
  const bool follows = position_ > 0 && indices_[position_ - 1] == i - 1;
  // What the frame before needed and this one does not, released before this one is built.
  f.segments.reset();
  f.nodes.reset();
  f.bound = 0;
  if (history_ == 0) f.tree.reset();
  // Frame i - 2's tree, for schedulers that plan from the last two frames.
  if (history_ < 2 || i < 2) {
    f.before_previous.reset();
  } else if (follows) {
    f.before_previous = std::move(f.previous);
  } else {
    f.before_previous = LoadTree(reader_, i - 2, k_);
  }
  if (i == 0 || history_ == 0) {
    f.previous.reset();
  } else if (follows) {
    f.previous = std::move(f.tree);  // Cell Tree scheduling needs frame i - 1's tree
  } else {
    f.previous = LoadTree(reader_, i - 1, k_);
  }
  f.tree.reset();  // moved to previous, or not kept
  // Trees parked while the frames before were replayed (ReplayFrames), read again from here:
  // made whole once the frame before's work is freed.
  for (CellTree* t : {f.previous.get(), f.before_previous.get()}) {
    if (t != nullptr && t->parked()) t->Unpark();
  }
  f.warm_up = !asked_for_[position_];
  f.position = reported_;
  f.index = i;
  f.number = reader_.frames()[i].frame;
  f.footprints = &reader_.FrameFootprints(i);
  return &f;
}

void FrameWalker::Build() {
  RAYCELL_CHECK_LT(position_, indices_.size());  // after Advance
  const std::size_t i = indices_[position_];
  const std::uint32_t cells = reader_.header().cell_count();
  LoadedFrame& f = frame_;
  // What the frame before held, before this one's arrays are made; only where trees are kept
  // across frames (the holes' cause; Max Work per segment ran ~10% longer with it).
  if (history_ > 0) ReturnFreedMemory();
  // The tree: for the work per node, the bound, the oracles, and the next frame's previous.
  // Kept where a replay reads it, or for the next frame's previous (none after the last one
  // walked where the caller reads no tree).
  const bool last = position_ + 1 == indices_.size();
  const bool keep = own_tree_ || (history_ > 0 && !(skip_last_tree_ && last));
  const bool need_tree = need_nodes_ || keep;
  if (!need_segments_ && k_ == 1) {  // per node the tree is all the replay needs: stream it
    f.tree = LoadTree(reader_, i, 1);
  } else if (k_ == 1 && reader_.frames()[i].visits > compact_above_) {
    // A large frame: the tree and the compact per-segment work from one stream of batches.
    CellTreeBuilder trees;
    if (need_tree) trees.Reserve(reader_.frames()[i].visits);
    RaySegmentWorkBuilder work(cells);
    work.Reserve(reader_.frames()[i]);
    reader_.ForEachBatch(i, [&](const RayBatch& b) {
      if (need_tree) trees.AddBatch(b);
      work.AddBatch(b);
    });
    if (need_tree) f.tree = std::make_unique<CellTree>(trees.Finish());
    f.segments = std::make_unique<WorkGraph>(work.Finish());
  } else {
    RayBatch rays = reader_.LoadFrame(i);
    if (k_ > 1) rays = SampleRayTrees(rays, k_);
    if (need_tree) f.tree = TreeOf(rays);
    if (need_segments_) f.segments = std::make_unique<WorkGraph>(RaySegmentWork(rays, cells));
  }
  if (need_nodes_) f.nodes = std::make_unique<WorkGraph>(PackedNodeWork(*f.tree, cells));
  f.bound = f.tree ? Bound(*f.tree) : 0;
  if (!keep) f.tree.reset();  // its work and bound made, no replay reads it
  // And what building them left (the builder's arrays, grown and freed): holes in the heap
  // otherwise resident beside the replays' own arrays (b4096, `celltree-adaptive`, 8
  // processors: 44 MB of the peak).
  if (history_ > 0) ReturnFreedMemory();
  if (!f.warm_up) ++reported_;
  ++position_;
}

namespace {

// The trees a replay of `frame` is told (FrameInfo): an earlier frame's tree in other cells (a
// dynamic subdivision whose boxes changed) says nothing about this frame's cells, so the
// schedulers get none, as in frame 0 (design §5).
// `current`: whether the frame's own tree is given (not when the replay begins before or while
// the frame is built: the walker's Build writes it then).
FrameTrees TreesOf(const LoadedFrame& frame, const TraceHeader& header, PlanCache* plans,
                   unsigned threads, bool current = true) {
  const std::uint32_t cells = header.cell_count();
  const SubdivisionInfo& sub = header.subdivision;
  const CellTree* previous = frame.previous && sub.SameCells(frame.index, frame.index - 1, cells)
                                 ? frame.previous.get()
                                 : nullptr;
  const CellTree* before =
      previous && frame.before_previous && sub.SameCells(frame.index, frame.index - 2, cells)
          ? frame.before_previous.get()
          : nullptr;
  return FrameTrees{
      frame.index, current ? frame.tree.get() : nullptr, previous, cells, before, plans, threads};
}

const std::vector<std::uint64_t>& FootprintsOf(const LoadedFrame& frame,
                                               const TraceHeader& header) {
  return frame.footprints ? *frame.footprints : header.footprints;
}

}  // namespace

std::unique_ptr<FrameStart> StartLoadedFrame(const LoadedFrame& frame, const TraceHeader& header,
                                             const ReplayConfig& config, const Scheduler& scheduler,
                                             MemoryState* memory, const MemoryUnits* units,
                                             PlanCache* plans, unsigned threads) {
  RAYCELL_CHECK(!scheduler.entry().oracle);  // an oracle begins with the frame's own tree
  const FrameTrees trees = TreesOf(frame, header, plans, threads, /*current=*/false);
  return std::make_unique<FrameStart>(FootprintsOf(frame, header), config, scheduler, trees, memory,
                                      units);
}

ReplayResult ReplayLoadedFrame(const LoadedFrame& frame, const TraceHeader& header,
                               const ReplayConfig& config, Scheduler& scheduler,
                               std::uint32_t sample_every, ReplayObserver* observer,
                               MemoryState* memory, const MemoryUnits* units, PlanCache* plans,
                               FrameStart* start, unsigned threads) {
  const bool per_ray = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay;
  const WorkGraph* work = per_ray ? frame.segments.get() : frame.nodes.get();
  RAYCELL_CHECK(work != nullptr);  // the walker was asked for this granularity
  ReplayResult r =
      ReplayFrame(*work, FootprintsOf(frame, header), config, scheduler,
                  TreesOf(frame, header, plans, threads), frame.bound, observer, memory, units,
                  /*seen=*/true, start);
  ScaleBack(r, sample_every, config.processors.count);
  r.frame = frame.number;
  return r;
}

// ---- Many configurations -----------------------------------------------------------------

ReplayConfig CanonicalConfig(const ReplayConfig& config) {
  ReplayConfig c = config;
  c.granularity = EffectiveGranularity(config);
  if (!c.scheduler->seeded) c.seed = 0;
  if (!c.scheduler->predicts) c.processors.prefetch = false;
  c.processors.queue_record_bytes = 1;
  return c;
}

ReplayFramesStats ReplayFrames(const TraceReader& reader,
                               const std::vector<std::size_t>& frame_indices,
                               const std::vector<ReplayConfig>& configs,
                               const ReplayFramesOptions& options, const FrameResults& on_frame) {
  if (options.sample_every < 1) throw InputError("sampling: 1 in k ray trees needs k >= 1");
  // An observer sees one replay as it ran: one configuration, not sampled.
  RAYCELL_CHECK(options.observer == nullptr || (configs.size() == 1 && options.sample_every == 1));
  // Each canonical configuration once; `which` maps every configuration to its own.
  std::vector<ReplayConfig> distinct;
  std::vector<std::size_t> which(configs.size());
  std::map<std::string, std::size_t> seen;
  for (std::size_t i = 0; i < configs.size(); ++i) {
    if (!options.checked) CheckReplay(configs[i], reader.header().cell_count());
    ReplayConfig c = CanonicalConfig(configs[i]);
    const auto it = seen.emplace(ToToml(c), distinct.size()).first;
    if (it->second == distinct.size()) distinct.push_back(std::move(c));
    which[i] = it->second;
  }
  bool need_segments = false, need_nodes = false;
  std::uint32_t history = 0;  // earlier frames' trees the schedulers read
  // Whether a replay reads the frame's own tree: an oracle's, or the bound where it holds.
  bool own_tree = false;
  std::vector<std::unique_ptr<Scheduler>> schedulers;
  std::vector<std::size_t> order;  // per-segment replays (the long ones) first
  const auto per_segment = [&](std::size_t d) {
    return distinct[d].granularity == ReplayConfig::Granularity::kRay;
  };
  for (std::size_t d = 0; d < distinct.size(); ++d) {
    (per_segment(d) ? need_segments : need_nodes) = true;
    schedulers.push_back(MakeScheduler(*distinct[d].scheduler, distinct[d].seed));
    history = std::max(history, distinct[d].scheduler->history);
    own_tree = own_tree || distinct[d].scheduler->oracle || BoundHolds(distinct[d]);
    order.push_back(d);
  }
  std::stable_partition(order.begin(), order.end(), per_segment);
  // Per distinct configuration with warm memory, what its levels hold between frames.
  // A volume that changes every frame keeps nothing: warm is cold there. Cells that are other
  // boxes every frame (a dynamic subdivision) keep what the fine cells say they still hold
  // (CarryOver).
  std::vector<std::unique_ptr<MemoryState>> memory(distinct.size());
  std::vector<std::size_t> warm;  // order's entries with warm memory
  for (std::size_t d : order) {
    if (distinct[d].memory.across_frames != MemoryConfig::AcrossFrames::kWarm) continue;
    if (reader.header().volume_changes()) continue;
    memory[d] = std::make_unique<MemoryState>();
    warm.push_back(d);
  }
  // What each distinct configuration's levels hold; checked before any frame is read.
  std::vector<MemoryUnits> units;
  for (const ReplayConfig& c : distinct) units.push_back(LevelUnitsOf(c, reader));
  // Whether some replay begins a frame again (a level's policy needs its future requests).
  bool again = false;
  for (const ReplayConfig& c : distinct) {
    for (const LevelConfig& l : c.levels) again = again || l.replacement->needs_future;
  }
  const TraceHeader& header = reader.header();
  FrameWalker walker(reader, frame_indices, need_segments, need_nodes, options.sample_every,
                     history, options.compact_above_visits, !warm.empty(), own_tree);
  if (!options.caller_reads_trees) walker.SkipLastTree();
  WorkerPool pool(unsigned(
      std::clamp<std::size_t>(options.jobs, 1, std::max<std::size_t>(distinct.size(), 1))));
  // What each replay may run its own work on (auto's check): the threads no configuration takes.
  const unsigned own_threads = std::max(1u, options.jobs / pool.threads());
  std::vector<ReplayResult> distinct_results(distinct.size()), results(configs.size());
  ReplayFramesStats stats;
  stats.own_threads = own_threads;
  stats.distinct = distinct.size();
  std::size_t walked = 0;
  // A dynamic subdivision's cells per fine cell, in the frame walked before and in this one.
  const bool carry = header.cells_change() && !warm.empty();
  std::vector<CellId> of_fine_before, of_fine;
  const std::vector<std::uint64_t>* footprints_before = nullptr;
  // Whether the replays begin each frame before its tree and work are built (FrameStart): when
  // no scheduler is an oracle (which begins with the frame's own tree) and no policy begins the
  // frame again (MIN), so that frame i-2's tree is freed before frame i's tree is built.
  bool start_early = !again;
  for (const auto& s : schedulers) start_early = start_early && !s->entry().oracle;
  while (LoadedFrame* frame = walker.Advance()) {
    ++walked;
    if (carry) {  // the walker walks every frame from 0 when some memory is warm
      of_fine = header.subdivision.CellOfFine(frame->index, header.cell_count());
      if (footprints_before != nullptr) {
        const FrameCells from{&of_fine_before, footprints_before}, to{&of_fine, frame->footprints};
        for (std::size_t d : warm) {
          if (memory[d]->empty()) continue;
          // What the levels keep of it: the cells that fit, as the policies keep them.
          *memory[d] = MemoryHierarchy::Fitted(distinct[d], *frame->footprints,
                                               CarryOver(*memory[d], from, to));
        }
      }
      of_fine_before.swap(of_fine);
      footprints_before = frame->footprints;
    }
    const std::vector<std::size_t>& run = frame->warm_up ? warm : order;
    // A warm-up frame is not watched: the observer sees the frames asked for.
    ReplayObserver* observer = frame->warm_up ? nullptr : options.observer;
    // This frame's plans: one cache for every configuration, or one each (searched again).
    PlanCache shared(true);
    std::vector<std::unique_ptr<PlanCache>> own(options.share_plans ? 0 : distinct.size());
    for (auto& p : own) p = std::make_unique<PlanCache>(false);
    // Frame i-2's tree and the plan caches are read only in BeginFrame (a scheduler holds what
    // it reads of the cache afterwards): freed once every replay of the frame began (issue 43),
    // unless a policy that needs its future requests (MIN) begins the frame again. So a value
    // one configuration holds (a union of trees and its plan) goes when its replay ends.
    const bool release = !again;
    const auto release_begun = [&] {
      shared.ReleaseAll();
      for (const auto& p : own) p->ReleaseAll();
      // The heap's free pages go back where frame i-2's tree goes (and what was made of it: the
      // replays of frames seen), as before the whole cache was released; not every frame of a
      // replay that keeps no tree (Max Work), which ran longer with it.
      if (frame->before_previous != nullptr) {
        walker.ReleaseBeforePrevious();
        ReturnFreedMemory();
      }
    };
    const auto plans_of = [&](std::size_t d) {
      return options.share_plans ? &shared : own[d].get();
    };
    std::vector<std::unique_ptr<FrameStart>> starts(distinct.size());
    const auto start = [&](std::size_t d) {
      if (starts[d] == nullptr) {
        starts[d] = StartLoadedFrame(*frame, header, distinct[d], *schedulers[d], memory[d].get(),
                                     &units[d], plans_of(d), own_threads);
      }
    };
    const auto begin_and_free = [&] {
      pool.ParallelFor(run.size(), [&](std::size_t n) {
        const std::size_t d = run[n];
        start(d);
        starts[d]->Begin(*schedulers[d]);
      });
      if (release) release_begun();
      // Nor, where no replay reads it once begun (Scheduler::ReadsEarlierTrees), the previous
      // frame's tree: it waits parked, as the frame's own below, until the next frame begins.
      bool park_previous = frame->previous != nullptr;
      for (std::size_t d : run) {
        park_previous = park_previous && !schedulers[d]->ReadsEarlierTrees();
      }
      if (park_previous && !frame->previous->parked()) frame->previous->Park();
    };
    // With a thread to spare (a replay given more threads than it has configurations), the
    // replays begin on it while the frame's tree and work are built, which BeginFrame never
    // reads (issue 43: the plans' time beside the build's, on 2 cores), where no configuration
    // reads frame i-2's tree (every scheduler's history at most 1): their plans are of one tree,
    // whose working memory beside the build's is small, where a union of two trees made beside
    // it was not (docs/design.md §2 "What a replay holds"). The results are the same either way.
    // Where some configuration reads frame i-2's tree, each makes first what it would make of
    // the two trees (Scheduler::Prepare: a union); where every one then reads nothing more of
    // them, they wait parked and the replays begin while the frame is built, as those of
    // history 1 do (the union is held through the replay anyway; only its plan's working
    // memory is beside the build's).
    bool prepared = start_early && own_threads > 1 && history == 2;
    if (prepared) {
      for (std::size_t d : run) {
        start(d);
        prepared = schedulers[d]->Prepare(starts[d]->info()) && prepared;
      }
      if (prepared) {
        for (CellTree* t : {frame->previous.get(), frame->before_previous.get()}) {
          if (t != nullptr && !t->parked()) t->Park();
        }
        ReturnFreedMemory();
      }
    }
    const bool overlap = start_early && own_threads > 1 && (history <= 1 || prepared);
    std::optional<Background> beginning;
    if (overlap) {
      ++stats.begun_while_built;
      beginning.emplace(begin_and_free);
    } else if (start_early) {
      begin_and_free();
    }
    walker.Build();
    if (overlap) beginning->Join();
    // Begun early, no replay reads the frame's own tree while it runs (no oracle; the work and
    // bound are made): it waits parked until the next frame begins (CellTree::Park; the
    // walker's Advance makes it whole again, once this frame's work is freed).
    const bool park = start_early && frame->tree != nullptr;
    if (park) {
      frame->tree->Park();
      ReturnFreedMemory();
    }
    std::atomic<std::size_t> to_begin{run.size()};
    const std::function<void()> begun = [&] {
      if (to_begin.fetch_sub(1, std::memory_order_acq_rel) == 1) release_begun();
    };
    const bool signal_begun = release && !start_early;
    // Begun early, the replays holding the most of what they began with go first (after the
    // per-segment ones, the long ones, as `order`): on one thread each such state then goes
    // before the next replay, instead of sitting beside it (issue 43: a sweep of `auto` and
    // `balanced-adaptive` at 4096 cells held the latter's union of two trees through the
    // former's replay). The results do not depend on the order.
    std::vector<std::size_t> replays = run;
    if (start_early) {
      std::stable_sort(replays.begin(), replays.end(), [&](std::size_t a, std::size_t b) {
        if (per_segment(a) != per_segment(b)) return per_segment(a);
        return schedulers[a]->HeldBytes() > schedulers[b]->HeldBytes();
      });
    }
    pool.ParallelFor(replays.size(), [&](std::size_t n) {
      const std::size_t d = replays[n];
      {
        BeginSignal signal(*schedulers[d], signal_begun ? begun : nullptr);
        Scheduler& scheduler = signal_begun ? static_cast<Scheduler&>(signal) : *schedulers[d];
        distinct_results[d] = ReplayLoadedFrame(
            *frame, header, distinct[d], scheduler, options.sample_every, observer, memory[d].get(),
            &units[d], plans_of(d), starts[d].get(), own_threads);
      }  // the signal, which refers to the scheduler, goes before it
      starts[d].reset();
      // What the scheduler kept of this frame (per node of its tree: matches, depths, levels;
      // its plans) is read by no later frame (design §5 "No state across frames"): freed now, by
      // a fresh scheduler, not held while the other configurations replay the frame and the
      // next frame's tree is built (issue 43: a sweep of 4 planning configurations at 4096 cells
      // held each one's beside the one replaying).
      schedulers[d] = MakeScheduler(*distinct[d].scheduler, distinct[d].seed);
    });
    stats.plans += shared.made();
    for (const auto& p : own) stats.plans += p->made();
    if (frame->warm_up) {
      if (options.progress) options.progress(double(walked) / double(walker.walked()));
      continue;
    }
    for (std::size_t i = 0; i < configs.size(); ++i) {
      results[i] = distinct_results[which[i]];
      results[i].peak_queued_bytes =
          CheckedMul(results[i].peak_queued_rays, configs[i].processors.queue_record_bytes);
    }
    ++stats.frames;
    if (options.progress) options.progress(double(walked) / double(walker.walked()));
    if (!on_frame(*frame, results)) break;
  }
  return stats;
}

TraceReplay ReplayTrace(const TraceReader& reader, const std::vector<std::size_t>& frame_indices,
                        const ReplayConfig& config, const std::function<void(double)>& progress,
                        std::uint32_t sample_every, ReplayObserver* observer, unsigned jobs) {
  ReplayFramesOptions options;
  options.jobs = jobs;
  options.sample_every = sample_every;
  options.progress = progress;
  options.observer = observer;
  options.caller_reads_trees = false;
  TraceReplay out;
  ReplayFrames(reader, frame_indices, {config}, options,
               [&](const LoadedFrame&, const std::vector<ReplayResult>& results) {
                 Accumulate(results[0], &out.total);
                 out.frames.push_back(results[0]);
                 return true;
               });
  FinishTotal(config.processors.count, &out.total);
  return out;
}

}  // namespace raycell
