#include "traces/ray_batch.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/cell_list.h"

namespace raycell {
namespace {

// Three rays: a primary with two visits, a shadow ray spawned at its second visit, and a
// reflection ray spawned at its first.
RayBatch SmallBatch(bool store_t) {
  RayBatch b(store_t);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 4, 5);
  b.AddVisit(CellId(3), 10, 0.5f, 1.5f);
  b.AddVisit(CellId(4), 20, 1.5f, 2.5f);
  b.BeginRay(RayKind::kShadow, 0, 1, 4, 5);
  b.AddVisit(CellId(4), 7, 0.f, 0.25f);
  b.BeginRay(RayKind::kReflection, 0, 0, 4, 5);
  b.AddVisit(CellId(3), 1, 0.f, 0.1f);
  b.AddVisit(CellId(0), 2, 0.1f, 0.2f);
  b.AddVisit(CellId(1), 3, 0.2f, 0.3f);
  return b;
}

TEST(RayBatchTest, BeginRayAndAddVisitFillColumnsAndViews) {
  const RayBatch b = SmallBatch(true);
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b.visit_count(), 6u);
  EXPECT_EQ(b.cells(), (testing::CellList{3, 4, 4, 3, 0, 1}));
  EXPECT_EQ(b.samples(), (std::vector<std::uint32_t>{10, 20, 7, 1, 2, 3}));
  EXPECT_EQ(b.visit_begin(2), 3u);
  EXPECT_EQ(b.visit_end(2), 6u);
  const RayView r = b.ray(1);
  EXPECT_EQ(r.id, 1u);
  EXPECT_EQ(r.parent, 0u);
  EXPECT_EQ(r.spawn, 1u);
  EXPECT_EQ(r.kind, RayKind::kShadow);
  EXPECT_FALSE(r.is_primary());
  ASSERT_EQ(r.visit_count, 1u);
  EXPECT_EQ(r.visit(0), (Visit{CellId(4), 7, 0.f, 0.25f}));
  EXPECT_TRUE(b.ray(0).is_primary());
}

TEST(RayBatchTest, WithoutTViewsHaveNoTAndVisitsReadZero) {
  const RayBatch b = SmallBatch(false);
  EXPECT_TRUE(b.t_enters().empty());
  EXPECT_EQ(b.ray(0).t_enter, nullptr);
  EXPECT_EQ(b.ray(0).visit(1), (Visit{CellId(4), 20, 0.f, 0.f}));
}

TEST(RayBatchTest, AddSamplesToLastVisit) {
  RayBatch b = SmallBatch(false);
  b.AddSamplesToLastVisit(5);
  EXPECT_EQ(b.samples().back(), 8u);
}

TEST(RayBatchTest, PopRayRemovesTheLastRayAndItsVisits) {
  RayBatch b = SmallBatch(true);
  RayBatch two(true);
  two.BeginRay(RayKind::kPrimary, kNoParent, 0, 4, 5);
  two.AddVisit(CellId(3), 10, 0.5f, 1.5f);
  two.AddVisit(CellId(4), 20, 1.5f, 2.5f);
  two.BeginRay(RayKind::kShadow, 0, 1, 4, 5);
  two.AddVisit(CellId(4), 7, 0.f, 0.25f);
  b.PopRay();
  EXPECT_EQ(b, two);
  b.BeginRay(RayKind::kRefraction, 1, 0, 1, 1);  // a ray without visits
  b.PopRay();
  EXPECT_EQ(b, two);
  b.PopRay();
  b.PopRay();
  EXPECT_TRUE(b.empty());
  EXPECT_EQ(b, RayBatch(true));
}

TEST(RayBatchTest, AppendRebasedKeepsParentsPointingAtTheSameRays) {
  RayBatch a = SmallBatch(false);
  RayBatch other = SmallBatch(false);
  other.set_first_id(100);  // other's parents are relative to 100
  RayBatch shifted(false);
  shifted.set_first_id(100);
  shifted.BeginRay(RayKind::kPrimary, kNoParent, 0, 1, 2);
  shifted.AddVisit(CellId(2), 2, 0, 0);
  shifted.BeginRay(RayKind::kShadow, 100, 0, 1, 2);
  shifted.AddVisit(CellId(2), 1, 0, 0);
  a.AppendRebased(shifted);
  ASSERT_EQ(a.size(), 5u);
  EXPECT_EQ(a.ray(3).parent, kNoParent);
  EXPECT_EQ(a.ray(4).parent, 3u);  // was 100 = first ray of `shifted`
  EXPECT_EQ(a.ray(4).id, 4u);
  EXPECT_EQ(a.visit_begin(3), 6u);
  EXPECT_EQ(a.cells().back(), CellId(2));
  RayBatch c(false);
  c.set_first_id(10);
  c.AppendRebased(SmallBatch(false));
  EXPECT_EQ(c.ray(2).parent, 10u);
}

TEST(RayBatchTest, AppendRebasedOfSplitBatchEqualsWhole) {
  std::mt19937 rng(7);
  RayBatch whole(true);
  for (int i = 0; i < 200; ++i) {
    const bool primary = i == 0 || rng() % 4 == 0;
    const RayId parent = primary ? kNoParent : rng() % i;
    whole.BeginRay(primary ? RayKind::kPrimary : RayKind::kShadow, parent, 0, rng() % 9, i);
    for (unsigned v = 0; v < rng() % 4; ++v)
      whole.AddVisit(CellId(rng() % 27), rng() % 50, v, v + 1);
  }
  RayBatch first(true), second(true), joined(true);
  for (std::size_t i = 0; i < whole.size(); ++i) {
    RayBatch& part = i < 120 ? first : second;
    const RayView r = whole.ray(i);
    part.BeginRay(r.kind, r.parent, r.spawn, r.pixel_x, r.pixel_y);
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      const Visit x = r.visit(v);
      part.AddVisit(x.cell, x.samples, x.t_enter, x.t_exit);
    }
  }
  second.set_first_id(120);
  joined.AppendRebased(first);
  joined.AppendRebased(second);
  EXPECT_EQ(joined, whole);
}

TEST(RayBatchTest, EqualityLooksAtEveryColumn) {
  const RayBatch a = SmallBatch(true);
  EXPECT_EQ(a, SmallBatch(true));
  EXPECT_NE(a, SmallBatch(false));
  RayBatch b = SmallBatch(true);
  b.set_first_id(1);
  EXPECT_NE(a, b);
  b = SmallBatch(true);
  b.AddSamplesToLastVisit(1);
  EXPECT_NE(a, b);
  b = SmallBatch(true);
  b.PopRay();
  b.BeginRay(RayKind::kReflection, 0, 0, 4, 5);
  b.AddVisit(CellId(3), 1, 0.f, 0.1f);
  b.AddVisit(CellId(0), 2, 0.1f, 0.2f);
  b.AddVisit(CellId(1), 3, 0.2f, 0.3001f);
  EXPECT_NE(a, b);
  b.PopRay();
  b.BeginRay(RayKind::kRefraction, 0, 0, 4, 5);
  b.AddVisit(CellId(3), 1, 0.f, 0.1f);
  b.AddVisit(CellId(0), 2, 0.1f, 0.2f);
  b.AddVisit(CellId(1), 3, 0.2f, 0.3f);
  EXPECT_NE(a, b);
}

TEST(RayBatchTest, ClearAndKindNames) {
  RayBatch b = SmallBatch(true);
  b.Clear();
  EXPECT_TRUE(b.empty());
  EXPECT_EQ(b.visit_count(), 0u);
  for (int k = 0; k < kRayKindCount; ++k) {
    EXPECT_EQ(ParseRayKind(ToString(RayKind(k))), RayKind(k));
  }
  EXPECT_EQ(ParseRayKind("diffuse"), std::nullopt);
}

}  // namespace
}  // namespace raycell

namespace raycell {
namespace {

TEST(RayBatchRebase, ShiftsIdsAndInsideParentsOnly) {
  RayBatch b(false);
  b.set_first_id(10);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  b.AddVisit(CellId(1), 1, 0, 0);
  b.BeginRay(RayKind::kShadow, 10, 0, 0, 0);  // parent inside the batch
  b.AddVisit(CellId(1), 1, 0, 0);
  b.BeginRay(RayKind::kShadow, 3, 0, 0, 0);  // parent before the batch
  b.AddVisit(CellId(2), 1, 0, 0);
  b.Rebase(100);
  EXPECT_EQ(b.first_id(), 100u);
  EXPECT_EQ(b.ray(0).id, 100u);
  EXPECT_EQ(b.parents()[0], kNoParent);
  EXPECT_EQ(b.parents()[1], 100u);
  EXPECT_EQ(b.parents()[2], 3u);
}

}  // namespace
}  // namespace raycell
