// The raycell command line end to end: record, trace cat, analyze; exit codes and messages
// for bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/test_util.h"

namespace {

struct Result {
  int code;
  std::string out;
};

// Runs `raycell ARGS` through the shell, stdout and stderr together.
Result Raycell(const std::string& args) {
  const std::string cmd = std::string(RAYCELL_BINARY) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  for (std::size_t n; (n = fread(buf.data(), 1, buf.size(), p)) > 0;) out.append(buf.data(), n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

std::filesystem::path Dir() {
  const auto d =
      std::filesystem::temp_directory_path() / ("raycell_cli_" + std::to_string(getpid()));
  std::filesystem::create_directories(d);
  return d;
}

// Two rays with paths A B and B A (cells 0 and 1): bound 2, Peel 3, optimum 3.
TEST(Cli, AnalyzePathsOfTwoCrossingRays) {
  const auto file = Dir() / "ab_ba.jsonl";
  std::ofstream(file)
      << R"({"id":0,"parent":null,"spawn":null,"kind":"primary","pixel":[0,0],"cells":[0,1],"samples":[1,1]})"
      << "\n"
      << R"({"id":1,"parent":null,"spawn":null,"kind":"primary","pixel":[1,0],"cells":[1,0],"samples":[1,1]})"
      << "\n";
  const Result r = Raycell("analyze --paths " + file.string() + " --exact --format json");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("\"rays\":2,\"nodes\":4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"bound\":2,\"peel_length\":3"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"optimum\":3,"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"peel_schedule\":["), std::string::npos) << r.out;
}

TEST(Cli, AnalyzeOfATraceEqualsAnalyzeOfItsJsonLines) {
  const auto d = Dir();
  const std::string trace = (d / "small.rct").string(), jsonl = (d / "small.jsonl").string();
  ASSERT_EQ(Raycell("record --res 32x32 --cells 3x3x3 --no-images --quiet --out " + trace).code, 0);
  ASSERT_EQ(Raycell("trace cat " + trace + " --frame 0 > " + jsonl).code, 0);
  const Result a = Raycell("analyze " + trace + " --format csv --quiet");
  const Result b = Raycell("analyze --paths " + jsonl + " --format csv");
  ASSERT_EQ(a.code, 0) << a.out;
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_EQ(a.out, b.out);  // byte for byte: no timing unless asked
  const Result t = Raycell("analyze " + trace + " --format csv --quiet --timing");
  EXPECT_NE(t.out.find("optimum_status,seconds,peel_schedule"), std::string::npos) << t.out;
}

TEST(Cli, DotOfAFrameRendersWithGraphviz) {
  const auto d = Dir();
  const std::string trace = (d / "dot.rct").string(), dot = (d / "tree.dot").string();
  ASSERT_EQ(Raycell("record --res 24x24 --no-images --quiet --out " + trace).code, 0);
  ASSERT_EQ(Raycell("analyze " + trace + " --dot " + dot + " --quiet").code, 0);
  ASSERT_TRUE(std::filesystem::exists(dot));
  if (std::system("command -v dot >/dev/null 2>&1") != 0) GTEST_SKIP() << "no `dot` (graphviz)";
  EXPECT_EQ(std::system(("dot -Tsvg " + dot + " -o " + dot + ".svg").c_str()), 0);
}

TEST(Cli, ReplayAndSweepAreDeterministicWhateverTheJobs) {
  const auto d = Dir();
  const std::string trace = (d / "sweep.rct").string();
  ASSERT_EQ(Raycell("record --res 24x24 --orbit 3:90 --no-images --quiet --out " + trace).code, 0);
  const Result a = Raycell("replay " + trace + " --format json --quiet");
  const Result b = Raycell("replay " + trace + " --format json --quiet");
  ASSERT_EQ(a.code, 0) << a.out;
  EXPECT_EQ(a.out, b.out);
  EXPECT_NE(a.out.find("\"frames\":["), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("\"total\":{\"fetches\":"), std::string::npos) << a.out;
  // Sampling 1 in 1 ray trees is the full replay; 1 in 2 scales its counts back.
  const Result s1 = Raycell("replay " + trace + " --format json --quiet --sample 1");
  EXPECT_EQ(s1.out, a.out);
  const Result s2 = Raycell("replay " + trace + " --format json --quiet --sample 2");
  ASSERT_EQ(s2.code, 0) << s2.out;
  EXPECT_NE(s2.out, a.out);
  const std::string vary = " --vary scheduler=maxwork,celltree,peel --vary processors.count=1,2";
  const std::string one = (d / "one.csv").string(), two = (d / "two.csv").string();
  ASSERT_EQ(Raycell("sweep " + trace + vary + " --jobs 1 --quiet --out " + one).code, 0);
  ASSERT_EQ(Raycell("sweep " + trace + vary + " --jobs 2 --quiet --out " + two).code, 0);
  const std::string rows = raycell::testing::ReadBytes(one);
  EXPECT_EQ(rows, raycell::testing::ReadBytes(two));
  EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), 2 + 6);  // comment, header, 6 rows
}

TEST(Cli, StudyWritesTheReportItsCsvsAndPlots) {
  const auto out = Dir() / "study";
  const Result r = Raycell(
      "study --res 24x24 --frames 3 --cells 2x2x2,1x2x1 --accuracy-frames 1 "
      "--accuracy-res 16x16 --quiet --out " +
      out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("report: " + (out / "report.md").string()), std::string::npos) << r.out;
  for (const char* cells : {"2x2x2", "1x2x1"}) {
    for (const std::string f : {"fetches_", "cell_trees_"}) {
      EXPECT_TRUE(std::filesystem::exists(out / (f + cells + ".csv"))) << f << cells;
      EXPECT_GT(std::filesystem::file_size(out / (f + cells + ".png")), 1000u) << f << cells;
    }
    EXPECT_TRUE(std::filesystem::exists(out / ("images_" + std::string(cells)) / "frame_0002.png"));
  }
  const std::string report = raycell::testing::ReadBytes((out / "report.md").string());
  EXPECT_NE(report.find("| fetches, Cell Tree scheduling |"), std::string::npos);
  EXPECT_NE(report.find("![fetches per frame](fetches_2x2x2.png)"), std::string::npos);
  const std::string fetches = raycell::testing::ReadBytes((out / "fetches_2x2x2.csv").string());
  EXPECT_EQ(std::count(fetches.begin(), fetches.end(), '\n'), 4);  // header + 3 frames
  // Run time against error: every knob's rows, finite, with their plot.
  EXPECT_NE(report.find("## Run time against error"), std::string::npos);
  EXPECT_NE(report.find("| renderer precision | single |"), std::string::npos) << report;
  EXPECT_NE(report.find("![run time against error](accuracy/accuracy.png)"), std::string::npos);
  EXPECT_GT(std::filesystem::file_size(out / "accuracy" / "accuracy.png"), 1000u);
  const std::string acc = raycell::testing::ReadBytes((out / "accuracy" / "accuracy.csv").string());
  EXPECT_EQ(std::count(acc.begin(), acc.end(), '\n'), 1 + 5 + 3 + 1 + 2 + 5) << acc;
  EXPECT_EQ(acc.find("nan"), std::string::npos) << acc;
  EXPECT_EQ(acc.find("inf"), std::string::npos) << acc;

  // A given capture is studied without recording, with the same results.
  const auto again = Dir() / "study_again";
  const std::string capture = (out / "capture_2x2x2.rct").string();
  const Result r2 =
      Raycell("study --trace " + capture + " --accuracy-frames 0 --quiet --out " + again.string());
  ASSERT_EQ(r2.code, 0) << r2.out;
  EXPECT_EQ(raycell::testing::ReadBytes((again / "fetches_capture_2x2x2.csv").string()), fetches);
  EXPECT_EQ(raycell::testing::ReadBytes((again / "cell_trees_capture_2x2x2.csv").string()),
            raycell::testing::ReadBytes((out / "cell_trees_2x2x2.csv").string()));
  EXPECT_GT(std::filesystem::file_size(again / "fetches_capture_2x2x2.png"), 1000u);
  EXPECT_FALSE(std::filesystem::exists(again / "images_2x2x2"));
  const Result r3 = Raycell("study --trace " + capture + " --cells 3x3x3 --out " + again.string());
  EXPECT_EQ(r3.code, 2);
  EXPECT_NE(r3.out.find("--cells excludes --trace"), std::string::npos) << r3.out;
}

TEST(Cli, BadInputGetsAClearMessageAndExitCode2) {
  const auto d = Dir();
  Result r = Raycell("analyze " + (d / "missing.rct").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("missing.rct"), std::string::npos) << r.out;
  r = Raycell("analyze --paths " + (d / "missing.jsonl").string());
  EXPECT_EQ(r.code, 2);
  const auto bad = d / "bad.jsonl";
  std::ofstream(bad)
      << R"({"id":0,"parent":7,"spawn":0,"kind":"shadow","pixel":[0,0],"cells":[1],"samples":[1]})"
      << "\n";
  r = Raycell("analyze --paths " + bad.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("bad.jsonl:1:"), std::string::npos) << r.out;
  r = Raycell("record --cells 2x2 --out " + (d / "x.rct").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("2x2"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(d / "x.rct"));
  r = Raycell("analyze --format yaml --paths " + bad.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("yaml"), std::string::npos) << r.out;
  r = Raycell("record --precision half --out " + (d / "x.rct").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--precision: half"), std::string::npos) << r.out;
  r = Raycell("record --no-such-option");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--no-such-option"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(d / "x.rct"));
  EXPECT_EQ(Raycell("record --help").code, 0);
}

// Sizes beyond the limits fail before any work, naming the option and the limit: record's
// --cells before the scene is read (the missing file is not the error), and replay's
// processors x cells when the trace is opened.
TEST(Cli, SizesBeyondTheLimitsFailUpFrontNamingTheOptionAndTheLimit) {
  const auto d = Dir();
  Result r = Raycell("record --cells 1000x1000x1000 --res 8x8 --scene " +
                     (d / "missing.vdb").string() + " --out " + (d / "big.rct").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--cells 1000x1000x1000: 1000000000 cells exceeds the trace format's "
                       "limit of 4194304"),
            std::string::npos)
      << r.out;
  r = Raycell("record --fov 0 --out " + (d / "big.rct").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--fov 0: the vertical field of view must be in (0, 180)"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(std::filesystem::exists(d / "big.rct.tmp"));
  const std::string trace = (d / "fine.rct").string();
  ASSERT_EQ(Raycell("record --res 8x8 --cells 64x64x64 --no-images --quiet --out " + trace).code,
            0);
  r = Raycell("replay " + trace + " --set processors.count=1024 --quiet");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("processors.count 1024 x 262144 cells of the trace = 268435456 exceeds "
                       "the limit of 134217728"),
            std::string::npos)
      << r.out;
}

TEST(Cli, RecordInSinglePrecisionSaysSoInTheTrace) {
  const auto d = Dir();
  const std::string out = (d / "single.rct").string();
  Result r = Raycell("record --res 16x16 --precision single --no-images --quiet --out " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  r = Raycell("trace info " + out);
  EXPECT_NE(r.out.find("single precision"), std::string::npos) << r.out;
  r = Raycell("record --res 16x16 --no-images --quiet --out " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(Raycell("trace info " + out).out.find("double precision"), std::string::npos);
}

}  // namespace
