// The column codec (traces/columns.h): any column encoded then decoded is identical, for
// random columns and for the edge values of each coding (escapes at 254/255, 64-bit
// extremes, zero runs of every length up to the bijective digits' carries). Format 6's range
// coded samples (traces/sample_coder.h): any values in any contexts round trip, a code must
// end at its last byte, and any bytes decode to bounded values.
#include "traces/columns.h"

#include <capnp/message.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "traces/sample_coder.h"

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

// ---- Format 6's sample code ---------------------------------------------------------------

struct Coded {
  std::vector<unsigned> contexts;
  Values values;
  std::vector<std::uint8_t> code;
};

// `n` values, mostly small (as residuals are), some of any size up to the largest, each in a
// random context, encoded.
Coded EncodeRandom(std::mt19937_64& rng, std::size_t n) {
  Coded c;
  SampleEncoder encoder;
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned context = static_cast<unsigned>(rng() % SampleContext::kCount);
    std::uint64_t v = rng() % 4;
    if (rng() % 8 == 0) v = rng() % 300;
    if (rng() % 64 == 0) v = rng() % (SampleModels::kMaxValue + 1);
    if (rng() % 256 == 0) v = SampleModels::kMaxValue;
    c.contexts.push_back(context);
    c.values.push_back(v);
    encoder.Add(context, v);
  }
  encoder.Finish();
  c.code = encoder.code();
  return c;
}

Values Decode(const Coded& c, const std::vector<std::uint8_t>& code) {
  SampleDecoder decoder(code.data(), code.size());
  Values out;
  for (const unsigned context : c.contexts) out.push_back(decoder.Next(context));
  decoder.Finish();
  return out;
}

TEST(SampleCoderTest, RandomValuesInRandomContextsRoundTrip) {
  std::mt19937_64 rng(3);
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{5}, std::size_t{20000}}) {
    const Coded c = EncodeRandom(rng, n);
    EXPECT_EQ(Decode(c, c.code), c.values) << n << " values";
  }
}

TEST(SampleCoderTest, TheCodeMustEndAtItsLastByte) {
  std::mt19937_64 rng(4);
  const Coded c = EncodeRandom(rng, 3000);
  std::vector<std::uint8_t> shorter(c.code.begin(), c.code.end() - 1), longer = c.code;
  longer.push_back(0);
  EXPECT_THROW(Decode(c, shorter), BadTraceData);
  EXPECT_THROW(Decode(c, longer), BadTraceData);
  EXPECT_THROW(Decode(c, {}), BadTraceData);
}

// Whatever the bytes, each value decodes in a bounded number of steps to at most 2^41 - 2
// (the reader then checks it as a residual or as samples).
TEST(SampleCoderTest, AnyBytesDecodeToBoundedValues) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<std::uint8_t> bytes(rng() % 200);
    for (std::uint8_t& b : bytes) b = static_cast<std::uint8_t>(rng());
    if (trial % 2) std::fill(bytes.begin(), bytes.end(), 0xFF);  // every length bit 1
    SampleDecoder decoder(bytes.data(), bytes.size());
    for (int i = 0; i < 2000; ++i) {
      const std::uint64_t v = decoder.Next(static_cast<unsigned>(rng() % SampleContext::kCount));
      ASSERT_LE(v, (std::uint64_t{1} << 41) - 2);
    }
  }
}

// The models adapt: a context's value seen again and again costs ever less, down to the
// probability's bound (15/2048 for the other bit: 0.0106 bits a value), so 100000 zeros
// take about 133 bytes.
TEST(SampleCoderTest, RepeatedValuesCostAlmostNothing) {
  SampleEncoder encoder;
  for (int i = 0; i < 100000; ++i) encoder.Add(7, 0);
  encoder.Finish();
  EXPECT_LE(encoder.code().size(), 160u);
  EXPECT_GE(encoder.code().size(), 120u);
}

}  // namespace
}  // namespace raycell
