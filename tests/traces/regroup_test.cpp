#include "traces/regroup.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/random.h"
#include "traces/subdivision.h"

namespace raycell {
namespace {

std::vector<CellId> Map(std::initializer_list<std::uint32_t> coarse) {
  std::vector<CellId> m;
  for (std::uint32_t c : coarse) m.push_back(CellId(c));
  return m;
}

// A ray visiting fine cells 0 1 5 6 2 (coarse 0 0 1 1 0), a shadow ray spawned at its fourth
// visit (fine cell 6, coarse visit 1) going 6 7 3, and a second primary ray.
RayBatch HandBatch() {
  RayBatch b(true);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 3, 4);
  b.AddVisit(CellId(0), 10, 0.f, 1.f);
  b.AddVisit(CellId(1), 20, 1.f, 2.f);
  b.AddVisit(CellId(5), 30, 2.f, 3.f);
  b.AddVisit(CellId(6), 40, 3.f, 4.f);
  b.AddVisit(CellId(2), 50, 4.f, 5.f);
  b.BeginRay(RayKind::kShadow, 0, 3, 3, 4);
  b.AddVisit(CellId(6), 1, 0.f, .5f);
  b.AddVisit(CellId(7), 2, .5f, 1.f);
  b.AddVisit(CellId(3), 3, 1.f, 2.f);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 5, 4);
  b.AddVisit(CellId(3), 7, 0.f, 9.f);
  return b;
}

TEST(RayRegrouper, MergesConsecutiveVisitsOfACoarseCellAndRemapsSpawnVisits) {
  // Fine cells 0-7; coarse: {0, 1, 2, 3} -> 0, {4, 5, 6, 7} -> 1.
  RayRegrouper g(Map({0, 0, 0, 0, 1, 1, 1, 1}));
  const RayBatch out = g.Regroup(HandBatch());
  RayBatch want(true);
  want.BeginRay(RayKind::kPrimary, kNoParent, 0, 3, 4);
  want.AddVisit(CellId(0), 30, 0.f, 2.f);
  want.AddVisit(CellId(1), 70, 2.f, 4.f);
  want.AddVisit(CellId(0), 50, 4.f, 5.f);
  want.BeginRay(RayKind::kShadow, 0, 1, 3, 4);  // spawned in fine visit 3: coarse visit 1
  want.AddVisit(CellId(1), 3, 0.f, 1.f);
  want.AddVisit(CellId(0), 3, 1.f, 2.f);
  want.BeginRay(RayKind::kPrimary, kNoParent, 0, 5, 4);
  want.AddVisit(CellId(0), 7, 0.f, 9.f);
  EXPECT_EQ(out, want);
}

TEST(RayRegrouper, BadRaysAreInputErrors) {
  RayRegrouper g(Map({0, 0}));  // two fine cells only
  EXPECT_THROW(g.Regroup(HandBatch()), InputError);
  RayBatch orphan(false);
  orphan.BeginRay(RayKind::kShadow, 7, 0, 0, 0);
  orphan.AddVisit(CellId(0), 1, 0.f, 0.f);
  RayRegrouper h(Map({0, 0, 0, 0, 1, 1, 1, 1}));
  EXPECT_THROW(h.Regroup(orphan), InputError);
  RayBatch far(false);
  far.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  far.AddVisit(CellId(0), 1, 0.f, 0.f);
  far.BeginRay(RayKind::kShadow, 0, 5, 0, 0);  // its parent has one visit
  far.AddVisit(CellId(0), 1, 0.f, 0.f);
  h.Reset();
  EXPECT_THROW(h.Regroup(far), InputError);
}

// Random ray trees on a fine grid: walks to neighbouring cells (never the same cell twice in
// a row), spawned rays starting in their parent's spawn cell.
RayBatch RandomTrees(std::uint64_t seed, const std::array<std::uint32_t, 3>& g, int trees) {
  SplitMix64 r(seed);
  RayBatch b(true);
  const auto step = [&](std::uint32_t c) {
    std::uint32_t x = c % g[0], y = c / g[0] % g[1], z = c / (g[0] * g[1]);
    for (;;) {
      const int axis = int(r.Next() % 3);
      const bool up = r.Next() % 2 != 0;
      std::uint32_t* v = axis == 0 ? &x : axis == 1 ? &y : &z;
      if (up && *v + 1 < g[axis]) return (++*v, x + g[0] * (y + g[1] * z));
      if (!up && *v > 0) return (--*v, x + g[0] * (y + g[1] * z));
    }
  };
  RayId id = 0;
  for (int t = 0; t < trees; ++t) {
    const RayId root = id;
    std::vector<std::vector<std::uint32_t>> cells;  // of the tree's rays
    const int rays = 1 + int(r.Next() % 5);
    for (int k = 0; k < rays; ++k, ++id) {
      std::uint32_t c;
      if (k == 0) {
        c = std::uint32_t(r.Next() % (g[0] * g[1] * g[2]));
        b.BeginRay(RayKind::kPrimary, kNoParent, 0, 1, 2);
      } else {
        const std::uint32_t parent = std::uint32_t(r.Next() % cells.size());
        const std::uint32_t spawn = std::uint32_t(r.Next() % cells[parent].size());
        c = cells[parent][spawn];
        b.BeginRay(RayKind::kShadow, root + parent, spawn, 1, 2);
      }
      cells.emplace_back();
      const int visits = 1 + int(r.Next() % 6);
      for (int v = 0; v < visits; ++v) {
        if (v > 0) c = step(c);
        cells.back().push_back(c);
        b.AddVisit(CellId(c), std::uint32_t(r.Next() % 9), float(v), float(v + 1));
      }
    }
  }
  return b;
}

TEST(RayRegrouper, IdentityKeepsTheRaysAndRegroupingComposes) {
  const std::array<std::uint32_t, 3> g{4, 4, 4};
  FineCells fine;
  fine.grid = g;
  const Subdivision mid = Subdivide(ParseSubdivisionSpec("2x4x2", "t"), fine);  // of 4x4x4
  FineCells mid_cells;
  mid_cells.grid = {2, 4, 2};
  const Subdivision top = Subdivide(ParseSubdivisionSpec("1x2x2", "t"), mid_cells);  // of 2x4x2
  const Subdivision direct = Subdivide(ParseSubdivisionSpec("1x2x2", "t"), fine);    // of 4x4x4
  std::vector<CellId> identity;
  for (std::uint32_t c = 0; c < 64; ++c) identity.push_back(CellId(c));
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const RayBatch b = RandomTrees(seed, g, 40);
    RayRegrouper same(identity);
    EXPECT_EQ(same.Regroup(b), b) << seed;
    RayRegrouper first(mid.coarse_of_fine), second(top.coarse_of_fine), once(direct.coarse_of_fine);
    const RayBatch two_steps = second.Regroup(first.Regroup(b));
    const RayBatch one_step = once.Regroup(b);
    EXPECT_EQ(two_steps, one_step) << seed;
    // Work is kept: the same samples in all, and no two consecutive visits in one cell.
    std::uint64_t in = 0, out = 0;
    for (std::uint32_t s : b.samples()) in += s;
    for (std::uint32_t s : one_step.samples()) out += s;
    EXPECT_EQ(in, out) << seed;
    for (std::size_t i = 0; i < one_step.size(); ++i) {
      for (std::size_t v = one_step.visit_begin(i) + 1; v < one_step.visit_end(i); ++v) {
        EXPECT_NE(one_step.cells()[v], one_step.cells()[v - 1]) << seed << " ray " << i;
      }
      // A spawned ray starts in its parent's spawn cell, as in any capture.
      const RayView r = one_step.ray(i);
      if (!r.is_primary()) {
        const RayView p = one_step.ray(std::size_t(r.parent));
        EXPECT_EQ(r.cells[0], p.cells[r.spawn]) << seed << " ray " << i;
      }
    }
  }
}

TEST(RayRegrouper, BatchesOfOneFrameMayCutARayTree) {
  const std::array<std::uint32_t, 3> g{4, 4, 4};
  FineCells fine;
  fine.grid = g;
  const Subdivision s = Subdivide(ParseSubdivisionSpec("2x2x2", "t"), fine);
  const RayBatch b = RandomTrees(99, g, 30);
  RayRegrouper whole(s.coarse_of_fine);
  const RayBatch want = whole.Regroup(b);
  // The same rays in batches of 7, cutting ray trees.
  RayRegrouper parts(s.coarse_of_fine);
  RayBatch joined(true);
  for (std::size_t first = 0; first < b.size(); first += 7) {
    RayBatch part(true);
    part.set_first_id(first);
    for (std::size_t i = first; i < std::min(b.size(), first + 7); ++i) {
      const RayView r = b.ray(i);
      part.BeginRay(r.kind, r.parent, r.spawn, r.pixel_x, r.pixel_y);
      for (std::size_t v = 0; v < r.visit_count; ++v) {
        const Visit x = r.visit(v);
        part.AddVisit(x.cell, x.samples, x.t_enter, x.t_exit);
      }
    }
    const RayBatch out = parts.Regroup(part);
    EXPECT_EQ(out.first_id(), first);
    for (std::size_t i = 0; i < out.size(); ++i) {
      const RayView r = out.ray(i);
      joined.BeginRay(r.kind, r.parent, r.spawn, r.pixel_x, r.pixel_y);
      for (std::size_t v = 0; v < r.visit_count; ++v) {
        const Visit x = r.visit(v);
        joined.AddVisit(x.cell, x.samples, x.t_enter, x.t_exit);
      }
    }
  }
  EXPECT_EQ(joined, want);
}

// Coarse cells that are empty (kNoCell): their visits are dropped, their samples and the rays
// spawned there go to the merged visit before (or the first), a spawned ray that no longer
// starts in its spawn visit's cell gets a zero-length visit there first, and a primary ray
// left with nothing is dropped, the ids closing up (worked by hand below).
TEST(RayRegrouper, DropsEmptyCellsAsACaptureOnTheCoarseCellsWould) {
  // Fine cells 0-5: 0, 1 -> coarse 0; 2, 3 -> empty; 4, 5 -> coarse 1.
  const std::vector<CellId> map = {CellId(0), CellId(0), kNoCell, kNoCell, CellId(1), CellId(1)};
  RayBatch fine(true);
  fine.BeginRay(RayKind::kPrimary, kNoParent, 0, 1, 1);  // ray 0: empty 2, 3 only: dropped
  fine.AddVisit(CellId(2), 0, 0.f, 1.f);
  fine.AddVisit(CellId(3), 0, 1.f, 2.f);
  fine.BeginRay(RayKind::kPrimary, kNoParent, 0, 2, 1);  // ray 1 -> new id 0
  fine.AddVisit(CellId(2), 2, 0.f, 1.f);  // leading empty: its 2 samples go to visit 0
  fine.AddVisit(CellId(0), 5, 1.f, 2.f);
  fine.AddVisit(CellId(1), 1, 2.f, 3.f);
  fine.AddVisit(CellId(3), 4, 3.f, 4.f);  // empty between: its 4 samples go to visit 0
  fine.AddVisit(CellId(4), 7, 4.f, 5.f);
  fine.BeginRay(RayKind::kShadow, 1, 3, 2, 1);      // ray 2 -> id 1, spawned in fine cell 3
  fine.AddVisit(CellId(3), 1, 0.f, .5f);            // (dropped: spawn goes to coarse visit 0)
  fine.AddVisit(CellId(5), 2, .5f, 1.f);            // starts in coarse 1, not 0: a zero-length 0
  fine.BeginRay(RayKind::kReflection, 1, 4, 2, 1);  // ray 3 -> id 2, spawned in fine 4
  fine.AddVisit(CellId(4), 3, 0.f, 1.f);
  RayRegrouper g(map);
  const RayBatch out = g.Regroup(fine);
  RayBatch want(true);
  want.BeginRay(RayKind::kPrimary, kNoParent, 0, 2, 1);
  want.AddVisit(CellId(0), 2 + 5 + 1 + 4, 1.f, 3.f);
  want.AddVisit(CellId(1), 7, 4.f, 5.f);
  want.BeginRay(RayKind::kShadow, 0, 0, 2, 1);
  want.AddVisit(CellId(0), 1, 0.f, 0.f);  // the dropped visit's sample: before the next one
  want.AddVisit(CellId(1), 2, .5f, 1.f);
  want.BeginRay(RayKind::kReflection, 0, 1, 2, 1);
  want.AddVisit(CellId(1), 3, 0.f, 1.f);
  EXPECT_EQ(out, want);
  EXPECT_EQ(out.first_id(), 0u);
  // The next batch of the frame continues the closed-up ids.
  RayBatch next(true);
  next.set_first_id(4);
  next.BeginRay(RayKind::kPrimary, kNoParent, 0, 3, 1);
  next.AddVisit(CellId(5), 1, 0.f, 1.f);
  EXPECT_EQ(g.Regroup(next).first_id(), 3u);
  // A primary ray with samples in empty cells only cannot come from a capture.
  RayRegrouper h(map);
  RayBatch bad(true);
  bad.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  bad.AddVisit(CellId(2), 1, 0.f, 1.f);
  EXPECT_THROW(h.Regroup(bad), InputError);
}

}  // namespace
}  // namespace raycell
