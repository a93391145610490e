// CellGrid and CellDDA (record/cell_grid.h): hand-written adversarial rays with their
// exact cell lists, and seeded random rays checked for the traversal's properties and
// against a brute-force reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "base/check.h"
#include "record/cell_grid.h"
#include "tests/cell_list.h"

namespace raycell {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using Cells = testing::CellList;

double Get(const Vec3d& v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }
void Set(Vec3d& v, int a, double x) { (a == 0 ? v.x : a == 1 ? v.y : v.z) = x; }
Vec3d Add(const Vec3d& a, const Vec3d& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3d Sub(const Vec3d& a, const Vec3d& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3d Mul(const Vec3d& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
Vec3d At(const Vec3d& o, const Vec3d& d, double t) { return Add(o, Mul(d, t)); }

CellGrid UnitGrid(std::uint32_t n = 2) { return CellGrid::Create({0, 0, 0}, {1, 1, 1}, {n, n, n}); }

Cells CellsOf(const std::vector<CellSegment>& segs) {
  Cells c;
  for (const auto& s : segs) c.push_back(s.cell);
  return c;
}

std::vector<CellSegment> Trace(const CellGrid& g, Vec3d o, Vec3d d, double tmin = 0,
                               double tmax = kInf, std::optional<CellId> start = std::nullopt) {
  return CollectSegments(CellDDA(g, o, d, tmin, tmax, start));
}

Cells TraceCells(const CellGrid& g, Vec3d o, Vec3d d, double tmin = 0, double tmax = kInf,
                 std::optional<CellId> start = std::nullopt) {
  return CellsOf(Trace(g, o, d, tmin, tmax, start));
}

std::string Dump(const std::vector<CellSegment>& segs) {
  std::string s;
  for (const auto& x : segs) s += x.ToString() + " ";
  return s;
}

// ------------------------------------------------------------------------------ CellGrid

TEST(CellGridTest, CreateRefusesBadBoundsAndCountsNamingTheAxis) {
  const Vec3d lo{0, 0, 0}, hi{1, 1, 1};
  const double nan = std::nan("");
  EXPECT_THROW(CellGrid::Create(lo, {1, 0, 1}, {2, 2, 2}), InputError);
  EXPECT_THROW(CellGrid::Create(lo, {1, 1, -1}, {2, 2, 2}), InputError);
  EXPECT_THROW(CellGrid::Create({nan, 0, 0}, hi, {2, 2, 2}), InputError);
  EXPECT_THROW(CellGrid::Create(lo, {kInf, 1, 1}, {2, 2, 2}), InputError);
  EXPECT_THROW(CellGrid::Create({-DBL_MAX, 0, 0}, {DBL_MAX, 1, 1}, {2, 2, 2}), InputError);
  EXPECT_THROW(CellGrid::Create(lo, hi, {2, 0, 2}), InputError);
  EXPECT_THROW(CellGrid::Create(lo, hi, {65536, 65536, 2}), InputError);
  // Cells of 1e-9 at 1e6 cannot be told apart in doubles.
  EXPECT_THROW(CellGrid::Create({1e6, 0, 0}, {1e6 + 1e-9, 1, 1}, {1, 1, 1}), InputError);
  try {
    CellGrid::Create(lo, {1, 1, 1}, {2, 0, 2});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("along y"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(
      CellGrid::Create({1e6, 1e6, 1e6}, {1e6 + 1e-3, 1e6 + 1e-3, 1e6 + 1e-3}, {7, 7, 7}));
  EXPECT_NO_THROW(CellGrid::Create(lo, hi, {65536, 65535, 1}));
}

TEST(CellGridTest, AccessorsAgreeOnCountsIndicesCoordinatesAndBounds) {
  const auto g = CellGrid::Create({-1, 0, 2}, {1, 3, 6}, {2, 3, 4});
  EXPECT_EQ(g.cell_count(), 24u);
  EXPECT_EQ(g.dims(), (std::array<std::uint32_t, 3>{2, 3, 4}));
  EXPECT_EQ(g.cell_size()[2], 1.0);
  EXPECT_EQ(g.CellIndex({1, 2, 3}), CellId(1u + 2 * (2 + 3 * 3)));
  EXPECT_EQ(g.CellCoords(CellId(23)), (std::array<std::uint32_t, 3>{1, 2, 3}));
  EXPECT_EQ(g.CellBounds(CellId(0)), (Box3d{{-1, 0, 2}, {0, 1, 3}}));
  EXPECT_EQ(g.CellBounds(CellId(23)), (Box3d{{0, 2, 5}, {1, 3, 6}}));
  EXPECT_EQ(g.ToString(), "CellGrid[(-1, 0, 2) - (1, 3, 6), 2x3x4 cells]");
  EXPECT_EQ(g.CellBounds(CellId(1)).ToString(), "[(0, 0, 2) - (1, 1, 3)]");
}

TEST(CellGridTest, CellOfAndCellBoundsAgree) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const double scale = std::pow(10.0, -6 + 12 * u(rng));
    const Vec3d lo{1e3 * scale * (u(rng) - 0.5), scale * u(rng), -scale};
    const Vec3d hi = Add(lo, {scale * (0.1 + u(rng)), scale, 3 * scale});
    const std::array<std::uint32_t, 3> dims{1 + unsigned(rng() % 7), 1 + unsigned(rng() % 7),
                                            1 + unsigned(rng() % 7)};
    const auto g = CellGrid::Create(lo, hi, dims);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(g.Plane(a, 0), Get(lo, a));
      EXPECT_EQ(g.Plane(a, dims[a]), Get(hi, a));
      for (std::uint32_t k = 0; k < dims[a]; ++k) EXPECT_LT(g.Plane(a, k), g.Plane(a, k + 1));
    }
    for (CellId c : CellRange(g.cell_count())) {
      const Box3d b = g.CellBounds(c);
      EXPECT_EQ(g.CellOf(b.lo), c) << g.ToString() << " cell " << c;
      EXPECT_EQ(g.CellOf(Mul(Add(b.lo, b.hi), 0.5)), c);
    }
    for (int i = 0; i < 50; ++i) {  // random points, some outside (clamped)
      Vec3d p;
      for (int a = 0; a < 3; ++a)
        Set(p, a, Get(lo, a) + (Get(hi, a) - Get(lo, a)) * (1.4 * u(rng) - 0.2));
      const Box3d b = g.CellBounds(g.CellOf(p));
      for (int a = 0; a < 3; ++a) {
        const double c = std::clamp(Get(p, a), Get(lo, a), Get(hi, a));
        EXPECT_LE(Get(b.lo, a), c);
        EXPECT_TRUE(c < Get(b.hi, a) || c == Get(hi, a));
      }
    }
  }
}

TEST(CellGridTest, CellOfClampsBoundaryPoints) {
  const auto g = UnitGrid(2);
  EXPECT_EQ(g.CellOf({1, 1, 1}), CellId(7));
  EXPECT_EQ(g.CellOf({1.5, -3, 0.5}), CellId(1u + 4));
  EXPECT_EQ(g.CellOf({0.5, 0.5, 0.5}), CellId(7));  // interior planes belong to the upper cell
  EXPECT_EQ(g.CellOf({std::nextafter(0.5, 0.0), 0, 0}), CellId(0));
  EXPECT_EQ(g.CellOf({-0.0, 0, 0}), CellId(0));
}

// ------------------------------------------------------- CellDDA: hand-written rays

TEST(CellDDATest, CornerDiagonalSkipsIntermediateCells) {
  const auto g = UnitGrid(2);
  auto segs = Trace(g, {-1, -1, -1}, {1, 1, 1});
  EXPECT_EQ(segs, (std::vector<CellSegment>{{CellId(0), 1, 1.5}, {CellId(7), 1.5, 2}}))
      << Dump(segs);
  EXPECT_EQ(TraceCells(g, {0, 0, 0}, {1, 1, 1}), (Cells{0, 7}));
  EXPECT_EQ(TraceCells(g, {1, 1, 1}, {-3, -3, -3}), (Cells{7, 0}));
  EXPECT_EQ(TraceCells(g, {1, 1, 1}, {3, 3, 3}), Cells{});  // starts on the corner, leaves
  EXPECT_EQ(TraceCells(g, {1, 1, 1}, {3, 3, 3}, -kInf), (Cells{0, 7}));
  EXPECT_EQ(TraceCells(g, {1, 0, 0}, {-1, 1, 1}), (Cells{1, 6}));
  EXPECT_EQ(TraceCells(g, {2, -1, 2}, {-1, 1, -1}), (Cells{5, 2}));
}

TEST(CellDDATest, CornerDiagonalWithInexactParameters) {
  // Crossing parameters of the three axes differ by rounding; they must still be taken
  // together.
  for (double scale : {1e-6, 1.0, 1e6}) {
    for (double offset : {0.0, 1e6, -3e5}) {
      const Vec3d lo = Add(Mul({0.1, 0.2, 0.3}, scale), {offset, offset, offset});
      const Vec3d hi = Add(Mul({0.7, 1.1, 1.9}, scale), {offset, offset, offset});
      if (offset != 0 && scale < 1e-3) continue;  // unresolvable, see CreateValidates
      const Vec3d d = Mul(Sub(hi, lo), 0.37);
      const auto g2 = CellGrid::Create(lo, hi, {2, 2, 2});
      const auto g3 = CellGrid::Create(lo, hi, {3, 3, 3});
      SCOPED_TRACE(g2.ToString());
      EXPECT_EQ(TraceCells(g2, lo, d), (Cells{0, 7}));
      EXPECT_EQ(TraceCells(g2, Sub(lo, d), d), (Cells{0, 7}));
      EXPECT_EQ(TraceCells(g2, hi, Mul(d, -1)), (Cells{7, 0}));
      EXPECT_EQ(TraceCells(g3, lo, d), (Cells{0, 13, 26}));
      EXPECT_EQ(TraceCells(g3, hi, Mul(d, -1)), (Cells{26, 13, 0}));
    }
  }
}

TEST(CellDDATest, AlongCellEdgesAndFaces) {
  const auto g = UnitGrid(2);
  // The edge y = z = 0.5 is owned by the cells above both planes.
  EXPECT_EQ(Trace(g, {-1, 0.5, 0.5}, {1, 0, 0}),
            (std::vector<CellSegment>{{CellId(6), 1, 1.5}, {CellId(7), 1.5, 2}}));
  EXPECT_EQ(TraceCells(g, {2, 0.5, 0.5}, {-1, 0, 0}), (Cells{7, 6}));
  // Edges and faces of the box are inside it (closed box).
  EXPECT_EQ(TraceCells(g, {-1, 0, 0}, {1, 0, 0}), (Cells{0, 1}));
  EXPECT_EQ(TraceCells(g, {-1, 1, 1}, {1, 0, 0}), (Cells{6, 7}));
  EXPECT_EQ(TraceCells(g, {0.25, -1, 1}, {0, 1, 0}), (Cells{4, 6}));
  // In the interior face z = 0.5: the cells above it.
  EXPECT_EQ(TraceCells(g, {-1, 0.25, 0.5}, {1, 0, 0}), (Cells{4, 5}));
  EXPECT_EQ(TraceCells(g, {0, 0, 0.5}, {1, 1, 0}), (Cells{4, 7}));  // through an edge, in a face
  EXPECT_EQ(TraceCells(g, {0.5, 0.5, -1}, {0, 0, 1}), (Cells{3, 7}));
}

TEST(CellDDATest, ParallelToEachAxis) {
  const auto g = UnitGrid(2);
  EXPECT_EQ(Trace(g, {-1, 0.25, 0.75}, {2, 0, 0}),
            (std::vector<CellSegment>{{CellId(4), 0.5, 0.75}, {CellId(5), 0.75, 1}}));
  EXPECT_EQ(Trace(g, {0.75, -1, 0.25}, {0, 1, 0}),
            (std::vector<CellSegment>{{CellId(1), 1, 1.5}, {CellId(3), 1.5, 2}}));
  EXPECT_EQ(Trace(g, {0.25, 0.75, 5}, {0, 0, -1}),
            (std::vector<CellSegment>{{CellId(6), 4, 4.5}, {CellId(2), 4.5, 5}}));
  // Signed zeros and denormal components behave as parallel.
  const double tiny = std::numeric_limits<double>::denorm_min();
  for (Vec3d d : {Vec3d{1, -0.0, 0.0}, Vec3d{1, tiny, -tiny}, Vec3d{1, 1e-310, -0.0}}) {
    EXPECT_EQ(Trace(g, {-1, 0.25, 0.75}, d),
              (std::vector<CellSegment>{{CellId(4), 1, 1.5}, {CellId(5), 1.5, 2}}));
  }
  // Starting in a plane with a denormal component across it: the side the ray moves to.
  EXPECT_EQ(TraceCells(g, {-1, 0.5, 0.25}, {1, 0, 0}), (Cells{2, 3}));
  EXPECT_EQ(TraceCells(g, {-1, 0.5, 0.25}, {1, tiny, 0}), (Cells{2, 3}));
  EXPECT_EQ(TraceCells(g, {-1, 0.5, 0.25}, {1, -tiny, 0}), (Cells{0, 1}));
}

TEST(CellDDATest, StartingOnBoundaries) {
  const auto g = UnitGrid(2);
  EXPECT_EQ(Trace(g, {0, 0.25, 0.25}, {1, 0, 0}),
            (std::vector<CellSegment>{{CellId(0), 0, 0.5}, {CellId(1), 0.5, 1}}));
  EXPECT_EQ(TraceCells(g, {0, 0.25, 0.25}, {-1, 0, 0}), Cells{});  // on the box, pointing out
  EXPECT_EQ(TraceCells(g, {1, 0.25, 0.25}, {1, 0, 0}), Cells{});
  EXPECT_EQ(TraceCells(g, {1, 0.25, 0.25}, {-1, 0, 0}), (Cells{1, 0}));
  EXPECT_EQ(TraceCells(g, {1, 1, 1}, {-1, -1, -2}), (Cells{7, 3}));  // leaves by an edge of 3
  // On an interior plane: the cell the ray goes into.
  EXPECT_EQ(Trace(g, {0.5, 0.25, 0.25}, {1, 0, 0}),
            (std::vector<CellSegment>{{CellId(1), 0, 0.5}}));
  EXPECT_EQ(Trace(g, {0.5, 0.25, 0.25}, {-1, 0, 0}),
            (std::vector<CellSegment>{{CellId(0), 0, 0.5}}));
  EXPECT_EQ(TraceCells(g, {0.5, 0.5, 0.5}, {1, 1, 1}), (Cells{7}));
  EXPECT_EQ(TraceCells(g, {0.5, 0.5, 0.5}, {-1, -1, -1}), (Cells{0}));
  EXPECT_EQ(TraceCells(g, {0.5, 0.5, 0.5}, {1, -1, 1}), (Cells{5}));
  EXPECT_EQ(TraceCells(g, {0.5, 0.5, 0.5}, {-1, 0, 0}), (Cells{6}));
}

TEST(CellDDATest, MissingTouchingAndPointingAway) {
  const auto g = UnitGrid(2);
  EXPECT_EQ(TraceCells(g, {2, 0.5, 0.5}, {1, 0, 0}), Cells{});
  EXPECT_EQ(TraceCells(g, {-1, 1, 0.5}, {1, -1, 0}), Cells{});         // touches the edge x=y=0
  EXPECT_EQ(TraceCells(g, {-1, 1, 1}, {1, -1, -1}), Cells{});          // touches the corner 0
  EXPECT_EQ(TraceCells(g, {-1, 2, 0.5}, {1, 0, 0}), Cells{});          // parallel, outside
  EXPECT_EQ(TraceCells(g, {-1, 0.5, 0.5}, {1, 0, 0}, 0, 1), Cells{});  // tmax at the entry
  EXPECT_EQ(CellDDA(g, {2, 0.5, 0.5}, {1, 0, 0}).done(), true);
}

TEST(CellDDATest, TRangeClipping) {
  const auto g = UnitGrid(2);
  const Vec3d o{-1, 0.25, 0.25}, d{1, 0, 0};
  EXPECT_EQ(Trace(g, o, d, 1.25, 1.75),
            (std::vector<CellSegment>{{CellId(0), 1.25, 1.5}, {CellId(1), 1.5, 1.75}}));
  EXPECT_EQ(Trace(g, o, d, 0, 1.5), (std::vector<CellSegment>{{CellId(0), 1, 1.5}}));
  EXPECT_EQ(Trace(g, o, d, 1.5, 5), (std::vector<CellSegment>{{CellId(1), 1.5, 2}}));
  EXPECT_EQ(Trace(g, o, d, 1.6, 1.6), std::vector<CellSegment>{});
  EXPECT_EQ(Trace(g, o, d, 1.7, 1.6), std::vector<CellSegment>{});
  EXPECT_EQ(Trace(g, {0.25, 0.25, 0.25}, d, -kInf, kInf),
            (std::vector<CellSegment>{{CellId(0), -0.25, 0.25}, {CellId(1), 0.25, 0.75}}));
}

TEST(CellDDATest, ForcedStartCell) {
  const auto g = UnitGrid(2);
  const Vec3d d{1, 0, 0};
  // On the plane between cells 0 and 1, heading into 1.
  EXPECT_EQ(Trace(g, {0.5, 0.25, 0.25}, d, 0, kInf, CellId(0)),
            (std::vector<CellSegment>{{CellId(0), 0, 0}, {CellId(1), 0, 0.5}}));
  EXPECT_EQ(Trace(g, {0.5, 0.25, 0.25}, d, 0, kInf, CellId(1)),
            (std::vector<CellSegment>{{CellId(1), 0, 0.5}}));
  // Rounding put the point a hair on the wrong side: the forced cell still comes first.
  EXPECT_EQ(Trace(g, {0.5 - 1e-12, 0.25, 0.25}, d, 0, kInf, CellId(1)),
            (std::vector<CellSegment>{{CellId(1), 0, 0.5 + 1e-12}}));
  EXPECT_EQ(Trace(g, {0.5 + 1e-12, 0.25, 0.25}, d, 0, kInf, CellId(0)),
            (std::vector<CellSegment>{{CellId(0), 0, 0}, {CellId(1), 0, 0.5 - 1e-12}}));
  EXPECT_EQ(TraceCells(g, {0.5 + 1e-12, 0.5, 0.5}, {1, -1, -1}, 0, kInf, CellId(0)), (Cells{0, 1}));
  // Leaves the box at once: one zero-length segment.
  EXPECT_EQ(Trace(g, {1, 0.25, 0.25}, d, 0, kInf, CellId(1)),
            (std::vector<CellSegment>{{CellId(1), 0, 0}}));
  EXPECT_EQ(Trace(g, {0.25, 0.25, 0.25}, d, 0, -1, CellId(0)),
            (std::vector<CellSegment>{{CellId(0), 0, 0}}));
  // Parallel to a face and a hair outside it: the start cell says the ray is in.
  EXPECT_EQ(Trace(g, {0.25, 1 + 1e-15, 0.25}, d, 0, kInf, CellId(2)),
            (std::vector<CellSegment>{{CellId(2), 0, 0.25}, {CellId(3), 0.25, 0.75}}));
  EXPECT_EQ(TraceCells(g, {0.25, 1 + 1e-15, 0.25}, d), Cells{});
  // Starts at tmin, not at the box entry.
  EXPECT_EQ(Trace(g, {0.25, 0.25, 0.25}, d, 0.5, 0.6, CellId(1)),
            (std::vector<CellSegment>{{CellId(1), 0.5, 0.6}}));
  EXPECT_THROW(CellDDA(g, {0.25, 0.25, 0.25}, d, -kInf, kInf, CellId(0)), InputError);
  EXPECT_THROW(CellDDA(g, {0.25, 0.25, 0.25}, d, 0, kInf, CellId(8)), InputError);
}

// A spawned ray starts half a voxel off the surface its parent hit, which in cells smaller
// than that lies cells away from the parent's cell: the forced cell comes first with zero
// length, then the ray goes on from where it really is. (These aborted on a CHECK that the
// start point was at most one cell from the forced cell: `raycell record --cells 255x255x255`.)
TEST(CellDDATest, ForcedStartCellFarFromTheStartPoint) {
  const auto g = UnitGrid(3);
  const Vec3d d{1, 0, 0};
  const double p1 = 1.0 / 3, p2 = 2 * (1.0 / 3);  // interior planes
  // Behind the forced cell (x = 2): the ray crosses cells 0, 1 and 2 after it.
  EXPECT_EQ(Trace(g, {0.1, 0.1, 0.1}, d, 0, kInf, CellId(2)),
            (std::vector<CellSegment>{{CellId(2), 0, 0},
                                      {CellId(0), 0, p1 - 0.1},
                                      {CellId(1), p1 - 0.1, p2 - 0.1},
                                      {CellId(2), p2 - 0.1, 0.9}}));
  // Two cells past it.
  EXPECT_EQ(Trace(g, {0.9, 0.1, 0.1}, d, 0, kInf, CellId(0)),
            (std::vector<CellSegment>{{CellId(0), 0, 0}, {CellId(2), 0, 1 - 0.9}}));
  // Off its slab on an axis the ray is parallel to (y = 2, not 0): cells 6, 7, 8.
  EXPECT_EQ(Trace(g, {0.1, 0.9, 0.1}, d, 0, kInf, CellId(0)),
            (std::vector<CellSegment>{{CellId(0), 0, 0},
                                      {CellId(6), 0, p1 - 0.1},
                                      {CellId(7), p1 - 0.1, p2 - 0.1},
                                      {CellId(8), p2 - 0.1, 0.9}}));
  // Outside the box, entering it later: in the forced cell (one segment from tmin) ...
  EXPECT_EQ(
      Trace(g, {-0.5, 0.1, 0.1}, d, 0, kInf, CellId(0)),
      (std::vector<CellSegment>{
          {CellId(0), 0, p1 + 0.5}, {CellId(1), p1 + 0.5, p2 + 0.5}, {CellId(2), p2 + 0.5, 1.5}}));
  // ... or elsewhere (the forced cell until the box entry).
  EXPECT_EQ(Trace(g, {-0.5, 0.1, 0.1}, d, 0, kInf, CellId(4)),
            (std::vector<CellSegment>{{CellId(4), 0, 0.5},
                                      {CellId(0), 0.5, p1 + 0.5},
                                      {CellId(1), p1 + 0.5, p2 + 0.5},
                                      {CellId(2), p2 + 0.5, 1.5}}));
  // Outside the box, never entering it: the forced cell alone.
  EXPECT_EQ(Trace(g, {0.1, 2, 0.1}, d, 0, kInf, CellId(0)),
            (std::vector<CellSegment>{{CellId(0), 0, 0}}));
  EXPECT_EQ(Trace(g, {0.1, 0.1, 0.1}, {-1, 0, 0}, 0, 0.05, CellId(2)),
            (std::vector<CellSegment>{{CellId(2), 0, 0}, {CellId(0), 0, 0.05}}));
  // Within 1e-6 of the box of the forced cell is rounding: the forced cell holds the ray.
  EXPECT_EQ(Trace(g, {p1 - 1e-7, 0.1, 0.1}, d, 0, kInf, CellId(1)),
            (std::vector<CellSegment>{{CellId(1), 0, p2 - (p1 - 1e-7)},
                                      {CellId(2), p2 - (p1 - 1e-7), 1 - (p1 - 1e-7)}}));
  EXPECT_EQ(TraceCells(g, {p1 - 1e-5, 0.1, 0.1}, d, 0, kInf, CellId(1)), (Cells{1, 0, 1, 2}));
  // A fraction of the box, not of a cell: the same on a grid of 3 or 300 cells an axis.
  const auto fine = UnitGrid(300);
  EXPECT_EQ(TraceCells(fine, {p1 - 1e-5, 0.1, 0.1}, d, 0, kInf, CellId(100 + 300 * (30 + 300 * 30)))
                .size(),
            202u);  // the forced cell, the one behind it, then cells 100..299
  // Far out on one axis, within the margin on another: the ray goes on from the cell holding
  // the start point but for the second axis, where it keeps the forced cell's index (cell 3 =
  // (0, 1, 0), not 0 = (0, 0, 0)).
  EXPECT_EQ(TraceCells(g, {p1 - 0.1, p1 - 1e-7, 0.1}, d, 0, kInf, CellId(4)), (Cells{4, 3, 4, 5}));
}

TEST(CellDDATest, InvalidRaysAreInputErrorsNamingTheProblem) {
  const auto g = UnitGrid(2);
  const double nan = std::nan("");
  EXPECT_THROW(CellDDA(g, {0, 0, 0}, {0, 0, 0}), InputError);
  EXPECT_THROW(CellDDA(g, {0, 0, 0}, {-0.0, 0, -0.0}), InputError);
  EXPECT_THROW(CellDDA(g, {nan, 0, 0}, {1, 0, 0}), InputError);
  EXPECT_THROW(CellDDA(g, {0, 0, 0}, {kInf, 0, 0}), InputError);
  EXPECT_THROW(CellDDA(g, {0, 0, 0}, {1, 0, 0}, nan), InputError);
  EXPECT_THROW(CellDDA(g, {0, 0, 0}, {1, 0, 0}, 0, nan), InputError);
  // t overflows: the chord is unbounded unless the range is finite.
  const double tiny = std::numeric_limits<double>::denorm_min();
  EXPECT_THROW(CellDDA(g, {0.25, 0.25, 0.25}, {tiny, 0, 0}), InputError);
  EXPECT_EQ(Trace(g, {0.25, 0.25, 0.25}, {tiny, 0, 0}, 0, 1),
            (std::vector<CellSegment>{{CellId(0), 0, 1}}));
  try {
    CellDDA(g, {0, 0, 0}, {0, 0, 0});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("direction is zero"), std::string::npos) << e.what();
  }
}

TEST(CellDDATest, HugeAndTinyScales) {
  {
    const double lo = 1e6, s = 1e-3;
    const auto g = CellGrid::Create({lo, lo, lo}, {lo + s, lo + s, lo + s}, {2, 2, 2});
    EXPECT_EQ(TraceCells(g, {lo - s, lo - s, lo - s}, {1, 1, 1}), (Cells{0, 7}));
    EXPECT_EQ(TraceCells(g, {lo - s, lo + s / 4, lo + 3 * s / 4}, {1, 0, 0}), (Cells{4, 5}));
    const double mid = g.Plane(0, 1);  // not lo + s/2: lo + s is not exact
    EXPECT_EQ(TraceCells(g, {mid, mid, lo - 1}, {0, 0, 1}), (Cells{3, 7}));
    EXPECT_EQ(TraceCells(g, {mid, std::nextafter(mid, 0.0), lo - 1}, {0, 0, 1}), (Cells{1, 5}));
    // From the world origin, 1e6 away, through the centre of cell 5's far half.
    EXPECT_EQ(TraceCells(g, {0, 0, 0}, {lo + 0.9 * s, lo + 0.15 * s, lo + 0.55 * s}),
              (Cells{1, 5}));
    EXPECT_EQ(TraceCells(g, {0, 0, 0}, {lo + s / 4, lo + s / 4, lo + s / 4}), (Cells{0, 7}));
  }
  {
    const double s = 1e-6;
    const auto g = CellGrid::Create({0, 0, 0}, {s, s, s}, {3, 3, 3});
    EXPECT_EQ(TraceCells(g, {0, 0, 0}, {1, 1, 1}), (Cells{0, 13, 26}));
    EXPECT_EQ(TraceCells(g, {s, 0, 0}, {-1e-9, 1e-9, 1e-9}), (Cells{2, 13, 24}));
    EXPECT_EQ(TraceCells(g, {-1, s / 6, s / 2}, {1, 0, 0}), (Cells{9, 10, 11}));
  }
  {
    const double s = 1e6;
    const auto g = CellGrid::Create({-s, -s, -s}, {s, s, s}, {3, 3, 3});
    EXPECT_EQ(TraceCells(g, {-s, -s, -s}, {1e-3, 1e-3, 1e-3}), (Cells{0, 13, 26}));
    EXPECT_EQ(TraceCells(g, {-2 * s, 0, 0}, {1, 0, 0}), (Cells{12, 13, 14}));
  }
}

TEST(CellDDATest, OneCellGridAndToString) {
  const auto g = CellGrid::Create({0, 0, 0}, {2, 2, 2}, {1, 1, 1});
  EXPECT_EQ(Trace(g, {-1, 0.3, 1.7}, {1, 0.1, -0.1}),
            (std::vector<CellSegment>{{CellId(0), 1, 3}}));
  CellDDA dda(g, {-1, 1, 1}, {1, 0, 0});
  EXPECT_NE(dda.ToString().find("CellDDA["), std::string::npos);
  EXPECT_EQ((CellSegment{CellId(3), 0.25, 0.5}).ToString(), "{cell 3, t [0.25, 0.5]}");
}

// ------------------------------------------------------------ CellDDA: random rays

struct Ray {
  Vec3d o, d;
  double tmin = 0, tmax = kInf;
};

std::string Describe(const CellGrid& g, const Ray& r) {
  char buf[160];
  std::snprintf(buf, sizeof buf, " t [%.17g, %.17g]", r.tmin, r.tmax);
  return g.ToString() + " o " + ToString(r.o) + " d " + ToString(r.d) + buf;
}

// The chord [t0, t1] through box ∩ [tmin, tmax], as the contract defines it, and the axes
// whose faces bound it (-1 for tmin or tmax).
struct ChordEnds {
  double t0, t1;
  int axis0 = -1, axis1 = -1;
};

ChordEnds Chord(const CellGrid& g, const Ray& r) {
  ChordEnds c{r.tmin, r.tmax};
  for (int a = 0; a < 3; ++a) {
    const double lo = Get(g.lo(), a), hi = Get(g.hi(), a), o = Get(r.o, a), d = Get(r.d, a);
    if (d == 0) {
      if (o < lo || o > hi) return {kInf, -kInf};
      continue;
    }
    const double ta = (lo - o) / d, tb = (hi - o) / d;
    if (std::min(ta, tb) > c.t0) c.t0 = std::min(ta, tb), c.axis0 = a;
    if (std::max(ta, tb) < c.t1) c.t1 = std::max(ta, tb), c.axis1 = a;
  }
  return c;
}

// Positional tolerance of the test on each axis: far above the traversal's own.
std::array<double, 3> TestEps(const CellGrid& g, const Vec3d& o) {
  std::array<double, 3> eps;
  for (int a = 0; a < 3; ++a) {
    const double mag = std::max(std::abs(Get(g.lo(), a)), std::abs(Get(g.hi(), a)));
    eps[a] = std::max(1e-9 * g.cell_size()[a], 1024 * DBL_EPSILON * (mag + std::abs(Get(o, a))));
  }
  return eps;
}

// How far a parameter may move when the ray's origin moves by the test tolerance.
double ParameterEps(const CellGrid& g, const Ray& r) {
  const auto eps = TestEps(g, r.o);
  double e = 0;
  for (int a = 0; a < 3; ++a)
    if (Get(r.d, a) != 0) e = std::max(e, 4 * eps[a] / std::abs(Get(r.d, a)));
  return e;
}

// Checks the properties every traversal has; returns "" or what is wrong.
std::string CheckTiling(const CellGrid& g, const Ray& r, const std::vector<CellSegment>& segs,
                        double t0, double t1, bool forced) {
  if (segs.empty()) return t0 < t1 ? "no segments for a chord of positive length" : "";
  if (!forced && !(t0 < t1)) return "segments for an empty chord";
  if (segs.front().t0 != t0) return "first t0 is not the chord start";
  if (segs.back().t1 != t1) return "last t1 is not the chord end";
  if (segs.size() > g.dim(0) + g.dim(1) + g.dim(2)) return "too many segments";
  double sum = 0;
  const auto eps = TestEps(g, r.o);
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const CellSegment& s = segs[i];
    if (s.cell.value() >= g.cell_count()) return "cell out of range";
    if (std::isnan(s.t0) || std::isnan(s.t1)) return "NaN";
    if (!(s.t0 < s.t1) && !(forced && i == 0 && s.t0 == s.t1)) return "empty segment";
    if (i > 0 && s.t0 != segs[i - 1].t1) return "gap or overlap";
    if (i > 0 && s.cell == segs[i - 1].cell) return "same cell twice in a row";
    sum += s.t1 - s.t0;
    const Vec3d m = At(r.o, r.d, 0.5 * (s.t0 + s.t1));
    const Box3d b = g.CellBounds(s.cell);
    for (int a = 0; a < 3; ++a) {
      const double slack = 4 * eps[a] + 0.5 * (s.t1 - s.t0) * std::abs(Get(r.d, a));
      if (Get(m, a) < Get(b.lo, a) - slack || Get(m, a) > Get(b.hi, a) + slack)
        return "segment midpoint outside its cell";
    }
  }
  if (std::abs(sum - (t1 - t0)) > 1e-9 * (t1 - t0)) return "lengths do not add up";
  return "";
}

struct Crossing {
  double t;
  int axis;  // -1 for tmin and tmax
};

// Whether crossings x and y are too close to tell apart: within the test tolerance along
// the axis of either.
bool TooClose(const Ray& r, const std::array<double, 3>& eps, const Crossing& x,
              const Crossing& y) {
  for (int a : {x.axis, y.axis})
    if (a >= 0 && std::abs(y.t - x.t) * std::abs(Get(r.d, a)) < 4 * eps[a]) return true;
  return false;
}

// Brute force: every crossing of every cell plane in the chord, sorted; the cell of each
// interval's midpoint. Empty when the ray grazes (two crossings, or a crossing and an end of
// the chord, or a midpoint and a plane within the test tolerance of each other), where the
// answer is a matter of rounding.
std::optional<std::vector<Crossing>> ReferenceCrossings(const CellGrid& g, const Ray& r,
                                                        const ChordEnds& c, Cells* cells) {
  const auto eps = TestEps(g, r.o);
  const Crossing start{c.t0, c.axis0}, end{c.t1, c.axis1};
  std::vector<Crossing> xs{start, end};
  for (int a = 0; a < 3; ++a) {
    const double lo = Get(g.lo(), a), hi = Get(g.hi(), a), d = Get(r.d, a);
    for (std::uint32_t k = 1; d != 0 && k < g.dim(a); ++k) {
      const Crossing x{(lo + (hi - lo) * k / g.dim(a) - Get(r.o, a)) / d, a};
      if (TooClose(r, eps, start, x) || TooClose(r, eps, x, end)) return {};
      if (c.t0 < x.t && x.t < c.t1) xs.push_back(x);
    }
  }
  std::sort(xs.begin(), xs.end(), [](const Crossing& x, const Crossing& y) { return x.t < y.t; });
  cells->clear();
  for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
    if (TooClose(r, eps, xs[i], xs[i + 1])) return {};
    const Vec3d m = At(r.o, r.d, 0.5 * (xs[i].t + xs[i + 1].t));
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t k = 0; k <= g.dim(a); ++k)
        if (std::abs(Get(m, a) - g.Plane(a, k)) < 4 * eps[a]) return {};
    cells->push_back(g.CellOf(m));
  }
  return xs;
}

// Compares a traversal with the reference; returns "" or what is wrong.
std::string CheckReference(const CellGrid& g, const Ray& r, const std::vector<CellSegment>& segs,
                           const Cells& cells, const std::vector<Crossing>& xs) {
  if (CellsOf(segs) != cells) return "cells differ from the reference";
  const auto eps = TestEps(g, r.o);
  for (std::size_t i = 0; i + 1 < segs.size(); ++i) {
    const int a = xs[i + 1].axis;
    if (std::abs(segs[i].t1 - xs[i + 1].t) * std::abs(Get(r.d, a)) > eps[a])
      return "crossing parameter differs from the reference";
  }
  return "";
}

class RandomRays {
 public:
  explicit RandomRays(std::uint64_t seed) : rng_(seed) {}

  double U(double a = 0, double b = 1) {
    return std::uniform_real_distribution<double>(a, b)(rng_);
  }
  std::uint32_t Pick(std::uint32_t n) { return static_cast<std::uint32_t>(rng_() % n); }

  CellGrid Grid() {
    const double scale = std::pow(10.0, U(-6, 6));
    const double offset = Pick(3) == 0 ? 0 : std::pow(10.0, U(-6, 6)) * (Pick(2) ? 1 : -1);
    const double off = std::clamp(offset, -1e9 * scale, 1e9 * scale);
    Vec3d lo, hi;
    for (int a = 0; a < 3; ++a) {
      Set(lo, a, off + scale * U(-1, 1));
      Set(hi, a, Get(lo, a) + scale * U(0.05, 2));
    }
    return CellGrid::Create(lo, hi, {1 + Pick(7), 1 + Pick(7), 1 + Pick(7)});
  }

  // A point of the grid's lattice: planes on the axes in `snap`, anywhere on the others.
  Vec3d LatticePoint(const CellGrid& g, int snap_mask, bool interior) {
    Vec3d p;
    for (int a = 0; a < 3; ++a) {
      const std::uint32_t n = g.dim(a);
      const std::uint32_t k = interior ? 1 + Pick(std::max(n - 1, 1u)) : Pick(n + 1);
      Set(p, a, (snap_mask >> a & 1) ? g.Plane(a, std::min(k, n)) : Inside(g, a, 0));
    }
    return p;
  }

  Ray Make(const CellGrid& g) {
    Ray r;
    r.o = Origin(g);
    r.d = Direction(g, r.o);
    const std::uint32_t range = Pick(10);
    if (range == 0) r.tmin = -kInf;
    if (range == 1 || range == 2) {
      const double t = g.cell_size()[0] / std::max(Norm(r.d), 1e-300);
      r.tmin = U(-3, 3) * t * Pick(3);
      r.tmax = r.tmin + U(0, 3) * t;
    }
    return r;
  }

 private:
  static double Norm(const Vec3d& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

  double Inside(const CellGrid& g, int a, double margin) {
    const double lo = Get(g.lo(), a), hi = Get(g.hi(), a);
    return lo + (hi - lo) * U(-margin, 1 + margin);
  }

  Vec3d Origin(const CellGrid& g) {
    const std::uint32_t mode = Pick(8);
    if (mode <= 2) return {Inside(g, 0, 0), Inside(g, 1, 0), Inside(g, 2, 0)};
    if (mode <= 5) return {Inside(g, 0, 1.5), Inside(g, 1, 1.5), Inside(g, 2, 1.5)};
    return LatticePoint(g, 1 + static_cast<int>(Pick(7)), false);  // on planes, edges, corners
  }

  Vec3d Direction(const CellGrid& g, const Vec3d& o) {
    std::normal_distribution<double> n;
    const std::uint32_t mode = Pick(10);
    if (mode <= 3) return {n(rng_), n(rng_), n(rng_)};
    if (mode <= 5) return Aimed(g, o, n);
    if (mode == 6) {
      Vec3d d{0, 0, 0};
      Set(d, static_cast<int>(Pick(3)), Pick(2) ? 1.0 : -1.0);
      return d;
    }
    Vec3d d{n(rng_), n(rng_), n(rng_)};
    const int keep = static_cast<int>(Pick(3));
    for (int a = 0; a < 3; ++a)
      if (a != keep && Pick(2)) Set(d, a, Special());
    return d;
  }

  // Towards a lattice point (edge, corner or face), scaled so that parameters are inexact.
  Vec3d Aimed(const CellGrid& g, const Vec3d& o, std::normal_distribution<double>& n) {
    const Vec3d p = LatticePoint(g, 1 + static_cast<int>(Pick(7)), Pick(2));
    const Vec3d d = Mul(Sub(p, o), std::pow(10.0, U(-3, 3)));
    return d == Vec3d{0, 0, 0} ? Vec3d{n(rng_), n(rng_), n(rng_)} : d;
  }

  double Special() {
    const double s = Pick(2) ? 1.0 : -1.0;
    switch (Pick(5)) {
      case 0:
        return 0.0;
      case 1:
        return -0.0;
      case 2:
        return s * std::numeric_limits<double>::denorm_min();
      case 3:
        return s * 1e-310;
      default:
        return s * 1e-30;
    }
  }

  std::mt19937_64 rng_;
};

struct Stats {
  int rays = 0, empty = 0, compared = 0, forced = 0, forced_compared = 0, failures = 0;
};

void Report(Stats* st, const std::string& what, const CellGrid& g, const Ray& r,
            const std::vector<CellSegment>& segs) {
  if (what.empty()) return;
  if (++st->failures <= 10) ADD_FAILURE() << what << ": " << Describe(g, r) << " -> " << Dump(segs);
}

// Restarts the ray at a cell boundary of its traversal with a forced start cell (the cell
// before or after the boundary), as a spawned ray would, and checks the rest.
void CheckForced(RandomRays& rr, const CellGrid& g, const Ray& r,
                 const std::vector<CellSegment>& segs, const Cells* ref, Stats* st) {
  const std::size_t i = rr.Pick(static_cast<std::uint32_t>(segs.size()));  // boundary i: t0 of i
  const std::size_t first = (i > 0 && rr.Pick(2)) ? i - 1 : i;
  Ray s{At(r.o, r.d, segs[i].t0), r.d, 0, kInf};
  const auto got = Trace(g, s.o, s.d, 0, kInf, segs[first].cell);
  ++st->forced;
  std::string what = got.empty() || got[0].cell != segs[first].cell ? "forced cell not first" : "";
  if (what.empty()) what = CheckTiling(g, s, got, 0, got.back().t1, true);
  if (what.empty() && ref) {  // the ray does not graze: rounding the start point is harmless
    ++st->forced_compared;
    if (CellsOf(got) != Cells(ref->begin() + static_cast<std::ptrdiff_t>(first), ref->end()))
      what = "forced ray's cells differ from the reference " + Describe(g, r) + " " + Dump(segs);
    else if (std::abs(got.back().t1 - (segs.back().t1 - segs[i].t0)) > ParameterEps(g, r))
      what = "forced ray ends elsewhere";
  }
  Report(st, what, g, s, got);
}

void CheckRandomRay(RandomRays& rr, const CellGrid& g, const Ray& r, Stats* st) {
  const auto segs = Trace(g, r.o, r.d, r.tmin, r.tmax);
  const ChordEnds c = Chord(g, r);
  ++st->rays;
  st->empty += segs.empty();
  std::string what = CheckTiling(g, r, segs, c.t0, c.t1, false);
  Cells cells;
  const auto xs = segs.empty() ? std::nullopt : ReferenceCrossings(g, r, c, &cells);
  if (what.empty() && xs) {
    ++st->compared;
    what = CheckReference(g, r, segs, cells, *xs);
  }
  Report(st, what, g, r, segs);
  if (what.empty() && !segs.empty() && r.tmax == kInf && std::isfinite(c.t0))
    CheckForced(rr, g, r, segs, xs ? &cells : nullptr, st);
}

TEST(CellDDARandomTest, PropertiesAndBruteForceReference) {
  RandomRays rr(20240601);
  Stats st;
  for (int batch = 0; batch < 2000; ++batch) {
    const CellGrid g = rr.Grid();
    for (int i = 0; i < 60; ++i) CheckRandomRay(rr, g, rr.Make(g), &st);
  }
  std::printf("rays %d (empty %d), compared with reference %d; forced %d (compared %d)\n", st.rays,
              st.empty, st.compared, st.forced, st.forced_compared);
  EXPECT_EQ(st.failures, 0);
  EXPECT_GE(st.rays, 100000);
  EXPECT_GE(st.compared, st.rays / 4);  // the reference must not be skipped wholesale
  EXPECT_GE(st.forced_compared, st.forced / 4);
}

// Rays aimed at an interior lattice corner step all three axes there at once.
TEST(CellDDARandomTest, CornerRaysStepDiagonally) {
  RandomRays rr(99);
  int checked = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const CellGrid g = rr.Grid();
    if (g.dim(0) < 2 || g.dim(1) < 2 || g.dim(2) < 2) continue;
    const Vec3d p = rr.LatticePoint(g, 7, true);
    Vec3d o;
    for (int a = 0; a < 3; ++a)
      Set(o, a, Get(g.lo(), a) + (Get(g.hi(), a) - Get(g.lo(), a)) * rr.U(-1, 2));
    const double s = std::pow(10.0, rr.U(-3, 3));
    const Vec3d d = Mul(Sub(p, o), s);
    if (d.x == 0 || d.y == 0 || d.z == 0) continue;
    const auto segs = Trace(g, o, d, -kInf, kInf);
    // p is the lower corner of cell q; the ray goes from the cell diagonally behind p to the
    // cell diagonally ahead of it, with nothing in between.
    const auto q = g.CellCoords(g.CellOf(p));
    std::array<std::uint32_t, 3> before, after;
    for (int a = 0; a < 3; ++a) {
      before[a] = q[a] - (Get(d, a) > 0 ? 1 : 0);
      after[a] = q[a] - (Get(d, a) < 0 ? 1 : 0);
    }
    const CellId from = g.CellIndex(before), to = g.CellIndex(after);
    bool found = false;
    for (std::size_t i = 0; i + 1 < segs.size(); ++i)
      found |= segs[i].cell == from && segs[i + 1].cell == to;
    ++checked;
    EXPECT_TRUE(found) << from << " -> " << to << " in " << Describe(g, {o, d, -kInf, kInf})
                       << " -> " << Dump(segs);
  }
  EXPECT_GT(checked, 5000);
}

// Rays entering or leaving the box where a face meets an interior plane, nearly parallel
// to the face: the plane crossing and the box face are taken together, so the first or last
// segment is no sliver, and it is in the cell on the inner side of the plane.
TEST(CellDDARandomTest, RaysThroughFaceEdgesLeaveNoSliver) {
  RandomRays rr(4242);
  int checked = 0;
  for (int trial = 0; trial < 40000; ++trial) {
    const CellGrid g = rr.Grid();
    const int face = static_cast<int>(rr.Pick(3)), across = (face + 1 + rr.Pick(2)) % 3;
    if (g.dim(across) < 2) continue;
    // p: on the face, on interior plane k of `across`, strictly inside on the third axis.
    Vec3d p = rr.LatticePoint(g, 1 << across, true);
    const bool high = rr.Pick(2);
    Set(p, face, high ? Get(g.hi(), face) : Get(g.lo(), face));
    // o: inside, close to the face so that the ray is nearly parallel to it.
    Vec3d o = rr.LatticePoint(g, 0, false);
    const double depth = std::pow(10.0, rr.U(-6, 0)) * g.cell_size()[face];
    Set(o, face, Get(p, face) + (high ? -depth : depth));
    if (Get(o, face) == Get(p, face)) continue;  // depth lost to rounding: o is on the face
    // Leaving: out through p. Entering: in through p, with t from -inf (the ray's origin is
    // inside). The origin is o (exact) or a rounded point between o and p, as a spawned
    // ray's would be: then the face crossing, nearly parallel to the ray, is uncertain by
    // far more than the plane crossing, and only taking both uncertainties into account
    // merges them. Skipped when the rounding could move the ray a noticeable part of a cell.
    const bool leaving = rr.Pick(2);
    const Vec3d in = Mul(Sub(o, p), std::pow(10.0, rr.U(-3, 3)));
    const Vec3d origin = rr.Pick(2) ? o : Add(p, Mul(Sub(o, p), rr.U(0.01, 1)));
    const Ray r = leaving ? Ray{origin, Mul(in, -1), 0, kInf} : Ray{origin, in, -kInf, kInf};
    double span = 0;  // cells per unit t along the fastest axis
    for (int a = 0; a < 3; ++a) span = std::max(span, std::abs(Get(r.d, a)) / g.cell_size()[a]);
    const double mag = std::max({std::abs(Get(p, 0)), std::abs(Get(p, 1)), std::abs(Get(p, 2))});
    if (4 * DBL_EPSILON * mag / std::abs(Get(r.d, face)) * span > 1e-7) continue;
    const auto segs = Trace(g, r.o, r.d, r.tmin, r.tmax);
    ASSERT_FALSE(segs.empty()) << Describe(g, r);
    const CellSegment& s = leaving ? segs.back() : segs.front();
    const std::uint32_t k = g.AxisCell(across, Get(p, across));  // p lies on plane k
    const std::uint32_t inner = (Get(r.d, across) > 0) == leaving ? k - 1 : k;
    ++checked;
    EXPECT_EQ(g.CellCoords(s.cell)[across], inner) << Describe(g, r) << " -> " << Dump(segs);
    EXPECT_GT((s.t1 - s.t0) * span, 1e-6) << Describe(g, r) << " -> " << Dump(segs);
  }
  EXPECT_GT(checked, 5000);
}

}  // namespace
}  // namespace raycell
