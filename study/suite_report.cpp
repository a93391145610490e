// report.md, suite.csv and suite.png of `raycell suite` (study/suite.h).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>

#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "study/report.h"
#include "study/suite.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;

const SuiteRow* Find(const SuiteSceneResult& r, const std::string& kind, const std::string& name,
                     const std::string& scheduler, std::uint32_t processors) {
  for (const SuiteRow& row : r.rows) {
    if (row.kind == kind && row.name == name && row.scheduler == scheduler &&
        row.processors == processors) {
      return &row;
    }
  }
  return nullptr;
}

std::optional<double> Ratio(double value, double base) {
  if (!(base > 0)) return std::nullopt;
  return value / base;
}

// "-12.3%" / "+4.5%" for a ratio.
std::string Pct(std::optional<double> r) {
  if (!r) return "n/a";
  const double c = 100.0 * (*r - 1.0);
  return (c > 0 ? "+" : c < 0 ? "-" : "") + FormatFixed(std::abs(c), 1) + "%";
}
std::string Times(std::optional<double> r) { return r ? FormatFixed(*r, 3) : "n/a"; }
using RatioFormat = std::string (*)(std::optional<double>);

// Ratios of one comparison over the scenes, with the geometric mean and the worst (largest).
struct Ratios {
  double log_sum = 0;
  int count = 0;
  double worst = 0;
  std::string worst_scene;
  std::vector<std::pair<std::string, double>> by_scene;

  void Add(std::optional<double> r, const std::string& scene) {
    if (!r || !(*r > 0)) return;
    log_sum += std::log(*r);
    ++count;
    by_scene.emplace_back(scene, *r);
    if (count == 1 || *r > worst) worst = *r, worst_scene = scene;
  }
  std::optional<double> geomean() const {
    if (count == 0) return std::nullopt;
    return std::exp(log_sum / count);
  }
  // A summary row's cell: the geometric mean, or the worst ratio and its scene.
  std::string Cell(bool worst_row, RatioFormat f) const {
    if (!worst_row) return f(geomean());
    return count ? f(worst) + " " + worst_scene : "n/a";
  }
  // "W on SCENE", the worst for a headline.
  std::string WorstOn(RatioFormat f) const {
    return count ? f(worst) + " on " + worst_scene : "n/a";
  }
  // "; SCENE R" when `scene` is one of the scenes (a headline's figure beside the suite's).
  std::string Beside(const std::string& scene, RatioFormat f) const {
    for (const auto& [name, r] : by_scene) {
      if (name == scene) return "; " + scene + " " + f(r);
    }
    return "";
  }
};

std::string Ms(std::uint64_t ps) { return FormatFixed(double(ps) / 1e9, 1); }

std::string CharacterTable(const std::vector<SuiteSceneResult>& scenes) {
  std::ostringstream s;
  s << "| scene | what it stands for | frames | rays per pixel | secondary rays | visits per ray "
       "| maxGen mean | maxGen largest |\n"
       "|---|---|---:|---:|---:|---:|---:|---:|\n";
  for (const SuiteSceneResult& r : scenes) {
    const CaptureCharacter& c = r.character;
    s << "| " << r.scene.name << " | " << r.scene.about << " | " << c.frames << " | "
      << FormatFixed(c.rays_per_pixel(), 2) << " | " << FormatFixed(100 * c.secondary_share(), 1)
      << "% | " << FormatFixed(c.visits_per_ray(), 2) << " | " << FormatFixed(c.mean_max_gen(), 2)
      << " | " << c.max_gen_largest << " |\n";
  }
  return s.str();
}

std::string ProcessorsSection(const SuiteOptions& o, const std::vector<SuiteSceneResult>& scenes,
                              const std::string& beside, std::vector<std::string>* headline) {
  const std::uint32_t p = o.processors;
  std::vector<std::string> names;
  for (const std::string& n : SuiteSchedulers(p)) {
    if (n != "maxwork") names.push_back(n);
  }
  std::ostringstream s;
  s << "## " << p << " processors against Max Work\n\n"
    << "Per scheduler: the change in fetches (every frame) / in simulated time over the frames "
       "after the first (frame 0 is the board's cold load, about the same for every "
       "scheduler), and in brackets the whole capture's time. Negative is better. The "
       "geometric mean is of the ratios to Max Work; the worst scene is the largest ratio.\n\n"
    << "| scene | Max Work: fetches, ms after frame 0, ms in all |";
  for (const std::string& n : names) s << " `" << n << "` |";
  s << "\n|---|---:|";
  for (std::size_t i = 0; i < names.size(); ++i) s << "---:|";
  s << "\n";
  std::vector<std::vector<Ratios>> cols(names.size(), std::vector<Ratios>(3));
  for (const SuiteSceneResult& r : scenes) {
    const SuiteRow* base = Find(r, "scheduler", "maxwork", "maxwork", p);
    if (!base) continue;
    s << "| " << r.scene.name << " | " << base->fetches << ", " << Ms(base->time_after_first_ps)
      << ", " << Ms(base->time_ps) << " |";
    for (std::size_t i = 0; i < names.size(); ++i) {
      const SuiteRow* row = Find(r, "scheduler", names[i], names[i], p);
      std::optional<double> f, t, w;
      if (row) {
        f = Ratio(double(row->fetches), double(base->fetches));
        t = Ratio(double(row->time_after_first_ps), double(base->time_after_first_ps));
        w = Ratio(double(row->time_ps), double(base->time_ps));
      }
      cols[i][0].Add(f, r.scene.name);
      cols[i][1].Add(t, r.scene.name);
      cols[i][2].Add(w, r.scene.name);
      s << " " << Pct(f) << " / " << Pct(t) << " (" << Pct(w) << ") |";
    }
    s << "\n";
  }
  for (bool worst : {false, true}) {
    s << "| **" << (worst ? "worst scene" : "geometric mean") << "** | |";
    for (const auto& c : cols) {
      s << " " << c[0].Cell(worst, Pct) << " / " << c[1].Cell(worst, Pct) << " ("
        << c[2].Cell(worst, Pct) << ") |";
    }
    s << "\n";
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] != "auto") continue;
    headline->push_back(std::to_string(p) + " processors, `auto` against Max Work: fetches " +
                        Pct(cols[i][0].geomean()) + " (geometric mean; worst " +
                        cols[i][0].WorstOn(Pct) + cols[i][0].Beside(beside, Pct) +
                        "), time after frame 0 " + Pct(cols[i][1].geomean()) + " (worst " +
                        cols[i][1].WorstOn(Pct) + cols[i][1].Beside(beside, Pct) + ")");
  }
  return s.str() + "\n";
}

std::string OneProcessorSection(const std::vector<SuiteSceneResult>& scenes,
                                const std::string& beside, std::vector<std::string>* headline) {
  std::vector<std::string> names;
  for (const std::string& n : SuiteSchedulers(1)) {
    if (n != "best") names.push_back(n);
  }
  std::ostringstream s;
  s << "## One processor: online against the oracle\n\n"
    << "Fetches of each online scheduler over those of `best` (the oracle: the best schedule "
       "found for the frame's own tree); 1 is the oracle's.\n\n"
    << "| scene | `best` fetches |";
  for (const std::string& n : names) s << " `" << n << "` |";
  s << "\n|---|---:|";
  for (std::size_t i = 0; i < names.size(); ++i) s << "---:|";
  s << "\n";
  std::vector<Ratios> cols(names.size());
  for (const SuiteSceneResult& r : scenes) {
    const SuiteRow* best = Find(r, "scheduler", "best", "best", 1);
    if (!best) continue;
    s << "| " << r.scene.name << " | " << best->fetches << " |";
    for (std::size_t i = 0; i < names.size(); ++i) {
      const SuiteRow* row = Find(r, "scheduler", names[i], names[i], 1);
      std::optional<double> q;
      if (row) q = Ratio(double(row->fetches), double(best->fetches));
      cols[i].Add(q, r.scene.name);
      s << " " << Times(q) << " |";
    }
    s << "\n";
  }
  for (bool worst : {false, true}) {
    s << "| **" << (worst ? "worst scene" : "geometric mean") << "** | |";
    for (const Ratios& r : cols) {
      s << " " << r.Cell(worst, Times) << " |";
    }
    s << "\n";
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] != "auto") continue;
    headline->push_back("1 processor, `auto` online / oracle: " + Times(cols[i].geomean()) +
                        " (geometric mean; worst " + cols[i].WorstOn(Times) +
                        cols[i].Beside(beside, Times) + ")");
  }
  return s.str() + "\n";
}

std::string CellsSection(const SuiteOptions& o, const std::vector<SuiteSceneResult>& scenes,
                         const std::string& beside, std::vector<std::string>* headline) {
  std::vector<std::string> schedulers;
  for (const SuiteSceneResult& r : scenes) {
    for (const SuiteRow& row : r.rows) {
      if (row.kind == "cells" &&
          std::find(schedulers.begin(), schedulers.end(), row.scheduler) == schedulers.end()) {
        schedulers.push_back(row.scheduler);
      }
    }
  }
  if (schedulers.empty()) return "";
  std::vector<std::string> specs;
  for (const std::string& spec : SuiteSubdivisions(o.cells)) {
    if (spec == o.cells) continue;
    for (const SuiteSceneResult& r : scenes) {
      if (Find(r, "cells", spec, schedulers.back(), 1)) {
        specs.push_back(spec);
        break;
      }
    }
  }
  std::ostringstream s;
  s << "## Subdivisions against the uniform " << o.cells << " grid\n\n"
    << "Each scene recorded once on " << o.fine
    << " cells (`--regroupable`) and regrouped; "
       "the cache holds the uniform grid's median cell (its footprint in bytes). Change in "
       "the bytes moved into the cache, one processor. Scenes whose volume changes per frame "
       "cannot be regrouped and are left out.\n\n";
  for (const std::string& sched : schedulers) {
    s << "Under `" << sched << "`:\n\n| scene | cache | " << o.cells << " cache MB |";
    for (const std::string& spec : specs) s << " `" << spec << "` |";
    s << "\n|---|---:|---:|";
    for (std::size_t i = 0; i < specs.size(); ++i) s << "---:|";
    s << "\n";
    std::vector<Ratios> cols(specs.size());
    for (const SuiteSceneResult& r : scenes) {
      const SuiteRow* base = Find(r, "cells", o.cells, sched, 1);
      if (!base) continue;
      s << "| " << r.scene.name << " | " << FormatFixed(double(r.cache_capacity) / 1024, 1)
        << " KiB | " << FormatFixed(double(base->cache_bytes) / 1e6, 2) << " |";
      for (std::size_t i = 0; i < specs.size(); ++i) {
        const SuiteRow* row = Find(r, "cells", specs[i], sched, 1);
        std::optional<double> q;
        if (row) q = Ratio(double(row->cache_bytes), double(base->cache_bytes));
        cols[i].Add(q, r.scene.name);
        s << " " << Pct(q) << " |";
      }
      s << "\n";
    }
    for (bool worst : {false, true}) {
      s << "| **" << (worst ? "worst scene" : "geometric mean") << "** | | |";
      for (const Ratios& r : cols) {
        s << " " << r.Cell(worst, Pct) << " |";
      }
      s << "\n";
    }
    s << "\n";
    for (std::size_t i = 0; i < specs.size(); ++i) {
      if (specs[i].rfind("auto:", 0) != 0 || sched != schedulers.back()) continue;
      headline->push_back("`--cells " + specs[i] + "` under `" + sched + "`: cache bytes " +
                          Pct(cols[i].geomean()) + " against " + o.cells +
                          " (geometric mean; worst " + cols[i].WorstOn(Pct) +
                          cols[i].Beside(beside, Pct) + ")");
    }
  }
  return s.str();
}

std::string SuiteCsv(const std::vector<SuiteSceneResult>& scenes) {
  std::ostringstream s;
  s << "scene,kind,name,scheduler,processors,fetches,cache_bytes,time_ps,time_after_first_ps\n";
  for (const SuiteSceneResult& r : scenes) {
    for (const SuiteRow& row : r.rows) {
      s << r.scene.name << "," << row.kind << "," << row.name << "," << row.scheduler << ","
        << row.processors << "," << row.fetches << "," << row.cache_bytes << "," << row.time_ps
        << "," << row.time_after_first_ps << "\n";
    }
  }
  return s.str();
}

}  // namespace

std::vector<std::string> SuiteHeadlines(const SuiteOptions& o,
                                        const std::vector<SuiteSceneResult>& scenes,
                                        const std::string& beside) {
  std::vector<std::string> headline;
  ProcessorsSection(o, scenes, beside, &headline);
  OneProcessorSection(scenes, beside, &headline);
  CellsSection(o, scenes, beside, &headline);
  return headline;
}

std::string SuiteReportText(const SuiteOptions& o, const std::vector<SuiteSceneResult>& scenes) {
  std::vector<std::string> headline;
  const std::string processors = ProcessorsSection(o, scenes, kSuiteBeside, &headline);
  const std::string one = OneProcessorSection(scenes, kSuiteBeside, &headline);
  const std::string cells = CellsSection(o, scenes, kSuiteBeside, &headline);
  std::ostringstream s;
  s << "# raycell suite\n\n"
    << scenes.size() << " scenes at " << o.res << ", " << o.frames << " frames each (a sequence: "
    << "at most its own), " << o.cells << " cells (regrouped from " << o.fine
    << " where the scene allows). Each figure is the geometric mean over the scenes and "
       "its worst scene, as a suite of workloads is reported, and the headlines give the "
    << kSuiteBeside << " scene's own figure beside them.\n\n";
  if (!headline.empty()) {
    s << "Headlines:\n";
    for (const std::string& h : headline) s << "- " << h << "\n";
    s << "\n";
  }
  s << "![the suite](suite.png)\n\n"
    << "## The scenes and their character\n\n"
    << "Rays per pixel (every kind, per frame), the share of secondary rays (reflection, "
       "refraction, shadow), and maxGen per cell over every frame's Cell Tree in "
    << o.cells << " cells (`raycell trace info`).\n\n"
    << CharacterTable(scenes) << "\n"
    << processors << one << cells;
  return s.str();
}

std::string SuiteReport(const SuiteOptions& o, const std::vector<SuiteSceneResult>& scenes) {
  const std::string report = SuiteReportText(o, scenes);
  fs::create_directories(o.out);
  WriteFileAtomically((fs::path(o.out) / "suite.csv").string(), SuiteCsv(scenes), "suite.csv");
  WriteFileAtomically((fs::path(o.out) / "report.md").string(), report, "report.md");
  RunPlotScript("plot_suite.py", {o.out, std::to_string(o.processors)});
  if (!fs::exists(fs::path(o.out) / "suite.png")) throw InputError("plot missing: suite.png");
  return report;
}

}  // namespace raycell
