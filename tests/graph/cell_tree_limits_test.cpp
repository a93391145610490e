// The Cell Tree keeps arrays indexed by cell, so the builder bounds cells as the trace format
// does (kTraceMaxCells): a JSON Lines path with cell 4000000000 made `analyze --paths`
// allocate 15 GB and run for two minutes (found by fuzz/jsonl.cpp; the input is kept in
// fuzz/corpus/jsonl/).
#include <gtest/gtest.h>

#include "graph/cell_tree.h"
#include "tests/test_util.h"
#include "traces/format.h"

namespace raycell {
namespace {

RayBatch OneRay(CellId a, CellId b) {
  RayBatch rays(false);
  rays.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  rays.AddVisit(a, 1, 0, 0);
  rays.AddVisit(b, 1, 0, 0);
  return rays;
}

TEST(CellTreeLimitsTest, CellsBeyondTheLargestGridAreRefused) {
  CellTreeBuilder builder;
  EXPECT_EQ(testing::ErrorOf([&] { builder.AddBatch(OneRay(CellId(1), CellId(4000000000u))); }),
            "ray 0: cell 4000000000 is beyond the largest cell grid (16777216 cells, "
            "kTraceMaxCells)");
  CellTreeBuilder at_limit;
  at_limit.AddBatch(OneRay(CellId(0), static_cast<CellId>(kTraceMaxCells - 1)));
  EXPECT_EQ(at_limit.Finish().cell_count(), kTraceMaxCells);
}

}  // namespace
}  // namespace raycell
