// `raycell study` of a volume sequence (one .vdb file per frame, named by a printf pattern):
// on a sequence generated here, so that it always runs.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "tests/test_util.h"
#include "tests/tools/cli_util.h"

namespace raycell::testing {
namespace {

// Frames 5..7 of a fog ball moving along x: seq_05.vdb, seq_06.vdb, seq_07.vdb.
std::string WriteSequence(const std::filesystem::path& dir) {
  openvdb::initialize();
  for (int f = 5; f <= 7; ++f) {
    auto ball = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        1.0f, {0.3f * float(f - 5), 0.f, 0.f}, 0.1f);
    openvdb::tools::sdfToFogVolume(*ball);
    ball->setName("density");
    char name[32];
    std::snprintf(name, sizeof name, "seq_%02d.vdb", f);
    openvdb::io::File((dir / name).string()).write({ball});
  }
  return (dir / "seq_%02d.vdb").string();
}

TEST(StudySequence, FramesAToBStudyTheSequenceWithAStillCamera) {
  const auto dir = CliDir("study_sequence");
  const std::string pattern = WriteSequence(dir);
  const auto out = dir / "study";
  const Result r = Raycell("study --scene '" + pattern +
                           "' --frames 5..7 --res 16x16 --cells 2x2x2 --accuracy-frames 1 "
                           "--accuracy-res 12x12 --quiet --out " +
                           out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string trees = ReadBytes((out / "cell_trees_2x2x2.csv").string());
  std::istringstream rows(trees);
  std::string line, frames;
  std::getline(rows, line);
  while (std::getline(rows, line)) frames += line.substr(0, line.find(',')) + " ";
  EXPECT_EQ(frames, "5 6 7 ") << trees;
  const std::string report = ReadBytes((out / "report.md").string());
  EXPECT_NE(report.find("Scene `" + pattern +
                        "` (one volume per frame), frames 5..7 with a still camera, 16x16."),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("## Run time against error"), std::string::npos) << report;
  EXPECT_EQ(report.find("Not measured"), std::string::npos) << report;
  EXPECT_TRUE(std::filesystem::exists(out / "images_2x2x2" / "frame_0007.png"));
  // One camera for every frame: the volumes move, the camera does not.
  const Result info = Raycell("trace info --cameras " + (out / "capture_2x2x2.rct").string());
  ASSERT_EQ(info.code, 0) << info.out;
  std::istringstream lines(info.out);
  std::vector<std::string> views;
  while (std::getline(lines, line)) {
    if (line.rfind("camera ", 0) == 0) views.push_back(line.substr(line.find(" eye ")));
  }
  ASSERT_EQ(views.size(), 3u) << info.out;
  EXPECT_EQ(std::count(views.begin(), views.end(), views[0]), 3) << info.out;
  std::filesystem::remove_all(dir);
}

TEST(StudySequence, APatternNeedsFrameNumbers) {
  const auto dir = CliDir("study_sequence_bad");
  Result r = Raycell("study --scene 'seq_%02d.vdb' --frames 3 --out " + (dir / "s").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--frames '3': --scene 'seq_%02d.vdb' is a sequence pattern: give the "
                       "frame numbers of its files, A..B"),
            std::string::npos)
      << r.out;
  r = Raycell("study --scene 'seq_%02d.vdb' --frames 5..5 --out " + (dir / "s").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--frames '5..5': a study needs 2 to 10000 frames"), std::string::npos)
      << r.out;
  r = Raycell("study --frames 1 --out " + (dir / "s").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--frames (a count of frames): 1 is out of range 2..10000"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "s"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace raycell::testing
