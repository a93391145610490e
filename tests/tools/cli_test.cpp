// The raycell command line end to end: record, trace cat, analyze; exit codes and messages
// for bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "base/file.h"
#include "study/accuracy.h"
#include "tests/test_util.h"
#include "tests/tools/cli_util.h"
#include "tests/tools/json_value.h"

namespace {

using raycell::testing::CsvRow;
using raycell::testing::Raycell;
using raycell::testing::Result;

// This process's folder for the tests' files (made once, emptied when made).
std::filesystem::path Dir() {
  static const std::filesystem::path dir = raycell::testing::TempDir("cli");
  return dir;
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

// The lines of `full` (as `trace cat` writes them) in the least form another tool may write:
// only frame, id, parent, spawn and cells, keys shuffled, ids a random increasing map with
// gaps, lines shuffled within each frame.
std::string ShuffledMinimal(const std::string& full, std::mt19937& rng) {
  using raycell::testing::Json;
  std::vector<std::vector<std::string>> frames;
  std::map<std::string, std::uint64_t> ids;  // "frame/id" -> new id
  std::uint64_t next = 1000;
  std::string frame = "none";
  std::istringstream in(full);
  for (std::string line; std::getline(in, line);) {
    const Json j = Json::Parse(line);
    const std::string f = j.members[0].first == "frame" ? j["frame"].text : "";
    if (frames.empty() || f != frame) frames.emplace_back();
    frame = f;
    next += 1 + rng() % 1000;
    ids[f + "/" + j["id"].text] = next;
    const bool primary = j["parent"].type == Json::Type::kNull;
    std::string cells = "[";
    for (const Json& c : j["cells"].items) cells += (cells.size() > 1 ? "," : "") + c.text;
    std::vector<std::string> kv = {
        "\"id\":" + std::to_string(next),
        "\"parent\":" + (primary ? "null" : std::to_string(ids.at(f + "/" + j["parent"].text))),
        "\"spawn\":" + (primary ? "null" : j["spawn"].text), "\"cells\":" + cells + "]"};
    if (!f.empty()) kv.push_back("\"frame\":" + f);
    std::shuffle(kv.begin(), kv.end(), rng);
    std::string out = "{";
    for (const std::string& x : kv) out += (out.size() > 1 ? ", " : "") + x;
    frames.back().push_back(out + "}\n");
  }
  std::string out;
  for (auto& lines : frames) {
    std::shuffle(lines.begin(), lines.end(), rng);
    for (const std::string& l : lines) out += l;
  }
  return out;
}

// Other tools write paths in other orders with fewer keys: the analysis is the same byte for
// byte (nothing it reports depends on kind, pixel or samples).
TEST(Cli, AnalyzePathsOfAShuffledMinimalFileEqualsTheOrderedFullFile) {
  const auto d = Dir();
  const std::string trace = (d / "two.rct").string(), full = (d / "full.jsonl").string(),
                    minimal = (d / "minimal.jsonl").string();
  ASSERT_EQ(
      Raycell("record --res 32x32 --cells 3x3x3 --orbit 2:40 --no-images --quiet --out " + trace)
          .code,
      0);
  ASSERT_EQ(Raycell("trace cat " + trace + " > " + full).code, 0);
  std::mt19937 rng(5);
  const std::string shuffled = ShuffledMinimal(raycell::testing::ReadBytes(full), rng);
  std::ofstream(minimal) << shuffled;
  ASSERT_NE(shuffled, raycell::testing::ReadBytes(full));
  const Result a = Raycell("analyze --paths " + full + " --format json", false);
  const Result b = Raycell("analyze --paths " + minimal + " --format json", false);
  ASSERT_EQ(a.code, 0) << a.out;
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_EQ(std::count(a.out.begin(), a.out.end(), '\n'), 2);  // both frames
  EXPECT_EQ(a.out, b.out);
  const Result t = Raycell("analyze " + trace + " --format json --quiet", false);
  EXPECT_EQ(t.out, a.out);
  const Result one = Raycell("analyze --paths " + minimal + " --frame 1 --format csv", false);
  ASSERT_EQ(one.code, 0) << one.out;
  EXPECT_EQ(one.out, Raycell("analyze " + trace + " --frame 1 --format csv --quiet", false).out);
}

// The tour's `raycell trace cat` and `raycell trace import` lines, run exactly as the README
// shows them (on a small capture with the tour's smoke.rct's cell grid): the import gives the
// same rays back, and replays.
TEST(Cli, ReadmeTourImportRunsAsShown) {
  std::istringstream readme(raycell::testing::ReadBytes(RAYCELL_SOURCE_DIR "/README.md"));
  std::string cat, import;
  for (std::string line; std::getline(readme, line);) {
    const std::string command = line.substr(0, line.find(" #"));
    if (line.rfind("raycell trace cat ", 0) == 0) cat = command;
    if (line.rfind("raycell trace import ", 0) == 0) import = command;
  }
  ASSERT_NE(cat, "") << "no `raycell trace cat` line in the README";
  ASSERT_NE(import, "") << "no `raycell trace import` line in the README";
  EXPECT_NE(cat.find("smoke.rct --frame 3"), std::string::npos) << cat;
  const auto d = Dir() / "tour";
  std::filesystem::create_directories(d);
  ASSERT_EQ(Raycell("record --res 24x24 --cells 3x3x3 --orbit 4:60 --no-images --quiet --out " +
                    (d / "smoke.rct").string())
                .code,
            0);
  const std::string in_dir = "cd " + d.string() + " && " + RAYCELL_BINARY;
  const auto run = [&](const std::string& command) {
    const std::string cmd = in_dir + command.substr(std::string("raycell").size()) + " 2>&1";
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  ASSERT_EQ(run(cat), 0) << cat;
  ASSERT_EQ(run(import), 0) << import;
  const std::string rays = raycell::testing::ReadBytes((d / "rays.jsonl").string());
  ASSERT_GT(rays.size(), 1000u);
  const std::string out = import.substr(import.find("--out ") + 6);
  const std::string imported = (d / out.substr(0, out.find(' '))).string();
  EXPECT_EQ(Raycell("trace cat " + imported, false).out, rays);
  const Result replay = Raycell("replay " + imported + " --format json --quiet", false);
  ASSERT_EQ(replay.code, 0) << replay.out;
  EXPECT_NE(replay.out.find("\"total\":{\"fetches\":"), std::string::npos) << replay.out;
  const Result analyze = Raycell("analyze " + imported + " --format csv --quiet", false);
  EXPECT_EQ(analyze.out,
            Raycell("analyze --paths " + (d / "rays.jsonl").string() + " --format csv", false).out);
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

// Segments and samples of the ray trees whose order in their frame is even, from the JSON
// Lines of `trace cat` (every frame; a primary ray starts a ray tree).
struct SampleCounts {
  std::uint64_t segments = 0, samples = 0;
};
SampleCounts EvenRayTrees(const std::string& jsonl) {
  SampleCounts c;
  std::string frame;
  long tree = -1;
  std::istringstream lines(jsonl);
  for (std::string line; std::getline(lines, line);) {
    const std::string f = line.substr(0, line.find(','));
    if (f != frame) frame = f, tree = -1;
    if (line.find("\"parent\":null") != std::string::npos) ++tree;
    if (tree % 2 != 0) continue;
    const std::size_t s = line.find("\"samples\":[") + 11;
    std::istringstream values(line.substr(s, line.find(']', s) - s));
    for (std::string v; std::getline(values, v, ',');) c.segments += 1, c.samples += std::stoull(v);
  }
  return c;
}

// The value of `key` in the "total" object of `raycell replay --format json`.
std::uint64_t TotalOf(const std::string& json, const std::string& key) {
  const std::size_t total = json.find("\"total\":{");
  const std::size_t at = json.find("\"" + key + "\":", total);
  if (total == std::string::npos || at == std::string::npos) return 0;
  return std::stoull(json.substr(at + key.size() + 3));
}

// The table shows each frame's time beside its lower bound under any scheduler and the
// time over the bound (at least 1), as the JSON's time_ps and time_bound_ps give them.
TEST(Cli, ReplayTableShowsTheTimeAgainstItsBound) {
  const auto d = Dir();
  const std::string trace = (d / "table.rct").string();
  ASSERT_EQ(Raycell("record --res 24x24 --orbit 2:90 --no-images --quiet --out " + trace).code, 0);
  for (const std::string options : {"", " --set processors.count=3"}) {
    const Result table = Raycell("replay " + trace + " --quiet" + options);
    const Result json = Raycell("replay " + trace + " --format json --quiet" + options);
    ASSERT_EQ(table.code, 0) << table.out;
    ASSERT_EQ(json.code, 0) << json.out;
    EXPECT_NE(table.out.find("      time ms time bound ms time/bound      work ms"),
              std::string::npos)
        << table.out;
    const std::uint64_t time = TotalOf(json.out, "time_ps");
    const std::uint64_t bound = TotalOf(json.out, "time_bound_ps");
    ASSERT_GT(bound, 0u) << json.out;
    EXPECT_LE(bound, time);
    char row[64];
    std::snprintf(row, sizeof row, " %12.3f %13.3f %10.3f ", double(time) * 1e-9,
                  double(bound) * 1e-9, double(time) / double(bound));
    const std::size_t total = table.out.find("\n   total ");
    ASSERT_NE(total, std::string::npos) << table.out;
    EXPECT_NE(table.out.find(row, total), std::string::npos) << row << "\n" << table.out;
  }
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
  // Sampling 1 in 1 ray trees is the full replay; 1 in 2 replays the even ray trees of each
  // frame and scales their segments and samples back by 2 (counted here from `trace cat`).
  const Result s1 = Raycell("replay " + trace + " --format json --quiet --sample 1");
  EXPECT_EQ(s1.out, a.out);
  const Result s2 = Raycell("replay " + trace + " --format json --quiet --sample 2");
  ASSERT_EQ(s2.code, 0) << s2.out;
  const Result cat = Raycell("trace cat " + trace);
  ASSERT_EQ(cat.code, 0);
  const SampleCounts even = EvenRayTrees(cat.out);
  ASSERT_GT(even.segments, 0u);
  EXPECT_EQ(TotalOf(s2.out, "segments"), 2 * even.segments) << s2.out;
  EXPECT_EQ(TotalOf(s2.out, "samples"), 2 * even.samples) << s2.out;
  EXPECT_NE(TotalOf(s2.out, "segments"), TotalOf(a.out, "segments"));
  const std::string vary = " --vary scheduler=maxwork,celltree,peel --vary processors.count=1,2";
  const std::string one = (d / "one.csv").string(), two = (d / "two.csv").string();
  ASSERT_EQ(Raycell("sweep " + trace + vary + " --jobs 1 --quiet --out " + one).code, 0);
  ASSERT_EQ(Raycell("sweep " + trace + vary + " --jobs 2 --quiet --out " + two).code, 0);
  const std::string rows = raycell::testing::ReadBytes(one);
  EXPECT_EQ(rows, raycell::testing::ReadBytes(two));
  EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), 2 + 6);  // comment, header, 6 rows
}

// The rows of a CSV file without its comment lines (# ...), each split into fields.
std::vector<std::vector<std::string>> CsvRows(const std::filesystem::path& file) {
  return raycell::testing::CsvText(raycell::testing::ReadBytes(file.string()));
}

// The samples of every frame of `capture`, as `raycell trace info` totals them.
std::uint64_t TraceSamples(const std::string& capture) {
  const Result info = Raycell("trace info " + capture);
  EXPECT_EQ(info.code, 0) << info.out;
  std::istringstream in(info.out);
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    // total, primary, reflection, refraction, shadow, rays, visits, samples, bytes, B/visit
    if (w.size() == 10 && w[0] == "total") return std::stoull(w[7]);
  }
  ADD_FAILURE() << "no total line in " << info.out;
  return 0;
}

// A study folder's processors.csv against `raycell sweep` of its capture on the same
// schedulers and processor counts: the same numbers, each time above its bound, and the work
// of the capture's samples (10 ns each, the default) in every row.
void ExpectProcessorsAsSweepGivesThem(const std::filesystem::path& study,
                                      const std::string& capture) {
  const auto rows = CsvRows(study / "processors.csv");
  ASSERT_EQ(rows.size(), 16u);  // header + 3 schedulers x 5 counts
  const std::vector<std::string> header = {"scheduler", "processors",    "fetches",
                                           "time_ps",   "time_bound_ps", "work_ps",
                                           "stall_ps",  "idle_ps",       "utilisation"};
  EXPECT_EQ(rows[0], header);
  const auto out = study / "processors_sweep.csv";
  const Result sweep = Raycell("sweep " + capture +
                               " --vary scheduler=maxwork,celltree,balanced --vary "
                               "processors.count=1,2,4,8,16 --quiet --out " +
                               out.string());
  ASSERT_EQ(sweep.code, 0) << sweep.out;
  const auto swept = CsvRows(out);
  ASSERT_EQ(swept.size(), rows.size());
  std::map<std::string, std::size_t> column;
  for (std::size_t c = 0; c < swept[0].size(); ++c) column[swept[0][c]] = c;
  column["processors"] = column.at("processors.count");
  const std::uint64_t samples = TraceSamples(capture);
  ASSERT_GT(samples, 0u);
  const std::vector<std::string> schedulers = {"maxwork", "celltree", "balanced"},
                                 counts = {"1", "2", "4", "8", "16"};
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const std::vector<std::string>& row = rows[i];
    ASSERT_EQ(row.size(), header.size()) << i;
    EXPECT_EQ(row[0], schedulers[(i - 1) / 5]) << i;
    EXPECT_EQ(row[1], counts[(i - 1) % 5]) << i;
    for (std::size_t c = 0; c < header.size(); ++c) {
      EXPECT_EQ(row[c], swept[i].at(column.at(header[c]))) << header[c] << " in row " << i;
    }
    EXPECT_EQ(swept[i].at(column.at("samples")), std::to_string(samples)) << i;
    EXPECT_GE(std::stoull(row[3]), std::stoull(row[4])) << "time below its bound in row " << i;
    EXPECT_EQ(std::stoull(row[5]), samples * 10000) << "work in row " << i;
    EXPECT_GT(std::stoull(row[2]), 0u) << i;
  }
  EXPECT_GT(std::filesystem::file_size(study / "processors.png"), 1000u);
}

// `raycell record` with no --out and no --images writes out/capture.rct and out/images/ and
// nothing else into the folder it runs in (out/ is git-ignored: a run in a clone leaves
// `git status` clean).
TEST(Cli, RecordDefaultsWriteOnlyUnderOut) {
  const auto cwd = Dir() / "record_cwd";
  std::filesystem::create_directories(cwd);
  const Result r = Raycell("record --res 8x8 --quiet", true, cwd.string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::vector<std::string> top;
  for (const auto& e : std::filesystem::directory_iterator(cwd)) {
    top.push_back(e.path().filename().string());
  }
  EXPECT_EQ(top, std::vector<std::string>{"out"});
  EXPECT_GT(std::filesystem::file_size(cwd / "out" / "capture.rct"), 100u);
  EXPECT_TRUE(std::filesystem::exists(cwd / "out" / "images" / "frame_0000.png"));
  EXPECT_EQ(Raycell("trace verify out/capture.rct", true, cwd.string()).code, 0);
  // --out's folder is made when missing; one that cannot be made (under a file) is bad input
  // naming the file, exit 2, as any unwritable --out.
  std::ofstream(cwd / "a_file") << "x";
  const Result bad =
      Raycell("record --res 8x8 --quiet --no-images --out a_file/x.rct", true, cwd.string());
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("a_file/x.rct"), std::string::npos) << bad.out;
}

TEST(Cli, StudyWritesTheReportItsCsvsAndPlots) {
  // The interpreter the study runs (tools/study_command.cpp: /usr/bin/python3 where it exists).
  const char* python = std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  if (std::system((std::string(python) + " -c 'import matplotlib' >/dev/null 2>&1").c_str()) != 0) {
    GTEST_SKIP() << "the study's plots need python3 with matplotlib (tools/setup.sh installs it)";
  }
  // Run with no --out from a folder of its own, as a user in a clone would: everything goes
  // to out/study/ and nothing else appears beside it (the plot scripts are found beside the
  // binary, not in the source tree).
  const auto cwd = Dir() / "study_cwd";
  std::filesystem::create_directories(cwd);
  const auto out = cwd / "out" / "study";
  const Result r = Raycell(
      "study --res 24x24 --frames 3 --cells 2x2x2,1x2x1 --accuracy-frames 1 "
      "--accuracy-res 16x16 --scale-frames 0 --quiet",
      true, cwd.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("report: out/study/report.md"), std::string::npos) << r.out;
  std::vector<std::string> top;
  for (const auto& e : std::filesystem::directory_iterator(cwd)) {
    top.push_back(e.path().filename().string());
  }
  EXPECT_EQ(top, std::vector<std::string>{"out"});
  std::vector<std::string> in_out;
  for (const auto& e : std::filesystem::directory_iterator(cwd / "out")) {
    in_out.push_back(e.path().filename().string());
  }
  EXPECT_EQ(in_out, std::vector<std::string>{"study"});
  for (const char* cells : {"2x2x2", "1x2x1"}) {
    for (const std::string f : {"fetches_", "cell_trees_"}) {
      EXPECT_TRUE(std::filesystem::exists(out / (f + cells + ".csv"))) << f << cells;
      EXPECT_GT(std::filesystem::file_size(out / (f + cells + ".png")), 1000u) << f << cells;
    }
    EXPECT_GT(std::filesystem::file_size(out / ("bracket_" + std::string(cells) + ".png")), 1000u);
    EXPECT_TRUE(std::filesystem::exists(out / ("images_" + std::string(cells)) / "frame_0002.png"));
  }
  const std::string report = raycell::testing::ReadBytes((out / "report.md").string());
  EXPECT_NE(report.find("| fetches, Cell Tree scheduling (Peel of frame i's tree) |"),
            std::string::npos);
  EXPECT_NE(report.find("![fetches per frame](fetches_2x2x2.png)"), std::string::npos);
  // The scale section (tests/study/scale_test) skipped as asked, saying so.
  EXPECT_NE(report.find("## Scale\n\nNot measured: skipped (--scale-frames 0)."),
            std::string::npos);
  EXPECT_NE(report.find("![bracket of the optimum](bracket_2x2x2.png)"), std::string::npos);
  EXPECT_NE(report.find("against the best-schedule oracle | "), std::string::npos) << report;
  // With two cells Peel meets the lower bound on every frame: nothing to close.
  EXPECT_NE(report.find("| share of Peel's distance to the lower bound closed by the best "
                        "schedule | - |"),
            std::string::npos)
      << report;
  const std::string fetches = raycell::testing::ReadBytes((out / "fetches_2x2x2.csv").string());
  EXPECT_EQ(std::count(fetches.begin(), fetches.end(), '\n'), 4);  // header + 3 frames
  EXPECT_EQ(fetches.substr(0, fetches.find('\n')),
            "frame,maxwork,celltree,celltree-best,celltree-union,celltree-adaptive,peel,best,bound,"
            "lower_bound,"
            "best_length");
  // Per frame: maxGen bound <= best lower bound <= best schedule found <= Peel's length, and
  // the optimum, where proved, is both ends.
  std::istringstream trees(raycell::testing::ReadBytes((out / "cell_trees_2x2x2.csv").string()));
  std::string row;
  std::getline(trees, row);
  EXPECT_EQ(row,
            "frame,rays,nodes,rays_per_node,bound,peel_length,splits,optimum,lower_bound,"
            "best_length,gap");
  int frames = 0;
  while (std::getline(trees, row)) {
    std::vector<std::string> v;
    std::istringstream cols(row);
    for (std::string c; std::getline(cols, c, ',');) v.push_back(c);
    ASSERT_EQ(v.size(), 11u) << row;
    const int bound = std::stoi(v[4]), peel = std::stoi(v[5]), lower = std::stoi(v[8]),
              best = std::stoi(v[9]);
    EXPECT_LE(bound, lower) << row;
    EXPECT_LE(lower, best) << row;
    EXPECT_LE(best, peel) << row;
    if (!v[7].empty()) {
      EXPECT_EQ(std::stoi(v[7]), lower) << row;
      EXPECT_EQ(std::stoi(v[7]), best) << row;
    }
    ++frames;
  }
  EXPECT_EQ(frames, 3);
  // Run time against error: every knob's rows, finite, with their plot.
  EXPECT_NE(report.find("## Run time against error"), std::string::npos);
  EXPECT_NE(report.find("| renderer precision | single |"), std::string::npos) << report;
  EXPECT_NE(report.find("![run time against error](accuracy/accuracy.png)"), std::string::npos);
  EXPECT_GT(std::filesystem::file_size(out / "accuracy" / "accuracy.png"), 1000u);
  const std::string acc = raycell::testing::ReadBytes((out / "accuracy" / "accuracy.csv").string());
  // One row per knob setting the library declares, in its order, with its value and default.
  std::vector<std::vector<std::string>> rows;
  for (std::size_t at = 0, end; (end = acc.find("\r\n", at)) != std::string::npos; at = end + 2) {
    rows.push_back(CsvRow(acc.substr(at, end - at)));
  }
  const std::vector<raycell::AccuracyKnob>& knobs = raycell::AccuracyKnobs();
  ASSERT_EQ(rows.size(), 1 + knobs.size()) << acc;
  EXPECT_EQ(rows[0], (std::vector<std::string>{"knob", "value", "seconds", "time_ratio", "error",
                                               "error_kind", "fetch_change", "default"}));
  for (std::size_t i = 0; i < knobs.size(); ++i) {
    const std::vector<std::string>& row = rows[i + 1];
    ASSERT_EQ(row.size(), 8u) << acc;
    EXPECT_EQ(row[0], knobs[i].knob) << acc;
    EXPECT_EQ(row[1], knobs[i].value) << acc;
    EXPECT_EQ(row[7], knobs[i].is_default ? "True" : "False") << acc;
  }
  EXPECT_EQ(acc.find("nan"), std::string::npos) << acc;
  EXPECT_EQ(acc.find("inf"), std::string::npos) << acc;
  // The depth section, from the max depth captures: depth.csv (max depth 0..5, record's default
  // 3 marked) and depth.png.
  EXPECT_NE(report.find("## Limited depth recursion\n\nThe renderer's maximum depth"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("![rays, fetches, time and error against max depth](depth.png)"),
            std::string::npos);
  EXPECT_GT(std::filesystem::file_size(out / "depth.png"), 1000u);
  std::istringstream depth(raycell::testing::ReadBytes((out / "depth.csv").string()));
  std::getline(depth, row);
  EXPECT_EQ(row,
            "max_depth,default,rays,primary_rays,reflection_rays,refraction_rays,shadow_rays,"
            "nodes,fetches_maxwork,fetches_celltree,time_maxwork_ps,time_celltree_ps,rmse");
  int depths = 0;
  while (std::getline(depth, row)) {
    const std::vector<std::string> v = CsvRow(row);
    ASSERT_EQ(v.size(), 13u) << row;
    EXPECT_EQ(v[0], std::to_string(depths)) << row;
    EXPECT_EQ(v[1], depths == 3 ? "1" : "0") << row;
    ++depths;
  }
  EXPECT_EQ(depths, 6);
  // The subdivision section: one fine capture regrouped into every SPEC, each under Max Work and
  // Cell Tree scheduling, the cache sized to the median 3x3x3 footprint; the uniform grid's rows
  // are what `raycell replay` of the fine capture with --cells 3x3x3 reports.
  EXPECT_NE(report.find("## Subdivisions\n\nCells of several shapes from one capture"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("![bytes moved and fetch stall per subdivision](subdivisions.png)"),
            std::string::npos);
  EXPECT_GT(std::filesystem::file_size(out / "subdivisions.png"), 1000u);
  std::istringstream subdivisions(raycell::testing::ReadBytes((out / "subdivisions.csv").string()));
  std::getline(subdivisions, row);
  EXPECT_EQ(row,
            "spec,scheduler,cells,footprint_min,footprint_median,footprint_max,fetches,cache_bytes,"
            "board_bytes,stall_ps,time_ps");
  std::vector<std::vector<std::string>> sub_rows;
  while (std::getline(subdivisions, row)) sub_rows.push_back(CsvRow(row));
  ASSERT_EQ(sub_rows.size(), 18u);
  EXPECT_EQ(sub_rows[0][0], "3x3x3");
  EXPECT_EQ(sub_rows[6][0], "kd:27:sqrt");
  EXPECT_EQ(sub_rows[12][0], "dynamic:27");
  EXPECT_EQ(sub_rows[14][0], "dynamic:27:sqrt");
  EXPECT_EQ(sub_rows[16][0], "grid:27:crossings");
  const Result uniform =
      Raycell("replay " + (out / "subdivisions" / "fine.rct").string() +
              " --cells 3x3x3 --scheduler celltree --set level.cache.capacity=" + sub_rows[1][4] +
              "B --format json");
  ASSERT_EQ(uniform.code, 0) << uniform.out;
  EXPECT_NE(uniform.out.find("\"total\":{\"fetches\":" + sub_rows[1][6] + ","), std::string::npos)
      << uniform.out;
  // Several processors, on the finest grid (the last of --cells) only.
  EXPECT_NE(report.find("## Several processors (1x2x1 cells)\n"), std::string::npos) << report;
  EXPECT_EQ(report.find("## Several processors (2x2x2 cells)"), std::string::npos) << report;
  EXPECT_NE(report.find("| processors | fetches, `maxwork` |"), std::string::npos) << report;
  EXPECT_NE(report.find("At 8 processors `balanced` fetches "), std::string::npos) << report;
  EXPECT_NE(report.find("![time and fetches against processors](processors.png)"),
            std::string::npos);
  ExpectProcessorsAsSweepGivesThem(out, (out / "capture_1x2x1.rct").string());

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
  // The given trace (the last one) is the finest grid: its 8 cells on several processors.
  const std::string again_report = raycell::testing::ReadBytes((again / "report.md").string());
  EXPECT_NE(again_report.find("## Several processors (`" + capture + "` (2x2x2 cells))\n"),
            std::string::npos)
      << again_report;
  ExpectProcessorsAsSweepGivesThem(again, capture);
  // No run time against error: no depth section, and the report says why.
  EXPECT_NE(again_report.find("## Limited depth recursion\n\nNot measured: it reads the run time "
                              "against error section's captures, which `--accuracy-frames 0` "
                              "skipped.\n"),
            std::string::npos)
      << again_report;
  EXPECT_FALSE(std::filesystem::exists(again / "depth.csv"));
  EXPECT_FALSE(std::filesystem::exists(again / "depth.png"));
  // --subdivision-frames 0 skips that section altogether.
  const Result r_nosub = Raycell("study --trace " + capture +
                                 " --accuracy-frames 0 --subdivision-frames 0 --quiet --out " +
                                 (Dir() / "study_nosub").string());
  ASSERT_EQ(r_nosub.code, 0) << r_nosub.out;
  EXPECT_EQ(raycell::testing::ReadBytes((Dir() / "study_nosub" / "report.md").string())
                .find("## Subdivisions"),
            std::string::npos);
  // A fine grid 3x3x3 is not made of is refused before any work, naming the option.
  const Result r_fine = Raycell("study --trace " + capture + " --subdivision-fine 8x8x8 --out " +
                                (Dir() / "study_badfine").string());
  EXPECT_EQ(r_fine.code, 2);
  EXPECT_NE(r_fine.out.find("--subdivision-fine '8x8x8': each count must be a multiple of 3"),
            std::string::npos)
      << r_fine.out;
  EXPECT_FALSE(std::filesystem::exists(Dir() / "study_badfine" / "report.md"));
  const Result r3 = Raycell("study --trace " + capture + " --cells 3x3x3 --out " + again.string());
  EXPECT_EQ(r3.code, 2);
  EXPECT_NE(r3.out.find("--cells excludes --trace"), std::string::npos) << r3.out;
  // 16 processors on 256x256x200 cells are beyond the memory model's limit: refused before
  // any recording.
  const auto huge = Dir() / "study_huge";
  const Result r4 = Raycell(
      "study --cells 2x2x2,256x256x200 --res 8x8 --frames 2 --accuracy-frames 0 --quiet --out " +
      huge.string());
  EXPECT_EQ(r4.code, 2) << r4.out;
  EXPECT_NE(r4.out.find("--cells '256x256x200': too many cells for the several processors "
                        "section: processors.count 16 x 13107200 cells"),
            std::string::npos)
      << r4.out;
  EXPECT_FALSE(std::filesystem::exists(huge));
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
  const auto big = d / "big_cell.jsonl";
  std::ofstream(big) << R"({"id":0,"parent":null,"spawn":null,"cells":[0]})"
                        "\n"
                     << R"({"id":1,"parent":null,"spawn":null,"cells":[8]})"
                        "\n";
  r = Raycell("trace import " + big.string() + " --cells 2x2x2 --out " + (d / "x.rct").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("big_cell.jsonl:2: ray 1: cell 8 out of range: --cells 2x2x2 has 8 cells"),
            std::string::npos)
      << r.out;
  r = Raycell("trace import " + big.string() + " --cells 3x3x3 --footprint 12 --out " +
              (d / "x.rct").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--footprint"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(d / "x.rct"));
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
  // A bad value of a command's own flag names the flag, not the configuration key it sets.
  ASSERT_EQ(Raycell("record --res 8x8 --quiet --images " + (d / "img").string() + " --out " +
                    (d / "small.rct").string())
                .code,
            0);
  for (const std::string flag : {"--scheduler", "--granularity"}) {
    r = Raycell("replay " + (d / "small.rct").string() + " " + flag + " foo");
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.out.find(flag + ": unknown"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("override"), std::string::npos) << r.out;
  }
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
                       "limit of 16777216"),
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
  // sweep checks every combination, from --vary or the configuration, before it writes
  // anything (it used to start replaying, allocating 2 GiB per combination).
  const auto sweep_out = d / "sweep.csv";
  r = Raycell("sweep " + trace + " --vary processors.count=1,1024 --quiet --out " +
              sweep_out.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--vary: combination 1: processors.count 1024 x 262144 cells of the trace "
                       "= 268435456 exceeds the limit of 134217728"),
            std::string::npos)
      << r.out;
  const auto toml = d / "many.toml";
  std::ofstream(toml) << "[processors]\ncount = 600\n";
  r = Raycell("sweep " + trace + " --config " + toml.string() + " --quiet --out " +
              sweep_out.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--config " + toml.string() + ": processors.count 600 x 262144 cells"),
            std::string::npos)
      << r.out;
  for (const char* suffix : {"", ".partial", ".checkpoint"}) {
    EXPECT_FALSE(std::filesystem::exists(sweep_out.string() + suffix)) << suffix;
  }
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

namespace timeline {

using raycell::testing::Json;

// `raycell replay --timeline`, run as the README's tour shows it (in a folder holding a small
// smoke.rct of four frames): a JSON document with the frames asked for, and the replay's
// output the same byte for byte as without a timeline.
TEST(Cli, ReadmeTourTimelineRunsAsShown) {
  std::istringstream readme(raycell::testing::ReadBytes(RAYCELL_SOURCE_DIR "/README.md"));
  std::string command;
  for (std::string line; std::getline(readme, line);) {
    if (line.rfind("raycell replay ", 0) == 0 && line.find("--timeline") != std::string::npos) {
      command = line.substr(0, line.find(" #"));
    }
  }
  ASSERT_NE(command, "") << "no `raycell replay ... --timeline` line in the README";
  EXPECT_NE(command.find("--frames 0..1"), std::string::npos) << command;
  const auto d = Dir() / "tour_timeline";
  std::filesystem::create_directories(d);
  const std::string trace = (d / "smoke.rct").string();
  ASSERT_EQ(
      Raycell("record --res 24x24 --cells 3x3x3 --orbit 4:60 --no-images --quiet --out " + trace)
          .code,
      0);
  const std::string run = "cd " + d.string() + " && " + RAYCELL_BINARY +
                          command.substr(std::string("raycell").size()) + " --quiet > /dev/null";
  ASSERT_EQ(std::system(run.c_str()), 0) << run;
  const std::string out = command.substr(command.find("--timeline ") + 11);
  const std::string file = (d / out.substr(0, out.find(' '))).string();
  const Json doc = Json::Parse(raycell::testing::ReadBytes(file));
  EXPECT_EQ(doc["otherData"]["schema"].text, "raycell-timeline/1");
  EXPECT_EQ(doc["otherData"]["frames"].text, "2");
  std::vector<std::string> frames;
  for (const Json& e : doc["traceEvents"].items) {
    if (e["ph"].text == "i") frames.push_back(e["name"].text);
  }
  EXPECT_EQ(frames, (std::vector<std::string>{"frame 0", "frame 1"}));
  EXPECT_FALSE(std::filesystem::exists(file + ".tmp"));

  const std::string options = " --frames 0..1 --format json --quiet --set processors.count=2";
  const Result with = Raycell("replay " + trace + options + " --timeline " + file, false);
  const Result without = Raycell("replay " + trace + options, false);
  ASSERT_EQ(with.code, 0) << with.out;
  EXPECT_EQ(with.out, without.out);
}

// Past its size limit (lowered by a hidden option) the timeline is refused, with a message
// that suggests --frames, and nothing is left behind: no file, no temporary. Nor can it be
// combined with --sample, and `raycell sweep` has no timeline.
TEST(Cli, TimelinePastItsLimitIsRefusedAndLeavesNothing) {
  const auto d = Dir() / "timeline_limit";
  std::filesystem::create_directories(d);
  const std::string trace = (d / "t.rct").string(), file = (d / "t.json").string();
  ASSERT_EQ(Raycell("record --res 24x24 --orbit 3:90 --no-images --quiet --out " + trace).code, 0);
  ASSERT_EQ(Raycell("replay " + trace + " --quiet --timeline " + file).code, 0);
  const std::uintmax_t size = std::filesystem::file_size(file);
  std::filesystem::remove(file);

  Result r = Raycell("replay " + trace + " --quiet --timeline " + file + " --timeline-limit " +
                     std::to_string(size - 1));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--timeline " + file + ": the timeline would exceed " +
                       std::to_string(size - 1) + " bytes (frames 0..2 fit)"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("--frames A..B"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(file));
  EXPECT_FALSE(std::filesystem::exists(file + ".tmp"));
  r = Raycell("replay " + trace + " --quiet --timeline " + file + " --timeline-limit " +
              std::to_string(size));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(std::filesystem::file_size(file), size);
  std::filesystem::remove(file);

  r = Raycell("replay " + trace + " --quiet --sample 2 --timeline " + file);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--timeline shows the replay as it ran"), std::string::npos) << r.out;
  r = Raycell("sweep " + trace + " --vary scheduler=maxwork --quiet --out " +
              (d / "s.csv").string() + " --timeline " + file);
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_FALSE(std::filesystem::exists(file));
  EXPECT_FALSE(std::filesystem::exists(file + ".tmp"));
}

}  // namespace timeline

namespace {

// Rows of a suite scene file (study/suite.h): the lines after its rows' header.
std::vector<std::string> SuiteRows(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<std::string> rows;
  bool past = false;
  for (std::string line; std::getline(in, line);) {
    if (past) rows.push_back(line);
    if (line.rfind("kind,", 0) == 0) past = true;
  }
  return rows;
}

}  // namespace

// raycell suite end to end on one scene file of the shipped suite (found beside the binary,
// where the build copies it): every comparison has its rows, a second run reuses the capture
// and writes the same bytes, and bad options fail at once, naming the option, leaving nothing.
TEST(Cli, SuiteReplaysEveryComparisonReusesItsCaptureAndRefusesBadOptions) {
  const auto d = Dir() / "suite";
  const std::string scene =
      (std::filesystem::path(RAYCELL_BINARY).parent_path() / "scenes" / "dense_fog.toml").string();
  const std::string args = "suite --quiet --scenes " + scene +
                           " --res 16x16 --frames 2 --fine 6x6x6 --out " + d.string();
  Result r = Raycell(args);
  ASSERT_EQ(r.code, 0) << r.out;
  const std::vector<std::string> rows = SuiteRows(d / "scenes" / "dense_fog.csv");
  std::map<std::string, int> kinds;
  for (const std::string& row : rows) {
    ++kinds[row.substr(0, row.find(','))];
    EXPECT_EQ(row.find(",0,"), std::string::npos) << "a replay without fetches or time: " << row;
  }
  EXPECT_GE(kinds["scheduler"], 8) << "1 and 8 processors, four schedulers each at least";
  EXPECT_GE(kinds["cells"], 10) << "five subdivisions at least, under two schedulers";
  std::string report, csv;
  ASSERT_TRUE(raycell::ReadFile((d / "report.md").string(), &report));
  ASSERT_TRUE(raycell::ReadFile((d / "suite.csv").string(), &csv));
  EXPECT_NE(report.find("| dense_fog | dense fog with early termination."), std::string::npos)
      << report;
  EXPECT_TRUE(std::filesystem::exists(d / "suite.png"));
  r = Raycell(args.substr(0, args.find(" --quiet")) + args.substr(args.find(" --quiet") + 8));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("dense_fog: capture reused"), std::string::npos) << r.out;
  std::string again;
  ASSERT_TRUE(raycell::ReadFile((d / "report.md").string(), &again));
  EXPECT_EQ(again, report);

  const auto bad = Dir() / "suite-bad";
  for (const auto& [options, named] :
       std::vector<std::pair<std::string, std::string>>{{"--frames 1", "--frames 1"},
                                                        {"--processors 65", "--processors 65"},
                                                        {"--res 16x", "16x"},
                                                        {"--only nowhere", "--only 'nowhere'"},
                                                        {"--report", "dense_fog.csv"}}) {
    r = Raycell("suite --quiet --scenes " + scene + " " + options + " --out " + bad.string());
    EXPECT_EQ(r.code, 2) << options << ": " << r.out;
    EXPECT_NE(r.out.find(named), std::string::npos) << options << ": " << r.out;
    EXPECT_FALSE(std::filesystem::exists(bad / "report.md")) << options;
    EXPECT_FALSE(std::filesystem::exists(bad / "captures")) << options;
  }
  r = Raycell("suite --quiet --scenes " + (Dir() / "missing.toml").string() + " --out " +
              bad.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("missing.toml"), std::string::npos) << r.out;
}
