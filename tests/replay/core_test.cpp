// The batch replay core (replay/replayer.cpp) against the reference replay it replaced
// (tests/oracle/reference_replayer.cpp, one engine event per unit through the Simulator's
// event queue): every field of the result equal, `events` included, on random frames under
// every scheduler, granularity and a wide range of configurations, ties in time included.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <sstream>

#include "graph/cell_tree.h"
#include "replay/config.h"
#include "replay/replayer.h"
#include "replay/work.h"
#include "scheduling/scheduler.h"
#include "tests/graph/test_trees.h"
#include "tests/oracle/reference_replayer.h"
#include "tests/replay/random_frame.h"

namespace raycell {
namespace {

// Every field, one per line, so that a difference names the field.
std::string Describe(const ReplayResult& r) {
  std::ostringstream s;
  s << "frame " << r.frame << "\nfetches " << r.fetches << "\nbound "
    << (r.bound ? std::to_string(*r.bound) : "-") << "\ntime " << r.time << "\nwork " << r.work
    << "\nstall " << r.stall << "\nidle " << r.idle << "\nutilisation " << r.utilisation
    << "\npeak rays " << r.peak_queued_rays << "\npeak bytes " << r.peak_queued_bytes << "\nrays "
    << r.rays << "\nsegments " << r.segments << "\nsamples " << r.samples << "\nevents " << r.events
    << "\nprefetches " << r.prefetches << "\nprefetch hits " << r.prefetch_hits << "\npasses "
    << r.passes << "\nmin converged " << r.min_converged << "\n";
  for (const LevelStats& l : r.levels) {
    s << "level " << l.name << " fetches " << l.fetches << " bytes " << l.bytes << "\n";
  }
  return s.str();
}

const char* const kSchedulers[] = {
    "maxwork",           "roundrobin", "random",          "peel",  "celltree", "affinity",
    "partition",         "steal",      "partition-steal", "share", "balanced", "balanced-critical",
    "celltree-adaptive", "auto"};

const ReplacementEntry* RandomReplacement(std::mt19937& rng) {
  switch (rng() % 4) {
    case 0:
      return &kFifoReplacement;
    case 1:
      return &kMinReplacement;
    default:
      return &kLruReplacement;
  }
}

// A configuration drawn from everything the replay model varies: 1-8 processors, caches of
// cells or bytes (some cells larger than a whole cache), prefetch, LRU/FIFO/MIN per level,
// one to three levels, bandwidths from 1 MB/s to unlimited, latencies from 0, times per
// sample from 1 ps, both granularities.
ReplayConfig RandomConfig(std::mt19937& rng, const std::vector<std::uint64_t>& footprints) {
  ReplayConfig c = DefaultConfig();
  c.processors.count = 1 + rng() % 8;
  c.processors.time_per_sample = SimTime::Picoseconds(1 + rng() % 3 * 5000);
  c.processors.queue_record_bytes = 1 + rng() % 64;
  c.seed = rng() % 5;
  c.granularity =
      rng() % 4 == 0 ? ReplayConfig::Granularity::kNode : ReplayConfig::Granularity::kRay;
  c.levels.resize(1 + rng() % 3);
  for (std::size_t i = 0; i < c.levels.size(); ++i) {
    LevelConfig& l = c.levels[i];
    l.name = "l" + std::to_string(i);
    if (rng() % 3 == 0) {
      l.capacity_unit = LevelConfig::CapacityUnit::kBytes;
      l.capacity = footprints[rng() % footprints.size()] * (1 + rng() % 3);
    } else {
      l.capacity_unit = LevelConfig::CapacityUnit::kCells;
      l.capacity = 1 + rng() % 5;
    }
    const char* bandwidths[] = {"unlimited", "1MB/s", "133MB/s", "1.6GB/s", "100GB/s"};
    l.bandwidth_below = ParseBandwidth(bandwidths[rng() % 5], "test");
    l.latency_below = SimTime::Picoseconds(rng() % 2 == 0 ? 0 : rng() % 100'000);
    l.replacement = RandomReplacement(rng);
  }
  const LevelConfig& cache = c.levels[0];
  const bool room_for_two =
      cache.capacity_unit == LevelConfig::CapacityUnit::kBytes || cache.capacity >= 2;
  c.processors.prefetch = room_for_two && rng() % 2 == 0;
  return c;
}

TEST(ReplayCore, EqualsTheReferenceOnRandomFramesAndConfigs) {
  std::mt19937 rng(2024);
  int compared = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::uint32_t cells = 2 + rng() % 7;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 60);
    const CellTree tree = testing::TreeOf(rays);
    const CellTree previous = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 60));
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1 + rng() % 200'000;
    const ReplayConfig base = RandomConfig(rng, footprints);
    const FrameTrees info{std::size_t(trial % 3), &tree, trial % 2 ? &previous : nullptr, cells};
    for (const char* name : kSchedulers) {
      ReplayConfig config = base;
      config.scheduler = &SchedulerByName(name, "test");
      const WorkGraph w = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay
                              ? RaySegmentWork(rays, cells)
                              : NodeWork(tree, cells);
      auto a = MakeScheduler(name, config.seed), b = MakeScheduler(name, config.seed);
      const ReplayResult fast = ReplayFrame(w, footprints, config, *a, info, Bound(tree));
      const ReplayResult reference =
          ReferenceReplayFrame(w, footprints, config, *b, info, Bound(tree));
      ASSERT_EQ(Describe(fast), Describe(reference))
          << "trial " << trial << " scheduler " << name << "\n"
          << ToToml(config);
      ++compared;
    }
  }
  EXPECT_EQ(compared, 300 * int(std::size(kSchedulers)));
}

// Many processors on few cells: most of them wait, are woken together, and ask for cells at
// the same instant; free fetches and zero-sample units put many events at one time.
TEST(ReplayCore, EqualsTheReferenceWhenEventsTie) {
  std::mt19937 rng(99);
  for (int trial = 0; trial < 100; ++trial) {
    const std::uint32_t cells = 2 + rng() % 3;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 80);
    const CellTree tree = testing::TreeOf(rays);
    const std::vector<std::uint64_t> footprints(cells, 4096);
    ReplayConfig config = DefaultConfig();
    config.granularity = ReplayConfig::Granularity::kRay;
    config.processors.count = 2 + rng() % 7;
    config.processors.time_per_sample = SimTime::Picoseconds(rng() % 2 ? 1 : 1000);
    for (LevelConfig& l : config.levels) {
      l.bandwidth_below = ParseBandwidth("unlimited", "test");
      l.latency_below = SimTime::Zero();
    }
    const FrameTrees info{0, &tree, nullptr, cells};
    for (const char* name : kSchedulers) {
      config.scheduler = &SchedulerByName(name, "test");
      const WorkGraph w = RaySegmentWork(rays, cells);
      auto a = MakeScheduler(name, 1), b = MakeScheduler(name, 1);
      ASSERT_EQ(Describe(ReplayFrame(w, footprints, config, *a, info, Bound(tree))),
                Describe(ReferenceReplayFrame(w, footprints, config, *b, info, Bound(tree))))
          << "trial " << trial << " scheduler " << name;
    }
  }
}

// Tens of processors (issue 43): sets of processors span several 64-bit words (the board keeps
// the waiting processors and those woken together in bit sets), dozens wait and are woken by
// each release, and with free fetches many calls fall at one instant.
TEST(ReplayCore, EqualsTheReferenceOnTensOfProcessors) {
  std::mt19937 rng(43);
  // Each side of the 64-bit words of the processors' sets: one, two and three words.
  const std::uint32_t counts[] = {63, 64, 65, 127, 128, 129, 139};
  for (int trial = 0; trial < 7; ++trial) {
    const std::uint32_t cells = 60 + rng() % 140;  // enough for most processors to hold one
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 600);
    const CellTree tree = testing::TreeOf(rays);
    const std::vector<std::uint64_t> footprints(cells, 4096);
    ReplayConfig config = DefaultConfig();
    config.granularity = ReplayConfig::Granularity::kRay;
    config.processors.count = counts[trial];
    config.processors.time_per_sample = SimTime::Picoseconds(rng() % 2 ? 1 : 1000);
    if (trial % 2 == 0) {
      for (LevelConfig& l : config.levels) {
        l.bandwidth_below = ParseBandwidth("unlimited", "test");
        l.latency_below = SimTime::Zero();
      }
    }
    const FrameTrees info{0, &tree, nullptr, cells};
    const WorkGraph w = RaySegmentWork(rays, cells);
    for (const char* name : kSchedulers) {
      config.scheduler = &SchedulerByName(name, "test");
      auto a = MakeScheduler(name, 1), b = MakeScheduler(name, 1);
      ASSERT_EQ(Describe(ReplayFrame(w, footprints, config, *a, info, Bound(tree))),
                Describe(ReferenceReplayFrame(w, footprints, config, *b, info, Bound(tree))))
          << "trial " << trial << " scheduler " << name << " processors "
          << config.processors.count;
    }
  }
}

// Without the packed records (as for units whose samples exceed 32 bits) the core reads the
// work graph's columns: the same results.
TEST(ReplayCore, EqualsTheReferenceOnTheColumns) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 100; ++trial) {
    const std::uint32_t cells = 2 + rng() % 5;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 40);
    const CellTree tree = testing::TreeOf(rays);
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1 + rng() % 200'000;
    ReplayConfig config = RandomConfig(rng, footprints);
    config.scheduler = &SchedulerByName(kSchedulers[trial % 5], "test");
    WorkGraph w = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay
                      ? RaySegmentWork(rays, cells)
                      : NodeWork(tree, cells);
    ASSERT_FALSE(w.packed.empty());
    w.packed.clear();
    const FrameTrees info{0, &tree, nullptr, cells};
    auto a = MakeScheduler(*config.scheduler, config.seed);
    auto b = MakeScheduler(*config.scheduler, config.seed);
    ASSERT_EQ(Describe(ReplayFrame(w, footprints, config, *a, info, Bound(tree))),
              Describe(ReferenceReplayFrame(w, footprints, config, *b, info, Bound(tree))))
        << "trial " << trial;
  }
}

// `rays` with every cell id times `cell_scale` (up to 2^17 cells: varints of 3 bytes),
// every sample count times `sample_scale`, and rays without visits added: primary ones, and
// spawned ones at random visits of earlier rays (they do no work, RaySegmentWork skips them).
RayBatch Widened(std::mt19937& rng, const RayBatch& rays, std::uint32_t cell_scale,
                 std::uint32_t sample_scale) {
  RayBatch out(false);
  std::vector<RayId> id(rays.size());
  std::size_t tree = 0;  // the current ray tree's primary ray (rays come one tree at a time)
  for (std::size_t r = 0; r < rays.size(); ++r) {
    const RayView ray = rays.ray(r);
    if (ray.is_primary()) {
      if (rng() % 4 == 0) out.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
      tree = r;
    } else if (rng() % 4 == 0) {
      const RayId p = id[tree + rng() % (r - tree)];
      const auto spawn = std::uint32_t(rng() % (out.visit_end(p) - out.visit_begin(p)));
      out.BeginRay(RayKind::kShadow, p, spawn, 0, 0);
    }
    id[r] = RayId(out.size());
    out.BeginRay(ray.kind, ray.is_primary() ? kNoParent : id[ray.parent], ray.spawn, 0, 0);
    for (std::size_t v = 0; v < ray.visit_count; ++v) {
      out.AddVisit(CellId(ray.cells[v].value() * cell_scale), ray.samples[v] * sample_scale, 0, 0);
    }
  }
  return out;
}

// The Compact form (large frames, built batch by batch without the frame) gives the
// reference's results on the columns of RaySegmentWork, field by field: cells and samples
// of several varint bytes, rays without visits, parents in earlier batches.
TEST(ReplayCore, EqualsTheReferenceOnTheCompactForm) {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 300; ++trial) {
    const std::uint32_t base_cells = 2 + rng() % 6;
    const std::uint32_t scale = trial % 10 == 0  ? (std::uint32_t{1} << 14)
                                : trial % 2 == 0 ? 70
                                                 : 1;
    const std::uint32_t sample_scale = trial % 4 == 0 ? 1 : trial % 4 == 1 ? 300 : 200'000'000;
    const RayBatch rays =
        Widened(rng, testing::RandomReplayFrame(rng, base_cells, 60), scale, sample_scale);
    const std::uint32_t cells = (base_cells - 1) * scale + 1;
    const CellTree tree = testing::TreeOf(rays);
    std::vector<std::uint64_t> footprints(cells, 4096);
    for (std::uint32_t c = 0; c < cells; c += scale) footprints[c] = 1 + rng() % 200'000;
    ReplayConfig config = cells > 10'000 ? DefaultConfig() : RandomConfig(rng, footprints);
    config.granularity = ReplayConfig::Granularity::kRay;
    config.scheduler = &SchedulerByName(kSchedulers[trial % 5], "test");
    if (cells > 10'000) config.processors.count = 1 + rng() % 3;
    const WorkGraph columns = RaySegmentWork(rays, cells);
    const WorkGraph compact = testing::CompactWork(rng, rays, cells, 1 + rng() % 20);
    ASSERT_TRUE(compact.packed.empty() && compact.cell.empty());
    ASSERT_EQ(compact.size(), columns.size());
    const FrameTrees info{0, &tree, nullptr, cells};
    auto a = MakeScheduler(*config.scheduler, config.seed);
    auto b = MakeScheduler(*config.scheduler, config.seed);
    ASSERT_EQ(Describe(ReplayFrame(compact, footprints, config, *a, info, Bound(tree))),
              Describe(ReferenceReplayFrame(columns, footprints, config, *b, info, Bound(tree))))
        << "trial " << trial << "\n"
        << ToToml(config);
  }
}

// Batches of hundreds of thousands of units (a worklist whose worked front is dropped, queues
// given a long worklist's room freed): the reference's results, in both forms.
TEST(ReplayCore, EqualsTheReferenceOnLongWorklists) {
  std::mt19937 rng(2);
  const std::uint32_t cells = 3;
  const RayBatch rays = testing::RandomReplayFrame(rng, cells, 300'000, 2);
  ASSERT_GT(rays.size(), 250'000u);  // 283,850 rays: batches of more than 2^16 units
  const CellTree tree = testing::TreeOf(rays);
  const std::vector<std::uint64_t> footprints(cells, 4096);
  const FrameTrees info{0, &tree, nullptr, cells};
  const WorkGraph packed = RaySegmentWork(rays, cells);
  const WorkGraph compact = testing::CompactWork(rng, rays, cells, 70'000);
  for (std::uint32_t processors : {1u, 3u}) {
    ReplayConfig config = DefaultConfig();
    config.granularity = ReplayConfig::Granularity::kRay;
    config.processors.count = processors;
    config.scheduler = &SchedulerByName("maxwork", "test");
    auto a = MakeScheduler("maxwork", 1), b = MakeScheduler("maxwork", 1);
    auto c = MakeScheduler("maxwork", 1);
    const std::string reference =
        Describe(ReferenceReplayFrame(packed, footprints, config, *b, info, Bound(tree)));
    EXPECT_EQ(Describe(ReplayFrame(packed, footprints, config, *a, info, Bound(tree))), reference);
    EXPECT_EQ(Describe(ReplayFrame(compact, footprints, config, *c, info, Bound(tree))), reference);
  }
}

// A parent outside the rays seen so far is bad input, named.
TEST(ReplayCore, CompactBuilderRejectsAnUnknownParent) {
  RayBatch batch(false);
  batch.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  batch.AddVisit(CellId(0), 1, 0, 0);
  batch.BeginRay(RayKind::kShadow, 0, 3, 0, 0);  // spawn 3 of a one-visit parent
  batch.AddVisit(CellId(0), 1, 0, 0);
  RaySegmentWorkBuilder builder(1);
  EXPECT_THROW(builder.AddBatch(batch), InputError);
}

// Samples beyond 32 bits cannot be packed; the replay still counts them exactly.
TEST(ReplayCore, UnitsBeyondThirtyTwoBitsAreReadFromTheColumns) {
  RayBatch rays(false);
  rays.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  rays.AddVisit(CellId(0), 4'000'000'000u, 0, 0);
  const CellTree tree = testing::TreeOf(rays);
  const WorkGraph w = NodeWork(tree, 1);
  ASSERT_FALSE(w.packed.empty());
  // Two rays through one node: 8e9 samples in it.
  RayBatch two = rays;
  two.BeginRay(RayKind::kPrimary, kNoParent, 0, 1, 0);
  two.AddVisit(CellId(0), 4'000'000'000u, 0, 0);
  const CellTree big = testing::TreeOf(two);
  const WorkGraph wide = NodeWork(big, 1);
  EXPECT_TRUE(wide.packed.empty());
  const FrameTrees info{0, &big, nullptr, 1};
  auto s = MakeScheduler("maxwork", 1);
  const ReplayResult r = ReplayFrame(wide, {4096}, DefaultConfig(), *s, info, Bound(big));
  EXPECT_EQ(r.samples, 8'000'000'000u);
  EXPECT_EQ(r.work, SimTime::Nanoseconds(80'000'000'000u));
}

}  // namespace
}  // namespace raycell
