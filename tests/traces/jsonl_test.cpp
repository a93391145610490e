// JSON Lines: the writer's exact lines, the reader's order, renumbering, defaults and errors.
#include "traces/jsonl.h"

#include <gtest/gtest.h>

#include <random>
#include <sstream>

#include "tests/test_util.h"
#include "tests/traces/random_paths.h"

namespace raycell {
namespace {

using namespace testing;

std::vector<JsonlFrame> ReadAll(const std::string& text, JsonlReadOptions options = {}) {
  std::istringstream in(text);
  JsonlReader reader(in, "r.jsonl", options);
  std::vector<JsonlFrame> frames;
  for (JsonlFrame f; reader.Next(f);) frames.push_back(std::move(f));
  return frames;
}

std::string Written(const RayBatch& b, std::optional<std::int32_t> frame = std::nullopt) {
  std::ostringstream out;
  {
    JsonlWriter w(out);
    for (std::size_t i = 0; i < b.size(); ++i) w.Write(b.ray(i), frame);
  }
  return out.str();
}

TEST(JsonlTest, WriterWritesTheDocumentedLines) {
  std::mt19937 rng(1);
  for (int round = 0; round < 50; ++round) {
    const RayBatch b = RandomFrame(rng, 1 + rng() % 30, 1 + rng() % 40);
    EXPECT_EQ(Written(b), CanonicalJsonl(b));
    EXPECT_EQ(Written(b, -3), CanonicalJsonl(b, -3));
  }
}

TEST(JsonlTest, ReadsBackWhatTheWriterWroteUnchanged) {
  std::mt19937 rng(2);
  for (int round = 0; round < 100; ++round) {
    const RayBatch b = RandomFrame(rng, 1 + rng() % 30, 1 + rng() % 40);
    const std::vector<JsonlFrame> frames = ReadAll(CanonicalJsonl(b));
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0].frame, 0);
    EXPECT_FALSE(frames[0].renumbered);
    EXPECT_EQ(frames[0].rays, b) << CanonicalJsonl(b);
  }
}

// Shuffled lines, other ids, keys in any order, defaults left out: the same rays come back,
// in raycell's order, renumbered 0..n-1.
TEST(JsonlTest, ReadsDisguisedFramesBackInRaycellOrder) {
  std::mt19937 rng(3);
  for (int round = 0; round < 200; ++round) {
    const RayBatch b = RandomFrame(rng, 1 + rng() % 30, 1 + rng() % 60);
    Disguise d;
    d.sparse_ids = round % 5 != 0;
    const std::string text = Join(DisguisedLines(rng, b, std::nullopt, d));
    const std::vector<JsonlFrame> frames = ReadAll(text);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0].rays, b) << text;
    EXPECT_EQ(CanonicalJsonl(frames[0].rays), CanonicalJsonl(b)) << text;
  }
}

TEST(JsonlTest, SeveralFramesComeOneAtATimeInFileOrder) {
  std::mt19937 rng(4);
  const RayBatch a = RandomFrame(rng, 8, 20), b = RandomFrame(rng, 8, 30);
  const std::string text = Join(DisguisedLines(rng, a, 151, {})) + "\n  \n" +
                           Join(DisguisedLines(rng, b, -2, {})) +
                           Join(DisguisedLines(rng, a, 150, {}));
  const std::vector<JsonlFrame> frames = ReadAll(text);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].frame, 151);
  EXPECT_EQ(frames[1].frame, -2);
  EXPECT_EQ(frames[2].frame, 150);
  EXPECT_EQ(frames[0].rays, a);
  EXPECT_EQ(frames[1].rays, b);
  EXPECT_EQ(frames[2].rays, a);
  EXPECT_EQ(frames[0].first_line, 1u);
  EXPECT_EQ(frames[0].last_line, 20u);
  EXPECT_EQ(frames[1].first_line, 23u);  // after a blank and a white line
  EXPECT_EQ(frames[2].last_line, 72u);
}

// Ids out of order (a child's id below its parent's), defaults and pixel inheritance.
TEST(JsonlTest, OrdersTreesByPrimaryIdAndRaysBySmallestReadyId) {
  const std::string text = R"({"id":50,"parent":null,"spawn":null,"cells":[0,1],"pixel":[4,5]})"
                           "\n"
                           R"({"id":3,"parent":50,"spawn":1,"cells":[1],"pixel":[9,9]})"
                           "\n"
                           R"({"id":10,"parent":null,"spawn":null,"cells":[2]})"
                           "\n"
                           R"({"id":1,"parent":3,"spawn":0,"cells":[1,0],"samples":[7,0]})"
                           "\n"
                           R"({"cells":[2,0],"spawn":0,"kind":"shadow","parent":10,"id":7})"
                           "\n"
                           R"({"id":2,"parent":50,"spawn":0,"cells":[0]})"
                           "\n";
  const std::vector<JsonlFrame> frames = ReadAll(text);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_TRUE(frames[0].renumbered);
  EXPECT_EQ(
      CanonicalJsonl(frames[0].rays),
      R"({"id":0,"parent":null,"spawn":null,"kind":"primary","pixel":[0,0],"cells":[2],"samples":[1]}
{"id":1,"parent":0,"spawn":0,"kind":"shadow","pixel":[0,0],"cells":[2,0],"samples":[1,1]}
{"id":2,"parent":null,"spawn":null,"kind":"primary","pixel":[4,5],"cells":[0,1],"samples":[1,1]}
{"id":3,"parent":2,"spawn":0,"kind":"reflection","pixel":[4,5],"cells":[0],"samples":[1]}
{"id":4,"parent":2,"spawn":1,"kind":"reflection","pixel":[9,9],"cells":[1],"samples":[1]}
{"id":5,"parent":4,"spawn":0,"kind":"reflection","pixel":[9,9],"cells":[1,0],"samples":[7,0]}
)");
}

TEST(JsonlTest, RaysWithoutVisitsAndEmptyInput) {
  EXPECT_TRUE(ReadAll("").empty());
  EXPECT_TRUE(ReadAll("\n \t\r\n").empty());
  const std::vector<JsonlFrame> frames =
      ReadAll(R"({"id":0,"parent":null,"spawn":null,"cells":[]})");  // no final newline
  ASSERT_EQ(frames.size(), 1u);
  ASSERT_EQ(frames[0].rays.size(), 1u);
  EXPECT_EQ(frames[0].rays.visit_count(), 0u);
}

const char kFirst[] =
    R"({"id":0,"parent":null,"spawn":null,"kind":"primary","pixel":[0,0],"cells":[0,1],"samples":[1,2]})"
    "\n";

// The error reading kFirst followed by `rest`.
std::string Error(const std::string& rest, JsonlReadOptions options = {}) {
  const std::string e = ErrorOf([&] { ReadAll(kFirst + rest + "\n", options); });
  return e.empty() ? "no error" : e;
}

std::string Ray1(const std::string& fields) {
  return R"({"id":1,"kind":"reflection","pixel":[0,0],)" + fields + "}";
}

TEST(JsonlTest, MalformedLinesNameTheLine) {
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1],"samples":[1])")), "no error");
  EXPECT_EQ(Error(R"({"id":1)"), "r.jsonl:2: column 8: expected '}'");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1],"samples":[1])") + "x"),
            "r.jsonl:2: column 90: unexpected text after the object");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1],"x":1)")),
            "r.jsonl:2: unknown key \"x\" (expected frame, id, parent, spawn, kind, pixel, cells "
            "or samples)");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1],"cells":[1])")),
            "r.jsonl:2: duplicate key \"cells\"");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1],"samples":"1")")),
            "r.jsonl:2: \"samples\": expected an array of non-negative integers");
  EXPECT_EQ(Error(Ray1(R"("parent":"0","spawn":1,"cells":[1])")),
            "r.jsonl:2: \"parent\": expected a non-negative integer or null");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[-1])")),
            "r.jsonl:2: column 73: expected a non-negative integer");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1.0,"cells":[1])")),
            "r.jsonl:2: column 63: expected an integer");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":01,"cells":[1])")),
            "r.jsonl:2: column 62: leading zero");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"cells":[1])")), "r.jsonl:2: missing \"spawn\"");
  EXPECT_EQ(Error(R"({"parent":null,"spawn":null,"cells":[1]})"), "r.jsonl:2: missing \"id\"");
  EXPECT_EQ(Error(R"({"id":1,"parent":null,"spawn":null})"), "r.jsonl:2: missing \"cells\"");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":null,"cells":[1])")),
            "r.jsonl:2: ray 1: \"parent\" and \"spawn\" must both be null or both be set");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":4294967296,"cells":[1])")),
            "r.jsonl:2: ray 1: \"spawn\" 4294967296 does not fit in 32 bits");
  EXPECT_EQ(Error(R"({"id":1,"parent":null,"spawn":null,"kind":"bouncy","cells":[1]})"),
            "r.jsonl:2: ray 1: unknown kind \"bouncy\" (expected primary, reflection, "
            "refraction or shadow)");
  EXPECT_EQ(Error(R"({"id":1,"parent":0,"spawn":1,"kind":"primary","cells":[1]})"),
            "r.jsonl:2: ray 1: kind \"primary\" with a parent (0)");
  EXPECT_EQ(Error(R"({"id":1,"parent":null,"spawn":null,"kind":"shadow","cells":[1]})"),
            "r.jsonl:2: ray 1: kind \"shadow\" without a parent (only primary rays have none)");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1],"samples":[1,2])")),
            "r.jsonl:2: ray 1: \"cells\" and \"samples\" differ in length (1 and 2)");
  EXPECT_EQ(Error(R"({"id":1,"parent":0,"spawn":1,"pixel":[1,2,3],"cells":[1]})"),
            "r.jsonl:2: ray 1: \"pixel\" must have 2 elements");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1,1],"samples":[1,1])")),
            "r.jsonl:2: ray 1: cell 1 repeated at visit 1");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1,16777216])")),
            "r.jsonl:2: ray 1: cell 16777216 out of range (at most 16777216 cells)");
  JsonlReadOptions grid;
  grid.cell_count = 8;
  grid.cells_what = "--cells 2x2x2";
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1,7])"), grid), "no error");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[1,8])"), grid),
            "r.jsonl:2: ray 1: cell 8 out of range: --cells 2x2x2 has 8 cells");
}

TEST(JsonlTest, InconsistentFramesNameTheLine) {
  EXPECT_EQ(Error(R"({"frame":3,"id":1,"parent":null,"spawn":null,"cells":[1]})"),
            "r.jsonl:2: a \"frame\" key, but line 1 has none (either every line has one or "
            "none does)");
  const std::string f1 = R"({"frame":1,"id":0,"parent":null,"spawn":null,"cells":[1]})"
                         "\n";
  const std::string f2 = R"({"frame":2,"id":0,"parent":null,"spawn":null,"cells":[1]})"
                         "\n";
  EXPECT_EQ(
      ErrorOf([&] { ReadAll(f1 + f1 + R"({"id":0,"parent":null,"spawn":null,"cells":[1]})"); }),
      "r.jsonl:3: no \"frame\" key, but line 1 has one (either every line has one or none "
      "does)");
  EXPECT_EQ(ErrorOf([&] { ReadAll(f1 + f2 + f2 + f1); }),
            "r.jsonl:4: frame 1 again, after frame 2: the lines of a frame must be together "
            "(frame 1 was at lines 1-1)");
  EXPECT_EQ(ErrorOf([&] {
              ReadAll(R"({"frame":2147483648,"id":0,"parent":null,"spawn":null,"cells":[]})");
            }),
            "r.jsonl:1: \"frame\" 2147483648 does not fit in 32 bits");
  EXPECT_EQ(ErrorOf([&] {
              ReadAll(R"({"frame":-2147483648,"id":0,"parent":null,"spawn":null,"cells":[]})");
            }),
            "");
}

// Errors that need the whole frame name the offending ray's line, and the other line
// involved.
TEST(JsonlTest, BrokenRayTreesNameTheLine) {
  EXPECT_EQ(Error(R"({"id":1,"parent":null,"spawn":null,"cells":[1]})"
                  "\n"
                  R"({"id":0,"parent":null,"spawn":null,"cells":[1]})"),
            "r.jsonl:3: ray 0: duplicate id (also the id of line 1)");
  EXPECT_EQ(Error(Ray1(R"("parent":9,"spawn":0,"cells":[1])")),
            "r.jsonl:2: ray 1: unknown parent 9");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":2,"cells":[1])")),
            "r.jsonl:2: ray 1: spawn 2 out of range: parent 0 (line 1) has 2 visits");
  EXPECT_EQ(Error(Ray1(R"("parent":0,"spawn":1,"cells":[0])")),
            "r.jsonl:2: ray 1: first cell 0 is not the cell 1 of parent 0 (line 1)'s spawn "
            "visit 1");
  EXPECT_EQ(Error(R"({"id":5,"parent":6,"spawn":0,"cells":[1]})"
                  "\n"
                  R"({"id":7,"parent":5,"spawn":0,"cells":[1]})"
                  "\n"
                  R"({"id":6,"parent":5,"spawn":0,"cells":[1]})"),
            "r.jsonl:2: ray 5: its chain of parents loops without reaching a primary ray: "
            "5 -> 6 -> 5");
  EXPECT_EQ(Error(R"({"id":8,"parent":7,"spawn":0,"cells":[1]})"
                  "\n"
                  R"({"id":7,"parent":7,"spawn":0,"cells":[1]})"),
            "r.jsonl:2: ray 8: its chain of parents loops without reaching a primary ray: "
            "8 -> 7 -> 7");
}

}  // namespace
}  // namespace raycell
