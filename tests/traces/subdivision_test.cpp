#include "traces/subdivision.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/random.h"
#include "traces/cell_dims.h"

namespace raycell {
namespace {

using Grid = std::array<std::uint32_t, 3>;

// A fine grid over a volume of leaf nodes that do not line up with the fine cells: leaves are
// blocks 1.5 fine cells wide, so most straddle two fine cells and a union of fine cells must
// count each once. Leaves are allocated densely near one corner and sparsely elsewhere, so
// footprints are uneven, as in a real volume. Samples: a fixed pseudo-random amount per cell.
struct LeafModel {
  Grid grid;
  std::uint64_t leaf_bytes = 512;

  static constexpr int kPerTwo = 3;  // a leaf is 3/2 fine cells wide
  std::uint32_t blocks(int a) const { return (2 * grid[a] + kPerTwo - 1) / kPerTwo; }
  bool Allocated(std::uint32_t bx, std::uint32_t by, std::uint32_t bz) const {
    SplitMix64 h((std::uint64_t{bx} << 40) ^ (std::uint64_t{by} << 20) ^ bz);
    const double d = double(bx + by + bz) / double(blocks(0) + blocks(1) + blocks(2));
    return double(h.Next() % 1000) / 1000.0 < 0.95 - 0.9 * d;
  }
  // The leaves a fine cell [x, x+1) overlaps: blocks i with 1.5 i < x + 1 and 1.5 (i + 1) > x.
  std::vector<std::uint64_t> Leaves(std::uint32_t f) const {
    const std::uint32_t x = f % grid[0], y = f / grid[0] % grid[1], z = f / (grid[0] * grid[1]);
    const std::array<std::uint32_t, 3> p{x, y, z};
    std::array<std::uint32_t, 3> lo{}, hi{};
    for (int a = 0; a < 3; ++a) {
      lo[a] = 2 * p[a] / kPerTwo;
      hi[a] = std::min(blocks(a), (2 * (p[a] + 1) + kPerTwo - 1) / kPerTwo);
    }
    std::vector<std::uint64_t> out;
    for (std::uint32_t bz = lo[2]; bz < hi[2]; ++bz) {
      for (std::uint32_t by = lo[1]; by < hi[1]; ++by) {
        for (std::uint32_t bx = lo[0]; bx < hi[0]; ++bx) {
          if (Allocated(bx, by, bz)) out.push_back(bx + blocks(0) * (by + blocks(1) * bz));
        }
      }
    }
    return out;
  }
  std::uint64_t Union(const std::vector<std::uint32_t>& fine) const {
    std::set<std::uint64_t> leaves;
    for (std::uint32_t f : fine) {
      for (std::uint64_t l : Leaves(f)) leaves.insert(l);
    }
    return leaves.size() * leaf_bytes;
  }
  FineCells Cells(bool with_samples = true, std::uint64_t seed = 7) const {
    FineCells c;
    c.grid = grid;
    c.union_footprint = [this](const std::vector<std::uint32_t>& f) { return Union(f); };
    if (with_samples) {
      SplitMix64 r(seed);
      for (std::uint32_t i = 0; i < c.count(); ++i) c.samples.push_back(r.Next() % 1000);
      c.crossings = {r.Next() % 1000, r.Next() % 1000, r.Next() % 1000};
      c.has_crossings = true;
    }
    return c;
  }
};

// The InputError message of subdividing `fine` by `spec`, or "no error".
std::string SubdivideError(const char* spec, const FineCells& fine) {
  try {
    Subdivide(ParseSubdivisionSpec(spec, "t"), fine);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// The fine cells of a box, computed here from its corners.
std::vector<std::uint32_t> Inside(const FineBox& b, const Grid& g) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t f = 0; f < g[0] * g[1] * g[2]; ++f) {
    const std::uint32_t x = f % g[0], y = f / g[0] % g[1], z = f / (g[0] * g[1]);
    if (x >= b.lo[0] && x < b.hi[0] && y >= b.lo[1] && y < b.hi[1] && z >= b.lo[2] && z < b.hi[2]) {
      out.push_back(f);
    }
  }
  return out;
}

// Every fine cell lies in exactly one box, every box holds at least one, and coarse_of_fine
// names the box that holds it.
void ExpectCoversOnce(const Subdivision& s, const Grid& g, const std::string& spec) {
  const std::uint32_t n = g[0] * g[1] * g[2];
  std::vector<int> count(n, 0);
  ASSERT_EQ(s.coarse_of_fine.size(), n) << spec;
  for (std::uint32_t c = 0; c < s.cells(); ++c) {
    const std::vector<std::uint32_t> in = Inside(s.boxes[c], g);
    EXPECT_FALSE(in.empty()) << spec << " cell " << c;
    for (std::uint32_t f : in) {
      ++count[f];
      EXPECT_EQ(s.coarse_of_fine[f], CellId(c)) << spec << " fine cell " << f;
    }
  }
  for (std::uint32_t f = 0; f < n; ++f) EXPECT_EQ(count[f], 1) << spec << " fine cell " << f;
}

TEST(SubdivisionSpec, ParsesEveryKindAndPrintsItBack) {
  for (const char* text :
       {"3x3x3", "12x1x4", "grid:1x3x9", "grid:27:crossings", "kd:27:footprint", "kd:8:work",
        "kd:9:sqrt", "kd:budget:256KiB", "octree:1MB", "octree:1500B", "dynamic:27", "auto:27"}) {
    const SubdivisionSpec s = ParseSubdivisionSpec(text, "--cells");
    EXPECT_EQ(s.ToString(), text);
    EXPECT_EQ(ParseSubdivisionSpec(s.ToString(), "--cells"), s);
  }
  const SubdivisionSpec kd = ParseSubdivisionSpec(" kd:27:footprint ", "--cells");
  EXPECT_EQ(kd.kind, SubdivisionSpec::Kind::kKdFootprint);
  EXPECT_EQ(kd.cells, 27u);
  EXPECT_EQ(ParseSubdivisionSpec("octree:256KiB", "x").budget, 256u * 1024);
  EXPECT_EQ(ParseSubdivisionSpec("4x5x6", "x").grid, (Grid{4, 5, 6}));
  const SubdivisionSpec grid = ParseSubdivisionSpec("grid:1x3x9", "x");
  EXPECT_EQ(grid.kind, SubdivisionSpec::Kind::kGrid);
  EXPECT_EQ(grid.grid, (Grid{1, 3, 9}));
  EXPECT_FALSE(grid == ParseSubdivisionSpec("1x3x9", "x"));
}

TEST(ParseCellDims, ParsesThreePositiveCountsAndNamesTheBadText) {
  EXPECT_EQ(ParseCellDims("3x3x3"), (std::array<std::uint32_t, 3>{3, 3, 3}));
  EXPECT_EQ(ParseCellDims("2X4x1"), (std::array<std::uint32_t, 3>{2, 4, 1}));
  EXPECT_EQ(ParseCellDims("65536x65535x1"), (std::array<std::uint32_t, 3>{65536, 65535, 1}));
  for (const char* bad : {"0x2x2", "2x2", "axbxc", "2x2x2x2", "", "x2x2", "2x2x", "-1x2x2",
                          "2x 2x2", "2.5x2x2", "99999999999x1x1", "65536x65536x2", "2x0x2"}) {
    try {
      ParseCellDims(bad);
      ADD_FAILURE() << "accepted \"" << bad << "\"";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--cells \"" + std::string(bad) + "\""),
                std::string::npos)
          << e.what();
    }
  }
}

// The limit is the caller's: a subdivision SPEC allows kMaxSubdivisionCells, record's --cells
// anything that fits 32 bits (the trace's own limit is checked where the grid is made).
TEST(ParseCellDims, TheCallersLimitAndWhatItSays) {
  EXPECT_EQ(ParseCellDims("4096x4096x1", "--cells", kMaxSubdivisionCells),
            (std::array<std::uint32_t, 3>{4096, 4096, 1}));
  for (const char* bad : {"4096x4096x2", "1x1x16777217", "99999x99999x99999"}) {
    try {
      ParseCellDims(bad, "SPEC", kMaxSubdivisionCells);
      ADD_FAILURE() << "accepted \"" << bad << "\"";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("more than 16777216"), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("SPEC \"" + std::string(bad) + "\"", 0), 0u)
          << e.what();
    }
  }
  try {
    ParseCellDims("0x1x1");
    ADD_FAILURE() << "accepted 0x1x1";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
  }
}

TEST(SubdivisionSpec, BadSpecsNameWhatIsWrong) {
  const auto message = [](const char* text) {
    try {
      ParseSubdivisionSpec(text, "--cells");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("3x3").find("is not a cell subdivision"), std::string::npos);
  EXPECT_NE(message("0x3x3").find("out of range"), std::string::npos);
  EXPECT_NE(message("kd:0:work").find("out of range"), std::string::npos);
  EXPECT_NE(message("kd:27:voxels").find("'footprint', 'work' or 'sqrt', not 'voxels'"),
            std::string::npos);
  EXPECT_NE(message("kd:x:work").find("not an integer"), std::string::npos);
  EXPECT_NE(message("octree:0B").find("greater than zero"), std::string::npos);
  EXPECT_NE(message("octree:12").find("missing unit"), std::string::npos);
  EXPECT_NE(message("octree:-1MB").find("negative"), std::string::npos);
  EXPECT_NE(message("sphere:3").find("expected NXxNYxNZ"), std::string::npos);
  EXPECT_NE(message("dynamic:27:work").find("'sqrt' (dynamic:N:sqrt), not 'work'"),
            std::string::npos);
  EXPECT_NE(message("dynamic:27:sqrt:x").find("is not a cell subdivision"), std::string::npos);
  EXPECT_NE(message("4096x4096x4096").find("more than"), std::string::npos);
  EXPECT_NE(message("").find("is not a cell subdivision"), std::string::npos);
  EXPECT_NE(message("grid:3x3").find("is not a cell subdivision"), std::string::npos);
  EXPECT_NE(message("grid:0x3x3").find("out of range"), std::string::npos);
  EXPECT_NE(message("grid:3x3x3:x").find("'crossings' (grid:N:crossings), not 'x'"),
            std::string::npos);
  EXPECT_NE(message("grid:0:crossings").find("out of range"), std::string::npos);
  EXPECT_EQ(message("kd:27:work").find("--cells"), std::string::npos);  // valid: no error
}

TEST(Subdivision, EverySubdivisionCoversEachFineCellExactlyOnce) {
  for (const Grid g : {Grid{12, 12, 12}, Grid{5, 7, 3}, Grid{1, 1, 1}, Grid{8, 1, 2}}) {
    const LeafModel m{g};
    const std::uint64_t whole = m.Union(Inside(FineBox{{0, 0, 0}, g}, g));
    std::vector<std::string> specs = {"1x1x1", "kd:1:footprint", "dynamic:1", "octree:1B",
                                      "kd:budget:1B"};
    if (g == Grid{12, 12, 12})
      specs.insert(specs.end(), {"3x3x3", "4x4x4", "6x6x6", "2x2x2", "12x12x12", "4x2x6",
                                 "grid:1x3x9", "grid:5x7x11", "grid:12x12x12"});
    if (g == Grid{5, 7, 3}) specs.insert(specs.end(), {"grid:2x3x2", "grid:5x7x3", "grid:4x1x2"});
    const std::uint32_t n = g[0] * g[1] * g[2];
    for (std::uint32_t k : {2u, 7u, 27u, n}) {
      if (k > n) continue;
      for (const char* kind : {"kd:%u:footprint", "kd:%u:work", "kd:%u:sqrt", "dynamic:%u",
                               "dynamic:%u:sqrt", "grid:%u:crossings", "auto:%u"}) {
        char buf[64];
        std::snprintf(buf, sizeof buf, kind, k);
        specs.push_back(buf);
      }
    }
    for (const std::uint64_t budget : {whole / 3 + 1, whole / 20 + 1}) {
      specs.push_back("octree:" + std::to_string(budget) + "B");
      specs.push_back("kd:budget:" + std::to_string(budget) + "B");
    }
    for (const std::string& text : specs) {
      const SubdivisionSpec spec = ParseSubdivisionSpec(text, "test");
      for (const bool samples : {true, false}) {
        if (!samples && (spec.kind == SubdivisionSpec::Kind::kKdWork ||
                         spec.kind == SubdivisionSpec::Kind::kKdSqrt ||
                         spec.kind == SubdivisionSpec::Kind::kGridCrossings)) {
          EXPECT_THROW(Subdivide(spec, m.Cells(false)), InputError) << text;  // needs weights
          continue;
        }
        if (spec.kind == SubdivisionSpec::Kind::kGridCrossings ||
            spec.kind == SubdivisionSpec::Kind::kAuto) {
          // A grid of k cells within g exists only for some k (7 in 5x7x3: 1x7x1).
          bool fits = false;
          for (std::uint32_t x = 1; x <= g[0]; ++x)
            for (std::uint32_t y = 1; y <= g[1]; ++y)
              for (std::uint32_t z = 1; z <= g[2]; ++z) fits = fits || x * y * z == spec.cells;
          if (!fits) {
            EXPECT_THROW(Subdivide(spec, m.Cells(samples)), InputError) << text;
            continue;
          }
        }
        const Subdivision s = Subdivide(spec, m.Cells(samples));
        ExpectCoversOnce(s, g, text);
        if (spec.cells > 0) {
          EXPECT_EQ(s.cells(), spec.cells) << text;
        }
      }
    }
  }
}

TEST(Subdivision, UniformNumbersItsCellsAsADirectGrid) {
  const Grid g{12, 12, 12};
  const Subdivision s = Subdivide(ParseSubdivisionSpec("3x2x4", "test"), LeafModel{g}.Cells());
  ASSERT_EQ(s.cells(), 24u);
  for (std::uint32_t f = 0; f < 12 * 12 * 12; ++f) {
    const std::uint32_t x = f % 12, y = f / 12 % 12, z = f / 144;
    EXPECT_EQ(s.coarse_of_fine[f], CellId(x / 4 + 3 * (y / 6 + 2 * (z / 3)))) << f;
  }
}

TEST(Subdivision, AUniformGridMustAlignWithTheFineOne) {
  const LeafModel m{Grid{12, 12, 12}};
  try {
    Subdivide(ParseSubdivisionSpec("5x3x3", "test"), m.Cells());
    FAIL() << "5 does not divide 12";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("5 cells along x do not divide the fine grid's 12"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(Subdivide(ParseSubdivisionSpec("kd:9:work", "t"), LeafModel{Grid{2, 2, 2}}.Cells()),
               InputError);  // more cells than fine cells
  EXPECT_THROW(
      Subdivide(ParseSubdivisionSpec("kd:4:work", "t"), LeafModel{Grid{2, 2, 2}}.Cells(false)),
      InputError);  // no samples to balance
}

TEST(Subdivision, GridCutsEachAxisAtTheNearestFineBoundaries) {
  const Grid g{12, 12, 12};
  const LeafModel m{g};
  // 9 cells along z of 12 fine: i * 12 / 9 = 0, 1.33, 2.67, 4, 5.33, 6.67, 8, 9.33, 10.67, 12,
  // rounded 0, 1, 3, 4, 5, 7, 8, 9, 11, 12; 3 along y divide evenly: 0, 4, 8, 12.
  const Subdivision s = Subdivide(ParseSubdivisionSpec("grid:1x3x9", "t"), m.Cells());
  ASSERT_EQ(s.cells(), 27u);
  const std::uint32_t z_at[] = {0, 1, 3, 4, 5, 7, 8, 9, 11, 12};
  for (std::uint32_t z = 0; z < 9; ++z) {
    for (std::uint32_t y = 0; y < 3; ++y) {
      const FineBox want{{0, 4 * y, z_at[z]}, {12, 4 * y + 4, z_at[z + 1]}};
      EXPECT_EQ(s.boxes[y + 3 * z], want) << "cell " << y + 3 * z;
    }
  }
  // Halves round up: 2 cells of 5 fine cut at 2.5 -> 3; 4 cells of 6 at 1.5, 3, 4.5 -> 2, 3, 5.
  const Subdivision h =
      Subdivide(ParseSubdivisionSpec("grid:2x4x1", "t"), LeafModel{Grid{5, 6, 1}}.Cells());
  ASSERT_EQ(h.cells(), 8u);
  EXPECT_EQ(h.boxes[0], (FineBox{{0, 0, 0}, {3, 2, 1}}));
  EXPECT_EQ(h.boxes[1], (FineBox{{3, 0, 0}, {5, 2, 1}}));
  EXPECT_EQ(h.boxes[3], (FineBox{{3, 2, 0}, {5, 3, 1}}));
  EXPECT_EQ(h.boxes[5], (FineBox{{3, 3, 0}, {5, 5, 1}}));
  EXPECT_EQ(h.boxes[7], (FineBox{{3, 5, 0}, {5, 6, 1}}));
  // Counts that divide give the uniform grid's boxes.
  EXPECT_EQ(Subdivide(ParseSubdivisionSpec("grid:3x2x4", "t"), m.Cells()).boxes,
            Subdivide(ParseSubdivisionSpec("3x2x4", "t"), m.Cells()).boxes);
  const std::string more = SubdivideError("grid:13x1x1", m.Cells());
  EXPECT_NE(more.find("13 cells along x are more than the fine grid's 12"), std::string::npos)
      << more;
}

// grid:N:crossings on 12x12x12 (11 fine boundaries inside each axis): the cost of NXxNYxNZ is
// (crossings x (NX - 1) + crossings y (NY - 1) + crossings z (NZ - 1)) / 11. With crossings
// 1000, 490, 110 (mj_smoke's frame 0 in thousands): 1x3x9 (490 x 2 + 110 x 8) / 11 = 169.1,
// 3x3x3 290.9, 3x1x9 261.8, 1x9x3 376.4, 3x9x1 538.2, 9x1x3 747.3, 9x3x1 816.4 (27 cells
// along one axis do not fit 12): 1x3x9. With 250, 880, 580 (the built-in scene's): 9x1x3
// (2000 + 1160) / 11 = 287.3 against 3x3x3's 310.9, 9x3x1 341.8, 3x1x9 467.3.
TEST(Subdivision, GridByCrossingsCutsLeastAcrossTheAxesRaysCrossMost) {
  const Grid g{12, 12, 12};
  const LeafModel m{g};
  const auto grid = [&](std::array<std::uint64_t, 3> crossings, const char* spec) {
    FineCells f = m.Cells();
    f.crossings = crossings;
    return Subdivide(ParseSubdivisionSpec(spec, "t"), f).boxes;
  };
  const auto boxes = [&](const char* spec) {
    return Subdivide(ParseSubdivisionSpec(spec, "t"), m.Cells()).boxes;
  };
  EXPECT_EQ(grid({1000, 490, 110}, "grid:27:crossings"), boxes("grid:1x3x9"));
  EXPECT_EQ(grid({250, 880, 580}, "grid:27:crossings"), boxes("grid:9x1x3"));
  EXPECT_EQ(grid({1, 1, 1}, "grid:27:crossings"), boxes("3x3x3"));  // even: the cube
  // Ties go to the lowest NX, then NY: with no crossings every grid costs 0.
  EXPECT_EQ(grid({0, 0, 0}, "grid:27:crossings"), boxes("grid:1x3x9"));
  EXPECT_EQ(grid({0, 0, 5}, "grid:12:crossings"), boxes("grid:1x12x1"));
  // 8 cells, crossings only along z: no cut across z.
  EXPECT_EQ(grid({0, 0, 5}, "grid:8:crossings"), boxes("grid:1x8x1"));
  // 1x2x4 costs (2 + 3) / 11, the least: 2x2x2 and 2x1x4 (3 + 3) / 11, 1x1x8 7 / 11.
  EXPECT_EQ(grid({3, 2, 1}, "grid:8:crossings"), boxes("grid:1x2x4"));
  const std::string none = SubdivideError("grid:13:crossings", m.Cells());  // 13 is prime
  EXPECT_NE(none.find("no grid of 13 cells fits the fine grid's 12x12x12"), std::string::npos)
      << none;
}

TEST(Subdivision, KdBudgetLeavesNoCellOverItsBudgetThatASplitCouldAvoid) {
  for (const Grid g : {Grid{12, 12, 12}, Grid{5, 7, 3}}) {
    const LeafModel m{g};
    const std::uint64_t whole = m.Union(Inside(FineBox{{0, 0, 0}, g}, g));
    std::uint64_t largest_fine = 0;
    for (std::uint32_t f = 0; f < g[0] * g[1] * g[2]; ++f) {
      largest_fine = std::max(largest_fine, m.Union({f}));
    }
    // Budgets from "everything fits" to below the largest fine cell (which no split helps).
    for (const std::uint64_t budget :
         {whole, whole / 2, whole / 7, whole / 27, largest_fine, largest_fine / 2}) {
      const std::string text = "kd:budget:" + std::to_string(budget) + "B";
      const Subdivision s = Subdivide(ParseSubdivisionSpec(text, "test"), m.Cells());
      std::size_t over = 0;
      for (const FineBox& b : s.boxes) {
        const std::uint64_t fp = m.Union(Inside(b, g));
        if (fp > budget) {
          ++over;
          EXPECT_EQ(b.volume(), 1u)
              << text << ": a cell of " << b.volume() << " fine cells is over its budget: " << fp;
        }
      }
      if (budget >= largest_fine) {
        EXPECT_EQ(over, 0u) << text;
      }
      if (budget == whole) {
        EXPECT_EQ(s.cells(), 1u) << text;  // nothing to split
      }
    }
  }
}

TEST(Subdivision, KdFootprintBalancesBetterThanTheUniformGrid) {
  // The point of kd:N:footprint: on an uneven volume its largest cell is smaller than the
  // uniform grid's at the same count.
  const Grid g{12, 12, 12};
  const LeafModel m{g};
  const auto largest = [&](const Subdivision& s) {
    std::uint64_t l = 0;
    for (const FineBox& b : s.boxes) l = std::max(l, m.Union(Inside(b, g)));
    return l;
  };
  const std::uint64_t uniform = largest(Subdivide(ParseSubdivisionSpec("3x3x3", "t"), m.Cells()));
  const std::uint64_t kd =
      largest(Subdivide(ParseSubdivisionSpec("kd:27:footprint", "t"), m.Cells()));
  EXPECT_LT(kd, uniform);
}

// kd:N:sqrt balances footprint / sqrt(samples + 1). Four fine cells in a row, 100 bytes each
// (no leaf shared), samples 0, 0, 3 and 96. The first split, by the larger half's weight:
//   at 1: [0,1) 100 / 1 = 100, [1,4) 300 / 10 = 30         -> 100
//   at 2: [0,2) 200 / 1 = 200, [2,4) 200 / 10 = 20         -> 200
//   at 3: [0,3) 300 / 2 = 150, [3,4) 100 / sqrt(97) = 10.2 -> 150
// so at 1, where kd:2:footprint splits at 2 (200 against 200) and kd:2:work at 3 (96 against
// 99 elsewhere). The third cell splits [1,4), the only box of more than one fine cell: at 2
// ([1,2) 100, [2,4) 20) and at 3 ([1,3) 200 / 2 = 100, [3,4) 10.2) tie at 100: the lower.
TEST(Subdivision, KdSqrtBalancesFootprintOverTheSquareRootOfWork) {
  FineCells fine;
  fine.grid = {4, 1, 1};
  fine.union_footprint = [](const std::vector<std::uint32_t>& f) { return 100 * f.size(); };
  fine.samples = {0, 0, 3, 96};
  const auto boxes = [&](const char* spec) {
    std::vector<std::uint32_t> upper;  // each box's upper x
    for (const FineBox& b : Subdivide(ParseSubdivisionSpec(spec, "t"), fine).boxes) {
      upper.push_back(b.hi[0]);
    }
    return upper;
  };
  EXPECT_EQ(boxes("kd:2:sqrt"), (std::vector<std::uint32_t>{1, 4}));
  EXPECT_EQ(boxes("kd:2:footprint"), (std::vector<std::uint32_t>{2, 4}));
  EXPECT_EQ(boxes("kd:2:work"), (std::vector<std::uint32_t>{3, 4}));
  EXPECT_EQ(boxes("kd:3:sqrt"), (std::vector<std::uint32_t>{1, 2, 4}));
}

TEST(Subdivision, DynamicIsDeterministicAndFollowsTheSamples) {
  const Grid g{12, 12, 12};
  const LeafModel m{g};
  const SubdivisionSpec spec = ParseSubdivisionSpec("dynamic:27", "t");
  const Subdivision a = Subdivide(spec, m.Cells(true, 11));
  const Subdivision b = Subdivide(spec, m.Cells(true, 11));
  EXPECT_EQ(a.boxes, b.boxes);
  EXPECT_EQ(a.coarse_of_fine, b.coarse_of_fine);
  // Frame 0 (no samples yet) splits by footprint, as kd:27:footprint does; later frames by
  // the previous frame's samples, as kd:27:work does.
  EXPECT_EQ(Subdivide(spec, m.Cells(false)).boxes,
            Subdivide(ParseSubdivisionSpec("kd:27:footprint", "t"), m.Cells(false)).boxes);
  EXPECT_EQ(a.boxes, Subdivide(ParseSubdivisionSpec("kd:27:work", "t"), m.Cells(true, 11)).boxes);
  EXPECT_NE(a.boxes, Subdivide(spec, m.Cells(true, 12)).boxes);  // other samples, other cells
}

// dynamic:N:sqrt is kd:N:sqrt on the previous frame's samples, and kd:N:footprint in frame 0.
TEST(Subdivision, DynamicSqrtBalancesAsKdSqrt) {
  const Grid g{12, 12, 12};
  const LeafModel m{g};
  const SubdivisionSpec spec = ParseSubdivisionSpec("dynamic:27:sqrt", "t");
  EXPECT_TRUE(spec.sqrt);
  EXPECT_EQ(Subdivide(spec, m.Cells(false)).boxes,
            Subdivide(ParseSubdivisionSpec("kd:27:footprint", "t"), m.Cells(false)).boxes);
  const Subdivision a = Subdivide(spec, m.Cells(true, 11));
  EXPECT_EQ(a.boxes, Subdivide(ParseSubdivisionSpec("kd:27:sqrt", "t"), m.Cells(true, 11)).boxes);
  EXPECT_NE(a.boxes, Subdivide(ParseSubdivisionSpec("dynamic:27", "t"), m.Cells(true, 11)).boxes);
}

}  // namespace
}  // namespace raycell
