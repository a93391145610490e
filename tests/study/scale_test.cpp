// The study's scale section (study/scale.h): the log-log fit, and the section run through
// the raycell binary on tiny points.
#include "study/scale.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace raycell {
namespace {

TEST(Scale, LogLogSlopeIsTheExponentOfAPowerLaw) {
  // y = 3 x^1.5 and y = 7 x^-0.5, written out: the fit returns the exponent.
  EXPECT_NEAR(LogLogSlope({1, 4, 16, 100}, {3, 24, 192, 3000}), 1.5, 1e-12);
  EXPECT_NEAR(LogLogSlope({1, 4, 100}, {7, 3.5, 0.7}), -0.5, 1e-12);
  // A constant has slope 0; so has a single x.
  EXPECT_NEAR(LogLogSlope({2, 20}, {5, 5}), 0.0, 1e-12);
  EXPECT_EQ(LogLogSlope({8, 8}, {1, 2}), 0.0);
  // (1, 1), (e, e^2), (e^2, e^2): log points (0,0), (1,2), (2,2); least squares: slope 1.
  const double e = std::exp(1.0);
  EXPECT_NEAR(LogLogSlope({1, e, e * e}, {1, e * e, e * e}), 1.0, 1e-12);
}

ScaleOptions Tiny(const std::string& out) {
  ScaleOptions o;
  o.scene = "builtin";
  o.binary = RAYCELL_BINARY;
  o.out = out;
  o.res = {"16x16", "32x32"};
  o.cells_at = "2x2x2";
  o.cells = {"1x1x1", "2x2x2"};
  o.res_at = "16x16";
  o.frames = 1;
  return o;
}

TEST(Scale, MeasuresEachCommandAtEachPointAsItsOwnProcess) {
  const auto out = testing::TempDir("scale_section");
  const ScaleStudy s = MeasureScale(Tiny(out.string()));
  ASSERT_TRUE(s.measured) << s.not_measured;
  // (16x16, 2x2x2) is in both series and measured once.
  ASSERT_EQ(s.points.size(), 3u);
  EXPECT_EQ(s.visits_series, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(s.cells_series, (std::vector<std::size_t>{2, 0}));
  EXPECT_EQ(s.points[2].cells, "1x1x1");
  EXPECT_EQ(s.points[2].cell_count, 1u);
  EXPECT_EQ(s.points[0].cell_count, 8u);
  // Four times the pixels, about four times the visits (the rays of a 2x2 block of pixels).
  EXPECT_GT(s.points[1].visits, 3 * s.points[0].visits);
  EXPECT_LT(s.points[1].visits, 5 * s.points[0].visits);
  for (const ScalePoint& p : s.points) {
    ASSERT_EQ(p.runs.size(), ScaleCommands().size());
    EXPECT_TRUE(std::filesystem::exists(out / (p.res + "_" + p.cells + ".rct")));
    for (const ScaleRun& r : p.runs) {
      EXPECT_GT(r.seconds, 0.0);
      // A child's own peak, not its parent's: more than a few MB, less than this test's
      // budget would allow a leak (a tiny capture needs well under 1 GB).
      EXPECT_GT(r.peak_kb, 4000u);
      EXPECT_LT(r.peak_kb, 1000000u);
    }
  }
  ASSERT_EQ(s.slopes.size(), ScaleCommands().size());
  for (const ScaleSlope& sl : s.slopes) EXPECT_TRUE(std::isfinite(sl.time_on_visits));
  const std::string csv = ScaleCsv(s);
  EXPECT_NE(csv.find("\n16x16,2x2x2,8," + std::to_string(s.points[0].visits) + ",both,record,"),
            std::string::npos)
      << csv;
  EXPECT_NE(ScaleReport(s).find("| 32x32 | 2x2x2 | " + std::to_string(s.points[1].visits)),
            std::string::npos);
  std::filesystem::remove_all(out);
}

TEST(Scale, AFailingCommandLeavesTheSectionNotMeasuredNamingIt) {
  const auto out = testing::TempDir("scale_failing");
  ScaleOptions o = Tiny(out.string());
  o.scene = (out / "missing.vdb").string();
  const ScaleStudy s = MeasureScale(o);
  EXPECT_FALSE(s.measured);
  EXPECT_TRUE(s.points.empty());
  EXPECT_NE(s.not_measured.find("`raycell record --scene " + o.scene), std::string::npos)
      << s.not_measured;
  EXPECT_NE(s.not_measured.find("exit 2"), std::string::npos) << s.not_measured;
  EXPECT_NE(ScaleReport(s).find("Not measured: `raycell record"), std::string::npos);
  o.binary.clear();
  EXPECT_FALSE(MeasureScale(o).measured);
  std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace raycell
