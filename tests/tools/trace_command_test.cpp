// `raycell trace verify` fails (exit 2, naming what is lost) on any damage, while the
// commands that read (`trace cat`, `replay`, `analyze`) warn and use the intact frames.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "tests/test_util.h"
#include "tests/tools/cli_util.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

using Result = testing::SplitResult;

Result Raycell(const std::string& args) { return testing::RaycellSplit(args, "trace_cmd"); }

bool Contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

std::size_t Lines(const std::string& text, const std::string& prefix) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < text.size(); i = text.find('\n', i) + 1) {
    n += text.compare(i, prefix.size(), prefix) == 0;
    if (text.find('\n', i) == std::string::npos) break;
  }
  return n;
}

class TraceCommandTest : public ::testing::Test {
 protected:
  // A 3-frame capture of the built-in scene (frames 0, 1, 2), recorded once.
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::TempDir("trace_cmd").string());
    const Result r = Raycell("record --res 16x16 --orbit 3:30 --no-images --quiet --out " + Good());
    ASSERT_EQ(r.code, 0) << r.err;
    const TraceReader reader = TraceReader::Open(Good());
    frames_ = new std::vector<FrameSummary>(reader.frames());
    bytes_ = new std::string(testing::ReadBytes(Good()));
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete frames_;
    delete bytes_;
  }
  static std::string Good() { return *dir_ + "/good.rct"; }
  static const FrameSummary& Frame(int k) { return (*frames_)[k]; }

  // Writes `bytes` to a damaged copy and returns its path.
  std::string Damaged(const std::string& bytes) {
    const std::string path = *dir_ + "/damaged.rct";
    testing::WriteBytes(path, bytes);
    return path;
  }

  static std::string* dir_;
  static std::vector<FrameSummary>* frames_;
  static std::string* bytes_;
};

std::string* TraceCommandTest::dir_ = nullptr;
std::vector<FrameSummary>* TraceCommandTest::frames_ = nullptr;
std::string* TraceCommandTest::bytes_ = nullptr;

TEST_F(TraceCommandTest, VerifyPassesAnIntactFile) {
  ASSERT_EQ(frames_->size(), 3u);
  const Result r = Raycell("trace verify " + Good());
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_EQ(Lines(r.out, "frame "), 3u) << r.out;
  EXPECT_TRUE(Contains(r.out, "3 frame(s), ")) << r.out;
  EXPECT_EQ(r.err, "");
}

TEST_F(TraceCommandTest, VerifyFailsATruncatedFileNamingWhatIsLost) {
  // Cut 10 bytes into frame 2: frames 0 and 1 are intact, frame 2 and the index are lost.
  const std::uint64_t cut = Frame(2).offset + 10;
  const std::string path = Damaged(bytes_->substr(0, cut));
  const Result r = Raycell("trace verify " + path);
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_TRUE(Contains(r.out, "frame 0: ok")) << r.out;
  EXPECT_TRUE(Contains(r.out, "frame 1: ok")) << r.out;
  EXPECT_FALSE(Contains(r.out, "frame 2: ok")) << r.out;
  EXPECT_TRUE(Contains(r.err, "raycell: error: " + path + ": verification failed")) << r.err;
  EXPECT_TRUE(Contains(r.err, "the index and bytes " + std::to_string(Frame(2).offset) + ".." +
                                  std::to_string(cut) + " (10 bytes) after the last intact " +
                                  "frame (frame 1, #1) are unreadable"))
      << r.err;
  EXPECT_TRUE(Contains(r.err, "index: missing")) << r.err;
  EXPECT_TRUE(
      Contains(r.err, "frame #2 (offset " + std::to_string(Frame(2).offset) + "): truncated"))
      << r.err;
}

TEST_F(TraceCommandTest, VerifyFailsAFileWithoutItsIndex) {
  // Every frame complete, only the index cut off (as an interrupted capture's .tmp).
  const std::string path = Damaged(bytes_->substr(0, Frame(2).offset + Frame(2).length));
  const Result r = Raycell("trace verify " + path);
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_EQ(Lines(r.out, "frame "), 3u) << r.out;
  EXPECT_TRUE(Contains(r.err, "the index is unreadable: " + path + ": index: missing")) << r.err;
}

TEST_F(TraceCommandTest, VerifyFailsADamagedIndexOrFrame) {
  std::string bytes = *bytes_;
  bytes[bytes.size() - 40] ^= 0x10;  // inside the index message
  Result r = Raycell("trace verify " + Damaged(bytes));
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_TRUE(Contains(r.err, "index: damaged: checksum mismatch")) << r.err;
  EXPECT_EQ(Lines(r.out, "frame "), 3u) << r.out;  // the scan still finds every frame

  bytes = *bytes_;
  bytes[Frame(1).offset + Frame(1).length / 2] ^= 0x10;  // inside frame 1; the index is intact
  const std::string path = Damaged(bytes);
  r = Raycell("trace verify " + path);
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_TRUE(Contains(r.out, "frame 0: ok")) << r.out;
  EXPECT_TRUE(Contains(r.out, "frame 1: DAMAGED")) << r.out;
  EXPECT_TRUE(Contains(r.out, "frame 2: ok")) << r.out;  // the others are still checked
  EXPECT_TRUE(Contains(r.err, "(1 problem(s)): " + path + ": frame 1 (#1, offset ")) << r.err;
}

TEST_F(TraceCommandTest, ReadingCommandsWarnAndUseTheIntactFrames) {
  const std::string path = Damaged(bytes_->substr(0, Frame(2).offset + 10));
  const Result all = Raycell("trace cat " + Good());
  ASSERT_EQ(all.code, 0) << all.err;
  const std::size_t rays01 = Lines(all.out, "{\"frame\":0,") + Lines(all.out, "{\"frame\":1,");
  ASSERT_EQ(rays01, Frame(0).rays + Frame(1).rays);

  const Result cat = Raycell("trace cat " + path);
  EXPECT_EQ(cat.code, 0) << cat.err;
  EXPECT_TRUE(Contains(cat.err, "raycell: warning: " + path + ": index: missing")) << cat.err;
  EXPECT_EQ(Lines(cat.out, "{\"frame\":"), rays01);
  EXPECT_EQ(Lines(cat.out, "{\"frame\":2,"), 0u);

  for (const std::string command : {"replay", "analyze"}) {
    const Result r = Raycell(command + " " + path);
    EXPECT_EQ(r.code, 0) << command << ": " << r.err;
    EXPECT_TRUE(Contains(r.err, "raycell: warning: " + path + ": index: missing"))
        << command << ": " << r.err;
    EXPECT_EQ(Lines(r.out, "       0 "), 1u) << command << ": " << r.out;
    EXPECT_EQ(Lines(r.out, "       1 "), 1u) << command << ": " << r.out;
    EXPECT_EQ(Lines(r.out, "       2 "), 0u) << command << ": " << r.out;
  }
}

// A regroupable capture regrouped into a subdivision by `trace regroup` and by --cells SPEC of
// the commands that read it: the same replay, analysis and sweep rows either way; bad uses
// exit 2 naming what is wrong, and leave nothing written.
TEST(TraceRegroupCommand, CellsSpecOfTheReadingCommandsEqualsTheRegroupedFile) {
  const std::string dir = testing::TempDir("trace_regroup").string();
  const std::string fine = dir + "/fine.rct", c3 = dir + "/c3.rct", plain = dir + "/plain.rct";
  Result r = Raycell(
      "record --res 24x24 --orbit 2:10 --cells 6x6x6 --regroupable --no-images "
      "--quiet --out " +
      fine);
  ASSERT_EQ(r.code, 0) << r.err;
  r = Raycell("trace regroup " + fine + " --cells 3x3x3 --out " + c3);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(Contains(r.err, "into 27 cells")) << r.err;
  for (const std::string command : {"replay --format json", "analyze --format json"}) {
    const Result file = Raycell(command + " " + c3);
    const Result view = Raycell(command + " " + fine + " --cells 3x3x3");
    ASSERT_EQ(file.code, 0) << file.err;
    ASSERT_EQ(view.code, 0) << view.err;
    EXPECT_EQ(file.out, view.out) << command;
  }
  // A dynamic subdivision's file keeps each frame's own footprints: the same replay too.
  const std::string dyn = dir + "/dyn.rct";
  ASSERT_EQ(Raycell("trace regroup " + fine + " --cells dynamic:5 --out " + dyn).code, 0);
  const Result dyn_file = Raycell("replay --format json " + dyn);
  const Result dyn_view = Raycell("replay --format json " + fine + " --cells dynamic:5");
  ASSERT_EQ(dyn_file.code, 0) << dyn_file.err;
  EXPECT_EQ(dyn_file.out, dyn_view.out);
  const std::string vary = " --vary scheduler=maxwork,celltree --quiet --out ";
  ASSERT_EQ(Raycell("sweep " + c3 + vary + dir + "/a.csv").code, 0);
  ASSERT_EQ(Raycell("sweep " + fine + " --cells 3x3x3" + vary + dir + "/b.csv").code, 0);
  const std::string a = testing::ReadBytes(dir + "/a.csv"), b = testing::ReadBytes(dir + "/b.csv");
  EXPECT_EQ(a.substr(a.find('\n')), b.substr(b.find('\n')));  // the rows, past the comments
  EXPECT_TRUE(Contains(b.substr(0, b.find('\n')), "cells=\"3x3x3\""));

  ASSERT_EQ(Raycell("record --res 8x8 --no-images --quiet --out " + plain).code, 0);
  r = Raycell("analyze " + plain + " --cells 2x2x2");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(Contains(r.err, "is not a regroupable capture")) << r.err;
  r = Raycell("replay " + fine + " --cells kd:0:work");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(Contains(r.err, "--cells 'kd:0:work'")) << r.err;
  r = Raycell("trace regroup " + fine + " --cells 4x4x4 --out " + dir + "/x.rct");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(Contains(r.err, "4x4x4")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.rct"));
  r = Raycell("record --regroupable --footprint dense --out " + dir + "/x.rct");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(Contains(r.err, "--regroupable needs sparse footprints")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.rct"));
}

}  // namespace
}  // namespace raycell

namespace raycell {
namespace {

// `record --cells auto:N` records on 4x4x4 fine cells per cell of auto:N's baseline grid and
// writes each frame in the cells auto:N chooses from the frames before it: the same trace,
// byte for byte, as the fine capture recorded on its own and regrouped by `trace regroup
// --cells auto:N`, and the same frames, visit for visit, as that capture read with --cells
// auto:N. Nothing but OUT is left.
TEST(TraceRegroupCommand, AutoRecordedDirectlyEqualsTheFineCaptureRegrouped) {
  const std::string dir = testing::TempDir("record_auto").string();
  const std::string direct = dir + "/direct.rct", fine = dir + "/fine.rct";
  const std::string common = "record --res 32x32 --orbit 4:20 --no-images --quiet ";
  Result r = Raycell(common + "--cells auto:8 --out " + direct);
  ASSERT_EQ(r.code, 0) << r.err;
  r = Raycell(common + "--cells 8x8x8 --regroupable --out " + fine);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_EQ(Raycell("trace regroup " + fine + " --cells auto:8 --out " + dir + "/re.rct").code, 0);
  EXPECT_EQ(testing::ReadBytes(direct), testing::ReadBytes(dir + "/re.rct"));
  const TraceReader a = TraceReader::Open(direct);
  const TraceReader b = TraceReader::Open(fine, "auto:8");
  EXPECT_EQ(a.header().subdivision, b.header().subdivision);
  EXPECT_EQ(a.header().subdivision.spec, "auto:8");
  ASSERT_EQ(a.frames().size(), 4u);
  for (std::size_t f = 0; f < 4; ++f) {
    EXPECT_EQ(a.frames()[f], b.frames()[f]);
    EXPECT_EQ(a.LoadFrame(f), b.LoadFrame(f));
  }
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 3u);  // direct, fine and re: the fine capture behind direct is gone
}

}  // namespace
}  // namespace raycell

namespace raycell {
namespace {

// `record --trace-format 6` (and 7) writes format 6 (samples range coded; 7), the default format 5;
// all hold the same rays (LoadFrame checks each frame's checksum of its decoded rays, the same hash
// in both), format 6 in fewer bytes; `trace regroup` keeps its input's format; another format is
// refused (exit 2) and nothing is written.
TEST(TraceFormatFlag, RecordWritesTheFormatAskedAndRegroupKeepsIt) {
  const std::string dir = testing::TempDir("trace_format").string();
  const std::string args =
      "record --res 24x24 --orbit 2:10 --cells 6x6x6 --regroupable "
      "--no-images --quiet --out ";
  Result r = Raycell(args + dir + "/v5.rct");
  ASSERT_EQ(r.code, 0) << r.err;
  r = Raycell(args + dir + "/v6.rct --trace-format 6");
  ASSERT_EQ(r.code, 0) << r.err;
  r = Raycell(args + dir + "/v7.rct --trace-format 7");
  ASSERT_EQ(r.code, 0) << r.err;
  r = Raycell(args + dir + "/v8.rct --trace-format 8");
  ASSERT_EQ(r.code, 0) << r.err;
  const TraceReader v5 = TraceReader::Open(dir + "/v5.rct");
  EXPECT_EQ(v5.header().format_version, 5u);
  ASSERT_EQ(v5.frames().size(), 2u);
  for (const std::uint32_t version : {6u, 7u, 8u}) {
    SCOPED_TRACE(version);
    const TraceReader other = TraceReader::Open(dir + "/v" + std::to_string(version) + ".rct");
    EXPECT_EQ(other.header().format_version, version);
    ASSERT_EQ(other.frames().size(), 2u);
    for (std::size_t f = 0; f < 2; ++f) {
      EXPECT_EQ(v5.frames()[f].checksum, other.frames()[f].checksum);
      EXPECT_TRUE(v5.LoadFrame(f) == other.LoadFrame(f));
    }
  }
  EXPECT_LT(std::filesystem::file_size(dir + "/v6.rct"),
            std::filesystem::file_size(dir + "/v5.rct"));
  for (const std::string v : {"5", "6", "7", "8"}) {
    r = Raycell("trace regroup " + dir + "/v" + v + ".rct --cells 3x3x3 --out " + dir + "/r" + v +
                ".rct");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(TraceReader::Open(dir + "/r" + v + ".rct").header().format_version,
              static_cast<std::uint32_t>(std::stoul(v)));
  }
  r = Raycell(args + dir + "/x.rct --trace-format 4");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(Contains(r.err, "--trace-format")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.rct"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace raycell
