// A capture's character on a hand-made trace whose figures are counted by hand.
#include "analysis/character.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "tests/test_util.h"
#include "tests/traces/trace_test_util.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

// 3x1x1 cells, a 2x1 image, two frames.
// Frame 10: ray 0 (primary) visits cells 0, 1, 0, 2: nodes A(0) gen 1, B(1) gen 1, C(0) gen 2,
// D(2) gen 1; ray 1 (reflection, spawned at ray 0's visit 1 in cell 1) visits 1, 2: a node
// E(2) under B, gen 1; ray 2 (shadow, spawned at visit 3 in cell 2) stays in D; ray 3
// (primary) visits 2: F(2) gen 1. maxGen: cell 0 2, cell 1 1, cell 2 1.
// Frame 11: ray 0 (primary) visits cell 1: maxGen cell 1 1.
std::string WriteCharacterTrace() {
  TraceHeader h = testing::TestHeader({3, 1, 1}, false, 2);
  h.settings.width = 2;
  h.settings.height = 1;
  const std::string path = testing::TempPath("character", "t.rct");
  std::remove(path.c_str());
  TraceWriter w = TraceWriter::Create(path, h);
  w.BeginFrame(10);
  RayBatch a(false);
  a.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  for (std::uint32_t c : {0u, 1u, 0u, 2u}) a.AddVisit(CellId(c), 5, 0, 0);
  a.BeginRay(RayKind::kReflection, 0, 1, 0, 0);
  a.AddVisit(CellId(1), 3, 0, 0);
  a.AddVisit(CellId(2), 3, 0, 0);
  a.BeginRay(RayKind::kShadow, 0, 3, 0, 0);
  a.AddVisit(CellId(2), 2, 0, 0);
  a.BeginRay(RayKind::kPrimary, kNoParent, 0, 1, 0);
  a.AddVisit(CellId(2), 7, 0, 0);
  w.Append(a);
  w.EndFrame();
  w.BeginFrame(11);
  RayBatch b(false);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 1, 0);
  b.AddVisit(CellId(1), 4, 0, 0);
  w.Append(b);
  w.EndFrame();
  w.Finish();
  return path;
}

TEST(CaptureCharacterTest, CountsRaysAndMaxGenerationsAsCountedByHand) {
  const std::string path = WriteCharacterTrace();
  const TraceReader r = TraceReader::OpenStored(path);
  for (unsigned threads : {1u, 2u}) {
    const CaptureCharacter c = Characterize(r, threads);
    EXPECT_EQ(c.frames, 2u);
    EXPECT_EQ(c.rays, 5u);
    EXPECT_EQ(c.visits, 9u);
    EXPECT_DOUBLE_EQ(c.rays_per_pixel(), 5.0 / 4.0);   // 5 rays over 2 pixels x 2 frames
    EXPECT_DOUBLE_EQ(c.secondary_share(), 2.0 / 5.0);  // a reflection and a shadow ray
    EXPECT_DOUBLE_EQ(c.visits_per_ray(), 9.0 / 5.0);
    EXPECT_EQ(c.busy_cells, 4u);   // 3 cells in frame 10, 1 in frame 11
    EXPECT_EQ(c.max_gen_sum, 5u);  // 2 + 1 + 1, then 1
    EXPECT_EQ(c.max_gen_largest, 2u);
    EXPECT_DOUBLE_EQ(c.mean_max_gen(), 5.0 / 4.0);
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace raycell
