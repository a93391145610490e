// `raycell record --frames A..B` records a range of a camera path, and `raycell trace concat`
// joins such ranges into the capture of the whole path, byte for byte (docs/design.md §3
// "Joining captures"); it refuses anything else (exit 2, naming the difference) and then
// writes nothing.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/test_util.h"
#include "tests/tools/cli_util.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

using Result = testing::SplitResult;

Result Raycell(const std::string& args) { return testing::RaycellSplit(args, "trace_concat"); }

bool Contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

bool Exists(const std::string& path) { return std::filesystem::exists(path); }

// The settings every capture here shares: small and quick (the built-in scene's fog, mirror
// sphere and glass icosahedron, by default at 32x32 in 2x2x2 cells).
const char kSmall[] = " --no-images --quiet --threads 2";

class TraceConcatTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::TempDir("trace_concat").string());
    // The one-shot capture of the 6-frame orbit, then ranges of it.
    Record("--orbit 6:90", "all");
    for (const char* range : {"0..2", "3..5", "0..1", "2..3", "4..5", "2..5"}) {
      Record(std::string("--orbit 6:90 --frames ") + range, range);
    }
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*dir_);
    delete dir_;
  }

  // Records `args` plus kSmall into NAME.rct; returns its path.
  static std::string Record(const std::string& args, const std::string& name,
                            const std::string& res = "32x32", const std::string& cells = "2x2x2") {
    const std::string out = Path(name);
    const Result r = Raycell("record " + args + " --res " + res + " --cells " + cells + kSmall +
                             " --out " + out);
    EXPECT_EQ(r.code, 0) << args << ": " << r.err;
    return out;
  }
  static std::string Path(const std::string& name) { return *dir_ + "/" + name + ".rct"; }
  // An input: NAME.rct here, or a path when it starts with '/'.
  static std::string Input(const std::string& name) { return name[0] == '/' ? name : Path(name); }

  // Runs `trace concat INPUTS --out OUT` (OUT fresh).
  static Result Concat(const std::vector<std::string>& names, const std::string& out) {
    std::filesystem::remove(Path(out));
    std::string args = "trace concat";
    for (const std::string& n : names) args += " " + Input(n);
    return Raycell(args + " --out " + Path(out));
  }

  // A refused join: exit 2, the message names `difference`, and neither OUT nor a temporary
  // file is left.
  static void ExpectRefused(const std::vector<std::string>& names, const std::string& difference) {
    const Result r = Concat(names, "refused");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_TRUE(Contains(r.err, difference)) << "expected '" << difference << "' in: " << r.err;
    EXPECT_FALSE(Exists(Path("refused")));
    for (const auto& entry : std::filesystem::directory_iterator(*dir_)) {
      EXPECT_FALSE(Contains(entry.path().filename().string(), "refused")) << entry.path();
    }
  }

  static std::string* dir_;
};

std::string* TraceConcatTest::dir_ = nullptr;

TEST_F(TraceConcatTest, TwoRangesJoinIntoTheOneShotCaptureByteForByte) {
  const std::string all = testing::ReadBytes(Path("all"));
  ASSERT_FALSE(all.empty());
  for (const std::vector<std::string>& order :
       {std::vector<std::string>{"0..2", "3..5"}, std::vector<std::string>{"3..5", "0..2"}}) {
    const Result r = Concat(order, "joined2");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(testing::ReadBytes(Path("joined2")) == all) << order[0] << " " << order[1];
  }
  const Result v = Raycell("trace verify " + Path("joined2"));
  EXPECT_EQ(v.code, 0) << v.out << v.err;
  EXPECT_TRUE(Contains(v.out, "6 frame(s)")) << v.out;
}

TEST_F(TraceConcatTest, ThreeRangesInAnyOrderJoinIntoTheOneShotCaptureByteForByte) {
  const std::string all = testing::ReadBytes(Path("all"));
  const Result r = Concat({"4..5", "0..1", "2..3"}, "joined3");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(testing::ReadBytes(Path("joined3")) == all);
  const Result v = Raycell("trace verify " + Path("joined3"));
  EXPECT_EQ(v.code, 0) << v.out << v.err;
}

TEST_F(TraceConcatTest, FramesOfARangeAreThoseOfTheOneShotOrbit) {
  const TraceReader all = TraceReader::Open(Path("all"));
  const TraceReader part = TraceReader::Open(Path("2..3"));
  ASSERT_EQ(part.frames().size(), 2u);
  ASSERT_EQ(all.header().cameras.size(), 6u);
  EXPECT_TRUE(part.header().path == all.header().path) << part.header().path.ToString();
  EXPECT_EQ(part.header().path.ToString().rfind("orbit of 90 degrees over frames 0..5", 0), 0u)
      << part.header().path.ToString();
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(part.frames()[i].frame, int(i) + 2);
    EXPECT_TRUE(part.header().cameras[i] == all.header().cameras[i + 2]) << i;
    EXPECT_TRUE(part.frames()[i] == all.frames()[i + 2]) << i;  // totals and checksum
    EXPECT_TRUE(part.ReadEncodedFrame(i) == all.ReadEncodedFrame(i + 2)) << i;
  }
  // The cameras differ from frame to frame (the orbit turns): a range numbered 0..1 would not
  // pass the comparisons above.
  EXPECT_FALSE(all.header().cameras[2].eye == all.header().cameras[0].eye);
}

TEST_F(TraceConcatTest, OrbitDegreesWithoutFramesTurnOverTheFramesRecorded) {
  // --orbit 90 --frames 4..7: 90 degrees over frames 4..7, frame 4 unturned (today's meaning).
  const TraceReader r = TraceReader::Open(Record("--orbit 90 --frames 4..7", "deg_only"));
  const TraceReader ref = TraceReader::Open(Record("--orbit 4:90", "deg_ref"));
  ASSERT_EQ(r.header().cameras.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(r.header().cameras[i].frame, int(i) + 4);
    EXPECT_TRUE(r.header().cameras[i].eye == ref.header().cameras[i].eye) << i;
  }
  EXPECT_EQ(r.header().path.first_frame, 4);
  EXPECT_EQ(r.header().path.frame_count, 4u);
}

TEST_F(TraceConcatTest, RecordRefusesFramesOutsideTheOrbit) {
  const Result r = Raycell(std::string("record --orbit 6:90 --frames 4..7 --res 32x32") + kSmall +
                           " --out " + Path("outside"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(Contains(r.err, "--frames 4..7: not frames of --orbit 6:90, whose frames are 0..5"))
      << r.err;
  EXPECT_FALSE(Exists(Path("outside")));
}

TEST_F(TraceConcatTest, StillCameraAndKeyframeRangesJoinIntoTheOneShotCapture) {
  const std::string keys = *dir_ + "/keys.txt";
  std::ofstream(keys) << "0 0 0.5 3 0 0 0 40\n5 2.5 1 1.5 0 0.2 0 30\n";
  for (const std::string& path : {std::string(""), "--keyframes " + keys}) {
    const std::string all = Record(path + " --frames 0..4", "path_all");
    Record(path + " --frames 0..1", "path_a");
    Record(path + " --frames 2..4", "path_b");
    const Result r = Concat({"path_b", "path_a"}, "path_joined");
    ASSERT_EQ(r.code, 0) << path << ": " << r.err;
    EXPECT_TRUE(testing::ReadBytes(Path("path_joined")) == testing::ReadBytes(all)) << path;
  }
  const TraceReader k = TraceReader::Open(Path("path_joined"));
  EXPECT_EQ(k.header().path.kind, "keyframes");
  EXPECT_FALSE(k.header().cameras[1].eye == k.header().cameras[3].eye);
}

TEST_F(TraceConcatTest, RefusesOverlappingRanges) {
  ExpectRefused({"0..2", "2..5"}, "overlapping frame ranges: ");
  ExpectRefused({"0..2", "2..5"}, "(frames 2..2 are in both)");
  ExpectRefused({"2..3", "all"}, "(frames 2..3 are in both)");
}

TEST_F(TraceConcatTest, RefusesRangesWithAGap) {
  ExpectRefused({"0..1", "4..5"}, "frame ranges with a gap: ");
  ExpectRefused({"4..5", "0..1"}, "(frames 2..3 are in neither)");
}

TEST_F(TraceConcatTest, RefusesDifferentCells) {
  Record("--orbit 6:90 --frames 3..5", "cells333", "32x32", "3x3x3");
  ExpectRefused({"0..2", "cells333"}, "differ in cell grid (--cells): 2x2x2 vs 3x3x3");
}

TEST_F(TraceConcatTest, RefusesDifferentResolutions) {
  Record("--orbit 6:90 --frames 3..5", "res48", "48x32");
  ExpectRefused({"0..2", "res48"}, "differ in resolution (--res): 32x32 vs 48x32");
}

TEST_F(TraceConcatTest, RefusesDifferentOrbits) {
  Record("--orbit 6:180 --frames 3..5", "orbit180");
  ExpectRefused({"0..2", "orbit180"}, "differ in camera path: orbit of 90 degrees");
  ExpectRefused({"0..2", "orbit180"}, "vs orbit of 180 degrees over frames 0..5");
  Record("--orbit 7:90 --frames 3..5", "orbit7");
  ExpectRefused({"0..2", "orbit7"}, "vs orbit of 90 degrees over frames 0..6");
}

TEST_F(TraceConcatTest, RefusesDamagedInputs) {
  const std::string bytes = testing::ReadBytes(Path("3..5"));
  const TraceReader r = TraceReader::Open(Path("3..5"));
  const FrameSummary& f = r.frames()[1];
  // Truncated: the index is gone.
  testing::WriteBytes(Path("cut"), bytes.substr(0, bytes.size() - 10));
  ExpectRefused({"0..2", "cut"}, "cut.rct: damaged or incomplete, not joined: ");
  // A bit flipped inside frame 4's compressed bytes: the index is intact, the zstd checksum
  // (or the zstd stream) is not.
  std::string flipped = bytes;
  flipped[f.offset + f.length / 2] ^= 0x08;
  testing::WriteBytes(Path("flipped"), flipped);
  ExpectRefused({"0..2", "flipped"}, "flipped.rct: frame 4 (#1, offset ");
  // A damaged header.
  std::string header = bytes;
  header[20] ^= 0x40;
  testing::WriteBytes(Path("badheader"), header);
  ExpectRefused({"badheader", "0..2"}, "badheader.rct: ");
}

TEST_F(TraceConcatTest, RefusesTracesWithoutACameraPath) {
  // Version 1 and 2 files (and imported traces) do not record their camera path.
  ExpectRefused({"0..2", std::string(RAYCELL_SOURCE_DIR) + "/tests/traces/data/v1_builtin.rct"},
                "its camera path is not recorded (format version 1");
}

}  // namespace
}  // namespace raycell
