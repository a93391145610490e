// The lower bound on a replay's time (replay/time_bound.h): each term worked by hand where it
// is the one that binds, the bound never above the replay's time under every scheduler on
// random frames and boards, and the same bound from each form of the work graph.
#include "replay/time_bound.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <utility>
#include <vector>

#include "graph/cell_tree.h"
#include "replay/config.h"
#include "replay/replayer.h"
#include "replay/work.h"
#include "scheduling/scheduler.h"
#include "tests/graph/test_trees.h"
#include "tests/replay/random_frame.h"

namespace raycell {
namespace {

constexpr CellId A{0}, B{1}, C{2}, D{3};

SimTime Ps(std::uint64_t ps) { return SimTime::Picoseconds(ps); }

// A ray of a hand-made frame: its parent and spawn visit, and its visits' cells and samples.
struct Ray {
  RayId parent = kNoParent;
  std::uint32_t spawn = 0;
  std::vector<std::pair<CellId, std::uint32_t>> visits;
};

RayBatch FrameOf(const std::vector<Ray>& rays) {
  RayBatch b(false);
  for (const Ray& r : rays) {
    b.BeginRay(r.parent == kNoParent ? RayKind::kPrimary : RayKind::kShadow, r.parent, r.spawn, 0,
               0);
    for (const auto& [cell, samples] : r.visits) b.AddVisit(cell, samples, 0, 0);
  }
  return b;
}

LevelConfig Level(const std::string& name, std::uint64_t cells, const std::string& bandwidth,
                  std::uint64_t latency_ps) {
  LevelConfig l;
  l.name = name;
  l.capacity_unit = LevelConfig::CapacityUnit::kCells;
  l.capacity = cells;
  l.bandwidth_below = ParseBandwidth(bandwidth, "test");
  l.latency_below = Ps(latency_ps);
  return l;
}

// `processors` processors at 10 ps a sample on `levels`.
ReplayConfig Board(std::uint32_t processors, std::vector<LevelConfig> levels) {
  ReplayConfig c = DefaultConfig();
  c.processors.count = processors;
  c.processors.time_per_sample = Ps(10);
  c.levels = std::move(levels);
  c.scheduler = &SchedulerByName("maxwork", "test");
  return c;
}

std::string Terms(std::uint64_t work, std::uint64_t links, std::uint64_t chain,
                  std::uint64_t busy) {
  return TimeBoundTerms{Ps(work), Ps(links), Ps(chain), Ps(busy)}.ToString();
}

// ---- Each term where it binds, by hand ------------------------------------------------

// Four independent rays of 3, 3, 3 and 2 samples in four cells on three processors:
// 11 samples x 10 ps = 110 ps of work, at least ceil(110 / 3) = 37 ps on some processor
// (36 rounded down would be wrong: 3 x 36 < 110). The longest chain is one ray, 30 ps. Cache
// links free (no latency, unlimited bandwidth), so busy is the work; board link: 4 x 6 ps =
// 24 ps. Per node the same: one node per ray.
TEST(TimeBound, WorkBindsOnManyIndependentUnits) {
  const RayBatch f = FrameOf({{kNoParent, 0, {{A, 3}}},
                              {kNoParent, 0, {{B, 3}}},
                              {kNoParent, 0, {{C, 3}}},
                              {kNoParent, 0, {{D, 2}}}});
  const ReplayConfig config =
      Board(3, {Level("cache", 1, "unlimited", 0), Level("board", 100, "unlimited", 6)});
  const std::vector<std::uint64_t> footprints(4, 4096);
  for (const WorkGraph& w : {RaySegmentWork(f, 4), NodeWork(testing::TreeOf(f), 4)}) {
    EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(37, 24, 30, 37));
    EXPECT_EQ(TimeLowerBound(w, footprints, config), Ps(37));
  }
}

// One ray A B (1 sample each) on one processor; C is not used (its huge footprint must not
// count). Cache link: 40 ps + 0.5 ps/byte (2TB/s): A (100 bytes) 90 ps, B (300) 190 ps,
// 280 ps on the one processor's link. Board link: 1000 ps + 1 ps/byte (1TB/s): 1100 + 1300 =
// 2400 ps. Host link below a third level: 700 ps each, unlimited: 1400 ps. Work and chain
// 20 ps; busy 20 + 280 = 300 ps.
TEST(TimeBound, SharedLinkBindsOnCostlyFetches) {
  const RayBatch f = FrameOf({{kNoParent, 0, {{A, 1}, {B, 1}}}});
  const std::vector<std::uint64_t> footprints = {100, 300, 1'000'000};
  ReplayConfig config =
      Board(1, {Level("cache", 1, "2TB/s", 40), Level("board", 100, "1TB/s", 1000),
                Level("far", 100, "unlimited", 700)});
  const WorkGraph w = RaySegmentWork(f, 3);
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(20, 2400, 20, 300));
  EXPECT_EQ(TimeLowerBound(w, footprints, config), Ps(2400));

  // Held at the start. The board holds A: the cache link still moves A and B (280 ps), the
  // board link B alone (1300 ps), the host link B alone (700 ps).
  const std::vector<bool> none(3, false), a = {true, false, false}, b = {false, true, false};
  std::vector<std::vector<bool>> held = {none, a, none};
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config, &held).ToString(), Terms(20, 1300, 20, 300));
  // The cache holds B, host-side level A: the cache link moves A (90 ps), the board link A
  // (1100 ps: B is above it), the host link nothing; busy 20 + 90.
  held = {b, none, a};
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config, &held).ToString(), Terms(20, 1100, 20, 110));
  // Everything in the caches: no link needs to move anything.
  held = {{true, true, false}, none, none};
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config, &held).ToString(), Terms(20, 0, 20, 20));

  // Unlimited board bandwidth: latencies alone, 2 x 1000 ps.
  config.levels[1].bandwidth_below = Bandwidth::Unlimited();
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(20, 2000, 20, 300));
  // Prefetch keeps the shared links' term, with one processor or two (time_bound.h (b)); its
  // transfers may overlap work, so busy is the work (d).
  config.levels[0].capacity = 2;
  config.processors.prefetch = true;
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(20, 2000, 20, 20));
  config.processors.count = 2;
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(10, 2000, 20, 10));
}

// Three one-sample rays in A, B, C (1, 2 and 4 bytes) on two processors whose cache links
// cost 1000 ps + 1 ps/byte: 1001 + 1002 + 1004 = 3007 ps over two links, ceil(3007 / 2) =
// 1504 ps. Board link 10 ps each: 30 ps. Work ceil(30 / 2) = 15 ps, chain 10 ps. Without
// prefetch busy adds the work: ceil((30 + 3007) / 2) = 1519 ps; with it (caches of two cells)
// the links bind.
TEST(TimeBound, CacheLinksBindOnSlowCaches) {
  const RayBatch f =
      FrameOf({{kNoParent, 0, {{A, 1}}}, {kNoParent, 0, {{B, 1}}}, {kNoParent, 0, {{C, 1}}}});
  ReplayConfig config =
      Board(2, {Level("cache", 1, "1TB/s", 1000), Level("board", 100, "unlimited", 10)});
  const WorkGraph w = RaySegmentWork(f, 3);
  EXPECT_EQ(TimeLowerBoundTerms(w, {1, 2, 4}, config).ToString(), Terms(15, 1504, 10, 1519));
  EXPECT_EQ(TimeLowerBound(w, {1, 2, 4}, config), Ps(1519));
  config.levels[0].capacity = 2;
  config.processors.prefetch = true;
  EXPECT_EQ(TimeLowerBoundTerms(w, {1, 2, 4}, config).ToString(), Terms(15, 1504, 10, 15));
  EXPECT_EQ(TimeLowerBound(w, {1, 2, 4}, config), Ps(1504));
}

// Four rays of 10 samples (100 ps), one in each of A..D, on two processors whose cache links
// cost 50 ps a cell; board free. Work ceil(400 / 2) = 200 ps, links ceil(4 x 50 / 2) = 100
// ps, chain 100 ps, but a processor cannot work while it fetches: busy ceil((400 + 200) / 2)
// = 300 ps. Max Work gives each processor two cells, fetch 50 + work 100 twice: 300 ps, the
// bound exactly. Held at the start in some cache, C and D need no fetch: busy 250 ps.
TEST(TimeBound, BusyBindsWhenFetchesStallTheProcessors) {
  const RayBatch f = FrameOf({{kNoParent, 0, {{A, 10}}},
                              {kNoParent, 0, {{B, 10}}},
                              {kNoParent, 0, {{C, 10}}},
                              {kNoParent, 0, {{D, 10}}}});
  ReplayConfig config =
      Board(2, {Level("cache", 1, "unlimited", 50), Level("board", 100, "unlimited", 0)});
  config.granularity = ReplayConfig::Granularity::kRay;
  const std::vector<std::uint64_t> footprints(4, 4096);
  const WorkGraph w = RaySegmentWork(f, 4);
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(200, 100, 100, 300));
  const CellTree tree = testing::TreeOf(f);
  const FrameTrees info{0, &tree, nullptr, 4};
  auto s = MakeScheduler("maxwork", 1);
  const ReplayResult r = ReplayFrame(w, footprints, config, *s, info, 0);
  EXPECT_EQ(r.time, Ps(300));
  EXPECT_EQ(r.time_bound, Ps(300));
  const std::vector<std::vector<bool>> held = {{false, false, true, true}, std::vector<bool>(4)};
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config, &held).ToString(), Terms(200, 50, 100, 250));
}

// Why busy leaves out fetches with prefetch: one processor, rays in A and B of 10 samples
// (100 ps), cache links of 100 ps, caches of two cells. Without prefetch fetch A, work A,
// fetch B, work B: 400 ps = busy (200 + 200). With prefetch B crosses the link while A is
// worked: 300 ps, under 400; busy is then the work (200) and the link's 200 ps binds.
TEST(TimeBound, PrefetchOverlapsFetchesWithWork) {
  const RayBatch f = FrameOf({{kNoParent, 0, {{A, 10}}}, {kNoParent, 0, {{B, 10}}}});
  ReplayConfig config =
      Board(1, {Level("cache", 2, "unlimited", 100), Level("board", 100, "unlimited", 0)});
  const std::vector<std::uint64_t> footprints(2, 4096);
  const WorkGraph w = RaySegmentWork(f, 2);
  const CellTree tree = testing::TreeOf(f);
  const FrameTrees info{0, &tree, nullptr, 2};
  auto s = MakeScheduler("maxwork", 1);
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(200, 200, 100, 400));
  EXPECT_EQ(ReplayFrame(w, footprints, config, *s, info, 0).time, Ps(400));
  config.processors.prefetch = true;
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(200, 200, 100, 200));
  const ReplayResult r = ReplayFrame(w, footprints, config, *s, info, 0);
  EXPECT_EQ(r.time, Ps(300));
  EXPECT_EQ(r.prefetches, 1u);
  EXPECT_EQ(r.time_bound, Ps(200));
}

// Ray 0 goes A B C (10 samples each); ray 1, spawned at its visit 2 (C), goes C A (10 each);
// ray 2 is B (5). The longest chain: ray 0's three visits then ray 1's two, 50 samples =
// 500 ps, although four processors share 550 ps of work (ceil(550 / 4) = 138 ps). Links of
// 1 ps each: ceil(3 / 4) = 1 and 3 ps. Per node: A, B, then C holding ray 0's C and ray 1's
// first visit (20 samples), then A: 500 ps too.
TEST(TimeBound, ChainBindsOnDependentWork) {
  const RayBatch f = FrameOf({{kNoParent, 0, {{A, 10}, {B, 10}, {C, 10}}},
                              {0, 2, {{C, 10}, {A, 10}}},
                              {kNoParent, 0, {{B, 5}}}});
  const ReplayConfig config =
      Board(4, {Level("cache", 1, "unlimited", 1), Level("board", 100, "unlimited", 1)});
  const std::vector<std::uint64_t> footprints(3, 4096);
  for (const WorkGraph& w : {RaySegmentWork(f, 3), NodeWork(testing::TreeOf(f), 3)}) {
    EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(138, 3, 500, 139));
    EXPECT_EQ(TimeLowerBound(w, footprints, config), Ps(500));
  }
}

// Per node a node's rays are released together: rays A B and A C (3 samples a visit) make
// node A (6 samples) with children B and C, a chain of 9 samples = 90 ps, where per segment
// each ray is its own chain of 6 samples = 60 ps.
TEST(TimeBound, NodeChainsHoldANodesRaysTogether) {
  const RayBatch f = FrameOf({{kNoParent, 0, {{A, 3}, {B, 3}}}, {kNoParent, 0, {{A, 3}, {C, 3}}}});
  const ReplayConfig config = Board(1, {Level("cache", 1, "unlimited", 0)});
  const std::vector<std::uint64_t> footprints(3, 4096);
  EXPECT_EQ(TimeLowerBoundTerms(RaySegmentWork(f, 3), footprints, config).chain, Ps(60));
  EXPECT_EQ(TimeLowerBoundTerms(NodeWork(testing::TreeOf(f), 3), footprints, config).chain, Ps(90));
}

// A prefetch from a shared level waits for the cell to arrive there. Rays A (150 samples), B
// and C (1 each); two processors, caches of two cells over a 10 ps link, a board over a 1000
// ps link from host memory, unlimited bandwidths; Max Work. At 0, p0 takes A (board link
// 0-1000, its link 1000-1010) and p1 takes B (board link 1000-2000, its link 2000-2010). At
// 1010 p0 prefetches C, which Max Work predicts: board link 2000-3000, its link 3000-3010. At
// 2010 p1 prefetches C too: the board holds it from 1010 but it arrives at 3000, so p1's link
// carries it 3000-3010; p1 works B until 2020, waits for C until 3010 and works it until
// 3020, the end (p0 works A until 2510). The bound: the board link's three cells, 3000 ps
// (chain 1500, work ceil(1520 / 2) = 760, caches' links ceil(3 x 10 / 2) = 15). Were C
// passed on before it arrived, p1 would finish at 2030, under the bound.
// Without prefetch p1 asks for C at 2020: the board link (2020-3020), its own (3020-3030),
// C worked until 3040 >= 3000.
TEST(TimeBound, APrefetchFromASharedLevelWaitsForTheCellToArrive) {
  const RayBatch f =
      FrameOf({{kNoParent, 0, {{A, 150}}}, {kNoParent, 0, {{B, 1}}}, {kNoParent, 0, {{C, 1}}}});
  ReplayConfig config =
      Board(2, {Level("cache", 2, "unlimited", 10), Level("board", 100, "unlimited", 1000)});
  config.granularity = ReplayConfig::Granularity::kRay;
  config.processors.prefetch = true;
  const std::vector<std::uint64_t> footprints(3, 4096);
  const WorkGraph w = RaySegmentWork(f, 3);
  const CellTree tree = testing::TreeOf(f);
  const FrameTrees info{0, &tree, nullptr, 3};
  auto s = MakeScheduler("maxwork", 1);
  const ReplayResult on = ReplayFrame(w, footprints, config, *s, info, 0);
  EXPECT_EQ(on.time, Ps(3020));
  EXPECT_EQ(on.prefetches, 2u);
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(760, 3000, 1500, 760));
  EXPECT_EQ(on.time_bound, Ps(3000));

  config.processors.prefetch = false;
  const ReplayResult off = ReplayFrame(w, footprints, config, *s, info, 0);
  EXPECT_EQ(off.time, Ps(3040));
  EXPECT_EQ(TimeLowerBoundTerms(w, footprints, config).ToString(), Terms(760, 3000, 1500, 775));
  EXPECT_EQ(off.time_bound, Ps(3000));
}

// ---- Never above the replay's time ----------------------------------------------------

// A board drawn from what the replay varies: `processors`, caches of 1, 2 or 4 cells or of
// bytes, a board of 2 cells or 256MiB or bytes, sometimes a third level, bandwidths down to
// 1MB/s and unlimited (the board's often), latencies from 0, LRU/FIFO/MIN, prefetch where
// the cache holds two cells, both granularities.
ReplayConfig RandomBoard(std::mt19937& rng, std::uint32_t processors,
                         const std::vector<std::uint64_t>& footprints) {
  ReplayConfig c = DefaultConfig();
  c.processors.count = processors;
  c.processors.time_per_sample = Ps(1 + rng() % 3 * 5000);
  c.granularity =
      rng() % 3 == 0 ? ReplayConfig::Granularity::kNode : ReplayConfig::Granularity::kRay;
  const char* bandwidths[] = {"unlimited", "1MB/s", "133MB/s", "1.6GB/s", "100GB/s"};
  const ReplacementEntry* const replacements[] = {&kLruReplacement, &kFifoReplacement,
                                                  &kMinReplacement};
  c.levels.resize(2 + rng() % 2);
  for (std::size_t i = 0; i < c.levels.size(); ++i) {
    LevelConfig& l = c.levels[i];
    l.name = "l" + std::to_string(i);
    const std::uint64_t cells[] = {1, 2, 4};
    if (rng() % 4 == 0) {
      l.capacity_unit = LevelConfig::CapacityUnit::kBytes;
      l.capacity = footprints[rng() % footprints.size()] * (1 + rng() % 3);
    } else {
      l.capacity_unit = LevelConfig::CapacityUnit::kCells;
      l.capacity = i == 0 ? cells[rng() % 3] : rng() % 2 == 0 ? 2 : 1 << 20;
    }
    l.bandwidth_below =
        ParseBandwidth(i == 1 && rng() % 2 == 0 ? "unlimited" : bandwidths[rng() % 5], "test");
    l.latency_below = Ps(rng() % 2 == 0 ? 0 : rng() % 100'000);
    l.replacement = replacements[rng() % 3];
  }
  const LevelConfig& cache = c.levels[0];
  c.processors.prefetch =
      (cache.capacity_unit == LevelConfig::CapacityUnit::kBytes || cache.capacity >= 2) &&
      rng() % 2 == 0;
  return c;
}

TEST(TimeBound, NeverAboveTheReplaysTimeUnderAnyScheduler) {
  std::mt19937 rng(22);
  const std::uint32_t processor_counts[] = {1, 2, 3, 8, 16};
  int cases = 0, near = 0, prefetching = 0, unlimited = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const std::uint32_t cells = 2 + rng() % 7;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 50);
    const CellTree tree = testing::TreeOf(rays);
    const CellTree previous = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 50));
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1 + rng() % 200'000;
    const ReplayConfig base = RandomBoard(rng, processor_counts[trial % 5], footprints);
    prefetching += base.processors.prefetch;
    unlimited += base.levels[1].bandwidth_below.unlimited();
    const FrameTrees info{1, &tree, &previous, cells, &previous};
    const WorkGraph w = EffectiveGranularity(base) == ReplayConfig::Granularity::kRay
                            ? RaySegmentWork(rays, cells)
                            : NodeWork(tree, cells);
    for (const SchedulerEntry& entry : SchedulerRegistry()) {
      ReplayConfig config = base;
      config.scheduler = &entry;
      const TimeBoundTerms terms = TimeLowerBoundTerms(w, footprints, config);
      auto s = MakeScheduler(entry, 1 + trial);
      const ReplayResult r = ReplayFrame(w, footprints, config, *s, info, Bound(tree));
      ASSERT_LE(r.time_bound, r.time)
          << "trial " << trial << " scheduler " << entry.name << ": " << terms.ToString() << "\n"
          << ToToml(config);
      ASSERT_EQ(r.time_bound, terms.value());
      ++cases;
      near += double(r.time.picoseconds()) <= 1.01 * double(r.time_bound.picoseconds());
    }
  }
  EXPECT_EQ(cases, 60 * int(SchedulerRegistry().size()));
  // The draws cover what they should: prefetch, unlimited board bandwidth; and some replays
  // come within 1% of their bound (it is not trivially loose).
  EXPECT_GT(prefetching, 10);
  EXPECT_GT(unlimited, 10);
  EXPECT_GT(near, 0);
}

// ---- The three forms ------------------------------------------------------------------

// The packed records, the columns and the Compact form of the same frame give the same terms;
// per node, the packed records and the columns.
TEST(TimeBound, EveryFormOfTheWorkGivesTheSameBound) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    const std::uint32_t cells = 2 + rng() % 7;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 60, 6);
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1 + rng() % 200'000;
    const ReplayConfig config = RandomBoard(rng, 1 + rng() % 4, footprints);
    const WorkGraph packed = RaySegmentWork(rays, cells);
    WorkGraph columns = packed;
    ASSERT_FALSE(columns.packed.empty());
    columns.packed.clear();
    const WorkGraph compact = testing::CompactWork(rng, rays, cells, 1 + rng() % 20);
    ASSERT_TRUE(compact.packed.empty() && compact.cell.empty());
    const std::string expected = TimeLowerBoundTerms(packed, footprints, config).ToString();
    EXPECT_EQ(TimeLowerBoundTerms(columns, footprints, config).ToString(), expected)
        << "trial " << trial;
    EXPECT_EQ(TimeLowerBoundTerms(compact, footprints, config).ToString(), expected)
        << "trial " << trial;
    const WorkGraph nodes = NodeWork(testing::TreeOf(rays), cells);
    WorkGraph node_columns = nodes;
    node_columns.packed.clear();
    EXPECT_EQ(TimeLowerBoundTerms(node_columns, footprints, config).ToString(),
              TimeLowerBoundTerms(nodes, footprints, config).ToString())
        << "trial " << trial;
  }
}

// A frame of hundreds of thousands of rays: the walks' queues and stacks grow, and the packed
// walk drops the front of its queue many times; still the same terms in every form.
TEST(TimeBound, EveryFormGivesTheSameBoundOnALargeFrame) {
  std::mt19937 rng(8);
  const std::uint32_t cells = 6;
  const RayBatch rays = testing::RandomReplayFrame(rng, cells, 300'000, 3);
  ASSERT_GT(rays.size(), 100'000u);  // 150,725
  const std::vector<std::uint64_t> footprints = {10, 20, 30, 40, 50, 60};
  ReplayConfig config = RandomBoard(rng, 4, footprints);
  const WorkGraph packed = RaySegmentWork(rays, cells);
  WorkGraph columns = packed;
  columns.packed.clear();
  const WorkGraph compact = testing::CompactWork(rng, rays, cells, 70'000);
  const std::string expected = TimeLowerBoundTerms(packed, footprints, config).ToString();
  EXPECT_EQ(TimeLowerBoundTerms(columns, footprints, config).ToString(), expected);
  EXPECT_EQ(TimeLowerBoundTerms(compact, footprints, config).ToString(), expected);
}

}  // namespace
}  // namespace raycell
