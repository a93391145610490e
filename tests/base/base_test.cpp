// base/: parsing edge cases, atomic writes (the temporary never survives a failure, the old
// file is kept), formatting and the hash whose values the trace format depends on.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "base/file.h"
#include "base/format.h"
#include "base/hash.h"
#include "base/parse.h"
#include "tests/test_util.h"

namespace raycell {
namespace {

using testing::ErrorOf;
using testing::ReadBytes;
using testing::TempPath;

TEST(Parse, TrimRemovesWhiteSpaceAtBothEndsOnly) {
  EXPECT_EQ(Trim(""), "");
  EXPECT_EQ(Trim(" \t\n"), "");
  EXPECT_EQ(Trim(" a b\t"), "a b");
}

TEST(Parse, JoinPutsTheSeparatorBetweenEachTwoParts) {
  EXPECT_EQ(Join({}, ", "), "");
  EXPECT_EQ(Join({"a"}, ", "), "a");
  EXPECT_EQ(Join({"a", "b", "c"}, ", "), "a, b, c");
  EXPECT_EQ(Join({"", "b", ""}, ","), ",b,");
  EXPECT_EQ(Join(Split("x,,y", ','), ","), "x,,y");  // the inverse of Split
}

TEST(Parse, SplitKeepsEveryEmptyField) {
  EXPECT_EQ(Split("", ','), std::vector<std::string>{""});
  EXPECT_EQ(Split("a,,b", ','), (std::vector<std::string>{"a", "", "b"}));
  EXPECT_EQ(Split("a,", ','), (std::vector<std::string>{"a", ""}));
  EXPECT_EQ(Split(",", ','), (std::vector<std::string>{"", ""}));
}

TEST(Parse, IntegersAreWholeDecimalNumbersInRange) {
  EXPECT_EQ(ParseInt("-12", "x"), -12);
  EXPECT_EQ(ParseInt("0", "x"), 0);
  EXPECT_EQ(ParseUint("18446744073709551615", "x"), 18446744073709551615ull);
  for (const char* bad : {"", " 1", "1 ", "+1", "1.0", "0x10", "1e3", "abc", "--1"}) {
    EXPECT_NE(ErrorOf([&] { ParseInt(bad, "--opt"); }).find("--opt: '"), std::string::npos) << bad;
  }
  EXPECT_NE(ErrorOf([] { ParseUint("-1", "--n"); }).find("--n"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseUint("18446744073709551616", "--n"); }).find("out of range"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseInt("5", "--n", 1, 4); }).find("--n: 5 is out of range 1..4"),
            std::string::npos);
  std::uint64_t v = 7;
  EXPECT_FALSE(TryParseUint("", &v));
  EXPECT_FALSE(TryParseUint("1a", &v));
  EXPECT_TRUE(TryParseUint("42", &v));
  EXPECT_EQ(v, 42u);
}

TEST(Parse, FrameRangesListEveryFrameAndBadRangesSayWhy) {
  EXPECT_EQ(ParseFrameRange("3"), std::vector<int>{3});
  EXPECT_EQ(ParseFrameRange("2..4"), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(ParseFrameRange("2-4"), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(ParseFrameRange("-2..-1"), (std::vector<int>{-2, -1}));
  EXPECT_NE(ErrorOf([] { ParseFrameRange("4..2"); }).find("ends before it starts"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseFrameRange("0..1000000"); }).find("too many"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseFrameRange("a..b"); }).find("--frames 'a..b'"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseFrameRange(""); }).find("--frames"), std::string::npos);
}

TEST(File, WriteFileAtomicallyReplacesTheFileAndLeavesNoTemporary) {
  const std::string path = TempPath("base", "atomic.txt");
  WriteFileAtomically(path, "first");
  WriteFileAtomically(path, [](std::ostream& out) { out << "second"; });
  EXPECT_EQ(ReadBytes(path), "second");
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  std::filesystem::remove(path);
}

TEST(File, AFailedWriteKeepsTheOldFileAndRemovesTheTemporary) {
  const std::string path = TempPath("base", "kept.txt");
  WriteFileAtomically(path, "old");
  EXPECT_THROW(WriteFileAtomically(path,
                                   [](std::ostream& out) {
                                     out << "half";
                                     throw std::runtime_error("writer failed");
                                   }),
               std::runtime_error);
  EXPECT_EQ(ReadBytes(path), "old");
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  std::filesystem::remove(path);
}

TEST(File, ARenameThatFailsRemovesTheTemporaryAndNamesWhat) {
  // The target is a non-empty folder: rename(2) fails after the temporary was written.
  const std::string dir = TempPath("base", "dir");
  std::filesystem::create_directories(dir + "/inside");
  const std::string message = ErrorOf([&] { WriteFileAtomically(dir, "x", "--out DIR"); });
  EXPECT_NE(message.find("--out DIR: cannot rename"), std::string::npos) << message;
  EXPECT_FALSE(std::filesystem::exists(dir + ".tmp"));
  EXPECT_TRUE(std::filesystem::is_directory(dir + "/inside"));
  std::filesystem::remove_all(dir);
}

TEST(File, AnUnwritableFolderIsAnInputError) {
  const std::string message =
      ErrorOf([] { WriteFileAtomically("/nonexistent-raycell-dir/out.csv", "x", "--out"); });
  EXPECT_NE(message.find("--out: cannot open"), std::string::npos) << message;
}

TEST(Format, JsonCsvAndNumbers) {
  EXPECT_EQ(JsonQuote("a\"b\\c\n\x01"), "\"a\\\"b\\\\c\\n\\u0001\"");
  EXPECT_EQ(CsvField("plain"), "plain");
  EXPECT_EQ(CsvField("a,\"b\""), "\"a,\"\"b\"\"\"");
  EXPECT_EQ(FormatReal(0.1), "0.1");
  EXPECT_EQ(FormatReal(1e300), "1e+300");
  EXPECT_EQ(FormatReal(-1.0 / 0.0), "-inf");
  EXPECT_EQ(FormatFixed(2.5, 2), "2.50");
  EXPECT_EQ(FormatFixed(0.125, 0), "0");
  EXPECT_EQ(FormatHex64(0), "0000000000000000");
  EXPECT_EQ(FormatHex64(0xABCDEF0123456789ull), "abcdef0123456789");
  EXPECT_EQ(FormatHex64(~0ull), "ffffffffffffffff");
}

// Python's repr of the same doubles (Python 3.11).
TEST(Format, PythonFloatIsPythonsRepr) {
  EXPECT_EQ(FormatPythonFloat(1.0), "1.0");
  EXPECT_EQ(FormatPythonFloat(0.0), "0.0");
  EXPECT_EQ(FormatPythonFloat(-0.0), "-0.0");
  EXPECT_EQ(FormatPythonFloat(0.25), "0.25");
  EXPECT_EQ(FormatPythonFloat(1.057131486000003), "1.057131486000003");
  EXPECT_EQ(FormatPythonFloat(-0.08681672025723473), "-0.08681672025723473");
  EXPECT_EQ(FormatPythonFloat(0.000898373563476485), "0.000898373563476485");
  EXPECT_EQ(FormatPythonFloat(0.0001), "0.0001");
  EXPECT_EQ(FormatPythonFloat(0.00001), "1e-05");
  EXPECT_EQ(FormatPythonFloat(1.5e-05), "1.5e-05");
  EXPECT_EQ(FormatPythonFloat(-2.5e-300), "-2.5e-300");
  EXPECT_EQ(FormatPythonFloat(123456.5), "123456.5");
  EXPECT_EQ(FormatPythonFloat(1e15), "1000000000000000.0");
  EXPECT_EQ(FormatPythonFloat(1e16), "1e+16");
  EXPECT_EQ(FormatPythonFloat(1.2345e17), "1.2345e+17");
  EXPECT_EQ(FormatPythonFloat(5e-324), "5e-324");
  EXPECT_EQ(FormatPythonFloat(1.0 / 0.0), "inf");
}

// The hash is part of the trace format: its values must never change. The expected values
// come from an independent Python transcription of the algorithm in traces/trace.capnp
// ("Checksums"), not from this code.
TEST(Hash, ValuesAreStable) {
  EXPECT_EQ(Hash64().Finish(), 0xb6cf3414414875d0ull);
  Hash64 bytes;
  bytes.AddBytes("raycell", 7);
  EXPECT_EQ(bytes.Finish(), 0xefa509afd368aa40ull);
  Hash64 word;
  word.Add(42);
  EXPECT_EQ(word.Finish(), 0x8dc5fc419cd24e33ull);
}

// StreamHash64 over bytes given in any pieces equals AddBytes over all of them at once.
TEST(Hash, StreamHashOfPiecesEqualsAddBytesOfTheWhole) {
  std::string bytes;
  for (int i = 0; i < 61; ++i) bytes += char(i * 37 + 11);
  for (std::size_t n = 0; n <= bytes.size(); ++n) {
    Hash64 whole;
    whole.AddBytes(bytes.data(), n);
    for (std::size_t cut1 = 0; cut1 <= n; cut1 += 3) {
      for (std::size_t cut2 = cut1; cut2 <= n; cut2 += 5) {
        StreamHash64 s;
        s.Add(bytes.data(), cut1);
        s.Add(bytes.data() + cut1, cut2 - cut1);
        s.Add(bytes.data() + cut2, n - cut2);
        ASSERT_EQ(s.Finish(), whole.Finish()) << n << " bytes cut at " << cut1 << ", " << cut2;
      }
    }
  }
  StreamHash64 r;
  r.Add("ray", 3);
  r.Add("cell", 4);
  EXPECT_EQ(r.Finish(), 0xefa509afd368aa40ull);  // AddBytes("raycell") above
}

}  // namespace
}  // namespace raycell
