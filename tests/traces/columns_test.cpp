// The column codec (traces/columns.h): any column encoded then decoded is identical, for
// random columns and for the edge values of each coding (escapes at 254/255, 64-bit
// extremes, zero runs of every length up to the bijective digits' carries).
#include "traces/columns.h"

#include <capnp/message.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace raycell {
namespace {

using Values = std::vector<std::uint64_t>;

constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();

Values Decode(schema::Column::Reader column, std::size_t n) {
  ColumnReader reader(column, n, "test");
  Values out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(reader.Next());
  reader.Finish();
  return out;
}

Values RoundTrip(const Values& values) {
  ColumnBuilder builder;
  for (std::uint64_t v : values) builder.Add(v);
  capnp::MallocMessageBuilder message;
  auto column = message.initRoot<schema::Column>();
  builder.Fill(column);
  // Narrow bytes are the values below 255, escapes otherwise; one wide word per escape.
  std::size_t escapes = 0;
  for (std::uint64_t v : values) escapes += v >= 255;
  EXPECT_EQ(column.getWide().size(), escapes);
  EXPECT_EQ(builder.bytes(), values.size() + 8 * escapes);
  return Decode(column.asReader(), values.size());
}

Values ZeroRunRoundTrip(const Values& values, std::size_t* stored = nullptr) {
  ZeroRunColumnBuilder builder;
  for (std::uint64_t v : values) builder.Add(v);
  builder.Finish();
  capnp::MallocMessageBuilder message;
  auto column = message.initRoot<schema::Column>();
  builder.Fill(column);
  if (stored) *stored = column.getNarrow().size();
  ZeroRunColumnReader reader(column.asReader(), "test");
  Values out;
  for (std::size_t i = 0; i < values.size(); ++i) out.push_back(reader.Next());
  reader.Finish();
  return out;
}

// Random values drawn from a mix of scales, so that escapes, small values and zero runs
// all occur.
Values RandomValues(std::mt19937_64& rng, std::size_t n, std::uint64_t max) {
  Values v;
  for (std::size_t i = 0; i < n; ++i) {
    switch (rng() % 6) {
      case 0:
        v.push_back(0);
        break;
      case 1:
        v.insert(v.end(), rng() % 300, 0);  // a zero run
        break;
      case 2:
        v.push_back(rng() % 4);
        break;
      case 3:
        v.push_back(250 + rng() % 10);
        break;
      case 4:
        v.push_back(rng() % (std::uint64_t{1} << (rng() % 40)));
        break;
      default:
        v.push_back(max - rng() % 3);
    }
  }
  return v;
}

TEST(ColumnsTest, RandomColumnsRoundTrip) {
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 300; ++trial) {
    const Values v = RandomValues(rng, rng() % 400, kMax);
    ASSERT_EQ(RoundTrip(v), v) << "trial " << trial;
  }
}

TEST(ColumnsTest, RandomZeroRunColumnsRoundTrip) {
  std::mt19937_64 rng(2);
  for (int trial = 0; trial < 300; ++trial) {
    const Values v = RandomValues(rng, rng() % 400, ZeroRunColumnBuilder::kMaxValue);
    ASSERT_EQ(ZeroRunRoundTrip(v), v) << "trial " << trial;
  }
}

TEST(ColumnsTest, EdgeValuesRoundTrip) {
  const Values edges{0, 1, 253, 254, 255, 256, 0xFFFFFFFF, std::uint64_t{1} << 32, kMax - 1, kMax};
  EXPECT_EQ(RoundTrip(edges), edges);
  EXPECT_EQ(RoundTrip({}), Values{});
  Values zero_run_edges = edges;
  zero_run_edges.pop_back();  // kMax + 1 does not fit: the zero-run coding stops at kMax - 1
  EXPECT_EQ(ZeroRunRoundTrip(zero_run_edges), zero_run_edges);
  EXPECT_EQ(ZeroRunRoundTrip({}), Values{});
}

TEST(ColumnsTest, ZeroRunsOfEveryLengthRoundTripInTheirDigitCount) {
  for (std::size_t n = 1; n <= 1100; ++n) {
    // Alone, between values, and next to values 1 and 2 (stored as 2 and 3, the first
    // codes that are not digits).
    for (const Values& v : {Values(n, 0), [&] {
                              Values w{1};
                              w.insert(w.end(), n, 0);
                              w.push_back(2);
                              return w;
                            }()}) {
      std::size_t stored = 0;
      ASSERT_EQ(ZeroRunRoundTrip(v, &stored), v) << n << " zeros";
      // A run of n zeros takes floor(log2(n + 1)) digits (bijective base 2).
      std::size_t digits = 0;
      for (std::size_t m = n + 1; m > 1; m /= 2) ++digits;
      ASSERT_EQ(stored, digits + (v.size() - n)) << n << " zeros";
    }
  }
}

TEST(ColumnsTest, ZigZagIsABijectionOnTheEdges) {
  for (std::int64_t d :
       {std::int64_t{0}, std::int64_t{-1}, std::int64_t{1},
        std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max()}) {
    EXPECT_EQ(UnZigZag(ZigZag(d)), d);
  }
  EXPECT_EQ(ZigZag(0), 0u);
  EXPECT_EQ(ZigZag(-1), 1u);
  EXPECT_EQ(ZigZag(1), 2u);
  EXPECT_EQ(ZigZag(-2), 3u);
  EXPECT_EQ(ApplyDelta(5, ZigZag(Delta(3, 5)), "x"), 3u);
  EXPECT_EQ(ApplyDelta(0, ZigZag(0xFFFFFFFF), "x"), 0xFFFFFFFFu);
  EXPECT_THROW(ApplyDelta(0, ZigZag(-1), "x"), BadTraceData);
  EXPECT_THROW(ApplyDelta(0xFFFFFFFF, ZigZag(1), "x"), BadTraceData);
}

TEST(ColumnsTest, ReaderRejectsColumnsThatDisagreeWithTheirUse) {
  capnp::MallocMessageBuilder message;
  auto column = message.initRoot<schema::Column>();
  auto narrow = column.initNarrow(3);
  narrow.set(0, 7);
  narrow.set(1, 255);
  narrow.set(2, 255);
  column.initWide(1).set(0, 1000);
  ColumnReader reader(column.asReader(), "c");
  EXPECT_EQ(reader.Next(), 7u);
  EXPECT_EQ(reader.Next(), 1000u);
  try {
    reader.Next();
    ADD_FAILURE() << "an escape without a wide value was read";
  } catch (const BadTraceData& e) {
    EXPECT_STREQ(e.what(), "column c: bad escape");
  }
  EXPECT_THROW(ColumnReader(column.asReader(), 2, "c"), BadTraceData);
  ColumnReader unread(column.asReader(), "c");
  EXPECT_THROW(unread.Finish(), BadTraceData);
}

}  // namespace
}  // namespace raycell
