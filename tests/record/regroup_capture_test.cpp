// Issue 23's exactness: a regroupable capture on a fine grid, regrouped into any grid whose
// planes are planes of the fine one, gives the trace recorded directly on that grid (docs/
// design.md §1 "Subdivisions"), with no tolerance.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <set>
#include <sstream>
#include <string>

#include "analysis/analysis.h"
#include "base/check.h"
#include "graph/cell_tree.h"
#include "graph/frame_tree.h"
#include "replay/config.h"
#include "runner/driver.h"
#include "tests/record/record_test_util.h"
#include "traces/trace_reader.h"
#include "traces/trace_regroup.h"

namespace raycell {
namespace {

using testing::SmallBuiltin;
using testing::TempDir;

class RegroupCaptureTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::filesystem::path(TempDir("regroup_capture"));
    std::ostringstream log;
    RecordOptions o = SmallBuiltin(*dir_, 64);
    o.settings.store_t = true;
    o.cells = {12, 12, 12};
    o.regroupable = true;
    o.out = Path("fine.rct");
    Record(o, log);
    o.regroupable = false;
    o.out = Path("plain12.rct");
    Record(o, log);
    for (std::uint32_t n : {2u, 3u, 4u, 6u}) {
      o.cells = {n, n, n};
      o.out = Path("direct" + std::to_string(n) + ".rct");
      Record(o, log);
    }
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*dir_);
    delete dir_;
  }
  static std::string Path(const std::string& name) { return (*dir_ / name).string(); }
  static std::filesystem::path* dir_;
};
std::filesystem::path* RegroupCaptureTest::dir_ = nullptr;

// Compares two frames ray by ray, everything included (t too); the rays that differ.
int Differing(const RayBatch& direct, const RayBatch& regrouped) {
  EXPECT_EQ(direct.size(), regrouped.size());
  int differ = 0;
  for (std::size_t i = 0; i < std::min(direct.size(), regrouped.size()); ++i) {
    const RayView a = direct.ray(i), b = regrouped.ray(i);
    bool same = a.kind == b.kind && a.parent == b.parent && a.spawn == b.spawn &&
                a.pixel_x == b.pixel_x && a.pixel_y == b.pixel_y && a.visit_count == b.visit_count;
    for (std::size_t v = 0; same && v < a.visit_count; ++v) {
      const Visit x = a.visit(v), y = b.visit(v);
      same = x.cell == y.cell && x.samples == y.samples && x.t_enter == y.t_enter &&
             x.t_exit == y.t_exit;
    }
    if (!same && ++differ <= 3) ADD_FAILURE() << "ray " << a.id << " differs";
  }
  return differ;
}

std::string Grid(std::uint32_t n) {
  return std::to_string(n) + "x" + std::to_string(n) + "x" + std::to_string(n);
}

// 12x12x12 regrouped to 2x2x2, 3x3x3, 4x4x4 and 6x6x6 against captures recorded directly on
// those grids: the same footprints, byte for byte, and the same rays, visit for visit and
// sample for sample, t included, with no tolerance. What makes it exact (docs/design.md §1
// "Subdivisions"): nested grids share their planes to the last bit, the renderer searches a
// ray over its whole chord whatever the cells, and a spawned ray's start point counts as in
// its cell within a fraction of the box, not of the cell.
TEST_F(RegroupCaptureTest, RegroupedGridsEqualDirectCapturesVisitForVisit) {
  for (std::uint32_t n : {2u, 3u, 4u, 6u}) {
    SCOPED_TRACE(Grid(n));
    const TraceReader direct = TraceReader::Open(Path("direct" + std::to_string(n) + ".rct"));
    const TraceReader regrouped = TraceReader::Open(Path("fine.rct"), Grid(n));
    EXPECT_EQ(regrouped.header().cells, direct.header().cells);
    EXPECT_EQ(regrouped.header().footprints, direct.header().footprints);
    const RayBatch a = direct.LoadFrame(0), b = regrouped.LoadFrame(0);
    EXPECT_GT(a.size(), 16000u);
    EXPECT_EQ(Differing(a, b), 0);
    EXPECT_EQ(regrouped.frames()[0], direct.frames()[0]);  // totals and checksum
  }
}

// So are the Cell Tree, its bound and its Peel schedule.
TEST_F(RegroupCaptureTest, RegroupedCellTreeBoundAndPeelEqualTheDirectCapture) {
  for (std::uint32_t n : {2u, 3u, 4u, 6u}) {
    SCOPED_TRACE(Grid(n));
    const TraceReader direct = TraceReader::Open(Path("direct" + std::to_string(n) + ".rct"));
    const TraceReader regrouped = TraceReader::Open(Path("fine.rct"), Grid(n));
    const CellTree a = BuildFrameTree(direct, 0), b = BuildFrameTree(regrouped, 0);
    ASSERT_EQ(a.node_count(), b.node_count());
    for (std::uint32_t i = 1; i <= a.node_count(); ++i) {
      const NodeId node(i);
      ASSERT_EQ(a.cell(node), b.cell(node));
      ASSERT_EQ(a.parent(node), b.parent(node));
    }
    const FrameAnalysis x = AnalyzeTree(a, {}), y = AnalyzeTree(b, {});
    EXPECT_GT(x.bound, 0u);
    EXPECT_EQ(x.bound, y.bound);
    EXPECT_EQ(x.peel_schedule, y.peel_schedule);
  }
}

// A dynamic subdivision's cells are other boxes each frame: each frame's footprints are its
// boxes' leaf unions (the replay uses them), the header's the largest over the frames, and the
// file `trace regroup` writes keeps them.
TEST_F(RegroupCaptureTest, DynamicCellsHaveEachFramesFootprints) {
  const TraceReader stored = TraceReader::OpenStored(Path("fine.rct"));
  const TraceReader view = TraceReader::Open(Path("fine.rct"), "dynamic:9");
  const TraceHeader& h = view.header();
  ASSERT_EQ(h.cell_count(), 9u);
  ASSERT_EQ(h.subdivision.boxes.size(), 9u * view.frames().size());
  EXPECT_TRUE(h.cells_change());
  std::vector<std::uint64_t> largest(9, 0);
  for (std::size_t f = 0; f < view.frames().size(); ++f) {
    const std::vector<std::uint64_t>& fp = view.FrameFootprints(f);
    ASSERT_EQ(fp.size(), 9u);
    for (std::uint32_t c = 0; c < 9; ++c) {
      const FineBox& b = h.subdivision.boxes[f * 9 + c];
      std::vector<std::uint32_t> members;
      for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
        for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y)
          for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x)
            members.push_back(x + 12 * (y + 12 * z));
      EXPECT_EQ(fp[c], stored.header().leaves.UnionBytes(members));
      largest[c] = std::max(largest[c], fp[c]);
    }
  }
  EXPECT_EQ(h.footprints, largest);
  RegroupTrace(Path("fine.rct"), "dynamic:9", Path("dyn.rct"));
  const TraceReader written = TraceReader::Open(Path("dyn.rct"));
  for (std::size_t f = 0; f < view.frames().size(); ++f) {
    EXPECT_EQ(written.FrameFootprints(f), view.FrameFootprints(f));
  }
}

// A dynamic subdivision whose boxes change between frames i - 1 and i: frame i - 1's tree is of
// other cells and says nothing about frame i's, so Cell Tree scheduling gets none and replays
// frame i as Max Work does (its frame-0 rule); with the boxes unchanged it follows the tree.
TEST(RegroupCaptureDynamicTest, ATreeOfOtherCellsIsNotGivenToTheSchedulers) {
  const auto dir = TempDir("regroup_dynamic");
  RecordOptions o = SmallBuiltin(dir, 32);
  o.cells = {12, 12, 12};
  o.regroupable = true;
  o.frames = {0, 1, 2, 3};
  o.camera.orbit_degrees = 90;
  std::ostringstream log;
  Record(o, log);
  const TraceReader view = TraceReader::Open(o.out, "dynamic:9");
  const auto& boxes = view.header().subdivision.boxes;
  std::vector<std::size_t> frames(view.frames().size());
  for (std::size_t f = 0; f < frames.size(); ++f) frames[f] = f;
  ReplayConfig celltree = DefaultConfig(), maxwork = DefaultConfig();
  ApplyOverride(celltree, "scheduler", "celltree", "test");
  ApplyOverride(maxwork, "scheduler", "maxwork", "test");
  const TraceReplay a = ReplayTrace(view, frames, celltree), b = ReplayTrace(view, frames, maxwork);
  int changed = 0;
  for (std::size_t f = 1; f < frames.size(); ++f) {
    if (std::equal(boxes.begin() + (f - 1) * 9, boxes.begin() + f * 9, boxes.begin() + f * 9)) {
      continue;
    }
    ++changed;
    EXPECT_EQ(a.frames[f].fetches, b.frames[f].fetches) << "frame " << f;
    EXPECT_EQ(a.frames[f].time, b.frames[f].time) << "frame " << f;
  }
  EXPECT_GT(changed, 0) << "no frame changed its boxes: the test shows nothing";
  std::filesystem::remove_all(dir);
}

// Without empty cells dropped, a regroupable capture's rays are those of a plain capture on
// the same grid: the empty visits it adds change nothing once dropped.
TEST_F(RegroupCaptureTest, ItsOwnGridIsThePlainCapture) {
  const TraceReader plain = TraceReader::Open(Path("plain12.rct"));
  const TraceReader fine = TraceReader::Open(Path("fine.rct"));
  const TraceReader stored = TraceReader::OpenStored(Path("fine.rct"));
  EXPECT_TRUE(fine.regrouped());
  EXPECT_EQ(fine.header().footprints, plain.header().footprints);
  EXPECT_EQ(fine.LoadFrame(0), plain.LoadFrame(0));
  EXPECT_EQ(fine.frames()[0], plain.frames()[0]);
  EXPECT_GT(stored.frames()[0].visits, plain.frames()[0].visits);  // the empty cells crossed
}

// grid:N:crossings picks the grid that the rays' steps cross least: the steps counted here from
// the fine capture as Open shows it (empty cells dropped), per axis |d| of the fine
// coordinates, and every grid of 27 and of 8 cells within 12x12x12 costed by design §1's sum.
TEST_F(RegroupCaptureTest, GridByCrossingsIsTheGridTheRaysCrossLeast) {
  const TraceReader fine = TraceReader::Open(Path("fine.rct"));
  std::array<double, 3> steps{};
  for (std::size_t f = 0; f < fine.frames().size(); ++f) {
    const RayBatch b = fine.LoadFrame(f);
    for (std::size_t r = 0; r < b.size(); ++r) {
      for (std::size_t v = b.visit_begin(r) + 1; v < b.visit_end(r); ++v) {
        const std::uint32_t c = b.cells()[v].value(), p = b.cells()[v - 1].value();
        steps[0] += std::abs(int(c % 12) - int(p % 12));
        steps[1] += std::abs(int(c / 12 % 12) - int(p / 12 % 12));
        steps[2] += std::abs(int(c / 144) - int(p / 144));
      }
    }
  }
  ASSERT_GT(steps[0] + steps[1] + steps[2], 0.0);
  for (const std::uint32_t n : {27u, 8u}) {
    std::string want;
    double least = 0;
    for (std::uint32_t x = 1; x <= 12; ++x) {
      for (std::uint32_t y = 1; y <= 12; ++y) {
        if (n % (x * y) != 0 || n / (x * y) > 12) continue;
        const std::uint32_t z = n / (x * y);
        const double cost = (steps[0] * (x - 1) + steps[1] * (y - 1) + steps[2] * (z - 1)) / 11;
        if (want.empty() || cost < least) {
          least = cost;
          want = "grid:" + std::to_string(x) + "x" + std::to_string(y) + "x" + std::to_string(z);
        }
      }
    }
    const std::string spec = "grid:" + std::to_string(n) + ":crossings";
    EXPECT_EQ(TraceReader::Open(Path("fine.rct"), spec).header().subdivision.boxes,
              TraceReader::Open(Path("fine.rct"), want).header().subdivision.boxes)
        << spec << " should be " << want;
  }
}

// `trace regroup` writes what Open shows: the regrouped trace reads back equal, with its
// subdivision in the header.
TEST_F(RegroupCaptureTest, TraceRegroupWritesTheRegroupedTrace) {
  const std::string out = Path("kd.rct");
  const RegroupSummary s = RegroupTrace(Path("fine.rct"), "kd:27:footprint", out);
  EXPECT_EQ(s.cells, 27u);
  const TraceReader view = TraceReader::Open(Path("fine.rct"), "kd:27:footprint");
  const TraceReader written = TraceReader::Open(out);
  EXPECT_EQ(written.header().subdivision.spec, "kd:27:footprint");
  EXPECT_EQ(written.header().subdivision.boxes.size(), 27u);
  EXPECT_EQ(written.header().footprints, view.header().footprints);
  EXPECT_EQ(written.LoadFrame(0), view.LoadFrame(0));
  EXPECT_THROW(RegroupTrace(Path("plain12.rct"), "3x3x3", Path("x.rct")), InputError);
  EXPECT_FALSE(std::filesystem::exists(Path("x.rct")));
  EXPECT_THROW(RegroupTrace(Path("fine.rct"), "5x5x5", Path("x.rct")), InputError);
  EXPECT_FALSE(std::filesystem::exists(Path("x.rct")));
}

// A board of coarser cells (level.NAME.cells; docs/design.md §2 "Levels of coarser cells")
// over the 6x6x6 view of the fine capture: its 3x3x3 cells hold the 6x6x6 cells by their
// coordinates, with the footprints of the capture recorded on 3x3x3; a roomy board loads each
// used one over PCI once; a board SPEC equal to the view's cells replays as "same".
TEST_F(RegroupCaptureTest, ABoardOfCoarserCellsReadsThemFromTheCapture) {
  const TraceReader fine = TraceReader::Open(Path("fine.rct"), "6x6x6");
  ReplayConfig c = DefaultConfig();
  ApplyOverride(c, "level.board.cells", "3x3x3");
  const MemoryUnits units = LevelUnitsOf(c, fine);
  ASSERT_EQ(units.size(), 2u);
  EXPECT_TRUE(units[0].identity());
  EXPECT_EQ(units[1].bytes, TraceReader::Open(Path("direct3.rct")).header().footprints);
  const auto coarse = [](std::uint32_t v) {
    const std::uint32_t x = v % 6, y = v / 6 % 6, z = v / 36;
    return CellId(x / 2 + 3 * (y / 2 + 3 * (z / 2)));
  };
  int nonempty = 0;
  for (std::uint32_t v = 0; v < 216; ++v) {
    if (fine.header().footprints[v] == 0) continue;
    ++nonempty;
    EXPECT_EQ(units[1].unit_of_cell[v], coarse(v)) << "cell " << v;
  }
  EXPECT_GT(nonempty, 100);

  // Each used board cell crosses PCI once (the board holds the volume); the cache fetches
  // cells of 6x6x6.
  std::set<std::uint32_t> used;
  fine.ForEachBatch(0, [&](const RayBatch& b) {
    for (std::size_t v = 0; v < b.visit_count(); ++v)
      used.insert(coarse(b.cells()[v].value()).value());
  });
  const TraceReplay r = ReplayTrace(fine, {0}, c);
  EXPECT_EQ(r.total.levels[1].fetches, used.size());
  std::uint64_t bytes = 0;
  for (const std::uint32_t u : used) bytes += units[1].bytes[u];
  EXPECT_EQ(r.total.levels[1].bytes, bytes);

  // The view's own cells as a SPEC: the replay of "same", every figure.
  for (const char* scheduler : {"maxwork", "celltree-2level"}) {
    ReplayConfig same = DefaultConfig(), own = DefaultConfig();
    for (ReplayConfig* x : {&same, &own}) {
      ApplyOverride(*x, "scheduler", scheduler);
      ApplyOverride(*x, "processors.count", "2");
      ApplyOverride(*x, "level.board.capacity", "600KiB");
    }
    ApplyOverride(own, "level.board.cells", "6x6x6");
    const TraceReplay a = ReplayTrace(fine, {0}, same), b = ReplayTrace(fine, {0}, own);
    EXPECT_EQ(a.total.time, b.total.time);
    EXPECT_EQ(a.total.time_bound, b.total.time_bound);
    ASSERT_EQ(a.total.levels.size(), b.total.levels.size());
    for (std::size_t i = 0; i < a.total.levels.size(); ++i) {
      EXPECT_EQ(a.total.levels[i].fetches, b.total.levels[i].fetches);
      EXPECT_EQ(a.total.levels[i].bytes, b.total.levels[i].bytes);
    }
  }
}

TEST_F(RegroupCaptureTest, ABoardOfCoarserCellsThatCannotBeMadeIsRefused) {
  ReplayConfig c = DefaultConfig();
  ApplyOverride(c, "level.board.cells", "3x3x3");
  const auto error = [&](const TraceReader& reader) {
    try {
      LevelUnitsOf(c, reader);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(TraceReader::Open(Path("fine.rct"), "4x4x4"))
                .find("level.board.cells: '3x3x3' does not hold whole cells of the replay (4x4x4)"),
            std::string::npos);
  EXPECT_NE(error(TraceReader::Open(Path("direct6.rct")))
                .find("level.board.cells: '3x3x3' needs a regroupable capture"),
            std::string::npos);
  EXPECT_NE(error(TraceReader::Open(Path("fine.rct"), "dynamic:8")).find("dynamic subdivision"),
            std::string::npos);
  ApplyOverride(c, "level.board.cells", "5x5x5");  // 5 does not divide 12
  EXPECT_EQ(error(TraceReader::Open(Path("fine.rct"), "6x6x6")),
            "level.board.cells: cell subdivision '5x5x5': its 5 cells along x do not divide the "
            "fine grid's 12 (a cell boundary must be a fine-cell boundary)");
  // A third level must hold unions of the board's cells.
  c.levels.push_back(c.levels[1]);
  c.levels[2].name = "host_cache";
  c.levels[1].cells = "2x2x2";
  c.levels[2].cells = "3x3x3";
  EXPECT_NE(error(TraceReader::Open(Path("fine.rct"), "6x6x6"))
                .find("a level's cells must be unions of the cells of the level above it"),
            std::string::npos);
  c.levels[2].cells = "";  // the replay's cells below a board of coarser ones
  EXPECT_NE(error(TraceReader::Open(Path("fine.rct"), "6x6x6"))
                .find("level.host_cache.cells: 'same' splits cell"),
            std::string::npos);
  c.levels[1].cells = "6x6x6";
  c.levels[2].cells = "3x3x3";
  EXPECT_EQ(error(TraceReader::Open(Path("fine.rct"), "6x6x6")), "no error");
}

// What a level of coarser cells is made from, as trace facts (TraceReader::SubdivideFineGrid):
// the 3x3x3 subdivision of the 12x12x12 fine grid beside the 6x6x6 view holds each fine cell
// by its coordinates, with the footprints of the capture recorded on 3x3x3, and the view's map
// puts each fine cell in its 6x6x6 cell (none for an empty one); kd:8:work, weighed by every
// frame's samples, is the subdivision --cells kd:8:work shows.
TEST_F(RegroupCaptureTest, TheFineGridsSubdivisionHasTheDirectCapturesFootprints) {
  const TraceReader fine = TraceReader::Open(Path("fine.rct"), "6x6x6");
  const FineSubdivision s = fine.SubdivideFineGrid(ParseSubdivisionSpec("3x3x3", "test"));
  EXPECT_EQ(s.footprints, TraceReader::Open(Path("direct3.rct")).header().footprints);
  ASSERT_EQ(s.subdivision.coarse_of_fine.size(), 1728u);
  ASSERT_EQ(s.view_of_fine.size(), 1728u);
  int empty = 0;
  for (std::uint32_t f = 0; f < 1728; ++f) {
    const std::uint32_t x = f % 12, y = f / 12 % 12, z = f / 144;
    EXPECT_EQ(s.subdivision.coarse_of_fine[f], CellId(x / 4 + 3 * (y / 4 + 3 * (z / 4)))) << f;
    const CellId six(x / 2 + 6 * (y / 2 + 6 * (z / 2)));
    const bool is_empty = fine.header().footprints[six.value()] == 0;
    empty += is_empty;
    EXPECT_EQ(s.view_of_fine[f], is_empty ? kNoCell : six) << f;
  }
  EXPECT_GT(empty, 0);

  const TraceReader kd = TraceReader::Open(Path("fine.rct"), "kd:8:work");
  const FineSubdivision k = fine.SubdivideFineGrid(ParseSubdivisionSpec("kd:8:work", "test"));
  EXPECT_EQ(k.subdivision.boxes, kd.header().subdivision.boxes);
  EXPECT_EQ(k.footprints, kd.header().footprints);
}

}  // namespace
}  // namespace raycell
