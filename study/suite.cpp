#include "study/suite.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <numeric>
#include <regex>
#include <sstream>

#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "base/hash.h"
#include "base/parallel.h"
#include "base/parse.h"
#include "record/record_flags.h"
#include "record/recorder.h"
#include "replay/config.h"
#include "runner/driver.h"
#include "scheduling/scheduler.h"
#include "study/subdivisions.h"
#include "traces/cell_dims.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;

// Degrees a volume's camera turns per frame, as the study's subdivision section turns it.
constexpr double kDegreesPerFrame = 3.75;

bool Registered(const std::string& name) {
  for (const SchedulerEntry& e : SchedulerRegistry()) {
    if (name == e.name) return true;
  }
  return false;
}

// What a scene file stands for: the first sentence of the comment block at its top.
std::string About(const std::string& path) {
  std::string text;
  if (!ReadFile(path, &text)) throw InputError("suite scene '" + path + "': cannot read it");
  std::istringstream in(text);
  std::string line, about;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] != '#') break;
    std::size_t i = line.find_first_not_of("# ");
    if (i == std::string::npos) continue;
    about += (about.empty() ? "" : " ") + line.substr(i);
  }
  // Its first sentence, without a leading "Character:".
  if (about.rfind("Character:", 0) == 0) about = Trim(about.substr(10));
  const std::size_t stop = about.find(". ");
  if (stop != std::string::npos) about = about.substr(0, stop + 1);
  return about;
}

// The volumes of `dir`: each .vdb file, and each run of numbered files NAME_0150.vdb ...
// (a sequence, as record's printf patterns read it) in a folder of its own.
void AddVolumes(const fs::path& dir, std::vector<SuiteScene>& out) {
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(dir)) entries.push_back(e.path());
  std::sort(entries.begin(), entries.end());
  static const std::regex numbered(R"((.*?)(\d+)\.vdb)");
  for (const fs::path& p : entries) {
    if (fs::is_regular_file(p) && p.extension() == ".vdb") {
      out.push_back({p.stem().string(), p.string(), "a volume of " + dir.string()});
    } else if (fs::is_directory(p)) {
      // A sequence: files PREFIX + digits + .vdb of one width.
      std::map<std::string, std::vector<int>> runs;  // pattern -> frame numbers
      for (const auto& f : fs::directory_iterator(p)) {
        std::smatch m;
        const std::string name = f.path().filename().string();
        if (!std::regex_match(name, m, numbered)) continue;
        const std::string pattern = m[1].str() + "%0" + std::to_string(m[2].length()) + "d.vdb";
        runs[pattern].push_back(std::stoi(m[2].str()));
      }
      for (auto& [pattern, frames] : runs) {
        std::sort(frames.begin(), frames.end());
        int count = 1;  // consecutive frames from the first
        while (count < int(frames.size()) && frames[count] == frames[0] + count) ++count;
        SuiteScene s{p.filename().string(), (p / pattern).string(),
                     "a volume sequence of " + dir.string() + " (its volume changes per frame)"};
        s.sequence = true;
        s.first_frame = frames[0];
        s.frame_count = count;
        out.push_back(s);
      }
    }
  }
}

void AddScenePath(const std::string& path, std::vector<SuiteScene>& out) {
  const fs::path p(path);
  if (fs::is_directory(p)) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(p)) {
      if (e.path().extension() == ".toml") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) out.push_back({f.stem().string(), f.string(), About(f)});
    AddVolumes(p, out);
    return;
  }
  if (!fs::is_regular_file(p)) {
    throw InputError("--scenes '" + path + "': no such file or folder");
  }
  if (p.extension() == ".toml") {
    out.push_back({p.stem().string(), path, About(path)});
  } else if (p.extension() == ".vdb") {
    out.push_back({p.stem().string(), path, "a volume"});
  } else {
    throw InputError("--scenes '" + path +
                     "': expected a scene file (.toml), a volume (.vdb) "
                     "or a folder of them");
  }
}

// The running binary, by size and modification time: a capture made by another build is made
// again (the renderer may have changed).
std::string Recorder() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "unknown";
  const auto size = fs::file_size(exe, ec);
  const auto time = fs::last_write_time(exe, ec).time_since_epoch().count();
  return std::to_string(size) + "/" + std::to_string(time);
}

std::string Stamp(const SuiteOptions& o, const SuiteScene& s, bool fine) {
  std::string text;
  Hash64 h;
  if (!s.sequence && ReadFile(s.file, &text)) h.AddBytes(text.data(), text.size());
  std::ostringstream out;
  out << "scene " << s.file << " content " << h.Finish() << " res " << o.res << " frames "
      << o.frames << " cells " << (fine ? o.fine + " regroupable" : o.cells) << " recorder "
      << Recorder() << "\n";
  return out.str();
}

struct SceneCapture {
  std::string path;
  bool fine = false;  // regroupable on options.fine: read regrouped
  double seconds = 0;
};

// Records the scene's capture unless an identical one (same stamp) is there. A regroupable
// fine capture when the scene allows it (one volume, not changing per frame), else one in
// options.cells.
SceneCapture RecordScene(const SuiteOptions& o, const SuiteScene& s) {
  const fs::path dir = fs::path(o.out) / "captures";
  fs::create_directories(dir);
  for (bool fine : {true, false}) {
    if (fine && s.sequence) continue;
    SceneCapture c{(dir / (s.name + (fine ? ".fine.rct" : ".rct"))).string(), fine};
    const std::string stamp_path = c.path + ".stamp", stamp = Stamp(o, s, fine);
    std::string old;
    if (fs::exists(c.path) && ReadFile(stamp_path, &old) && old == stamp) return c;
    RecordFlags flags;
    flags.opt.scene.source = s.file;
    flags.res = o.res;
    flags.cells = fine ? o.fine : o.cells;
    flags.opt.regroupable = fine;
    flags.opt.out = c.path;
    flags.opt.threads = o.threads;
    flags.no_images = true;
    flags.quiet = true;
    const int first = s.sequence ? s.first_frame : 0;
    const int count = s.sequence ? std::min(o.frames, s.frame_count) : o.frames;
    flags.frames = std::to_string(first) + ".." + std::to_string(first + count - 1);
    if (fs::path(s.file).extension() == ".vdb" && !s.sequence) {
      flags.orbit = std::to_string(count) + ":" + FormatReal(kDegreesPerFrame * count);
    }
    RecordOptions record = ToRecordOptions(flags);
    record.images_dir.clear();
    record.progress = !o.quiet;
    std::ostringstream log;
    try {
      const RecordSummary sum = Record(record, log);
      c.seconds = sum.seconds;
    } catch (const InputError& e) {
      // A scene whose volume changes per frame cannot be recorded regroupable: record it in
      // the replay's cells instead (its subdivision rows are then left out).
      if (fine && std::string(e.what()).find("regroupable") != std::string::npos) continue;
      throw;
    }
    WriteFileAtomically(stamp_path, stamp);
    return c;
  }
  RAYCELL_CHECK(false);
  return {};
}

// One replay per config over every frame: totals and the time of the frames after the first.
std::vector<SuiteRow> Replay(const TraceReader& reader, const std::vector<ReplayConfig>& configs,
                             std::vector<SuiteRow> rows) {
  std::vector<std::size_t> frames(reader.frames().size());
  std::iota(frames.begin(), frames.end(), std::size_t{0});
  ReplayFramesOptions opt;
  opt.jobs = std::max(1u, std::min(HardwareThreads(), unsigned(configs.size())));
  opt.caller_reads_trees = false;
  ReplayFrames(reader, frames, configs, opt,
               [&](const LoadedFrame& f, const std::vector<ReplayResult>& results) {
                 for (std::size_t i = 0; i < results.size(); ++i) {
                   const ReplayResult& r = results[i];
                   SuiteRow& row = rows[i];
                   row.fetches += r.fetches;
                   RAYCELL_CHECK(!r.levels.empty());
                   row.cache_bytes += r.levels[0].bytes;
                   const auto ps = std::uint64_t(r.time.picoseconds());
                   row.time_ps += ps;
                   if (f.position > 0) row.time_after_first_ps += ps;
                 }
                 return true;
               });
  return rows;
}

ReplayConfig Config(const std::string& scheduler, std::uint32_t processors,
                    std::uint64_t cache_bytes) {
  ReplayConfig c = DefaultConfig();
  const std::string where = "raycell suite";
  ApplyOverride(c, "scheduler", scheduler, where);
  ApplyOverride(c, "processors.count", std::to_string(processors), where);
  if (cache_bytes) {
    ApplyOverride(c, "level.cache.capacity", std::to_string(cache_bytes) + "B", where);
  }
  ValidateConfig(c, where);
  return c;
}

std::string Field(const std::string& text) {
  for (char ch : text) {
    if (ch == ',' || ch == '\n' || ch == '"') {
      std::string q = "\"";
      for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
      return q + "\"";
    }
  }
  return text;
}

}  // namespace

std::string SuiteFolder() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw InputError("suite: cannot find the running binary (/proc/self/exe)");
  const fs::path dir = exe.parent_path();
  for (const fs::path& p : {dir / "scenes", dir / ".." / "share" / "raycell" / "scenes"}) {
    if (fs::is_directory(p)) return p.lexically_normal().string();
  }
  throw InputError("suite: no scenes/ beside " + exe.string() + " nor in " +
                   (dir / ".." / "share" / "raycell" / "scenes").lexically_normal().string() +
                   " (the build copies the suite there; give --scenes DIR)");
}

std::vector<SuiteScene> SuiteScenes(const SuiteOptions& o) {
  std::vector<SuiteScene> out;
  if (o.scenes.empty()) {
    AddScenePath(SuiteFolder(), out);
    if (!o.data.empty() && fs::is_directory(o.data)) AddVolumes(o.data, out);
  } else {
    for (const std::string& p : o.scenes) AddScenePath(p, out);
  }
  std::map<std::string, std::string> seen;
  for (const SuiteScene& s : out) {
    auto [it, fresh] = seen.emplace(s.name, s.file);
    if (!fresh) {
      throw InputError("suite: two scenes are named '" + s.name + "' (" + it->second + " and " +
                       s.file + "): rename one");
    }
  }
  if (out.empty()) throw InputError("suite: no scene (.toml or .vdb) in the scenes given");
  return out;
}

std::vector<std::string> SuiteSchedulers(std::uint32_t processors) {
  const std::vector<std::string> one = {"maxwork", "celltree", "celltree-adaptive", "auto", "best"};
  const std::vector<std::string> many = {"maxwork", "balanced", "balanced-critical",
                                         "celltree-adaptive", "auto"};
  std::vector<std::string> out;
  for (const std::string& s : processors == 1 ? one : many) {
    if (Registered(s)) out.push_back(s);
  }
  return out;
}

std::vector<std::string> SuiteSubdivisions(const std::string& cells) {
  const auto d = ParseCellDims(cells, "--cells");
  const std::string n = std::to_string(std::uint64_t{d[0]} * d[1] * d[2]);
  return {cells,
          "auto:" + n,
          "kd:" + n + ":footprint",
          "kd:" + n + ":sqrt",
          "dynamic:" + n + ":sqrt",
          "grid:" + n + ":crossings"};
}

SuiteSceneResult RunSuiteScene(const SuiteOptions& o, const SuiteScene& s) {
  SuiteSceneResult r;
  r.scene = s;
  if (!o.quiet) std::cerr << "suite: " << s.name << " (" << s.file << ")\n";
  const SceneCapture c = RecordScene(o, s);
  r.record_seconds = c.seconds;
  if (!o.quiet) {
    std::cerr << "suite: " << s.name << ": "
              << (c.seconds > 0 ? "recorded in " + FormatFixed(c.seconds, 1) + " s"
                                : std::string("capture reused"))
              << "\n";
  }
  const TraceReader reader =
      c.fine ? TraceReader::Open(c.path, o.cells) : TraceReader::Open(c.path);
  r.character = Characterize(reader, HardwareThreads());

  std::vector<ReplayConfig> configs;
  std::vector<SuiteRow> rows;
  for (std::uint32_t p : {1u, o.processors}) {
    if (p == o.processors && p == 1 && !configs.empty()) break;
    for (const std::string& name : SuiteSchedulers(p)) {
      configs.push_back(Config(name, p, 0));
      rows.push_back({"scheduler", name, name, p});
    }
  }
  r.rows = Replay(reader, configs, rows);

  if (c.fine) {
    // The cache holds the uniform grid's median cell, so the cells' shapes make the difference.
    r.cache_capacity = MedianFootprint(NonEmptyFootprints(reader.header().footprints));
    const std::string sched = Registered("auto") ? "auto" : "celltree-best";
    for (const std::string& spec : SuiteSubdivisions(o.cells)) {
      std::unique_ptr<TraceReader> regrouped;
      try {
        regrouped = std::make_unique<TraceReader>(TraceReader::Open(c.path, spec));
      } catch (const InputError& e) {
        if (spec.rfind("auto:", 0) == 0) continue;  // not built into this binary
        throw;
      }
      std::vector<ReplayConfig> sc;
      std::vector<SuiteRow> sr;
      for (const std::string& name : {std::string("maxwork"), sched}) {
        sc.push_back(Config(name, 1, r.cache_capacity));
        sr.push_back({"cells", spec, name, 1});
      }
      for (const SuiteRow& row : Replay(*regrouped, sc, sr)) r.rows.push_back(row);
    }
  }
  const fs::path file = fs::path(o.out) / "scenes" / (s.name + ".csv");
  fs::create_directories(file.parent_path());
  WriteFileAtomically(file.string(), SuiteSceneCsv(r), "suite scene file");
  return r;
}

std::vector<SuiteSceneResult> ReadSuiteResults(const std::string& dir, SuiteOptions* options) {
  std::vector<std::string> files;
  std::error_code error;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "scenes", error)) {
    if (e.path().extension() == ".csv") files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  std::vector<SuiteSceneResult> results;
  bool cells_seen = false;
  options->processors = 1;
  for (const std::string& f : files) {
    results.push_back(ReadSuiteSceneCsv(f));
    for (const SuiteRow& row : results.back().rows) {
      options->processors = std::max(options->processors, row.processors);
      if (row.kind == "cells" && !cells_seen) options->cells = row.name, cells_seen = true;
    }
  }
  return results;
}

std::string SuiteSceneCsv(const SuiteSceneResult& r) {
  const CaptureCharacter& c = r.character;
  std::ostringstream out;
  out << "# raycell suite scene 1\n"
      << "# name," << Field(r.scene.name) << "\n# file," << Field(r.scene.file) << "\n# about,"
      << Field(r.scene.about) << "\n# character," << c.frames << "," << c.pixels << "," << c.rays
      << "," << c.visits << "," << c.samples;
  for (std::uint64_t k : c.rays_by_kind) out << "," << k;
  out << "," << c.busy_cells << "," << c.max_gen_sum << "," << c.max_gen_largest << "\n"
      << "# cache_capacity," << r.cache_capacity << "\n"
      << "kind,name,scheduler,processors,fetches,cache_bytes,time_ps,time_after_first_ps\n";
  for (const SuiteRow& row : r.rows) {
    out << row.kind << "," << Field(row.name) << "," << row.scheduler << "," << row.processors
        << "," << row.fetches << "," << row.cache_bytes << "," << row.time_ps << ","
        << row.time_after_first_ps << "\n";
  }
  return out.str();
}

namespace {

// Splits one CSV line (fields quoted as Field quotes them).
std::vector<std::string> CsvFields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (quoted) {
      if (ch == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (ch == '"') {
        quoted = false;
      } else {
        out.back() += ch;
      }
    } else if (ch == '"') {
      quoted = true;
    } else if (ch == ',') {
      out.emplace_back();
    } else {
      out.back() += ch;
    }
  }
  return out;
}

}  // namespace

SuiteSceneResult ReadSuiteSceneCsv(const std::string& path) {
  std::string text;
  if (!ReadFile(path, &text)) throw InputError(path + ": cannot read");
  std::istringstream in(text);
  std::string line;
  SuiteSceneResult r;
  int line_no = 0;
  auto bad = [&](const std::string& why) {
    return InputError(path + ":" + std::to_string(line_no) + ": " + why +
                      " (not a raycell suite scene file)");
  };
  auto number = [&](const std::string& t) {
    std::uint64_t v = 0;
    if (!TryParseUint(t, &v)) throw bad("'" + t + "' is not a count");
    return v;
  };
  bool rows = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (line_no == 1) {
      if (line != "# raycell suite scene 1") throw bad("no '# raycell suite scene 1' line");
      continue;
    }
    if (!rows && line.rfind("# ", 0) == 0) {
      const auto f = CsvFields(line.substr(2));
      if (f[0] == "name" && f.size() == 2) {
        r.scene.name = f[1];
      } else if (f[0] == "file" && f.size() == 2) {
        r.scene.file = f[1];
      } else if (f[0] == "about" && f.size() == 2) {
        r.scene.about = f[1];
      } else if (f[0] == "character" && f.size() == 6 + kRayKindCount + 3) {
        CaptureCharacter& c = r.character;
        c.frames = number(f[1]), c.pixels = number(f[2]), c.rays = number(f[3]);
        c.visits = number(f[4]), c.samples = number(f[5]);
        for (int k = 0; k < kRayKindCount; ++k) c.rays_by_kind[k] = number(f[6 + k]);
        c.busy_cells = number(f[6 + kRayKindCount]);
        c.max_gen_sum = number(f[7 + kRayKindCount]);
        c.max_gen_largest = std::uint32_t(number(f[8 + kRayKindCount]));
      } else if (f[0] == "cache_capacity" && f.size() == 2) {
        r.cache_capacity = number(f[1]);
      } else {
        throw bad("unknown line '" + line + "'");
      }
      continue;
    }
    if (!rows) {
      if (line != "kind,name,scheduler,processors,fetches,cache_bytes,time_ps,time_after_first_ps")
        throw bad("expected the rows' header");
      rows = true;
      continue;
    }
    const auto f = CsvFields(line);
    if (f.size() != 8) throw bad("expected 8 fields");
    SuiteRow row{f[0],         f[1],         f[2],         std::uint32_t(number(f[3])),
                 number(f[4]), number(f[5]), number(f[6]), number(f[7])};
    if (row.kind != "scheduler" && row.kind != "cells") throw bad("unknown kind '" + f[0] + "'");
    r.rows.push_back(row);
  }
  if (!rows || r.scene.name.empty()) throw bad("incomplete");
  return r;
}

void RunSuite(const SuiteOptions& o) {
  ParseResolution(o.res);
  ParseCellDims(o.cells, "--cells");
  ParseCellDims(o.fine, "--fine");
  if (o.frames < 2 || o.frames > 10000) {
    throw InputError("--frames " + std::to_string(o.frames) +
                     ": must be in [2, 10000] (time is compared over the frames after the first)");
  }
  if (o.processors < 2 || o.processors > 64) {
    throw InputError("--processors " + std::to_string(o.processors) + ": must be in [2, 64]");
  }
  const std::vector<SuiteScene> scenes = SuiteScenes(o);
  if (o.list) {
    for (const SuiteScene& s : scenes) std::cout << s.name << "\t" << s.file << "\n";
    return;
  }
  std::vector<SuiteSceneResult> results;
  if (!o.only.empty()) {
    for (const SuiteScene& s : scenes) {
      if (s.name == o.only) {
        RunSuiteScene(o, s);
        return;
      }
    }
    std::string names;
    for (const SuiteScene& s : scenes) names += (names.empty() ? "" : ", ") + s.name;
    throw InputError("--only '" + o.only + "': no such scene (the suite's: " + names + ")");
  }
  for (const SuiteScene& s : scenes) {
    const fs::path file = fs::path(o.out) / "scenes" / (s.name + ".csv");
    if (o.report_only) {
      if (!fs::exists(file)) {
        throw InputError("--report: " + file.string() +
                         " is missing (run its scene first: "
                         "raycell suite --only " +
                         s.name + ")");
      }
      results.push_back(ReadSuiteSceneCsv(file.string()));
    } else {
      results.push_back(RunSuiteScene(o, s));
    }
  }
  SuiteReport(o, results);
  if (!o.quiet)
    std::cerr << "suite: report in " << (fs::path(o.out) / "report.md").string() << "\n";
}

}  // namespace raycell
