// auto:N (traces/auto_cells.h; docs/design.md §1 "Subdivisions", "auto:N"): its spec, its
// baseline, that it falls back to the baseline where the frames seen show the baseline cheaper
// and leaves it where they show a candidate cheaper by its margin, that frame i's cells come
// from frames before i only, and that a regrouped view keeps every ray's samples.
#include "traces/auto_cells.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "base/check.h"
#include "tests/traces/trace_test_util.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

using Grid = std::array<std::uint32_t, 3>;

TEST(AutoCells, SpecParsesAndPrintsBack) {
  const SubdivisionSpec s = ParseSubdivisionSpec(" auto:27 ", "t");
  EXPECT_EQ(s.kind, SubdivisionSpec::Kind::kAuto);
  EXPECT_EQ(s.cells, 27u);
  EXPECT_TRUE(s.per_frame());
  EXPECT_EQ(s.ToString(), "auto:27");
  EXPECT_EQ(ParseSubdivisionSpec(s.ToString(), "t"), s);
  for (const char* bad : {"auto:0", "auto:", "auto:x", "auto:27:sqrt"}) {
    EXPECT_THROW(ParseSubdivisionSpec(bad, "t"), InputError) << bad;
  }
}

// The most cubic counts: the smallest largest count, then the largest smallest, then the lowest
// NX and NY; within the fine grid.
TEST(AutoCells, TheBaselineIsTheGridNearestACube) {
  EXPECT_EQ(CubicGrid(27, {12, 12, 12}, "t"), (Grid{3, 3, 3}));
  EXPECT_EQ(CubicGrid(12, {12, 12, 12}, "t"), (Grid{2, 2, 3}));  // not 1x3x4
  EXPECT_EQ(CubicGrid(8, {12, 12, 12}, "t"), (Grid{2, 2, 2}));
  EXPECT_EQ(CubicGrid(7, {12, 12, 12}, "t"), (Grid{1, 1, 7}));
  EXPECT_EQ(CubicGrid(27, {1, 12, 12}, "t"), (Grid{1, 3, 9}));
  EXPECT_THROW(CubicGrid(13, {12, 12, 12}, "t"), InputError);  // 13 fits no axis
  // Frame 0 of auto:N, and Subdivide's auto:N, is that grid's.
  FineCells fine;
  fine.grid = {12, 12, 12};
  EXPECT_EQ(Subdivide(ParseSubdivisionSpec("auto:27", "t"), fine).boxes,
            Subdivide(ParseSubdivisionSpec("3x3x3", "t"), fine).boxes);
}

// A fine row of 4 cells: leaves of 300, 100, 100 and 100 bytes, one per cell. auto:2's
// baseline is [0,2) [2,4) (400 and 200 bytes); kd:2:footprint cuts [0,1) [1,4) (300 and 300).
FineCells Row() {
  FineCells fine;
  fine.grid = {4, 1, 1};
  fine.union_footprint = [](const std::vector<std::uint32_t>& cells) {
    std::uint64_t b = 0;
    for (std::uint32_t c : cells) b += c == 0 ? 300 : 100;
    return b;
  };
  return fine;
}

// `rays` primary rays, each bouncing between fine cells a and b three times (a b a b a b), a
// shadow ray spawned at each visit.
RayBatch Bouncing(std::uint32_t a, std::uint32_t b, int rays) {
  RayBatch out(false);
  for (int r = 0; r < rays; ++r) {
    const RayId primary = out.size();
    out.BeginRay(RayKind::kPrimary, kNoParent, 0, std::uint32_t(r), 0);
    for (int v = 0; v < 6; ++v) out.AddVisit(CellId(v % 2 ? b : a), 10, 0.f, 0.f);
    for (std::uint32_t v = 0; v < 6; ++v) {
      out.BeginRay(RayKind::kShadow, primary, v, std::uint32_t(r), 0);
      out.AddVisit(CellId(v % 2 ? b : a), 1, 0.f, 0.f);
    }
  }
  return out;
}

std::vector<std::string> Rules(const AutoCells& a) {
  std::vector<std::string> out;
  for (const AutoCells::Frame& f : a.frames()) out.push_back(f.rule);
  return out;
}

// Rays bouncing between fine cells 0 and 1 stay in the baseline's first cell (one fetch of 400
// bytes) but cross kd:2:footprint's boundary at 1 six times (1800 bytes): every candidate
// costs more or the same, and auto:2 keeps the baseline every frame.
TEST(AutoCells, FallsBackToTheBaselineWhereItIsCheaper) {
  AutoCells a(2, Row(), "t");
  const std::vector<FineBox> uniform = a.next().boxes;
  EXPECT_EQ(uniform, (std::vector<FineBox>{{{0, 0, 0}, {2, 1, 1}}, {{2, 0, 0}, {4, 1, 1}}}));
  for (int f = 0; f < 6; ++f) {
    EXPECT_EQ(a.next().boxes, uniform) << "frame " << f;
    a.AddBatch(Bouncing(0, 1, 50));
    a.EndFrame();
  }
  EXPECT_EQ(Rules(a), std::vector<std::string>(6, "uniform"));
  EXPECT_EQ(a.next().boxes, uniform);
  // The candidate was estimated dearer on every frame.
  for (const AutoCells::Frame& f : a.frames()) {
    for (const auto& [rule, ratio] : f.ratios) EXPECT_GE(ratio, 1.0) << rule;
  }
}

// Rays bouncing between fine cells 1 and 2 stay in kd:2:footprint's cell [1,4) (one fetch of
// 300 bytes) but cross the baseline's boundary at 2 six times: once the candidate has won on
// two frames (frames 0 and 1) by more than its ratio moved, frame 2 on takes its cells.
TEST(AutoCells, TakesACandidateThatWinsOnTheFramesSeen) {
  AutoCells a(2, Row(), "t");
  const std::vector<FineBox> uniform = a.next().boxes;
  for (int f = 0; f < 5; ++f) {
    a.AddBatch(Bouncing(1, 2, 50));
    a.EndFrame();
  }
  const std::vector<std::string> rules = Rules(a);
  EXPECT_EQ(rules[0], "uniform");  // nothing seen
  EXPECT_EQ(rules[1], "uniform");  // the candidate evaluated on one frame only
  for (std::size_t f = 2; f < rules.size(); ++f) EXPECT_NE(rules[f], "uniform") << f;
  EXPECT_NE(a.next().boxes, uniform);
  // Its cells keep the bouncing rays in one cell.
  EXPECT_EQ(a.next().coarse_of_fine[1], a.next().coarse_of_fine[2]);
}

// The choice among rules from their ratios on the frames seen and their switch costs (rule 0
// the baseline, its ratios 1).
TEST(AutoCells, SwitchesOnlyToARuleWhoseSavingsOnTheLatestFramesPayItsSwitch) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> cheap{0, 0.1, 0.1};
  // Rule 1 cheaper on the last two frames by 0.1 each (0.2 in all): pays a switch of 0.1, not
  // one of 0.3.
  EXPECT_EQ(ChooseAutoRule({{1, 1}, {0.9, 0.9}, {nan, nan}}, cheap, 0), 1u);
  EXPECT_EQ(ChooseAutoRule({{1, 1}, {0.9, 0.9}, {nan, nan}}, {0, 0.3, 0}, 0), 0u);
  // A longer run of cheaper frames pays more: 0.1 on each of four frames pays 0.3.
  EXPECT_EQ(
      ChooseAutoRule({{1, 1, 1, 1}, {0.9, 0.9, 0.9, 0.9}, {nan, nan, nan, nan}}, {0, 0.3, 0}, 0),
      1u);
  // ...but the run ends at the latest frame on which the rule was not cheaper.
  EXPECT_EQ(
      ChooseAutoRule({{1, 1, 1, 1}, {0.9, 0.9, 1.0, 0.9}, {nan, nan, nan, nan}}, {0, 0.15, 0}, 0),
      0u);
  // One frame is no run, however cheap: a rule with one ratio (NaN before) or one cheap frame.
  EXPECT_EQ(ChooseAutoRule({{1, 1}, {nan, 0.5}, {1.1, 0.5}}, cheap, 0), 0u);
  // Of two rules that pay, the least ratio on the last frame; ties to the lowest.
  EXPECT_EQ(ChooseAutoRule({{1, 1}, {0.8, 0.8}, {0.9, 0.7}}, cheap, 0), 2u);
  EXPECT_EQ(ChooseAutoRule({{1, 1}, {0.8, 0.7}, {0.9, 0.7}}, cheap, 0), 1u);
  // The rule chosen before stays while no other pays its switch against it, the baseline
  // included: rule 1 dearer than the baseline on the last frame only...
  EXPECT_EQ(ChooseAutoRule({{1, 1, 1}, {0.8, 0.9, 1.2}, {nan, nan, nan}}, {0.1, 0, 0}, 1), 1u);
  // ...and on two (0.1 + 0.2 saved by falling back pays 0.25), or by too little (0.01 each).
  EXPECT_EQ(ChooseAutoRule({{1, 1, 1}, {0.8, 1.1, 1.2}, {nan, nan, nan}}, {0.25, 0, 0}, 1), 0u);
  EXPECT_EQ(ChooseAutoRule({{1, 1, 1}, {0.8, 1.01, 1.01}, {nan, nan, nan}}, {0.25, 0, 0}, 1), 1u);
  // Against the rule chosen before, not the baseline: rule 2 must be cheaper than rule 1.
  EXPECT_EQ(ChooseAutoRule({{1, 1}, {0.7, 0.7}, {0.8, 0.8}}, cheap, 1), 1u);
  EXPECT_EQ(ChooseAutoRule({{1, 1}, {0.7, 0.7}, {0.6, 0.6}}, cheap, 1), 2u);
}

// A regroupable capture of Row()'s fine cells, one frame per letter of `frames`: 'W' frames
// of rays bouncing between fine cells 1 and 2 (a candidate wins), 'L' frames between 0 and 1
// (the baseline wins).
void WriteCapture(const std::string& path, const std::string& frames) {
  TraceHeader h = testing::TestHeader({4, 1, 1}, false, int(frames.size()));
  h.regroupable = true;
  h.leaves.bytes = {300, 100, 100, 100};
  h.leaves.begin = {0, 1, 2, 3, 4};
  h.leaves.leaves = {0, 1, 2, 3};
  h.footprints = h.leaves.bytes;
  TraceWriter w = TraceWriter::Create(path, h);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    w.BeginFrame(10 + int(f));
    w.Append(frames[f] == 'W' ? Bouncing(1, 2, 20) : Bouncing(0, 1, 20));
    w.EndFrame();
  }
  w.Finish();
}

class AutoCellsCapture : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("raycell_auto_cells_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

// Frame i's cells come from frames before i only: a capture, the same capture's first 3 frames,
// and the same first 3 frames followed by other ones give the same cells and rays in frames
// 0-2, and in frame 3, decided from frames 0-2 alone. The other frames then change the cells
// of the frames after them.
TEST_F(AutoCellsCapture, UsesNoFutureInformation) {
  WriteCapture(Path("a.rct"), "WWWWWW");
  WriteCapture(Path("first3.rct"), "WWW");
  WriteCapture(Path("other.rct"), "WWWLLL");
  const TraceReader a = TraceReader::Open(Path("a.rct"), "auto:2");
  const TraceReader first3 = TraceReader::Open(Path("first3.rct"), "auto:2");
  const TraceReader other = TraceReader::Open(Path("other.rct"), "auto:2");
  ASSERT_EQ(a.header().cell_count(), 2u);
  const auto boxes = [](const TraceReader& r, std::size_t f) {
    const auto& all = r.header().subdivision.boxes;
    return std::vector<FineBox>(all.begin() + std::ptrdiff_t(2 * f),
                                all.begin() + std::ptrdiff_t(2 * (f + 1)));
  };
  const std::vector<FineBox> uniform{{{0, 0, 0}, {2, 1, 1}}, {{2, 0, 0}, {4, 1, 1}}};
  for (std::size_t f = 0; f < 4; ++f) {
    SCOPED_TRACE(f);
    EXPECT_EQ(boxes(a, f), f < 2 ? uniform : boxes(a, 2));
    EXPECT_EQ(boxes(a, f), boxes(other, f));
    EXPECT_EQ(a.CellMap(f), other.CellMap(f));
    if (f < 3) {
      EXPECT_EQ(a.LoadFrame(f), other.LoadFrame(f));
      EXPECT_EQ(boxes(a, f), boxes(first3, f));
      EXPECT_EQ(a.LoadFrame(f), first3.LoadFrame(f));
      EXPECT_EQ(a.frames()[f], first3.frames()[f]);
      EXPECT_EQ(a.FrameFootprints(f), first3.FrameFootprints(f));
    }
  }
  EXPECT_NE(boxes(a, 2), uniform);
  // Frames 3 and 4's 'L' rays cost the candidate more: one frame is not enough to change the
  // cells again (frame 4 keeps the candidate's), two are, frame 5 falls back to the baseline.
  EXPECT_EQ(boxes(other, 4), boxes(a, 2));
  EXPECT_EQ(boxes(other, 5), uniform);
  EXPECT_EQ(boxes(a, 5), boxes(a, 2));
}

// Every sample of the fine capture is kept, once, in every frame, and the view's cells are
// each frame's boxes: the frame regrouped by its boxes as read from the header gives the view's
// rays.
TEST_F(AutoCellsCapture, KeepsEverySampleOnce) {
  WriteCapture(Path("a.rct"), "WWWLLW");
  const TraceReader stored = TraceReader::OpenStored(Path("a.rct"));
  const TraceReader view = TraceReader::Open(Path("a.rct"), "auto:2");
  ASSERT_EQ(view.frames().size(), 6u);
  EXPECT_TRUE(view.header().cells_change());
  EXPECT_EQ(view.header().subdivision.spec, "auto:2");
  for (std::size_t f = 0; f < 6; ++f) {
    SCOPED_TRACE(f);
    const RayBatch fine = stored.LoadFrame(f), coarse = view.LoadFrame(f);
    EXPECT_EQ(std::accumulate(coarse.samples().begin(), coarse.samples().end(), std::uint64_t{0}),
              std::accumulate(fine.samples().begin(), fine.samples().end(), std::uint64_t{0}));
    EXPECT_EQ(view.frames()[f].samples, stored.frames()[f].samples);
    std::vector<CellId> map = view.header().subdivision.CellOfFine(f, 2);
    for (std::size_t c = 0; c < map.size(); ++c) {
      if (view.FrameFootprints(f)[map[c].value()] == 0) map[c] = kNoCell;
    }
    RayRegrouper regroup(map);
    EXPECT_EQ(regroup.Regroup(fine), coarse);
    // Sample for sample: per fine cell of a coarse cell, as many samples in the coarse cell.
    std::vector<std::uint64_t> by_cell(2, 0), expect(2, 0);
    for (std::size_t v = 0; v < coarse.visit_count(); ++v) {
      by_cell[coarse.cells()[v].value()] += coarse.samples()[v];
    }
    for (std::size_t v = 0; v < fine.visit_count(); ++v) {
      expect[map[fine.cells()[v].value()].value()] += fine.samples()[v];
    }
    EXPECT_EQ(by_cell, expect);
  }
  // The cells changed over the frames: the candidate's from frame 2, the baseline's again after
  // the 'L' frames.
  EXPECT_NE(view.CellMap(2), view.CellMap(0));
  EXPECT_EQ(view.CellMap(5), view.CellMap(0));
}

}  // namespace
}  // namespace raycell
