// Memory across frames (docs/design.md §2 "Memory"): with memory.across_frames = "warm" every
// level starts a frame with what the previous frame left; "cold" starts empty. Fetch counts
// against hand-worked frames, a static volume that fits the board crossing PCI once per
// capture, and frame ranges that start from the state the whole replay gives them.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <set>

#include "replay/replayer.h"
#include "runner/driver.h"
#include "scheduling/scheduler.h"
#include "tests/graph/test_trees.h"
#include "tests/replay/random_frame.h"
#include "tests/test_util.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

constexpr CellId A{0}, B{1}, C{2};
constexpr auto kWarm = MemoryConfig::AcrossFrames::kWarm;
constexpr auto kCold = MemoryConfig::AcrossFrames::kCold;

// Rays A B, A B and C A, three samples a visit: Max Work fetches A, B, C, then A again.
RayBatch Frame() {
  return testing::RaysOf({{kNoParent, 0, {A, B}}, {kNoParent, 0, {A, B}}, {kNoParent, 0, {C, A}}},
                         3);
}

// Two frames of Frame() under Max Work, one processor with a one-cell cache; the second's
// result, its memory carried from the first when `warm`.
ReplayResult SecondFrame(ReplayConfig config, const std::string& scheduler = "maxwork") {
  config.scheduler = &SchedulerByName(scheduler, "test");
  const RayBatch rays = Frame();
  const CellTree tree = testing::TreeOf(rays);
  const WorkGraph w = NodeWork(tree, 3);
  const std::vector<std::uint64_t> footprints(3, 4096);
  auto s = MakeScheduler(*config.scheduler, config.seed);
  const bool warm = config.memory.across_frames == kWarm;
  MemoryState memory;
  const ReplayResult first =
      ReplayFrame(w, footprints, config, *s, FrameTrees{0, &tree, nullptr, 3}, Bound(tree), nullptr,
                  warm ? &memory : nullptr);
  EXPECT_EQ(first.fetches, scheduler == "maxwork" ? 4u : 3u);  // a cold start either way
  return ReplayFrame(w, footprints, config, *s, FrameTrees{1, &tree, &tree, 3}, Bound(tree),
                     nullptr, warm ? &memory : nullptr);
}

// The board holds all three cells. Cold, frame 2 is frame 1 again: 4 cache fetches, 3 over
// PCI. Warm, the cache still holds A (Max Work's last cell) and the board every cell: the
// first A is a hit, then B, C and A are fetched from the board: 3 cache fetches, none over PCI.
TEST(WarmMemory, HandWorkedFetchCountsWithARoomyBoard) {
  ReplayConfig config = DefaultConfig();
  config.memory.across_frames = kCold;
  const ReplayResult cold = SecondFrame(config);
  EXPECT_EQ(cold.levels[0].fetches, 4u);
  EXPECT_EQ(cold.levels[1].fetches, 3u);
  ASSERT_TRUE(cold.bound.has_value());
  EXPECT_EQ(*cold.bound, 3u);
  config.memory.across_frames = kWarm;
  const ReplayResult warm = SecondFrame(config);
  EXPECT_EQ(warm.levels[0].fetches, 3u);
  EXPECT_EQ(warm.levels[1].fetches, 0u);
  // The warm cell may save the first fetch: the bound reported is one less, and still holds.
  ASSERT_TRUE(warm.bound.has_value());
  EXPECT_EQ(*warm.bound, 2u);
  // Less stall: three cache fetches at 40ns + 4096 B / 1.6 GB/s = 2.6 us each, no PCI.
  EXPECT_EQ(warm.stall.picoseconds(), 3 * (40'000 + 2'560'000));
  // The Peel oracle (C A B) fetches all three: the warm A is not where it starts.
  const ReplayResult peel = SecondFrame(config, "peel");
  EXPECT_EQ(peel.levels[0].fetches, 3u);
  EXPECT_EQ(peel.levels[1].fetches, 0u);
}

// A board of two cells, LRU. Frame 1: A, B, C (evicts A), A (evicts B): 4 over PCI, the board
// ends holding C then A (oldest first), the cache A. Warm frame 2: A hits in the cache; B
// evicts C, C evicts A, A evicts B: 3 over PCI and 3 cache fetches. Cold: 4 and 4.
TEST(WarmMemory, HandWorkedFetchCountsWithASmallBoard) {
  ReplayConfig config = DefaultConfig();
  config.levels[1].capacity_unit = LevelConfig::CapacityUnit::kCells;
  config.levels[1].capacity = 2;
  config.memory.across_frames = kCold;
  const ReplayResult cold = SecondFrame(config);
  EXPECT_EQ(cold.levels[0].fetches, 4u);
  EXPECT_EQ(cold.levels[1].fetches, 4u);
  config.memory.across_frames = kWarm;
  const ReplayResult warm = SecondFrame(config);
  EXPECT_EQ(warm.levels[0].fetches, 3u);
  EXPECT_EQ(warm.levels[1].fetches, 3u);
  // FIFO keeps the order cells came in: the board holds C then A as with LRU here.
  config.levels[1].replacement = &kFifoReplacement;
  EXPECT_EQ(SecondFrame(config).levels[1].fetches, 3u);
}

// A capture of `frames` random frames over 2x2x2 cells (a static volume: one footprint per
// cell for the whole capture).
class StaticVolume : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    path_ = new std::string(testing::TempPath("warm", "trace.rct"));
    // Few rays, so that some frames leave cells out that others use.
    used_ = new std::set<std::uint32_t>;
    for (const RayBatch& rays :
         testing::WriteRandomCapture(*path_, {2, 2, 2}, kFrames, 0, 11, 6, 2,
                                     [](std::uint32_t c) { return 3000 + 100 * c; })) {
      for (const CellId c : rays.cells()) used_->insert(c.value());
    }
    reader_ = new TraceReader(TraceReader::Open(*path_));
  }
  static void TearDownTestSuite() {
    delete reader_;
    delete used_;
    std::remove(path_->c_str());
    delete path_;
  }
  static std::vector<std::size_t> All() {
    std::vector<std::size_t> all(kFrames);
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    return all;
  }

  static constexpr int kFrames = 8;
  static std::string* path_;
  static TraceReader* reader_;
  static std::set<std::uint32_t>* used_;  // cells some frame visits
};
std::string* StaticVolume::path_ = nullptr;
TraceReader* StaticVolume::reader_ = nullptr;
std::set<std::uint32_t>* StaticVolume::used_ = nullptr;

// With warm memory and a board that holds the volume, each cell the capture uses crosses PCI
// exactly once, whatever the scheduler and processors; cold, once per frame that uses it.
TEST_F(StaticVolume, CrossesPciOncePerCaptureWhenItFits) {
  std::uint64_t per_frame = 0;  // cold: the cells each frame uses, summed
  for (std::size_t i = 0; i < kFrames; ++i) {
    const RayBatch rays = reader_->LoadFrame(i);
    const std::set<CellId> cells(rays.cells().begin(), rays.cells().end());
    per_frame += cells.size();
  }
  ASSERT_GT(per_frame, used_->size());  // some cell is used by several frames
  for (const SchedulerEntry& s : SchedulerRegistry()) {
    for (std::uint32_t p : {1u, 2u, 4u, 8u}) {
      ReplayConfig config = DefaultConfig();
      config.scheduler = &s;
      config.processors.count = p;
      const TraceReplay warm = ReplayTrace(*reader_, All(), config);
      EXPECT_EQ(warm.total.levels[1].fetches, used_->size()) << s.name << " P" << p;
      config.memory.across_frames = kCold;
      const TraceReplay cold = ReplayTrace(*reader_, All(), config);
      EXPECT_EQ(cold.total.levels[1].fetches, per_frame) << s.name << " P" << p;
      EXPECT_EQ(warm.total.samples, cold.total.samples);
      EXPECT_LE(warm.total.time, cold.total.time) << s.name << " P" << p;
      // The time bound counts what warm memory holds at each frame's start, and still holds.
      for (const ReplayResult& f : warm.frames) EXPECT_LE(f.time_bound, f.time) << s.name;
      EXPECT_LT(warm.total.time_bound, cold.total.time_bound) << s.name << " P" << p;
    }
  }
}

// A range of frames, or a selection with gaps, starts each frame from the memory the replay of
// the whole capture leaves it: the same results frame by frame.
TEST_F(StaticVolume, FrameRangesStartFromTheWholeReplaysMemory) {
  for (const char* scheduler : {"maxwork", "celltree", "celltree-best"}) {
    for (std::uint32_t p : {1u, 3u}) {
      ReplayConfig config = DefaultConfig();
      config.scheduler = &SchedulerByName(scheduler, "test");
      config.processors.count = p;
      config.levels[1].capacity_unit = LevelConfig::CapacityUnit::kCells;
      config.levels[1].capacity = 3;  // evictions, so the state depends on every frame before
      const TraceReplay whole = ReplayTrace(*reader_, All(), config);
      for (const std::vector<std::size_t>& part :
           {std::vector<std::size_t>{5, 6, 7}, {3}, {2, 6}}) {
        const TraceReplay t = ReplayTrace(*reader_, part, config);
        ASSERT_EQ(t.frames.size(), part.size());
        for (std::size_t n = 0; n < part.size(); ++n) {
          const ReplayResult& a = t.frames[n];
          const ReplayResult& b = whole.frames[part[n]];
          EXPECT_EQ(a.frame, b.frame);
          EXPECT_EQ(a.levels[0].fetches, b.levels[0].fetches) << scheduler << " P" << p;
          EXPECT_EQ(a.levels[1].fetches, b.levels[1].fetches) << scheduler << " P" << p;
          EXPECT_EQ(a.time, b.time) << scheduler << " P" << p;
          EXPECT_EQ(a.events, b.events) << scheduler << " P" << p;
        }
      }
    }
  }
}

// A capture of a sequence of volumes (a --scene pattern) is new data every frame: warm memory
// keeps nothing there, and gives what cold gives.
TEST(WarmMemory, ASequenceOfVolumesKeepsNothing) {
  const std::string path = testing::TempPath("warm", "sequence.rct");
  testing::WriteRandomCapture(
      path, {2, 2, 1}, 3, 0, 5, 20, 4, [](std::uint32_t) { return 4096; }, "fluid_%04d.vdb");
  const TraceReader reader = TraceReader::Open(path);
  ASSERT_TRUE(reader.header().volume_changes());
  ReplayConfig config = DefaultConfig();
  const TraceReplay warm = ReplayTrace(reader, {0, 1, 2}, config);
  config.memory.across_frames = kCold;
  const TraceReplay cold = ReplayTrace(reader, {0, 1, 2}, config);
  EXPECT_EQ(warm.total.levels[1].fetches, cold.total.levels[1].fetches);
  EXPECT_EQ(warm.total.time, cold.total.time);
  std::remove(path.c_str());
}

// A dynamic subdivision's cells are other boxes every frame: what a level held carries over
// through the fine cells (CarryOver). Four fine cells in a row; the old cells X = {0, 1},
// Y = {2} and Z = {3} (empty: no data); the new ones P = {0}, Q = {1}, S = {2, 3}.
TEST(WarmMemory, CarryOverKeepsTheNewCellsWhoseDataIsHeld) {
  const std::vector<CellId> old_of_fine{CellId(0), CellId(0), CellId(1), CellId(2)};
  const std::vector<CellId> new_of_fine{CellId(0), CellId(1), CellId(2), CellId(2)};
  const std::vector<std::uint64_t> old_fp{100, 50, 0}, new_fp{60, 40, 50};
  const FrameCells from{&old_of_fine, &old_fp}, to{&new_of_fine, &new_fp};
  MemoryState state;
  // Level 0, two processors: one holds X (P and Q, ties by number), one Y (S: Z holds no
  // data). Level 1 holds Y then X (Y the first victim): S first, then P and Q.
  state.held = {{{CellId(0)}, {CellId(1)}}, {{CellId(1), CellId(0)}}};
  const MemoryState out = CarryOver(state, from, to);
  ASSERT_EQ(out.held.size(), 2u);
  ASSERT_EQ(out.held[0].size(), 2u);
  EXPECT_EQ(out.held[0][0], (std::vector<CellId>{CellId(0), CellId(1)}));
  EXPECT_EQ(out.held[0][1], (std::vector<CellId>{CellId(2)}));
  EXPECT_EQ(out.held[1][0], (std::vector<CellId>{CellId(2), CellId(0), CellId(1)}));
  // Back the other way: a new cell partly held is not held. Holding P alone keeps none of
  // X = {P, Q}; holding Q and S keeps Y, not X; an empty cell (Z) is never held.
  const FrameCells back_from{&new_of_fine, &new_fp}, back_to{&old_of_fine, &old_fp};
  state.held = {{{CellId(0)}, {CellId(1), CellId(2)}}};
  const MemoryState back = CarryOver(state, back_from, back_to);
  EXPECT_EQ(back.held[0][0], std::vector<CellId>{});
  EXPECT_EQ(back.held[0][1], (std::vector<CellId>{CellId(1)}));
}

// The same through a whole replay: a trace of a dynamic:2 subdivision of four fine cells in a
// row, a one-cell cache and a board that holds everything (the default configuration).
//   frame 0: X = {0, 1}, Y = {2, 3}; one ray in X. PCI: X.
//   frame 1: P = {0}, Q = {1, 2, 3}; a ray P then Q. P lies in X: the cache and the board hold
//            it. Q is partly in Y, never loaded: fetched over PCI. Warm: 1 cache fetch, 1 PCI.
//   frame 2: X and Y again; a ray Y then X. The board holds both (P and Q cover them), the
//            cache Y (in Q): Y hits, X comes from the board. Warm: 1 cache fetch, 0 PCI.
// Cold, every cell visited is fetched over PCI: 2 and 2.
TEST(WarmMemory, ADynamicSubdivisionCarriesItsCellsThroughTheFineCells) {
  const std::string path = testing::TempPath("warm", "dynamic.rct");
  TraceHeader h;
  h.producer = "raycell test";
  h.scene = "builtin:test";
  h.cells = {2, 1, 1};
  h.subdivision.spec = "dynamic:2";
  h.subdivision.fine = {4, 1, 1};
  const auto box = [](std::uint32_t lo, std::uint32_t hi) {
    return FineBox{{lo, 0, 0}, {hi, 1, 1}};
  };
  h.subdivision.boxes = {box(0, 2), box(2, 4), box(0, 1), box(1, 4), box(0, 2), box(2, 4)};
  h.subdivision.frame_footprints = {4096, 4096, 2048, 8192, 4096, 4096};
  h.footprints = {4096, 8192};
  for (int f = 0; f < 3; ++f) h.cameras.push_back({f, {1, 2, 3.0 + f}, {0, 0, 0}, {0, 1, 0}, 40});
  {
    TraceWriter w = TraceWriter::Create(path, h, 3);
    const std::vector<RayBatch> frames = {testing::RaysOf({{kNoParent, 0, {A}}}, 3),
                                          testing::RaysOf({{kNoParent, 0, {A, B}}}, 3),
                                          testing::RaysOf({{kNoParent, 0, {B, A}}}, 3)};
    for (int f = 0; f < 3; ++f) {
      w.BeginFrame(f);
      w.Append(frames[std::size_t(f)]);
      w.EndFrame();
    }
    w.Finish();
  }
  const TraceReader reader = TraceReader::Open(path);
  ASSERT_TRUE(reader.header().cells_change());
  ReplayConfig config = DefaultConfig();
  const TraceReplay warm = ReplayTrace(reader, {0, 1, 2}, config);
  ASSERT_EQ(warm.frames.size(), 3u);
  const std::vector<std::uint64_t> cache{1, 1, 1}, pci{1, 1, 0};
  for (std::size_t f = 0; f < 3; ++f) {
    SCOPED_TRACE(f);
    EXPECT_EQ(warm.frames[f].levels[0].fetches, cache[f]);
    EXPECT_EQ(warm.frames[f].levels[1].fetches, pci[f]);
  }
  EXPECT_EQ(warm.frames[1].levels[1].bytes, 8192u);  // Q, at its frame-1 footprint
  // A range that starts at frame 2 replays frames 0 and 1 first: the same frame 2.
  const TraceReplay last = ReplayTrace(reader, {2}, config);
  ASSERT_EQ(last.frames.size(), 1u);
  EXPECT_EQ(last.frames[0].levels[0].fetches, 1u);
  EXPECT_EQ(last.frames[0].levels[1].fetches, 0u);
  EXPECT_EQ(last.frames[0].time, warm.frames[2].time);
  config.memory.across_frames = kCold;
  const TraceReplay cold = ReplayTrace(reader, {0, 1, 2}, config);
  for (std::size_t f = 1; f < 3; ++f) {
    EXPECT_EQ(cold.frames[f].levels[0].fetches, 2u);
    EXPECT_EQ(cold.frames[f].levels[1].fetches, 2u);
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace raycell
