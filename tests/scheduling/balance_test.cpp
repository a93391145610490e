// The schedulers for several processors (scheduling/balanced_scheduler.h) in the replay: every
// ray, segment and sample processed exactly once for 1..16 processors (counted from the rays,
// not from the work graph), with one processor the planners choose as celltree-best, and a
// processor that joins a busy cell or postpones changes the replay as documented.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <random>
#include <sstream>

#include "replay/replayer.h"
#include "replay/work.h"
#include "scheduling/balanced_scheduler.h"
#include "scheduling/scheduler.h"
#include "tests/graph/test_trees.h"
#include "tests/replay/random_frame.h"

namespace raycell {
namespace {

// With the watching schedulers (issue 24), which must work with any number of processors too.
const char* const kBalancing[] = {"affinity",
                                  "partition",
                                  "steal",
                                  "partition-steal",
                                  "share",
                                  "balanced",
                                  "balanced-critical",
                                  "celltree-adaptive",
                                  "balanced-adaptive"};

std::string Describe(const ReplayResult& r) {
  std::ostringstream s;
  s << r.fetches << " " << r.time << " " << r.work << " " << r.stall << " " << r.idle << " "
    << r.events << " " << r.peak_queued_rays;
  for (const LevelStats& l : r.levels) s << " " << l.fetches;
  return s.str();
}

// What balanced reads of frame i-1's tree (StatsOf) against a dense cells x cells table made
// here: per cell its samples and samples per visit, and per cell `from` the share of the rays
// leaving it (into nodes whose parent lies in `from`) that enter each cell `to`, each pair
// summed in node order and each row's total over increasing `to`, so equal as doubles.
TEST(Balance, TreeStatsAreTheDenseTablesSums) {
  std::mt19937 rng(43);
  std::size_t entries = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::uint32_t cells = 2 + rng() % 23;  // RandomTree needs two
    const CellTree t = testing::RandomTree(rng, cells, 1 + int(rng() % 300), 8);
    std::vector<double> work(cells, 0.0), visits(cells, 0.0);
    std::vector<std::vector<double>> table(cells, std::vector<double>(cells, 0.0));
    std::vector<std::vector<bool>> present(cells, std::vector<bool>(cells, false));
    for (std::size_t i = 1; i < t.size(); ++i) {
      const NodeId n(static_cast<std::uint32_t>(i));
      work[t.cell(n).value()] += double(t.samples(n));
      visits[t.cell(n).value()] += double(t.visits(n));
      if (t.parent(n) == kRootNode) continue;
      const std::uint32_t from = t.cell(t.parent(n)).value(), to = t.cell(n).value();
      table[from][to] += double(t.enter(n));
      present[from][to] = true;
    }
    for (const bool affinity : {false, true}) {
      const BalancedScheduler::TreeStats s = BalancedScheduler::StatsOf(&t, cells, affinity);
      ASSERT_EQ(s.work, work);
      ASSERT_EQ(s.samples_per_visit.size(), cells);
      for (std::uint32_t c = 0; c < cells; ++c) {
        EXPECT_EQ(s.samples_per_visit[c], visits[c] > 0 ? work[c] / visits[c] : 0.0);
      }
      ASSERT_EQ(s.flow_begin.size(), cells + 1);
      std::size_t k = 0;
      for (std::uint32_t from = 0; from < cells; ++from) {
        ASSERT_EQ(s.flow_begin[from], k) << "row " << from;
        double out = 0.0;
        for (std::uint32_t to = 0; to < cells; ++to) {
          if (present[from][to]) out += table[from][to];
        }
        for (std::uint32_t to = 0; to < cells && affinity; ++to) {
          if (!present[from][to]) continue;
          ASSERT_LT(k, s.flow.size());
          EXPECT_EQ(s.flow[k].first, to) << "row " << from;
          EXPECT_EQ(s.flow[k].second, out > 0 ? table[from][to] / out : table[from][to])
              << "row " << from << " to " << to;
          ++k;
        }
      }
      EXPECT_EQ(s.flow_begin[cells], k);
      EXPECT_EQ(s.flow.size(), k);
      if (affinity) entries += k;
    }
  }
  EXPECT_GT(entries, 200u);  // the rows are not all empty
}

TEST(Balance, EveryRaySegmentAndSampleOnceForOneToSixteenProcessors) {
  std::mt19937 rng(22);
  int replays = 0;
  for (int trial = 0; trial < 16; ++trial) {
    const std::uint32_t cells = 2 + rng() % 12;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 80);
    const RayBatch before = testing::RandomReplayFrame(rng, cells, 80);
    const CellTree tree = testing::TreeOf(rays), previous = testing::TreeOf(before);
    const testing::RayCounts expected = testing::CountRays(rays);
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1000 + rng() % 300'000;
    for (const std::uint32_t p : {1u, 2u, 3u, 4u, 8u, 16u}) {
      for (const char* name : kBalancing) {
        ReplayConfig config = DefaultConfig();
        config.scheduler = &SchedulerByName(name, "test");
        config.processors.count = p;
        if (trial % 2 == 1) config.levels[0].capacity = 2;
        const WorkGraph w = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay
                                ? RaySegmentWork(rays, cells)
                                : NodeWork(tree, cells);
        auto s = MakeScheduler(*config.scheduler, config.seed);
        const FrameTrees info{1, &tree, trial % 3 == 0 ? nullptr : &previous, cells};
        const ReplayResult r = ReplayFrame(w, footprints, config, *s, info, Bound(tree));
        EXPECT_EQ(r.rays, expected.rays) << name << " P" << p << " trial " << trial;
        EXPECT_EQ(r.segments, expected.segments) << name << " P" << p;
        EXPECT_EQ(r.samples, expected.samples) << name << " P" << p;
        EXPECT_EQ(r.work, config.processors.time_per_sample * expected.samples) << name;
        // Each processor's work, stall and idle add up to the time.
        EXPECT_EQ(r.work + r.stall + r.idle, r.time * p) << name << " P" << p;
        EXPECT_LE(r.time_bound, r.time) << name << " P" << p;
        ++replays;
      }
    }
  }
  EXPECT_EQ(replays, 16 * 6 * int(std::size(kBalancing)));
}

// With one processor nothing is busy, shared or postponed, and the one partition is the whole
// plan: the planners replay exactly as celltree-best, frame 0 (Max Work) included.
TEST(Balance, OneProcessorFollowsThePlanAsCellTreeBest) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 24; ++trial) {
    const std::uint32_t cells = 2 + rng() % 10;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 60);
    const CellTree tree = testing::TreeOf(rays);
    const CellTree previous = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 60));
    const std::vector<std::uint64_t> footprints(cells, 50'000);
    ReplayConfig config = DefaultConfig();
    config.granularity =
        trial % 2 ? ReplayConfig::Granularity::kRay : ReplayConfig::Granularity::kNode;
    const WorkGraph w = trial % 2 ? RaySegmentWork(rays, cells) : NodeWork(tree, cells);
    const FrameTrees info{std::size_t(trial % 2), &tree, trial % 4 == 0 ? nullptr : &previous,
                          cells};
    const auto replay = [&](const char* name) {
      config.scheduler = &SchedulerByName(name, "test");
      auto s = MakeScheduler(*config.scheduler, 1);
      return Describe(ReplayFrame(w, footprints, config, *s, info, Bound(tree)));
    };
    const std::string reference = replay("celltree-best");
    for (const char* name : {"partition", "partition-steal", "balanced", "balanced-critical"}) {
      EXPECT_EQ(replay(name), reference) << name << " trial " << trial;
    }
    // And the adaptive combination as the adaptive rule alone.
    EXPECT_EQ(replay("balanced-adaptive"), replay("celltree-adaptive")) << "trial " << trial;
  }
}

// `paths` at 2 us a visit, per ray segment, on `processors` processors whose fetches take
// 10.04 us (16000 B at 1.6 GB/s after 40 ns; the board free), under scheduler `name`.
ReplayResult ReplayOnProcessors(const std::vector<testing::TestRay>& paths, std::uint32_t cells,
                                const char* name, std::uint32_t processors = 2) {
  const RayBatch rays = testing::RaysOf(paths, 200);
  const CellTree tree = testing::TreeOf(rays);
  const WorkGraph w = RaySegmentWork(rays, cells);
  const std::vector<std::uint64_t> footprints(cells, 16'000);
  ReplayConfig config = DefaultConfig();
  config.processors.count = processors;
  config.levels[1].bandwidth_below = ParseBandwidth("unlimited", "test");
  config.levels[1].latency_below = SimTime::Zero();
  config.scheduler = &SchedulerByName(name, "test");
  auto s = MakeScheduler(*config.scheduler, 1);
  return ReplayFrame(w, footprints, config, *s, FrameTrees{0, &tree, nullptr, cells}, Bound(tree));
}

// Two processors, per ray segment; 40 rays A B and one ray C, 2 us a visit; a fetch into a
// cache takes 10.04 us (40 ns + 16000 B at 1.6 GB/s), the board costs nothing.
// Max Work: p0 takes A (ready 10.04), p1 takes C (10.04, done 12.04), then B, whose first ray
// p0 released at 12.04 (ready 22.08); p0 releases a B ray every 2 us until 90.04 and p1, never
// starved, takes B's queue whenever its worklist runs out (6 rays at 22.08, 34.08, ..., 82.08)
// and works the 40 until 22.08 + 80 = 102.08 us: 3 fetches.
// `share` chooses as Max Work while a free cell has work, so the same until 90.04, when p0,
// done with A, finds only B, busy, with 4 rays queued (84.04 .. 90.04): it joins B (ready
// 100.08), but p1 took those 4 at 94.08 and has one left not started, too few to split (it
// works the third, 98.08-100.08), so p0 leaves with nothing: 4 fetches, same time.
TEST(Balance, ASharingProcessorJoinsBusyCellsHandWorked) {
  constexpr CellId A{0}, B{1}, C{2};
  std::vector<testing::TestRay> paths;
  for (int i = 0; i < 40; ++i) paths.push_back({kNoParent, 0, {A, B}});
  paths.push_back({kNoParent, 0, {C}});
  const ReplayResult maxwork = ReplayOnProcessors(paths, 3, "maxwork");
  const ReplayResult share = ReplayOnProcessors(paths, 3, "share");
  EXPECT_EQ(maxwork.fetches, 3u);
  EXPECT_EQ(maxwork.time, SimTime::Picoseconds(102'080'000));
  EXPECT_EQ(share.fetches, 4u);
  EXPECT_EQ(share.time, SimTime::Picoseconds(102'080'000));
  EXPECT_EQ(share.samples, maxwork.samples);
}

// A joining processor takes half of the holder's worklist when the queue gives it nothing
// (design §2). Two processors, per ray segment, 2 us a visit, fetches 10.04 us as above: 20
// rays in A, one ray C A. Both schedulers: p0 takes A (ready 10.04; works its 20 rays until
// 50.04 alone), p1 takes C (ready 10.04) and works C until 12.04, releasing a visit into A,
// busy. Max Work waits; p0 takes it at 50.04: 52.04 us, 2 fetches. `share` joins A (ready
// 22.08), takes that visit (22.08-24.08), then, with the queue empty, half of p0's units not
// started: p0 works its 8th, 24.04-26.04, and has 12 left, so p1 takes the last 6
// (24.08-36.08) and p0 ends at 26.04 + 12 = 38.04 us: 3 fetches.
TEST(Balance, AJoinerSplitsTheHoldersWorklistHandWorked) {
  constexpr CellId A{0}, C{1};
  std::vector<testing::TestRay> paths;
  for (int i = 0; i < 20; ++i) paths.push_back({kNoParent, 0, {A}});
  paths.push_back({kNoParent, 0, {C, A}});
  const ReplayResult maxwork = ReplayOnProcessors(paths, 2, "maxwork");
  const ReplayResult share = ReplayOnProcessors(paths, 2, "share");
  EXPECT_EQ(maxwork.fetches, 2u);
  EXPECT_EQ(maxwork.time, SimTime::Picoseconds(52'040'000));
  EXPECT_EQ(share.fetches, 3u);
  EXPECT_EQ(share.time, SimTime::Picoseconds(38'040'000));
  EXPECT_EQ(share.work, maxwork.work);
  EXPECT_EQ(share.samples, maxwork.samples);
}

// Released work wakes first the waiting processors whose cache holds its cell (design §2).
// Three processors, Max Work, per ray segment, 2 us a visit, fetches 10.04 us as above; cells
// X, Y, Z; rays: 3 in Y, 2 in X, and in Z a chain of four rays each spawned by the one before,
// the last going on to X. p0 takes Y (the most rays; ready 10.04, done 16.04), p1 X (done
// 14.04), p2 Z, whose five units end at 20.04 releasing a visit into X; p0 and p1 wait. p1,
// which holds X, asks first: a hit, 20.04-22.04, 3 fetches. Woken in processor order, p0
// would fetch X instead: ready 30.08, done 32.08, 4 fetches.
TEST(Balance, ReleasedWorkGoesFirstToAWaitingProcessorThatHoldsItsCellHandWorked) {
  constexpr CellId X{0}, Y{1}, Z{2};
  std::vector<testing::TestRay> paths;
  for (int i = 0; i < 3; ++i) paths.push_back({kNoParent, 0, {Y}});
  for (int i = 0; i < 2; ++i) paths.push_back({kNoParent, 0, {X}});
  paths.push_back({kNoParent, 0, {Z}});
  for (RayId parent = 5; parent < 8; ++parent) paths.push_back({parent, 0, {Z}});
  paths.push_back({8, 0, {Z, X}});
  const ReplayResult r = ReplayOnProcessors(paths, 3, "maxwork", 3);
  EXPECT_EQ(r.fetches, 3u);
  EXPECT_EQ(r.time, SimTime::Picoseconds(22'040'000));
  EXPECT_EQ(r.samples, 11u * 200u);  // 11 visits
}

// `balanced` does not join a busy cell for less than 3 fetches' worth of queued work
// (kPostponeFactor): it waits, and the holder takes those rays. Frame i-1 gives 10 samples a
// visit in B; a fetch of B costs 100 samples; B is busy with 29 queued rays (290 samples,
// under 300): `balanced` waits where `share` joins; with 30 both join.
TEST(Balance, BalancedJoinsABusyCellOnlyForThreeFetchesOfWork) {
  constexpr CellId A{0}, B{1};
  const CellTree previous =
      testing::TreeOf(testing::RaysOf({{kNoParent, 0, {A, B}}, {kNoParent, 0, {B}}}, 10));
  const std::vector<double> fetch_samples = {100, 100};
  const std::vector<std::uint64_t> open = {~std::uint64_t{0}, 0};  // B busy
  const std::vector<std::uint64_t> view = {0, 0};                  // its rays masked out
  for (const std::uint64_t queued : {29u, 30u}) {
    for (const char* name : {"balanced", "share"}) {
      auto s = MakeScheduler(name, 1);
      FrameInfo info{1, nullptr, &previous, 2};
      info.processors = 2;
      info.fetch_samples = &fetch_samples;
      s->BeginFrame(info);
      const std::vector<std::uint64_t> all = {0, queued};
      QueueView v = QueueView::Of(view, A);
      v.working = 1;
      v.open = open.data();
      v.all_queued = all.data();
      const bool joins = queued >= 30 || std::string(name) == "share";
      EXPECT_EQ(s->Next(v), joins ? std::optional<CellId>(B) : std::nullopt)
          << name << " " << queued;
    }
  }
}

// balanced-critical's rule, hand-worked. Frame i-1: one ray A B, one ray B C D; its only
// shortest plan is A B C D (A must precede B for the first ray, B C D follow), so `balanced`
// fetches A first. The queued node of A matches frame i-1's node A (height 2: A, B), that of B
// the node B (height 3: B, C, D): with two processors balanced-critical starts the longer chain,
// B; with one it follows the plan as celltree-best. Once B's queue is taken, B's level is that
// of the work queued there since.
TEST(Balance, CriticalStartsTheLongestPredictedChainHandWorked) {
  constexpr CellId A{0}, B{1}, C{2}, D{3};
  const CellTree previous =
      testing::TreeOf(testing::RaysOf({{kNoParent, 0, {A, B}}, {kNoParent, 0, {B, C, D}}}, 10));
  std::vector<std::uint64_t> queued = {10, 1, 0, 0};
  for (const std::uint32_t p : {1u, 2u}) {
    for (const char* name : {"balanced", "balanced-critical"}) {
      auto s = MakeScheduler(name, 1);
      FrameInfo info{1, nullptr, &previous, 4};
      info.processors = p;
      s->BeginFrame(info);
      s->Arrived({1, 0, A, 10});
      s->Arrived({2, 0, B, 1});
      QueueView v = QueueView::Of(queued);
      const bool critical = p > 1 && std::string(name) == "balanced-critical";
      EXPECT_EQ(s->Next(v), critical ? B : A) << name << " P" << p;
      EXPECT_EQ(s->Reason() == "critical path first", critical) << name << " P" << p;
      if (critical) {
        // B's queue taken, then a ray of A's node enters B: frame i-1's node A B, height 1,
        // below A's 2.
        s->Taken(B);
        s->Arrived({3, 1, B, 1, A});
        std::vector<std::uint64_t> left = {10, 1, 0, 0};
        QueueView w = QueueView::Of(left);
        EXPECT_EQ(s->Next(w), A);
        EXPECT_GT(s->Cost().decisions, 0u);
      }
    }
  }
}

// Issue 43: the replay keeps each view's most queued cell, of the cells in view
// (QueueView::most) and of every cell (QueueView::all_most), so that a decision need not scan
// the cells; the schedulers take them where their scans took the cell with the most queued
// rays (balanced's affinity-weighted choice, celltree-adaptive's orphans). A wrapper checks on
// every call that the replay's cells are the scans' (ScanMostQueued), and that a twin of the
// scheduler told the same frame, shown the same views without them (so that MostQueuedCell and
// MostQueuedAll scan), chooses the same cells at the same cost.
class Twin : public Scheduler {
 public:
  Twin(const SchedulerEntry& entry, int* calls)
      : Scheduler(entry), a_(MakeScheduler(entry, 1)), b_(MakeScheduler(entry, 1)), calls_(calls) {}
  void BeginFrame(const FrameInfo& frame) override {
    a_->BeginFrame(frame);
    b_->BeginFrame(frame);
  }
  std::optional<CellId> Next(const QueueView& v) override {
    const std::optional<CellId> a = a_->Next(Check(v));
    EXPECT_EQ(a, b_->Next(Strip(v))) << Name();
    return a;
  }
  std::optional<CellId> Peek(const QueueView& v) const override {
    const std::optional<CellId> a = a_->Peek(Check(v));
    EXPECT_EQ(a, b_->Peek(Strip(v))) << Name();
    return a;
  }
  bool Watches() const override { return a_->Watches(); }
  void Arrived(const Arrival& arrival) override {
    a_->Arrived(arrival);
    b_->Arrived(arrival);
  }
  void Taken(CellId cell) override {
    a_->Taken(cell);
    b_->Taken(cell);
  }
  DecisionCost Cost() const override {
    EXPECT_EQ(a_->Cost().steps, b_->Cost().steps) << Name();
    return a_->Cost();
  }

 private:
  const QueueView& Check(const QueueView& v) const {
    ++*calls_;
    EXPECT_EQ(v.most_of, v.queued_rays);
    EXPECT_EQ(v.most, ScanMostQueued(v.queued_rays, v.cells)) << Name();
    if (entry().joins) {  // kept only for a scheduler that may join
      EXPECT_EQ(v.all_most_of, v.all_queued);
      EXPECT_EQ(v.all_most, ScanMostQueued(v.all_queued, v.cells)) << Name();
    }
    return v;
  }
  static QueueView Strip(QueueView v) {
    v.most_of = nullptr;
    v.all_most_of = nullptr;
    return v;
  }
  std::unique_ptr<Scheduler> a_, b_;
  int* calls_;
};

TEST(Balance, TheReplaysMostQueuedCellsAreTheScans) {
  std::mt19937 rng(43);
  int calls = 0;
  for (int trial = 0; trial < 3; ++trial) {
    const std::uint32_t cells = 3 + rng() % 12;
    const RayBatch rays = testing::RandomReplayFrame(rng, cells, 60);
    const CellTree tree = testing::TreeOf(rays);
    const CellTree previous = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 60));
    const CellTree before = testing::TreeOf(testing::RandomReplayFrame(rng, cells, 60));
    std::vector<std::uint64_t> footprints(cells);
    for (auto& f : footprints) f = 1000 + rng() % 100'000;
    const WorkGraph w = RaySegmentWork(rays, cells);
    for (const std::uint32_t p : {2u, 8u}) {
      for (const char* name :
           {"share", "balanced", "balanced-critical", "balanced-adaptive", "celltree-adaptive"}) {
        ReplayConfig config = DefaultConfig();
        config.scheduler = &SchedulerByName(name, "test");
        config.processors.count = p;
        config.granularity = ReplayConfig::Granularity::kRay;
        Twin twin(*config.scheduler, &calls);
        const FrameTrees info{2, &tree, trial % 3 == 0 ? nullptr : &previous, cells,
                              trial % 2 == 0 ? nullptr : &before};
        ReplayFrame(w, footprints, config, twin, info, Bound(tree));
      }
    }
  }
  EXPECT_GT(calls, 1000);
}

}  // namespace
}  // namespace raycell
