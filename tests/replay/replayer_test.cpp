// The replay model: conservation, fetch counts against hand-worked frames and the Peel
// bounds, the two granularities, determinism and timing sanity.
#include "replay/replayer.h"

#include <gtest/gtest.h>

#include <random>

#include "base/check.h"
#include "graph/peel.h"
#include "replay/config.h"
#include "replay/work.h"
#include "scheduling/scheduler.h"
#include "tests/graph/test_trees.h"
#include "tests/replay/random_frame.h"

namespace raycell {
namespace {

constexpr CellId A{0}, B{1}, C{2};

using testing::RandomReplayFrame;
using testing::TestRay;
using testing::TreeOf;

// Three samples per visit.
RayBatch Frame(const std::vector<TestRay>& rays) { return testing::RaysOf(rays, 3); }

struct Outcome {
  ReplayResult result;
  std::uint64_t bound, peel;
};

Outcome Replay(const RayBatch& rays, const std::string& scheduler, ReplayConfig config,
               const CellTree* previous = nullptr, std::uint32_t cells = 3) {
  config.scheduler = &SchedulerByName(scheduler, "test");
  CheckReplay(config, cells);  // as the runner does when it opens a trace
  const CellTree tree = TreeOf(rays);
  auto s = MakeScheduler(scheduler, config.seed);
  const FrameTrees info{previous ? 1u : 0u, &tree, previous, cells};
  const WorkGraph w = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay
                          ? RaySegmentWork(rays, cells)
                          : NodeWork(tree, cells);
  const std::vector<std::uint64_t> footprints(cells, 4096);
  return {ReplayFrame(w, footprints, config, *s, info, Bound(tree)), Bound(tree),
          Peel(tree).schedule.size()};
}

// Rays A B, A B and C A. Max Work: A has 2 queued rays (fetch A), then B has 2 (fetch B),
// then C (fetch C), then the third ray's A again: 4 fetches. The Peel oracle follows
// C A B: C sends its ray to A, A works all three, B: 3 fetches, the bound.
TEST(Replay, HandWorkedFetchCounts) {
  const RayBatch f =
      Frame({{kNoParent, 0, {A, B}}, {kNoParent, 0, {A, B}}, {kNoParent, 0, {C, A}}});
  const ReplayConfig config = DefaultConfig();
  EXPECT_EQ(Replay(f, "maxwork", config).result.fetches, 4u);
  const Outcome oracle = Replay(f, "peel", config);
  EXPECT_EQ(oracle.result.fetches, 3u);
  EXPECT_EQ(oracle.bound, 3u);
  ASSERT_TRUE(oracle.result.bound.has_value());
  EXPECT_EQ(*oracle.result.bound, 3u);
  // Cell Tree scheduling of the same rays with this frame's tree as the previous one's.
  const CellTree previous = TreeOf(f);
  EXPECT_EQ(Replay(f, "celltree", config, &previous).result.fetches, 3u);
  EXPECT_EQ(Replay(f, "celltree", config).result.fetches, 4u);  // frame 0: Max Work
}

// A spawned ray is worked in its parent's cell in the same fetch, never queued there.
TEST(Replay, SpawnedRaysAreWorkedInPlace) {
  // Ray 0: A B; ray 1 spawned at its visit 1 (B) goes B C; ray 2 spawned at ray 0's visit 0
  // (A) goes A C. Max Work: A (ray 0 and ray 2 start; queues: B 1, C 1) -> B (ray 1 spawns
  // in B, worked, queued at C: C 2) -> C: 3 fetches.
  const RayBatch f = Frame({{kNoParent, 0, {A, B}}, {0, 1, {B, C}}, {0, 0, {A, C}}});
  for (auto g : {ReplayConfig::Granularity::kRay, ReplayConfig::Granularity::kNode}) {
    ReplayConfig config = DefaultConfig();
    config.granularity = g;
    const Outcome r = Replay(f, "maxwork", config);
    EXPECT_EQ(r.result.fetches, 3u);
    EXPECT_EQ(r.result.rays, 3u);
    EXPECT_EQ(r.result.segments, 6u);
    EXPECT_EQ(r.result.samples, 18u);
  }
}

std::uint64_t TotalSamples(const RayBatch& b) {
  std::uint64_t s = 0;
  for (auto x : b.samples()) s += x;
  return s;
}

// Every scheduler and granularity processes exactly the trace's rays, segments and
// samples; with a one-cell cache the Peel oracle fetches between the bound and Peel's
// length; both granularities give the same fetches (and, with one processor, the same time);
// replays are deterministic.
TEST(Replay, ConservationBoundsGranularityAndDeterminismOnRandomFrames) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 400; ++trial) {
    const std::uint32_t cells = 2 + rng() % 5;
    const RayBatch f = RandomReplayFrame(rng, cells);
    const CellTree previous = TreeOf(RandomReplayFrame(rng, cells));
    for (const std::string& s : SchedulerNames()) {
      SCOPED_TRACE(s + " trial " + std::to_string(trial));
      // One processor: per node is exact whatever the cache and prefetch.
      ReplayConfig ray = DefaultConfig(), node = DefaultConfig();
      ray.granularity = ReplayConfig::Granularity::kRay;
      node.granularity = ReplayConfig::Granularity::kNode;
      if (trial % 2 == 1) {
        for (ReplayConfig* c : {&ray, &node}) {
          c->levels[0].capacity = 2;
          c->processors.prefetch = true;
        }
      }
      const Outcome a = Replay(f, s, ray, &previous, cells),
                    b = Replay(f, s, node, &previous, cells);
      for (const Outcome* r : {&a, &b}) {
        EXPECT_EQ(r->result.rays, f.size());
        EXPECT_EQ(r->result.segments, f.visit_count());
        EXPECT_EQ(r->result.samples, TotalSamples(f));
        if (r->result.bound) {
          EXPECT_GE(r->result.fetches, r->bound);
        }
      }
      EXPECT_EQ(a.result.fetches, b.result.fetches);
      EXPECT_EQ(a.result.time, b.result.time);
      if (std::string(s) == "peel" && a.result.bound) {
        EXPECT_LE(a.result.fetches, a.peel);
      }
      const Outcome again = Replay(f, s, ray, &previous, cells);
      EXPECT_EQ(again.result.time, a.result.time);
      EXPECT_EQ(again.result.stall, a.result.stall);
      if (::testing::Test::HasFailure()) return;
    }
  }
}

// PackedNodeWork, made straight from the tree, holds what NodeWork's columns give the replay:
// the same records, roots, totals and shape, and a replay on it the same results (the
// columns are its reference here, not itself).
TEST(Replay, PackedNodeWorkIsNodeWorksRecordsWithoutTheColumns) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const std::uint32_t cells = 2 + rng() % 6;
    const CellTree tree = TreeOf(RandomReplayFrame(rng, cells));
    const WorkGraph full = NodeWork(tree, cells), packed = PackedNodeWork(tree, cells);
    ASSERT_FALSE(full.packed.empty());
    EXPECT_TRUE(packed.cell.empty() && packed.samples.empty() && packed.succ.empty());
    EXPECT_EQ(packed.size(), full.size());
    ASSERT_EQ(packed.packed.size(), full.packed.size());
    for (std::size_t x = 0; x < full.packed.size(); ++x) {
      EXPECT_EQ(packed.packed[x].cell, full.packed[x].cell) << x;
      EXPECT_EQ(packed.packed[x].samples, full.packed[x].samples) << x;
      EXPECT_EQ(packed.packed[x].queued_rays, full.packed[x].queued_rays) << x;
      EXPECT_EQ(packed.packed[x].first_child, full.packed[x].first_child) << x;
    }
    EXPECT_EQ(packed.roots, full.roots);
    EXPECT_EQ(packed.totals.samples, full.totals.samples);
    EXPECT_EQ(packed.totals.segments, full.totals.segments);
    EXPECT_EQ(packed.totals.rays, full.totals.rays);
    ASSERT_TRUE(packed.shape && full.shape);
    EXPECT_EQ(packed.shape->chain_samples, full.shape->chain_samples);
    EXPECT_EQ(packed.shape->used, full.shape->used);
    ReplayConfig config = DefaultConfig();
    config.scheduler = &SchedulerByName("celltree", "test");
    config.processors.count = 1 + trial % 3;
    const std::vector<std::uint64_t> footprints(cells, 4096);
    const FrameTrees info{1, &tree, &tree, cells};
    auto s1 = MakeScheduler("celltree", 0), s2 = MakeScheduler("celltree", 0);
    const ReplayResult a = ReplayFrame(full, footprints, config, *s1, info, Bound(tree));
    const ReplayResult b = ReplayFrame(packed, footprints, config, *s2, info, Bound(tree));
    EXPECT_EQ(a.fetches, b.fetches);
    EXPECT_EQ(a.time, b.time);
    EXPECT_EQ(a.events, b.events);
    EXPECT_EQ(a.rays, b.rays);
    EXPECT_EQ(a.segments, b.segments);
    EXPECT_EQ(a.samples, b.samples);
    if (::testing::Test::HasFailure()) return;
  }
}

TEST(Replay, TimingSanity) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const RayBatch f = RandomReplayFrame(rng, 4);
    ReplayConfig slow = DefaultConfig(), fast = DefaultConfig(), inf = DefaultConfig();
    for (LevelConfig& l : fast.levels) l.bandwidth_below = ParseBandwidth("100GB/s", "test");
    for (LevelConfig& l : inf.levels) {
      l.bandwidth_below = ParseBandwidth("inf", "test");
      l.latency_below = SimTime::Zero();
    }
    const Outcome a = Replay(f, "peel", slow, nullptr, 4), b = Replay(f, "peel", fast, nullptr, 4),
                  c = Replay(f, "peel", inf, nullptr, 4);
    EXPECT_EQ(c.result.stall, SimTime::Zero());
    EXPECT_LE(b.result.stall, a.result.stall);
    EXPECT_LE(b.result.time, a.result.time);
    EXPECT_EQ(a.result.work, b.result.work);  // the same schedule does the same work
    EXPECT_EQ(a.result.fetches, b.result.fetches);
    // Work + stall + idle add up to time for the one processor.
    EXPECT_EQ(a.result.work + a.result.stall + a.result.idle, a.result.time);
  }
}

// Belady's MIN on the processor's cache: with one processor the request sequence does not
// depend on the cache, so MIN (exact after one rerun) never fetches more than LRU or FIFO.
TEST(Replay, MinNeverFetchesMoreThanLruOrFifo) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    const std::uint32_t cells = 3 + rng() % 4;
    const RayBatch f = RandomReplayFrame(rng, cells);
    std::uint64_t fetches[3];
    int k = 0;
    for (auto policy : {&kLruReplacement, &kFifoReplacement, &kMinReplacement}) {
      ReplayConfig config = DefaultConfig();
      config.levels[0].capacity = 2;
      config.levels[0].replacement = policy;
      const Outcome r = Replay(f, "maxwork", config, nullptr, cells);
      if (policy == &kMinReplacement) {
        EXPECT_TRUE(r.result.min_converged);
        EXPECT_EQ(r.result.passes, 2u);
      }
      fetches[k++] = r.result.fetches;
    }
    EXPECT_LE(fetches[2], fetches[0]) << "trial " << trial;
    EXPECT_LE(fetches[2], fetches[1]) << "trial " << trial;
  }
}

// Double buffering: ray 0 works 100 us in A; ray 1 needs B. Max Work takes A first (a tie,
// lowest cell), predicts B and prefetches it while A is worked: B's fetch (about 34 us from
// host memory over PCI and RDRAM) is hidden entirely, so the stall is A's fetch alone,
// half of what it is without prefetch.
TEST(Replay, PrefetchHidesTheNextFetchBehindTheWork) {
  RayBatch f(false);
  f.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  f.AddVisit(A, 10000, 0, 0);
  f.BeginRay(RayKind::kPrimary, kNoParent, 0, 1, 0);
  f.AddVisit(B, 1, 0, 0);
  ReplayConfig off = DefaultConfig();
  off.levels[0].capacity = 2;
  ReplayConfig on = off;
  on.processors.prefetch = true;
  const Outcome a = Replay(f, "maxwork", off), b = Replay(f, "maxwork", on);
  EXPECT_EQ(a.result.prefetches, 0u);
  EXPECT_EQ(b.result.prefetches, 1u);
  EXPECT_EQ(b.result.prefetch_hits, 1u);
  EXPECT_EQ(a.result.fetches, 2u);
  EXPECT_EQ(b.result.fetches, 2u);
  EXPECT_EQ(a.result.stall, b.result.stall * 2);
  EXPECT_EQ(a.result.work, b.result.work);
  EXPECT_LT(b.result.time, a.result.time);
}

TEST(Replay, PrefetchNeedsRoomForTwoCellsAndKeepsConservation) {
  std::mt19937 rng(13);
  ReplayConfig one_cell = DefaultConfig();
  one_cell.processors.prefetch = true;
  const RayBatch f = RandomReplayFrame(rng, 4);
  EXPECT_THROW(Replay(f, "maxwork", one_cell, nullptr, 4), InputError);
  for (int trial = 0; trial < 100; ++trial) {
    const RayBatch g = RandomReplayFrame(rng, 4);
    for (const char* s : {"maxwork", "roundrobin", "random", "peel", "celltree"}) {
      ReplayConfig config = DefaultConfig();
      config.levels[0].capacity = 2;
      config.processors.prefetch = true;
      config.processors.count = 1 + trial % 2;
      const Outcome r = Replay(g, s, config, nullptr, 4), again = Replay(g, s, config, nullptr, 4);
      EXPECT_EQ(r.result.segments, g.visit_count()) << s;
      EXPECT_EQ(r.result.samples, TotalSamples(g)) << s;
      EXPECT_LE(r.result.prefetch_hits, r.result.prefetches) << s;
      EXPECT_EQ(r.result.time, again.result.time) << s;
    }
  }
}

// Where fetches cost nothing, one processor is never idle, so its time is the frame's work;
// with two, at any moment until the end at least one works, so they never take longer. (With
// costly fetches list-scheduling anomalies can make more processors slower; the model
// promises nothing there.)
TEST(Replay, TwoProcessorsNeverTakeLongerWhenFetchesAreFree) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 200; ++trial) {
    const RayBatch f = RandomReplayFrame(rng, 5);
    for (const char* s : {"maxwork", "roundrobin", "peel", "celltree"}) {
      ReplayConfig one = DefaultConfig();
      for (LevelConfig& l : one.levels) {
        l.bandwidth_below = ParseBandwidth("inf", "test");
        l.latency_below = SimTime::Zero();
      }
      ReplayConfig two = one;
      two.processors.count = 2;
      const Outcome a = Replay(f, s, one, nullptr, 5), b = Replay(f, s, two, nullptr, 5);
      EXPECT_EQ(a.result.time, a.result.work) << s;
      EXPECT_LE(b.result.time, a.result.time) << s << " trial " << trial;
      EXPECT_EQ(a.result.work, b.result.work) << s;
    }
  }
}

TEST(Sampling, KeepsOneInKRayTreesWithTheirDescendants) {
  // Trees: {0: A B, 1: spawned at 0's visit 1 (B C)}, {2: C}, {3: A, 4: spawned at 3 (A B)}.
  const RayBatch f = Frame({{kNoParent, 0, {A, B}},
                            {0, 1, {B, C}},
                            {kNoParent, 0, {C}},
                            {kNoParent, 0, {A}},
                            {3, 0, {A, B}}});
  EXPECT_TRUE(SampleRayTrees(f, 1) == f);
  const RayBatch s = SampleRayTrees(f, 2);  // trees 0 and 2
  ASSERT_EQ(s.size(), 4u);
  EXPECT_EQ(s.parents()[1], 0u);
  EXPECT_EQ(s.parents()[3], 2u);  // ray 4 became ray 3, its parent ray 3 became ray 2
  EXPECT_EQ(s.ray(3).visit_count, 2u);
  const RayBatch t = SampleRayTrees(f, 3);  // tree 0 only
  EXPECT_EQ(t.size(), 2u);
}

}  // namespace
}  // namespace raycell
