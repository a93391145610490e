#include "base/table.h"

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

TEST(StatsPrinters, TextAlignsValuesAndPrintsStringsAndNumbersExactly) {
  EXPECT_EQ(ToText(Small()),
            "fetches      42\n"
            "utilisation  0.1\n"
            "scheduler    peel, \"greedy\"\n"
            "bytes        18446744073709551615\n"
            "ratio        1e+300\n");
}

TEST(StatsPrinters, JsonEscapesQuotesAndPrintsNumbersExactly) {
  EXPECT_EQ(ToJson(Small()),
            "{\n"
            "  \"fetches\": 42,\n"
            "  \"utilisation\": 0.1,\n"
            "  \"scheduler\": \"peel, \\\"greedy\\\"\",\n"
            "  \"bytes\": 18446744073709551615,\n"
            "  \"ratio\": 1e+300\n"
            "}\n");
}

TEST(StatsPrinters, CsvQuotesFieldsWithCommasOrQuotesAndPrintsNumbersExactly) {
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

// A replay-like table: fixed decimals, no value, a flag and a list of per-level tables, as
// one JSON line (nested), CSV and text (flattened into NAME_KEY columns).
StatsTable Levels() {
  StatTables levels(2);
  levels[0].AddText("name", "cache").AddCount("fetches", 3).AddCount("bytes", 300);
  levels[1].AddText("name", "board").AddCount("fetches", 1).AddCount("bytes", 100);
  StatsTable t;
  t.AddInt("frame", -2)
      .AddCount("fetches", 3)
      .AddNone("bound")
      .AddFixed("utilisation", 0.04044, 4)
      .AddBool("converged", false)
      .AddTables("levels", levels);
  return t;
}

TEST(StatsPrinters, FixedNoneBoolAndNestedTables) {
  const StatsTable t = Levels();
  EXPECT_EQ(ToJsonLine(t),
            "{\"frame\":-2,\"fetches\":3,\"bound\":null,\"utilisation\":0.0404,\"converged\":false,"
            "\"levels\":[{\"name\":\"cache\",\"fetches\":3,\"bytes\":300},"
            "{\"name\":\"board\",\"fetches\":1,\"bytes\":100}]}");
  EXPECT_EQ(ToCsv(t),
            "frame,fetches,bound,utilisation,converged,cache_fetches,cache_bytes,board_fetches,"
            "board_bytes\n-2,3,,0.0404,false,3,300,1,100\n");
  EXPECT_EQ(ToText(t),
            "frame          -2\n"
            "fetches        3\n"
            "bound          -\n"
            "utilisation    0.0404\n"
            "converged      false\n"
            "cache_fetches  3\n"
            "cache_bytes    300\n"
            "board_fetches  1\n"
            "board_bytes    100\n");
  EXPECT_EQ(ToJson(StatsTable().AddFixed("x", 2.5, 2).AddNone("y")),
            "{\n  \"x\": 2.50,\n  \"y\": null\n}\n");
  EXPECT_EQ(t.Count("fetches"), 3u);
  EXPECT_EQ(t.Real("utilisation"), 0.04044);  // the value, not its printed form
  EXPECT_EQ(ToCsvHeader(t) + ToCsvRow(t), ToCsv(t));
}

TEST(StatsTableDeathTest, DuplicateKeyIsACheckFailure) {
  StatsTable t;
  t.AddCount("x", 1);
  EXPECT_DEATH(t.AddReal("x", 2.0), "CHECK failed");
}

}  // namespace
}  // namespace raycell
