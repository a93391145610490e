// The recommended scheduler (scheduling/auto_scheduler.h; docs/design.md §5 "The recommended
// scheduler"): its model of the board fetches as the replay per node with one processor; it
// processes every ray, segment and sample once on 1, 2 and 8 processors, on random frames and
// on a capture of frames that resemble each other; with one processor it runs celltree-adaptive
// in every frame; with several it falls back to Max Work exactly when the replay of the frames
// seen shows the candidates doing worse, and follows the best of them otherwise.
// (That it uses no future information: tests/scheduling/adaptive_test.cpp; that frame ranges
// give the whole replay's frames: tests/runner/driver_test.cpp.)
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "replay/config.h"
#include "replay/replayer.h"
#include "replay/work.h"
#include "runner/driver.h"
#include "scheduling/adaptive_scheduler.h"
#include "scheduling/auto_scheduler.h"
#include "scheduling/best_scheduler.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/max_work.h"
#include "tests/graph/test_trees.h"
#include "tests/replay/random_frame.h"
#include "tests/test_util.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

ReplayConfig Config(const SchedulerEntry& s, std::uint32_t processors) {
  ReplayConfig c = DefaultConfig();
  c.scheduler = &s;
  c.processors.count = processors;
  return c;
}

ReplayResult ReplayOn(const RayBatch& rays, const ReplayConfig& config, Scheduler& s,
                      const FrameTrees& info, const std::vector<std::uint64_t>& footprints) {
  const std::uint32_t cells = std::uint32_t(footprints.size());
  const CellTree tree = testing::TreeOf(rays);
  const WorkGraph w = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay
                          ? RaySegmentWork(rays, cells)
                          : NodeWork(tree, cells);
  return ReplayFrame(w, footprints, config, s, info, Bound(tree));
}

// What auto's check measures of scheduler `e` (one object for both frames): frame i-1 (`f1`,
// planned from `t2`, frame i-2's tree) then frame i-2 (`f2`, planned from `t1`) replayed under
// `node`, fetches and time summed.
ReplayResult OnFramesSeen(const SchedulerEntry& e, const RayBatch& f1, const RayBatch& f2,
                          const CellTree& t1, const CellTree& t2, const ReplayConfig& node,
                          const std::vector<std::uint64_t>& footprints) {
  const std::uint32_t cells = std::uint32_t(footprints.size());
  const FrameTrees seen{1, nullptr, &t2, cells}, back{1, nullptr, &t1, cells};
  auto s = MakeScheduler(e, 1);
  ReplayResult r = ReplayOn(f1, node, *s, seen, footprints);
  const ReplayResult q = ReplayOn(f2, node, *s, back, footprints);
  r.fetches += q.fetches;
  r.time = r.time + q.time;
  return r;
}

// With one processor the replay per node is exact (docs/design.md §2 "Granularity"), and the
// model is that replay: it fetches as many cells, for every scheduler auto asks it about.
TEST(AutoModel, FetchesAsTheReplayWithOneProcessor) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 40; ++trial) {
    const std::uint32_t cells = 2 + rng() % 8;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 60);
    const CellTree tree = testing::TreeOf(rays);
    const CellTree previous = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 20));
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1000 + rng() % 300'000;
    // Auto's candidate at one processor, the planners and Max Work (the model serves several
    // processors' checks, and outside a replay).
    const std::vector<const SchedulerEntry*> entries = {&kCellTreeAdaptiveEntry,
                                                        &kCellTreeUnionEntry, &kCellTreeBestEntry,
                                                        &kCellTreeEntry, &kMaxWorkEntry};
    for (const SchedulerEntry* e : entries) {
      ReplayConfig config = Config(*e, 1);
      config.granularity = ReplayConfig::Granularity::kNode;
      const FrameTrees info{1, nullptr, trial % 4 == 0 ? nullptr : &previous, cells};
      auto a = MakeScheduler(*e, 1), b = MakeScheduler(*e, 1);
      const ReplayResult r = ReplayOn(rays, config, *a, info, footprints);
      const std::vector<double> fetch_samples(cells, 7.0);
      FrameInfo f;
      f.frame_index = 1;
      f.previous = info.previous;
      f.cells = cells;
      f.fetch_samples = &fetch_samples;
      const ModelResult m = ModelFrame(tree, *b, f);
      EXPECT_EQ(m.fetches, r.fetches) << e->name << " trial " << trial;
      // Time: every sample once, 7 per fetch (the processor waits for its fetches).
      std::uint64_t samples = 0;
      for (const NodeId n : tree.nodes()) samples += tree.samples(n);
      EXPECT_EQ(m.time, double(samples) + 7.0 * double(m.fetches)) << e->name;
    }
  }
}

TEST(Auto, EveryRaySegmentAndSampleOnceOnRandomFrames) {
  std::mt19937 rng(43);
  int replays = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const std::uint32_t cells = 2 + rng() % 12;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 80);
    const CellTree previous = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 20));
    const CellTree before = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 20));
    const testing::RayCounts expected = testing::CountRays(rays);
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1000 + rng() % 300'000;
    for (const std::uint32_t p : {1u, 2u, 8u}) {
      ReplayConfig config = Config(kAutoEntry, p);
      if (trial % 2 == 1) config.levels[0].capacity = 2;
      if (trial % 3 == 1) config.granularity = ReplayConfig::Granularity::kNode;
      AutoScheduler s(1);
      FrameTrees info{2, nullptr, &previous, cells, &before};
      if (trial % 4 == 3) info = FrameTrees{1, nullptr, &previous, cells};
      const ReplayResult r = ReplayOn(rays, config, s, info, footprints);
      EXPECT_EQ(r.rays, expected.rays) << "P" << p << " trial " << trial;
      EXPECT_EQ(r.segments, expected.segments) << "P" << p;
      EXPECT_EQ(r.samples, expected.samples) << "P" << p;
      EXPECT_EQ(r.work + r.stall + r.idle, r.time * p) << "P" << p;
      ++replays;
    }
  }
  EXPECT_EQ(replays, 12 * 3);
}

// A capture whose frames resemble each other (a base frame, and in each frame a few rays with
// one more visit at their end), so that plans from earlier frames are worth following: every
// frame of a replay under auto processes exactly the frame's rays, segments and samples.
TEST(Auto, EveryRaySegmentAndSampleOnceOnACaptureOfSimilarFrames) {
  const std::string path = testing::TempPath("auto", "similar.rct");
  TraceHeader h;
  h.producer = "raycell test";
  h.scene = "builtin:test";
  h.cells = {3, 2, 1};
  for (std::uint32_t c = 0; c < h.cell_count(); ++c) h.footprints.push_back(20'000 * (c + 1));
  const int frames = 5;
  for (int f = 0; f < frames; ++f)
    h.cameras.push_back({f, {1, 2, 3.0 + f}, {0, 0, 0}, {0, 1, 0}, 40});
  h.settings.store_t = false;
  std::mt19937 rng(44);
  const RayBatch base = testing::RandomReplayFrame(rng, h.cell_count(), 80);
  std::vector<testing::RayCounts> expected;
  {
    TraceWriter w = TraceWriter::Create(path, h, 3);
    for (int f = 0; f < frames; ++f) {
      RayBatch b(false);
      for (std::size_t i = 0; i < base.size(); ++i) {
        const RayView ray = base.ray(i);
        b.BeginRay(ray.kind, ray.parent, ray.spawn, 0, 0);
        for (std::size_t v = 0; v < ray.visit_count; ++v) {
          b.AddVisit(ray.cells[v], ray.samples[v], 0, 0);
        }
        if (rng() % 8 == 0) {  // one more visit, to a cell other than its last
          CellId next;
          do next = CellId(std::uint32_t(rng() % h.cell_count()));
          while (next == ray.cells[ray.visit_count - 1]);
          b.AddVisit(next, 1 + std::uint32_t(rng() % 10), 0, 0);
        }
      }
      expected.push_back(testing::CountRays(b));
      w.BeginFrame(f);
      w.Append(b);
      w.EndFrame();
    }
    w.Finish();
  }
  const TraceReader reader = TraceReader::Open(path);
  for (const std::uint32_t p : {1u, 2u, 8u}) {
    const TraceReplay t = ReplayTrace(reader, {0, 1, 2, 3, 4}, Config(kAutoEntry, p));
    ASSERT_EQ(t.frames.size(), std::size_t(frames));
    for (int f = 0; f < frames; ++f) {
      EXPECT_EQ(t.frames[f].rays, expected[f].rays) << "P" << p << " frame " << f;
      EXPECT_EQ(t.frames[f].segments, expected[f].segments) << "P" << p << " frame " << f;
      EXPECT_EQ(t.frames[f].samples, expected[f].samples) << "P" << p << " frame " << f;
    }
  }
  std::remove(path.c_str());
}

// What a scheduler chose in one frame's replay, in order.
class Chooser : public Scheduler {
 public:
  explicit Chooser(std::unique_ptr<Scheduler> s) : Scheduler(s->entry()), s_(std::move(s)) {}
  std::vector<std::string> chosen;
  void BeginFrame(const FrameInfo& frame) override { s_->BeginFrame(frame); }
  std::optional<CellId> Next(const QueueView& q) override {
    // The cells chosen, in order. A call that chooses nothing is not recorded: how often the
    // replay asks while only busy cells have work depends on the scheduler's entry (Max Work
    // says it never joins one, SchedulerEntry::joins), not on the choices.
    const std::optional<CellId> c = s_->Next(q);
    if (c) chosen.push_back(std::to_string(c->value()));
    return c;
  }
  std::optional<CellId> Peek(const QueueView& q) const override { return s_->Peek(q); }
  bool Watches() const override { return s_->Watches(); }
  void Arrived(const Arrival& a) override { s_->Arrived(a); }
  void Taken(CellId c) override { s_->Taken(c); }
  DecisionCost Cost() const override { return s_->Cost(); }
  Scheduler& inner() { return *s_; }

 private:
  std::unique_ptr<Scheduler> s_;
};

// With one processor auto runs celltree-adaptive, falling back to Max Work only where Max Work
// saved kOneProcessorFallbackPercent of celltree-adaptive's fetches on the frames seen (frame i-1
// planned from frame i-2 and frame i-2 from frame i-1, replayed here on their own): on random
// frames i-2, i-1 and i its choices in frames 0 and 1 are celltree-adaptive's, one for one, and
// in frame 2 celltree-adaptive's or, where Max Work saved that share, Max Work's. Each case
// occurs, and frames where Max Work fetched fewer by less than that share keep the candidate.
TEST(Auto, OneProcessorFallsBackOnlyWhenMaxWorkSavedAQuarter) {
  std::mt19937 rng(45);
  ASSERT_EQ(AutoScheduler::CandidatesFor(1),
            std::vector<const SchedulerEntry*>{&kCellTreeAdaptiveEntry});
  int fell_back = 0, kept_though_max_work_fewer = 0, adaptive_fewer = 0;
  for (int trial = 0; trial < 80; ++trial) {
    // Half the trials repeat one frame (then the plans fit the frames seen), half draw each.
    const std::uint32_t cells = 2 + rng() % 6;
    const RayBatch f2 = testing::RandomReplayFrame(rng, cells, 30),
                   f1 = trial % 2 == 0 ? f2 : testing::RandomReplayFrame(rng, cells, 30),
                   f0 = testing::RandomReplayFrame(rng, cells, 30);
    const CellTree t2 = testing::TreeOf(f2), t1 = testing::TreeOf(f1);
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1000 + rng() % 300'000;
    ReplayConfig node = Config(kAutoEntry, 1);
    node.granularity = ReplayConfig::Granularity::kNode;
    const auto both = [&](const SchedulerEntry& e) {
      return OnFramesSeen(e, f1, f2, t1, t2, node, footprints).fetches;
    };
    const std::uint64_t m = both(kMaxWorkEntry), c = both(kCellTreeAdaptiveEntry);
    const bool fall_back = m * 4 < c * 3;  // Max Work saved a quarter
    fell_back += fall_back;
    kept_though_max_work_fewer += m < c && !fall_back;
    adaptive_fewer += c < m;
    const ReplayConfig ray = Config(kAutoEntry, 1);
    for (const FrameTrees& now :
         {FrameTrees{0, nullptr, nullptr, cells}, FrameTrees{1, nullptr, &t2, cells},
          FrameTrees{2, nullptr, &t1, cells, &t2}}) {
      const bool checked = now.frame_index == 2;
      const SchedulerEntry& runs = checked && fall_back ? kMaxWorkEntry : kCellTreeAdaptiveEntry;
      Chooser a(MakeScheduler(kAutoEntry, 1)), expected(MakeScheduler(runs, 1));
      ReplayOn(f0, ray, a, now, footprints);
      ReplayOn(f0, ray, expected, now, footprints);
      const AutoScheduler& inner = dynamic_cast<const AutoScheduler&>(a.inner());
      EXPECT_EQ(inner.checked(), checked);
      EXPECT_EQ(inner.chosen(), checked && fall_back ? AutoScheduler::kNone : 0u)
          << "trial " << trial << " frame " << now.frame_index << ": Max Work " << m
          << ", celltree-adaptive " << c;
      EXPECT_EQ(a.chosen, expected.chosen) << "trial " << trial << " frame " << now.frame_index;
    }
  }
  EXPECT_GE(fell_back, 2);
  EXPECT_GE(kept_though_max_work_fewer, 2);
  EXPECT_GE(adaptive_fewer, 5);
}

// With several processors the check replays the frames seen on the replay's own board
// (FrameInfo::seen: per node, its links and levels, joins), judged here by the replay itself:
// a candidate is taken when it fetched at least kMarginPerProcessor per processor fewer than
// Max Work over the two frames and, when it took longer, saved at least kTimeWaiverPercent of
// Max Work's fetches; the fewest fetches, then the least time, then the first listed; else Max
// Work. Both cases occur, and a candidate that fetched fewer but was refused for its time.
TEST(Auto, SeveralProcessorsJudgeOnTheReplaysOwnBoard) {
  std::mt19937 rng(47);
  const std::uint32_t p = 2;
  const std::vector<const SchedulerEntry*> candidates = AutoScheduler::CandidatesFor(p);
  int fell_back = 0, followed = 0, refused_for_time = 0;
  for (int trial = 0; trial < 40; ++trial) {
    // Half the trials repeat one frame (plans from the frames seen then fit), half draw each.
    const std::uint32_t cells = 3 + rng() % 6;
    const RayBatch f2 = testing::RandomReplayFrame(rng, cells, 40),
                   f1 = trial % 2 == 0 ? f2 : testing::RandomReplayFrame(rng, cells, 40),
                   f0 = trial % 2 == 0 ? f2 : testing::RandomReplayFrame(rng, cells, 30);
    const CellTree t2 = testing::TreeOf(f2), t1 = testing::TreeOf(f1);
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1000 + rng() % 300'000;
    ReplayConfig node = Config(kAutoEntry, p);
    node.granularity = ReplayConfig::Granularity::kNode;
    const auto both = [&](const SchedulerEntry& e) {
      return OnFramesSeen(e, f1, f2, t1, t2, node, footprints);
    };
    const ReplayResult rm = both(kMaxWorkEntry);
    const SchedulerEntry* best = nullptr;
    ReplayResult rb;
    for (const SchedulerEntry* e : candidates) {
      const ReplayResult r = both(*e);
      if (r.fetches + kMarginPerProcessor * p > rm.fetches) continue;
      if (r.time > rm.time && (rm.fetches - r.fetches) * 100 < rm.fetches * kTimeWaiverPercent) {
        ++refused_for_time;
        continue;
      }
      if (best == nullptr || r.fetches < rb.fetches ||
          (r.fetches == rb.fetches && r.time < rb.time)) {
        best = e, rb = r;
      }
    }
    const FrameTrees now{2, nullptr, &t1, cells, &t2};
    Chooser a(MakeScheduler(kAutoEntry, 1)),
        expected(MakeScheduler(best == nullptr ? kMaxWorkEntry : *best, 1));
    const ReplayConfig ray = Config(kAutoEntry, p);
    ReplayOn(f0, ray, a, now, footprints);
    ReplayOn(f0, ray, expected, now, footprints);
    const AutoScheduler& inner = dynamic_cast<const AutoScheduler&>(a.inner());
    EXPECT_TRUE(inner.checked());
    EXPECT_EQ(a.chosen, expected.chosen) << "trial " << trial;
    if (best == nullptr) {
      EXPECT_EQ(inner.chosen(), AutoScheduler::kNone) << "trial " << trial;
      ++fell_back;
    } else {
      EXPECT_EQ(candidates[inner.chosen()], best) << "trial " << trial;
      ++followed;
    }
  }
  EXPECT_GE(fell_back, 2);
  EXPECT_GE(followed, 2);
  EXPECT_GE(refused_for_time, 1);
  std::printf("fell back %d, followed %d, refused for time %d\n", fell_back, followed,
              refused_for_time);
}

// A scheduler that watches only once it began a frame, counting what it is told.
class WatchesOnceBegun : public Scheduler {
 public:
  WatchesOnceBegun() : Scheduler(kMaxWorkEntry) {}
  void BeginFrame(const FrameInfo&) override { begun_ = true; }
  std::optional<CellId> Next(const QueueView& q) override { return max_work_.Next(q); }
  bool Watches() const override { return begun_; }
  void Arrived(const Arrival&) override { ++arrivals; }
  std::size_t arrivals = 0;

 private:
  bool begun_ = false;
  MaxWorkScheduler max_work_;
};

// Whether a scheduler watches may depend on the frame (auto watches as the candidate it runs):
// the replay asks once the scheduler began the frame, so one that watches from then on is told
// every unit queued, and auto, running Max Work in frames 0 and 1 with several processors,
// watches nothing there, while with one processor it watches as celltree-adaptive does.
TEST(Auto, TheReplayAsksWhetherItWatchesOnceTheFrameBegan) {
  std::mt19937 rng(47);
  const std::uint32_t cells = 5;
  const RayBatch f = testing::RandomReplayFrame(rng, cells, 60);
  const CellTree tree = testing::TreeOf(f);
  const std::vector<std::uint64_t> footprints(cells, 50'000);
  for (const ReplayConfig::Granularity g :
       {ReplayConfig::Granularity::kNode, ReplayConfig::Granularity::kRay}) {
    ReplayConfig config = Config(kMaxWorkEntry, 2);
    config.granularity = g;
    WatchesOnceBegun w;
    ReplayOn(f, config, w, FrameTrees{0, nullptr, nullptr, cells}, footprints);
    EXPECT_GE(w.arrivals, tree.size() - 1);  // every node queued, at least once
  }
  for (const std::uint32_t processors : {1u, 8u}) {
    auto a = MakeScheduler(kAutoEntry, 1);
    ReplayOn(f, Config(kAutoEntry, processors), *a, FrameTrees{0, nullptr, nullptr, cells},
             footprints);
    EXPECT_EQ(a->Watches(), processors == 1) << processors << " processors";
  }
}

// With several processors, frames 0 and 1 (nothing seen to judge by) run Max Work.
TEST(Auto, SeveralProcessorsRunMaxWorkInFramesZeroAndOne) {
  std::mt19937 rng(46);
  for (int trial = 0; trial < 10; ++trial) {
    const std::uint32_t cells = 2 + rng() % 8;
    const RayBatch f1 = testing::RandomReplayFrame(rng, cells, 60),
                   f0 = testing::RandomReplayFrame(rng, cells, 60);
    const CellTree t1 = testing::TreeOf(f1);
    std::vector<std::uint64_t> footprints(cells, 50'000);
    const ReplayConfig eight = Config(kAutoEntry, 8);
    for (const FrameTrees& info :
         {FrameTrees{0, nullptr, nullptr, cells}, FrameTrees{1, nullptr, &t1, cells}}) {
      Chooser a(MakeScheduler(kAutoEntry, 1)), m(MakeScheduler(kMaxWorkEntry, 1));
      ReplayOn(f0, eight, a, info, footprints);
      ReplayOn(f0, eight, m, info, footprints);
      EXPECT_EQ(a.chosen, m.chosen) << "trial " << trial << " frame " << info.frame_index;
    }
  }
}

}  // namespace
}  // namespace raycell
