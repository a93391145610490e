#include "engine/stats.h"

#include <gtest/gtest.h>

#include <limits>
#include <sstream>

namespace raycell {
namespace {

StatsTable Small() {
  StatsTable t;
  t.AddCount("fetches", 42)
      .AddReal("utilisation", 0.1)
      .AddText("scheduler", "peel, \"greedy\"")
      .AddCount("bytes", 18446744073709551615u)
      .AddReal("ratio", 1e300);
  return t;
}

TEST(StatsTable, KeepsOrderAndFinds) {
  const StatsTable t = Small();
  ASSERT_EQ(t.size(), 5u);
  EXPECT_EQ(t.entries()[2].key, "scheduler");
  ASSERT_NE(t.Find("fetches"), nullptr);
  EXPECT_EQ(std::get<std::uint64_t>(*t.Find("fetches")), 42u);
  EXPECT_EQ(t.Find("missing"), nullptr);
}

TEST(StatsTable, FormatsRealsShortestRoundTrip) {
  EXPECT_EQ(FormatValue(0.1), "0.1");
  EXPECT_EQ(FormatValue(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(FormatValue(2.0), "2");
  EXPECT_EQ(FormatValue(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(FormatValue(-std::numeric_limits<double>::infinity()), "-inf");
}

TEST(StatsPrinters, Text) {
  EXPECT_EQ(ToText(Small()),
            "fetches      42\n"
            "utilisation  0.1\n"
            "scheduler    peel, \"greedy\"\n"
            "bytes        18446744073709551615\n"
            "ratio        1e+300\n");
}

TEST(StatsPrinters, Json) {
  EXPECT_EQ(ToJson(Small()),
            "{\n"
            "  \"fetches\": 42,\n"
            "  \"utilisation\": 0.1,\n"
            "  \"scheduler\": \"peel, \\\"greedy\\\"\",\n"
            "  \"bytes\": 18446744073709551615,\n"
            "  \"ratio\": 1e+300\n"
            "}\n");
}

TEST(StatsPrinters, Csv) {
  EXPECT_EQ(ToCsv(Small()),
            "fetches,utilisation,scheduler,bytes,ratio\n"
            "42,0.1,\"peel, \"\"greedy\"\"\",18446744073709551615,1e+300\n");
}

TEST(StatsPrinters, CsvRowsForSweeps) {
  std::ostringstream os;
  StatsTable a, b;
  a.AddCount("n", 1).AddText("name", "a\nb");
  b.AddCount("n", 2).AddText("name", "plain");
  PrintCsvHeader(a, os);
  PrintCsvRow(a, os);
  PrintCsvRow(b, os);
  EXPECT_EQ(os.str(), "n,name\n1,\"a\nb\"\n2,plain\n");
}

TEST(StatsPrinters, JsonEscapesControlsAndNonFinite) {
  StatsTable t;
  t.AddText("k\"\\", std::string("tab\there\x01", 9))
      .AddReal("nan", std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(ToJson(t),
            "{\n"
            "  \"k\\\"\\\\\": \"tab\\there\\u0001\",\n"
            "  \"nan\": null\n"
            "}\n");
  EXPECT_EQ(ToJson(StatsTable()), "{}\n");
  EXPECT_EQ(ToText(StatsTable()), "");
}

TEST(StatsTableDeathTest, DuplicateKeyIsACheckFailure) {
  StatsTable t;
  t.AddCount("x", 1);
  EXPECT_DEATH(t.AddReal("x", 2.0), "CHECK failed");
}

}  // namespace
}  // namespace raycell
