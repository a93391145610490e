// Sharded analysis end to end: `raycell analyze --frames A..B --part FILE` on disjoint ranges,
// joined by `raycell analyze merge`, gives the bytes of one run over the whole trace; merge
// refuses overlaps, gaps and parts of another trace or other options (docs/design.md §6
// "Sharded analysis").
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/test_util.h"
#include "tests/tools/cli_util.h"

namespace {

using raycell::testing::Raycell;
using raycell::testing::ReadBytes;
using raycell::testing::Result;

std::filesystem::path Dir() {
  static const std::filesystem::path dir = raycell::testing::TempDir("analyze_part");
  return dir;
}

// A 6-frame capture, recorded once per process.
const std::string& Capture() {
  static const std::string trace = [] {
    const std::string t = (Dir() / "six.rct").string();
    const Result r =
        Raycell("record --res 32x32 --cells 2x2x2 --orbit 6:90 --no-images --quiet --out " + t);
    EXPECT_EQ(r.code, 0) << r.out;
    return t;
  }();
  return trace;
}

// Writes the part of frames `range` and returns its path.
std::string Part(const std::string& trace, const std::string& range, const std::string& options,
                 const std::string& name) {
  const std::string part = (Dir() / name).string();
  const Result r = Raycell("analyze " + trace + " --quiet --frames " + range + " --part " + part +
                           " " + options);
  EXPECT_EQ(r.code, 0) << r.out;
  return part;
}

std::string Merge(const std::vector<std::string>& parts, const std::string& out, int* code) {
  std::string args = "analyze merge";
  for (const std::string& p : parts) args += " " + p;
  const Result r = Raycell(args + " --out " + out);
  *code = r.code;
  return r.out;
}

TEST(AnalyzePart, MergedShardsEqualTheOneShotRunByteForByte) {
  const std::string& trace = Capture();
  for (const std::string format : {"json", "csv", "table"}) {
    SCOPED_TRACE(format);
    const std::string options = "--bracket --effort quick --format " + format;
    const Result one = Raycell("analyze " + trace + " --quiet " + options, false);
    ASSERT_EQ(one.code, 0) << one.out;
    ASSERT_NE(one.out.find('5'), std::string::npos);
    if (format == "csv") {  // the search's threads change nothing printed
      EXPECT_EQ(Raycell("analyze " + trace + " --quiet --jobs 1 " + options, false).out, one.out);
      EXPECT_EQ(Raycell("analyze " + trace + " --quiet --jobs 3 " + options, false).out, one.out);
    }
    const std::vector<std::vector<std::string>> shardings = {{"0..2", "3..5"},
                                                             {"4..5", "0..1", "2..3"}};
    for (const auto& ranges : shardings) {
      std::vector<std::string> parts;
      for (const std::string& range : ranges) {
        parts.push_back(Part(trace, range, options, format + "_" + range));
      }
      const std::string out = (Dir() / (format + "_merged")).string();
      int code = 0;
      const std::string msg = Merge(parts, out, &code);
      ASSERT_EQ(code, 0) << msg;
      EXPECT_EQ(ReadBytes(out), one.out) << ranges.size() << " parts";
    }
  }
}

TEST(AnalyzePart, MergeRefusesOverlapsGapsAndPartsOfAnotherAnalysis) {
  const std::string& trace = Capture();
  const std::string csv = "--format csv";
  const std::string a = Part(trace, "0..2", csv, "a"), b = Part(trace, "3..5", csv, "b"),
                    over = Part(trace, "2..4", csv, "over"),
                    late = Part(trace, "4..5", csv, "late"),
                    json = Part(trace, "3..5", "--format json", "json"),
                    exact = Part(trace, "3..5", csv + " --exact", "exact");
  const std::string other = (Dir() / "other.rct").string();
  ASSERT_EQ(
      Raycell("record --res 32x32 --cells 2x2x2 --orbit 6:60 --no-images --quiet --out " + other)
          .code,
      0);
  const std::string foreign = Part(other, "3..5", csv, "foreign");
  const std::string out = (Dir() / "refused.csv").string();
  struct Case {
    std::vector<std::string> parts;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{a, over}, "frames 2..2 are in both"},
      {{b, a, over}, "frames 2..2 are in both"},
      {{a, late}, "frames 3..3 are in none of the parts"},
      {{a, foreign}, "another trace"},
      {{a, json}, "format json against csv"},
      {{a, exact}, "other options"},
      {{a, trace}, "not a part written by `raycell analyze --part`"},
  };
  for (const Case& c : cases) {
    int code = 0;
    const std::string msg = Merge(c.parts, out, &code);
    EXPECT_EQ(code, 2) << msg;
    EXPECT_NE(msg.find(c.message), std::string::npos) << msg;
    EXPECT_FALSE(std::filesystem::exists(out)) << msg;
    EXPECT_FALSE(std::filesystem::exists(out + ".tmp")) << msg;
  }
  int code = 0;
  EXPECT_EQ(Merge({b, a}, out, &code), "");
  EXPECT_EQ(code, 0);
  // A part that lost its last line is incomplete.
  const std::string cut = (Dir() / "cut").string();
  std::string bytes = ReadBytes(b);
  bytes.pop_back();
  raycell::testing::WriteBytes(cut, bytes);
  const std::string msg = Merge({a, cut}, (Dir() / "cut.csv").string(), &code);
  EXPECT_EQ(code, 2);
  EXPECT_NE(msg.find("incomplete"), std::string::npos) << msg;
}

// --frames selects the same frames of a trace and of its JSON Lines.
TEST(AnalyzePart, FramesOfPathsAreThoseOfTheTrace) {
  const std::string& trace = Capture();
  const std::string jsonl = (Dir() / "six.jsonl").string();
  ASSERT_EQ(Raycell("trace cat " + trace + " > " + jsonl).code, 0);
  const Result a = Raycell("analyze " + trace + " --quiet --format csv --frames 2..3", false);
  const Result b = Raycell("analyze --paths " + jsonl + " --format csv --frames 2..3", false);
  ASSERT_EQ(a.code, 0) << a.out;
  EXPECT_EQ(a.out, b.out);
  EXPECT_EQ(std::count(a.out.begin(), a.out.end(), '\n'), 3);  // the header, frames 2 and 3
  EXPECT_EQ(a.out.find("\n1,"), std::string::npos);
  EXPECT_NE(a.out.find("\n3,"), std::string::npos);
}

TEST(AnalyzePart, BadFramesAndPartOptionsAreRefused) {
  const std::string& trace = Capture();
  const std::string part = (Dir() / "bad").string();
  const struct {
    std::string args, message;
  } cases[] = {
      {trace + " --frames 3..1 --part " + part, "ends before it starts"},
      {trace + " --frames 9..12 --part " + part, "no frame in --frames 9..12"},
      {trace + " --frames 0..1 --frame 1", "--frames and --frame exclude each other"},
      {"--paths x.jsonl --part " + part, "--part needs a TRACE"},
  };
  for (const auto& c : cases) {
    const Result r = Raycell("analyze " + c.args + " --quiet");
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.out;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << r.out;
    EXPECT_FALSE(std::filesystem::exists(part));
    EXPECT_FALSE(std::filesystem::exists(part + ".tmp"));
  }
}

}  // namespace
