// The frame walk under every replay (runner/driver.h): each frame's result equals ReplayFrame
// on that frame's own work graph, tree and previous frame's tree built by hand, for
// contiguous and skipping frame lists, sampled frames, both granularities and many
// configurations at once on several threads; totals add up as documented.
#include "runner/driver.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <random>
#include <sstream>
#include <tuple>

#include "replay/replacement.h"
#include "scheduling/max_work.h"
#include "scheduling/scheduler.h"
#include "tests/graph/test_trees.h"
#include "tests/replay/random_frame.h"
#include "tests/test_util.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

std::string Describe(const ReplayResult& r) {
  std::ostringstream s;
  s << r.frame << " " << r.fetches << " " << (r.bound ? std::to_string(*r.bound) : "-") << " "
    << r.time << " " << r.time_bound << " " << r.work << " " << r.stall << " " << r.idle << " "
    << r.utilisation << " " << r.peak_queued_rays << " " << r.peak_queued_bytes << " " << r.rays
    << " " << r.segments << " " << r.samples << " " << r.events << " " << r.prefetches << " "
    << r.prefetch_hits;
  for (const LevelStats& l : r.levels) s << " " << l.name << " " << l.fetches << " " << l.bytes;
  return s.str();
}

class DriverTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    path_ = new std::string(testing::TempPath("driver", "trace.rct"));
    testing::WriteRandomCapture(*path_, {2, 2, 1}, 5, 10, 3, 60, 4,
                                [](std::uint32_t c) { return 5000 * (c + 1); });
    reader_ = new TraceReader(TraceReader::Open(*path_));
  }
  static void TearDownTestSuite() {
    delete reader_;
    std::remove(path_->c_str());
    delete path_;
  }

  // Frame i under `config`, everything built by hand; `k` samples 1 in k ray trees. With warm
  // memory, frames 0 .. i - 1 are replayed first and their memory carried to frame i.
  static ReplayResult ByHand(std::size_t i, const ReplayConfig& config, std::uint32_t k = 1) {
    if (config.memory.across_frames == MemoryConfig::AcrossFrames::kCold) {
      return ByHand(i, config, k, nullptr);
    }
    MemoryState memory;
    for (std::size_t j = 0; j < i; ++j) ByHand(j, config, k, &memory);
    return ByHand(i, config, k, &memory);
  }
  static ReplayResult ByHand(std::size_t i, const ReplayConfig& config, std::uint32_t k,
                             MemoryState* memory) {
    const TraceHeader& h = reader_->header();
    const RayBatch rays = SampleRayTrees(reader_->LoadFrame(i), k);
    const CellTree tree = testing::TreeOf(rays);
    const CellTree previous =
        testing::TreeOf(i > 0 ? SampleRayTrees(reader_->LoadFrame(i - 1), k) : RayBatch(false));
    const CellTree before =
        testing::TreeOf(i > 1 ? SampleRayTrees(reader_->LoadFrame(i - 2), k) : RayBatch(false));
    const WorkGraph w = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay
                            ? RaySegmentWork(rays, h.cell_count())
                            : NodeWork(tree, h.cell_count());
    auto s = MakeScheduler(*config.scheduler, config.seed);
    const bool two = config.scheduler->history == 2 && i > 1;
    const FrameTrees info{i, &tree, i > 0 ? &previous : nullptr, h.cell_count(),
                          two ? &before : nullptr};
    ReplayResult r = ReplayFrame(w, h.footprints, config, *s, info, Bound(tree), nullptr, memory);
    r.frame = reader_->frames()[i].frame;
    if (k > 1) {  // as ReplayTrace scales a sample back
      const SimTime extra = r.work * (k - 1);
      r.rays *= k, r.segments *= k, r.samples *= k, r.work = r.work * k;
      r.time = r.time + SimTime::Picoseconds(extra.picoseconds() / config.processors.count);
      r.time_bound =
          r.time_bound + SimTime::Picoseconds(extra.picoseconds() / config.processors.count);
    }
    return r;
  }

  static ReplayConfig Config(const char* scheduler, std::uint32_t processors) {
    ReplayConfig c = DefaultConfig();
    c.scheduler = &SchedulerByName(scheduler, "test");
    c.processors.count = processors;
    c.levels[0].capacity = processors > 1 ? 2 : 1;
    return c;
  }

  static std::string* path_;
  static TraceReader* reader_;
};

std::string* DriverTest::path_ = nullptr;
TraceReader* DriverTest::reader_ = nullptr;

TEST_F(DriverTest, EveryFrameEqualsItsReplayBuiltByHand) {
  for (const std::vector<std::size_t>& frames :
       {std::vector<std::size_t>{0, 1, 2, 3, 4}, {1, 3}, {2}, {0, 2, 3}}) {
    for (const char* scheduler : {"celltree", "peel", "maxwork", "random", "best", "celltree-best",
                                  "celltree-union", "auto"}) {
      for (std::uint32_t processors : {1u, 2u}) {
        for (std::uint32_t k : {1u, 2u}) {
          ReplayConfig config = Config(scheduler, processors);
          // Warm memory for the schedulers that follow plans, cold for the others.
          if (std::string(scheduler) == "maxwork" || std::string(scheduler) == "random") {
            config.memory.across_frames = MemoryConfig::AcrossFrames::kCold;
          }
          const TraceReplay t = ReplayTrace(*reader_, frames, config, {}, k);
          ASSERT_EQ(t.frames.size(), frames.size());
          ReplayResult total;
          SimTime time_bounds;  // added here, not by Accumulate
          for (std::size_t n = 0; n < frames.size(); ++n) {
            const ReplayResult expected = ByHand(frames[n], config, k);
            EXPECT_EQ(Describe(t.frames[n]), Describe(expected))
                << scheduler << " P" << processors << " k" << k << " frame " << frames[n];
            EXPECT_LE(t.frames[n].time_bound, t.frames[n].time);  // scaled back alike
            Accumulate(expected, &total);
            time_bounds = time_bounds + expected.time_bound;
          }
          FinishTotal(processors, &total);
          EXPECT_EQ(Describe(t.total), Describe(total));
          EXPECT_EQ(t.total.time_bound, time_bounds);
          EXPECT_EQ(t.total.frame, 0);
        }
      }
    }
  }
}

// Many configurations on two threads: each gets exactly what it gets alone, in order, and
// configurations differing only in the queue record size get their own peak bytes.
TEST_F(DriverTest, ManyConfigurationsAtOnceEqualEachAlone) {
  std::vector<ReplayConfig> configs;
  for (const std::string& s : SchedulerNames()) {
    for (std::uint32_t p : {1u, 2u, 3u}) configs.push_back(Config(s.c_str(), p));
  }
  configs.push_back(configs[4]);
  configs.back().processors.queue_record_bytes = 7;
  const std::vector<std::size_t> frames = {1, 2, 4};
  std::vector<std::vector<std::string>> got(configs.size());
  ReplayFramesOptions options;
  options.jobs = 2;
  const ReplayFramesStats stats =
      ReplayFrames(*reader_, frames, configs, options,
                   [&](const LoadedFrame& f, const std::vector<ReplayResult>& results) {
                     EXPECT_EQ(f.index, frames[f.position]);
                     for (std::size_t c = 0; c < results.size(); ++c)
                       got[c].push_back(Describe(results[c]));
                     return true;
                   });
  EXPECT_EQ(stats.frames, 3u);
  EXPECT_EQ(stats.distinct, configs.size() - 1);
  for (std::size_t c = 0; c < configs.size(); ++c) {
    const TraceReplay alone = ReplayTrace(*reader_, frames, configs[c]);
    for (std::size_t n = 0; n < frames.size(); ++n) {
      EXPECT_EQ(got[c][n], Describe(alone.frames[n])) << "config " << c << " frame " << n;
    }
  }
  EXPECT_NE(got.back(), got[4]);  // peak bytes: 7 per ray, not 32
}

// Frames above ReplayFramesOptions::compact_above_visits replay per segment from the Compact
// form, built from the frame's batches: every result equals the usual replay's.
TEST_F(DriverTest, TheCompactFormGivesTheSameResults) {
  std::vector<ReplayConfig> configs;
  for (const std::string& s : SchedulerNames()) {
    for (std::uint32_t p : {2u, 3u}) configs.push_back(Config(s.c_str(), p));
  }
  const std::vector<std::size_t> frames = {0, 1, 3, 4};
  std::vector<std::vector<std::string>> usual(configs.size()), compact(configs.size());
  for (const bool small : {false, true}) {
    ReplayFramesOptions options;
    options.jobs = 2;
    if (small) options.compact_above_visits = 0;
    ReplayFrames(*reader_, frames, configs, options,
                 [&](const LoadedFrame& f, const std::vector<ReplayResult>& results) {
                   EXPECT_EQ(f.segments->compact.units != 0, small);
                   EXPECT_EQ(f.segments->packed.empty(), small);
                   for (std::size_t c = 0; c < results.size(); ++c) {
                     (small ? compact : usual)[c].push_back(Describe(results[c]));
                   }
                   return true;
                 });
  }
  for (std::size_t c = 0; c < configs.size(); ++c) {
    ASSERT_EQ(compact[c].size(), frames.size());
    EXPECT_EQ(compact[c], usual[c]) << ToToml(configs[c]);
  }
}

// The seed reaches every scheduler whose choices depend on it (random, and the planners'
// seeded schedule searches): configurations that differ only in it are replayed apart, and
// the canonical form keeps it; for the others it is dropped, so they are replayed once.
TEST_F(DriverTest, TheSeedIsKeptForEverySchedulerThatUsesIt) {
  for (const std::string& s : SchedulerNames()) {
    // The planners seed their searches; random its draws.
    const bool seeded = s == "random" || s == "best" || s == "celltree-best" ||
                        s == "celltree-union" || s == "partition" || s == "partition-steal" ||
                        s == "balanced" || s == "celltree-2level-best" ||
                        s == "celltree-adaptive" || s == "balanced-adaptive" ||
                        s == "balanced-critical" || s == "celltree-dag" ||
                        s == "celltree-dag-oracle" || s == "auto";
    ReplayConfig a = Config(s.c_str(), 1), b = a;
    a.seed = 7, b.seed = 8;
    EXPECT_EQ(CanonicalConfig(a).seed, seeded ? 7u : 0u) << s;
    const ReplayFramesStats stats =
        ReplayFrames(*reader_, {1}, {a, b}, {},
                     [](const LoadedFrame&, const std::vector<ReplayResult>&) { return true; });
    EXPECT_EQ(stats.distinct, seeded ? 2u : 1u) << s;
  }
}

// Frame i-2's tree is read only in BeginFrame (issue 43): once every replay of the frame began
// it is freed, before the frame's results are told; a replay that begins the frame again
// (Belady's MIN, a pass per level) keeps it. The results stay those built by hand
// (EveryFrameEqualsItsReplayBuiltByHand, with auto and celltree-union).
TEST_F(DriverTest, FrameBeforePreviousGoesOnceEveryReplayBegan) {
  for (const bool min : {false, true}) {
    std::vector<ReplayConfig> configs = {Config("celltree-union", 1), Config("auto", 2),
                                         Config("maxwork", 3)};
    if (min) configs[1].levels[0].replacement = &kMinReplacement;
    ReplayFramesOptions options;
    options.jobs = 2;
    std::size_t frames = 0;
    ReplayFrames(*reader_, {0, 1, 2, 4}, configs, options,
                 [&](const LoadedFrame& f, const std::vector<ReplayResult>& results) {
                   ++frames;
                   EXPECT_EQ(results.size(), configs.size());
                   EXPECT_EQ(f.before_previous != nullptr, min && f.index >= 2) << f.index;
                   EXPECT_EQ(f.previous != nullptr, f.index >= 1) << f.index;
                   return true;
                 });
    EXPECT_EQ(frames, 4u);
  }
}

// The walker's two steps (issue 43): Advance gives the frame with its earlier trees only, so
// that its replays begin (FrameStart) and frame i-2's tree goes before Build makes the frame's
// own tree, work and bound; Next is both. The trees are the frames' own, counted by hand.
TEST_F(DriverTest, AdvanceGivesTheEarlierTreesAndBuildTheFramesOwn) {
  const std::uint32_t cells = reader_->header().cell_count();
  const auto nodes_of = [&](std::size_t i) {
    return testing::TreeOf(reader_->LoadFrame(i)).size();
  };
  FrameWalker walker(*reader_, {0, 1, 2, 4}, /*need_segments=*/true, /*need_nodes=*/false,
                     /*sample_every=*/1, /*history=*/2);
  for (const std::size_t i : {0, 1, 2, 4}) {
    LoadedFrame* f = walker.Advance();
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(f->index, i);
    EXPECT_EQ(f->tree, nullptr);
    EXPECT_EQ(f->segments, nullptr);
    EXPECT_EQ(f->bound, 0u);
    ASSERT_EQ(f->previous != nullptr, i >= 1);
    if (i >= 1) {
      EXPECT_EQ(f->previous->size(), nodes_of(i - 1));
    }
    ASSERT_EQ(f->before_previous != nullptr, i >= 2);
    if (i >= 2) {
      EXPECT_EQ(f->before_previous->size(), nodes_of(i - 2));
    }
    walker.ReleaseBeforePrevious();
    walker.Build();
    ASSERT_NE(f->tree, nullptr);
    EXPECT_EQ(f->tree->size(), nodes_of(i));
    EXPECT_EQ(f->bound, Bound(*f->tree));
    ASSERT_NE(f->segments, nullptr);
    EXPECT_EQ(f->segments->size(), RaySegmentWork(reader_->LoadFrame(i), cells).size());
  }
  EXPECT_EQ(walker.Advance(), nullptr);
}

// Where no replay reads the previous frame's tree once begun (Scheduler::ReadsEarlierTrees), it
// waits parked while the frame is built and replayed (issue 43), and the frame's own tree too;
// every scheduler's frames are still those of its replay built by hand (a scheduler that read
// a parked tree would read freed arrays). celltree-adaptive matches in the previous tree itself
// with one processor and in the union of the last two with several; balanced-critical matches
// in it.
TEST_F(DriverTest, EarlierTreesParkedWhereNoReplayReadsThem) {
  const std::vector<std::size_t> frames{0, 1, 2, 3, 4};
  for (const std::string& name : SchedulerNames()) {
    const SchedulerEntry& entry = SchedulerByName(name, "test");
    if (entry.oracle) continue;  // an oracle reads the frame's own tree: nothing is parked
    for (std::uint32_t processors : {1u, 3u}) {
      const ReplayConfig config = Config(name.c_str(), processors);
      std::vector<ReplayResult> got;
      std::vector<bool> previous_parked, own_parked;
      ReplayFrames(*reader_, frames, {config}, {},
                   [&](const LoadedFrame& f, const std::vector<ReplayResult>& results) {
                     got.push_back(results[0]);
                     previous_parked.push_back(f.previous != nullptr && f.previous->parked());
                     own_parked.push_back(f.tree != nullptr && f.tree->parked());
                     return true;
                   });
      ASSERT_EQ(got.size(), frames.size());
      for (std::size_t i : frames) {
        EXPECT_EQ(Describe(got[i]), Describe(ByHand(i, config)))
            << name << " P" << processors << " frame " << i;
        if (entry.history == 0) {
          EXPECT_FALSE(previous_parked[i]) << name;  // no tree kept at all
          continue;
        }
        EXPECT_EQ(own_parked[i], true) << name << " P" << processors << " frame " << i;
        bool reads = true;  // whether the previous tree is read during the frame
        if (name == "celltree-adaptive") reads = processors == 1 || i < 2;
        if (name == "balanced-critical" || name == "celltree-dag") reads = true;
        if (name == "celltree" || name == "celltree-best" || name == "celltree-union") {
          reads = false;
        }
        if (name == "celltree-adaptive" || name == "balanced-critical" || name == "celltree" ||
            name == "celltree-best" || name == "celltree-union" || name == "celltree-dag") {
          EXPECT_EQ(previous_parked[i], i >= 1 && !reads)
              << name << " P" << processors << " frame " << i;
        }
      }
    }
  }
}

// A caller that reads no tree (a replay, a sweep): the last frame's tree is built only where a
// replay reads it (an oracle), as no next frame plans from it; the results are the same.
TEST_F(DriverTest, TheLastFramesTreeIsBuiltOnlyWhereSomethingReadsIt) {
  const std::vector<std::size_t> frames{0, 1, 2, 3};
  for (const char* name : {"celltree", "balanced-critical", "auto", "best"}) {
    const bool oracle = SchedulerByName(name, "test").oracle;
    for (const bool caller_reads : {true, false}) {
      ReplayFramesOptions options;
      options.caller_reads_trees = caller_reads;
      std::vector<bool> has_tree;
      std::size_t i = 0;
      ReplayFrames(*reader_, frames, {Config(name, 3)}, options,
                   [&](const LoadedFrame& f, const std::vector<ReplayResult>& results) {
                     has_tree.push_back(f.tree != nullptr);
                     EXPECT_EQ(Describe(results[0]), Describe(ByHand(i++, Config(name, 3))))
                         << name;
                     return true;
                   });
      ASSERT_EQ(has_tree.size(), frames.size());
      for (std::size_t k = 0; k < frames.size(); ++k) {
        const bool last = k + 1 == frames.size();
        EXPECT_EQ(has_tree[k], oracle || caller_reads || !last) << name << " frame " << k;
      }
    }
  }
}

// `auto`'s check runs its replays of the frames seen on the threads a replay is given
// (ReplayFramesOptions::jobs over the configurations running at once): every result, its
// decision steps and bytes among them, is the same for any number of threads, and equals the
// replay built by hand (on one thread).
// With a thread to spare (a replay given more threads than configurations), the replays begin a
// frame (their plans from frame i-1's tree) while its tree and work are built, where no
// configuration reads frame i-2's tree or where each made first what it reads of both (a union,
// Scheduler::Prepare) and the trees wait parked: every scheduler's results equal the replay built
// by hand, frame by frame, as on one thread; the others (auto, whose check replays both trees)
// and the oracles begin as before.
TEST_F(DriverTest, BeginningWhileTheFrameIsBuiltGivesTheSameResults) {
  const std::vector<std::size_t> frames{0, 1, 2, 3, 4};
  for (const std::string& name : SchedulerNames()) {
    const SchedulerEntry& entry = SchedulerByName(name, "test");
    for (const std::uint32_t processors : {1u, 3u}) {
      const ReplayConfig config = Config(name.c_str(), processors);
      for (const unsigned jobs : {1u, 2u}) {
        ReplayFramesOptions options;
        options.jobs = jobs;
        std::size_t n = 0;
        const ReplayFramesStats stats =
            ReplayFrames(*reader_, frames, {config}, options,
                         [&](const LoadedFrame&, const std::vector<ReplayResult>& results) {
                           EXPECT_EQ(Describe(results[0]), Describe(ByHand(frames[n], config)))
                               << name << " P" << processors << " jobs " << jobs << " frame " << n;
                           ++n;
                           return true;
                         });
        EXPECT_EQ(n, frames.size());
        // Those of history 2 whose union of frames i-2 and i-1 is made first (Scheduler::Prepare)
        // from frame 2 on: celltree-union, and celltree-adaptive and balanced-adaptive with
        // several processors.
        const bool prepares =
            name == "celltree-union" ||
            ((name == "celltree-adaptive" || name == "balanced-adaptive") && processors > 1);
        std::size_t overlaps = 0;
        if (jobs > 1 && !entry.oracle && entry.history <= 1) overlaps = frames.size();
        if (jobs > 1 && entry.history == 2 && prepares) overlaps = frames.size() - 2;
        EXPECT_EQ(stats.begun_while_built, overlaps)
            << name << " P" << processors << " jobs " << jobs;
      }
    }
  }
}

TEST_F(DriverTest, AutosCheckGivesTheSameResultsOnAnyNumberOfThreads) {
  const std::vector<std::size_t> frames{0, 1, 2, 3, 4};
  for (const std::uint32_t processors : {1u, 2u, 8u}) {
    const ReplayConfig config = Config("auto", processors);
    std::vector<std::string> one;
    for (const unsigned jobs : {1u, 2u, 3u}) {
      const TraceReplay t = ReplayTrace(*reader_, frames, config, {}, 1, nullptr, jobs);
      ASSERT_EQ(t.frames.size(), frames.size());
      std::vector<std::string> got;
      for (std::size_t n = 0; n < frames.size(); ++n) {
        const ReplayResult& r = t.frames[n];
        got.push_back(Describe(r) + " " + std::to_string(r.decisions) + " " +
                      std::to_string(r.decision_steps) + " " + std::to_string(r.scheduler_bytes));
        EXPECT_EQ(Describe(r), Describe(ByHand(frames[n], config)))
            << "P" << processors << " jobs " << jobs << " frame " << n;
      }
      if (jobs == 1) one = got;
      EXPECT_EQ(got, one) << "P" << processors << " jobs " << jobs;
    }
  }
  // What each replay is given: the jobs over the configurations running at once.
  for (const auto& [jobs, configs, own] : std::vector<std::tuple<unsigned, std::size_t, unsigned>>{
           {1, 1, 1}, {2, 1, 2}, {3, 1, 3}, {3, 2, 1}, {4, 2, 2}, {2, 5, 1}}) {
    ReplayFramesOptions options;
    options.jobs = jobs;
    std::vector<ReplayConfig> list;
    for (std::size_t c = 0; c < configs; ++c) list.push_back(Config("auto", 1 + unsigned(c)));
    const ReplayFramesStats stats = ReplayFrames(
        *reader_, {0}, list, options, [](const LoadedFrame&, const auto&) { return true; });
    EXPECT_EQ(stats.own_threads, own) << jobs << " jobs, " << configs << " configurations";
  }
  // And a replay's start hands its threads to the replayer of frames seen.
  const CellTree tree = testing::TreeOf(reader_->LoadFrame(0));
  for (const unsigned threads : {1u, 4u}) {
    FrameTrees trees{2, nullptr, &tree, reader_->header().cell_count(), &tree};
    trees.threads = threads;
    const ReplayConfig config = Config("auto", 2);
    const auto s = MakeScheduler(*config.scheduler, config.seed);
    const FrameStart start(reader_->header().footprints, config, *s, trees, nullptr, nullptr);
    ASSERT_NE(start.info().seen, nullptr);
    EXPECT_EQ(start.info().seen->threads(), threads);
  }
}

// A scheduler that counts how often one object began a frame: Max Work's choices.
struct Begins {  // atomic: the configurations of a frame are replayed on several threads
  static inline std::atomic<int> again{0};  // BeginFrame on an object that had begun a frame
  static inline std::atomic<int> made{0};
};
class CountingScheduler : public Scheduler {
 public:
  explicit CountingScheduler(const SchedulerEntry& entry) : Scheduler(entry) { ++Begins::made; }
  void BeginFrame(const FrameInfo& frame) override {
    Begins::again += int(begun_);
    begun_ = true;
    max_work_.BeginFrame(frame);
  }
  std::optional<CellId> Next(const QueueView& queues) override { return max_work_.Next(queues); }

 private:
  bool begun_ = false;
  MaxWorkScheduler max_work_;
};
const SchedulerEntry kCountingEntry = [] {
  SchedulerEntry e;
  e.name = "counting";
  e.meaning = "Max Work, counting the frames each object begins (a test's)";
  e.label = "counting";
  e.make = [](std::uint64_t) -> std::unique_ptr<Scheduler> {
    return std::make_unique<CountingScheduler>(kCountingEntry);
  };
  e.seeded = true;  // so that two seeds are two configurations
  return e;
}();

// What a scheduler kept of a frame is read by no later frame (design §5 "No state across
// frames"), so the replay frees it with the scheduler once the frame's replay ended (issue 43):
// every frame of every configuration begins on a scheduler that began no frame before, for
// any number of threads, and the results are the reused ones' (Max Work's).
TEST_F(DriverTest, EachFrameBeginsOnAFreshScheduler) {
  for (const std::size_t jobs : {1u, 2u}) {
    std::vector<ReplayConfig> configs = {Config("maxwork", 2), Config("maxwork", 2)};
    configs[0].scheduler = configs[1].scheduler = &kCountingEntry;
    configs[1].seed = configs[0].seed + 1;
    ReplayFramesOptions options;
    options.jobs = jobs;
    Begins::again = 0;
    Begins::made = 0;
    const std::vector<std::size_t> frames = {0, 1, 2, 4};
    std::vector<std::string> got;
    ReplayFrames(*reader_, frames, configs, options,
                 [&](const LoadedFrame&, const std::vector<ReplayResult>& results) {
                   for (const ReplayResult& r : results) got.push_back(Describe(r));
                   return true;
                 });
    EXPECT_EQ(Begins::again.load(), 0) << jobs << " jobs";
    EXPECT_GE(Begins::made.load(), int(configs.size() * frames.size())) << jobs << " jobs";
    const TraceReplay alone = ReplayTrace(*reader_, frames, Config("maxwork", 2));
    ASSERT_EQ(got.size(), 2 * frames.size());
    for (std::size_t n = 0; n < got.size(); ++n) {
      EXPECT_EQ(got[n], Describe(alone.frames[n / 2])) << "result " << n;
    }
  }
}

TEST_F(DriverTest, StopsWhenTold) {
  std::size_t seen = 0;
  const ReplayFramesStats stats = ReplayFrames(
      *reader_, {0, 1, 2, 3}, {Config("maxwork", 1)}, {},
      [&](const LoadedFrame&, const std::vector<ReplayResult>&) { return ++seen < 2; });
  EXPECT_EQ(seen, 2u);
  EXPECT_EQ(stats.frames, 2u);
}

}  // namespace
}  // namespace raycell
