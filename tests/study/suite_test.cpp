// raycell suite's per-scene files and report (study/suite.h): a scene's results survive the
// file a cluster task writes, and the report's geometric means and worst scenes are those of
// ratios worked out by hand.
#include "study/suite.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <tuple>

#include "base/check.h"
#include "tests/test_util.h"

namespace raycell {
namespace {

SuiteSceneResult Scene(const std::string& name, std::uint64_t maxwork_fetches,
                       std::uint64_t balanced_fetches, std::uint64_t maxwork_after,
                       std::uint64_t balanced_after) {
  SuiteSceneResult r;
  r.scene = {name, "scenes/" + name + ".toml", "fog, \"dense\", with early termination"};
  r.character.frames = 8;
  r.character.pixels = 128 * 128;
  r.character.rays = 1000;
  r.character.rays_by_kind = {400, 100, 200, 300};
  r.character.visits = 2500;
  r.character.samples = 99999;
  r.character.busy_cells = 40;
  r.character.max_gen_sum = 70;
  r.character.max_gen_largest = 5;
  r.record_seconds = 1.5;
  r.cache_capacity = 4096;
  r.rows.push_back(
      {"scheduler", "maxwork", "maxwork", 8, maxwork_fetches, 11, 5000, maxwork_after});
  r.rows.push_back(
      {"scheduler", "balanced", "balanced", 8, balanced_fetches, 12, 4000, balanced_after});
  r.rows.push_back({"cells", "kd:27:sqrt", "maxwork", 1, 7, 123456, 9, 3});
  return r;
}

TEST(SuiteSceneFileTest, RoundTripsEveryField) {
  const SuiteSceneResult a = Scene("fog", 100, 60, 900, 450);
  const std::string path = testing::TempPath("suite", "fog.csv");
  { std::ofstream(path) << SuiteSceneCsv(a); }
  const SuiteSceneResult b = ReadSuiteSceneCsv(path);
  EXPECT_EQ(b.scene.name, a.scene.name);
  EXPECT_EQ(b.scene.file, a.scene.file);
  EXPECT_EQ(b.scene.about, a.scene.about);  // a comma and quotes inside
  EXPECT_EQ(b.character.rays, 1000u);
  EXPECT_EQ(b.character.rays_by_kind[3], 300u);
  EXPECT_EQ(b.character.samples, 99999u);
  EXPECT_EQ(b.character.max_gen_sum, 70u);
  EXPECT_EQ(b.character.max_gen_largest, 5u);
  EXPECT_EQ(b.cache_capacity, 4096u);
  ASSERT_EQ(b.rows.size(), a.rows.size());
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    EXPECT_EQ(b.rows[i].kind, a.rows[i].kind);
    EXPECT_EQ(b.rows[i].name, a.rows[i].name);
    EXPECT_EQ(b.rows[i].scheduler, a.rows[i].scheduler);
    EXPECT_EQ(b.rows[i].processors, a.rows[i].processors);
    EXPECT_EQ(b.rows[i].fetches, a.rows[i].fetches);
    EXPECT_EQ(b.rows[i].cache_bytes, a.rows[i].cache_bytes);
    EXPECT_EQ(b.rows[i].time_ps, a.rows[i].time_ps);
    EXPECT_EQ(b.rows[i].time_after_first_ps, a.rows[i].time_after_first_ps);
  }
  std::filesystem::remove(path);
}

TEST(SuiteSceneFileTest, RefusesWhatItDidNotWriteNamingTheFileAndLine) {
  const std::string good = SuiteSceneCsv(Scene("fog", 100, 60, 900, 450));
  const std::string path = testing::TempPath("suite", "bad.csv");
  for (const std::string& text :
       {std::string("kind,name\n"), good.substr(0, good.find("kind,")),  // no rows' header
        good + "scheduler,maxwork,maxwork,8,x,1,2,3\n",                  // not a count
        good + "oops,maxwork,maxwork,8,1,1,2,3\n"}) {                    // unknown kind
    { std::ofstream(path) << text; }
    try {
      ReadSuiteSceneCsv(path);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path + ":"), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove(path);
}

TEST(SuiteReportTest, GeometricMeanAndWorstSceneOfTheRatiosToMaxWork) {
  SuiteOptions o;
  // Scene a: balanced fetches 50/100 = 0.5, time after frame 0 450/900 = 0.5.
  // Scene b: fetches 200/100 = 2, time 1800/900 = 2. Geometric means: 1 (0.0%); worst: b, +100%.
  // Scene c: fetches 80/100 = 0.8, time 720/900 = 0.8. With c: geometric mean 0.8^(1/3) =
  // 0.928 (-7.2%).
  const std::string two =
      SuiteReportText(o, {Scene("a", 100, 50, 900, 450), Scene("b", 100, 200, 900, 1800)});
  EXPECT_NE(two.find("| **geometric mean** | | 0.0% / 0.0% (-20.0%) |"), std::string::npos) << two;
  EXPECT_NE(two.find("| **worst scene** | | +100.0% b / +100.0% b (-20.0% a) |"), std::string::npos)
      << two;
  const std::string three =
      SuiteReportText(o, {Scene("a", 100, 50, 900, 450), Scene("b", 100, 200, 900, 1800),
                          Scene("c", 100, 80, 900, 720)});
  EXPECT_NE(three.find("| **geometric mean** | | -7.2% / -7.2% (-20.0%) |"), std::string::npos)
      << three;
  // The character table: 1000 rays over 128x128 pixels x 8 frames; 600 of 1000 secondary;
  // maxGen mean 70 / 40.
  EXPECT_NE(three.find("| a | fog, \"dense\", with early termination | 8 | 0.01 | 60.0% | 2.50 | "
                       "1.75 | 5 |"),
            std::string::npos)
      << three;
}

TEST(SuiteReportTest, HeadlinesFromTheFilesOfAFolderWithOneScenesOwnFigure) {
  // `auto` against Max Work at 8 processors. Scene a: fetches 50/100 = 0.5, time after frame 0
  // 450/900 = 0.5; scene b: 80/100 = 0.8, 720/900 = 0.8. Geometric mean sqrt(0.4) = 0.632
  // (-36.8%); worst b (-20.0%). One processor: auto / best 30/20 = 1.5 (a), 22/20 = 1.1 (b):
  // geometric mean sqrt(1.65) = 1.285, worst a.
  const auto dir = testing::TempDir("suite_headlines");
  std::filesystem::create_directories(dir / "scenes");
  for (auto [name, f, t, one] : {std::tuple{"a", 50, 450, 30}, std::tuple{"b", 80, 720, 22}}) {
    SuiteSceneResult r = Scene(name, 100, 1, 900, 1);
    r.rows.pop_back();  // the subdivisions: the uniform grid first, as the suite writes them
    r.rows.push_back({"cells", "3x3x3", "auto", 1, 9, 1000, 1, 1});
    r.rows.push_back(
        {"cells", "auto:27", "auto", 1, 9, name == std::string("a") ? 900u : 1100u, 1, 1});
    r.rows.push_back({"scheduler", "auto", "auto", 8, std::uint64_t(f), 0, 5000, std::uint64_t(t)});
    r.rows.push_back({"scheduler", "best", "best", 1, 20, 0, 1, 1});
    r.rows.push_back({"scheduler", "auto", "auto", 1, std::uint64_t(one), 0, 1, 1});
    std::ofstream(dir / "scenes" / (std::string(name) + ".csv")) << SuiteSceneCsv(r);
  }
  SuiteOptions o;
  o.processors = 3;
  o.cells = "2x2x2";
  const std::vector<SuiteSceneResult> scenes = ReadSuiteResults(dir.string(), &o);
  ASSERT_EQ(scenes.size(), 2u);
  EXPECT_EQ(scenes[0].scene.name, "a");
  EXPECT_EQ(o.processors, 8u);  // the largest count of the rows
  EXPECT_EQ(o.cells, "3x3x3");  // the first subdivision row's
  const std::vector<std::string> h = SuiteHeadlines(o, scenes, "b");
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[0],
            "8 processors, `auto` against Max Work: fetches -36.8% (geometric mean; worst -20.0% "
            "on b; b -20.0%), time after frame 0 -36.8% (worst -20.0% on b; b -20.0%)");
  EXPECT_EQ(h[1],
            "1 processor, `auto` online / oracle: 1.285 (geometric mean; worst 1.500 on a; "
            "b 1.100)");
  // auto:27's cache bytes 900/1000 (a), 1100/1000 (b): sqrt(0.99) = 0.995 (-0.5%).
  EXPECT_EQ(h[2],
            "`--cells auto:27` under `auto`: cache bytes -0.5% against 3x3x3 (geometric "
            "mean; worst +10.0% on b; b +10.0%)");
  // A scene that is not one of the suite's: no figure beside.
  EXPECT_EQ(SuiteHeadlines(o, scenes, "zzz")[1],
            "1 processor, `auto` online / oracle: 1.285 (geometric mean; worst 1.500 on a)");
  // No folder: no results.
  EXPECT_TRUE(ReadSuiteResults((dir / "none").string(), &o).empty());
  std::filesystem::remove_all(dir);
}

TEST(SuiteScenesTest, RefusesMissingFilesUnknownKindsAndTwoScenesOfOneName) {
  SuiteOptions o;
  o.scenes = {"/nonexistent/fog.toml"};
  EXPECT_THROW(SuiteScenes(o), InputError);
  const auto dir = testing::TempDir("suite_scenes");
  std::ofstream(dir / "notes.txt") << "x";
  std::ofstream(dir / "fog.toml") << "# a fog\n# dense\n[camera]\n";
  std::filesystem::create_directories(dir / "other");
  std::ofstream(dir / "other" / "fog.toml") << "# another fog\n";
  o.scenes = {(dir / "notes.txt").string()};
  EXPECT_THROW(SuiteScenes(o), InputError);
  o.scenes = {(dir / "fog.toml").string(), (dir / "other" / "fog.toml").string()};
  EXPECT_THROW(SuiteScenes(o), InputError);
  o.scenes = {dir.string()};
  const auto scenes = SuiteScenes(o);
  ASSERT_EQ(scenes.size(), 1u);  // the folder's .toml files; notes.txt is not a scene
  EXPECT_EQ(scenes[0].name, "fog");
  EXPECT_EQ(scenes[0].about, "a fog dense");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace raycell
