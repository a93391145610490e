// The plan taken as a DAG (scheduling/dag_scheduler.h): with one processor celltree-dag-oracle
// replays as the plan followed (best), fetch for fetch; at 1, 2 and 8 processors every ray,
// segment and sample is worked once, and the same frame gives the same replay.
#include <gtest/gtest.h>

#include <random>
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

ReplayResult Replay(const char* name, const RayBatch& rays, const CellTree& tree,
                    const CellTree* previous, std::uint32_t cells, std::uint32_t processors,
                    bool node) {
  ReplayConfig config = DefaultConfig();
  config.scheduler = &SchedulerByName(name, "test");
  config.processors.count = processors;
  if (node) config.granularity = ReplayConfig::Granularity::kNode;
  const WorkGraph w = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay
                          ? RaySegmentWork(rays, cells)
                          : NodeWork(tree, cells);
  const std::vector<std::uint64_t> footprints(cells, 50'000);
  auto s = MakeScheduler(*config.scheduler, config.seed);
  const FrameTrees info{1, &tree, previous, cells};
  return ReplayFrame(w, footprints, config, *s, info, Bound(tree));
}

// Every entry's work has arrived when it comes first in line, so one processor follows the
// plan: the oracle fetches as `best` does, and celltree-dag on a frame that repeats its
// predecessor as celltree-best does.
TEST(Dag, OneProcessorFollowsThePlan) {
  std::mt19937 rng(4242);
  for (int trial = 0; trial < 12; ++trial) {
    const std::uint32_t cells = 2 + rng() % 8;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 60);
    const CellTree tree = testing::TreeOf(rays);
    for (const bool node : {true, false}) {
      const ReplayResult best = Replay("best", rays, tree, &tree, cells, 1, node);
      const ReplayResult dag = Replay("celltree-dag-oracle", rays, tree, &tree, cells, 1, node);
      EXPECT_EQ(dag.fetches, best.fetches) << "trial " << trial << " node " << node;
      EXPECT_EQ(dag.time, best.time) << "trial " << trial << " node " << node;
      const ReplayResult follow = Replay("celltree-best", rays, tree, &tree, cells, 1, node);
      const ReplayResult online = Replay("celltree-dag", rays, tree, &tree, cells, 1, node);
      EXPECT_EQ(online.fetches, follow.fetches) << "trial " << trial << " node " << node;
    }
  }
}

TEST(Dag, EveryRaySegmentAndSampleOnceAtOneTwoAndEightProcessors) {
  std::mt19937 rng(4243);
  for (int trial = 0; trial < 12; ++trial) {
    const std::uint32_t cells = 2 + rng() % 8;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 40);
    const CellTree tree = testing::TreeOf(rays);
    const CellTree previous = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 40));
    const testing::RayCounts expected = testing::CountRays(rays);
    for (const std::uint32_t p : {1u, 2u, 8u}) {
      for (const char* name : {"celltree-dag", "celltree-dag-oracle"}) {
        const CellTree* before = trial % 3 == 0 ? nullptr : &previous;  // frame 0: Max Work
        const ReplayResult r = Replay(name, rays, tree, before, cells, p, false);
        EXPECT_EQ(r.rays, expected.rays) << name << " P" << p << " trial " << trial;
        EXPECT_EQ(r.segments, expected.segments) << name << " P" << p;
        EXPECT_EQ(r.samples, expected.samples) << name << " P" << p;
        const ReplayResult again = Replay(name, rays, tree, before, cells, p, false);
        EXPECT_EQ(again.fetches, r.fetches) << name << " P" << p;
        EXPECT_EQ(again.time, r.time) << name << " P" << p;
      }
    }
  }
}

}  // namespace
}  // namespace raycell
