// raycell analyze: each frame's Cell Tree: size, maxGen bound, Peel, the exact optimum.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

#include "analysis/analysis.h"
#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "base/parse.h"
#include "base/progress.h"
#include "graph/frame_tree.h"
#include "graph/links.h"
#include "tools/analyze_part.h"
#include "tools/commands.h"
#include "tools/frames.h"
#include "traces/jsonl.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

struct AnalyzeArgs {
  std::string trace, paths, format = "table", dot, effort = "default", frames, part, cells;
  std::optional<int> frame;
  unsigned jobs = 0;  // the search's threads; 0: the hardware's
  bool all = false, quiet = false, timing = false;
  AnalyzeOptions options;
  std::vector<std::string> merge_parts;
  std::string merge_out;
};

std::string Schedule(const std::vector<CellId>& s, const char* sep) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) out += (i ? sep : "") + std::to_string(s[i].value());
  return out;
}

std::string OptionalNumber(const std::optional<std::uint64_t>& v, const char* none) {
  return v ? std::to_string(*v) : none;
}

std::string Gap(const FrameAnalysis& a) {
  return a.optimum ? std::to_string(std::int64_t(a.peel_length()) - std::int64_t(*a.optimum)) : "";
}

// The version of the JSON output's schema (docs/schemas.md), the first key of every object.
constexpr char kJsonSchema[] = "raycell-analyze/1";

void PrintJson(const FrameAnalysis& a, bool timing, std::ostream& out) {
  out << "{\"schema\":\"" << kJsonSchema << "\",\"frame\":" << a.frame << ",\"rays\":" << a.rays
      << ",\"nodes\":" << a.nodes << ",\"rays_per_node\":" << FormatFixed(a.rays_per_node(), 3)
      << ",\"bound\":" << a.bound << ",\"peel_length\":" << a.peel_length()
      << ",\"peel_schedule\":[" << Schedule(a.peel_schedule, ",") << "],\"splits\":" << a.splits
      << ",\"peel_minus_bound\":" << a.peel_length() - a.bound
      << ",\"optimum\":" << OptionalNumber(a.optimum, "null")
      << ",\"optimum_status\":" << JsonQuote(a.optimum_status)
      << ",\"lower_bound\":" << OptionalNumber(a.lower_bound, "null")
      << ",\"lower_bound_method\":" << (a.lower_bound ? JsonQuote(a.lower_bound_method) : "null")
      << ",\"best_length\":" << OptionalNumber(a.best_length, "null") << ",\"best_schedule\":"
      << (a.best_length ? "[" + Schedule(a.best_schedule, ",") + "]" : "null")
      << ",\"best_method\":" << (a.best_length ? JsonQuote(a.best_method) : "null")
      << ",\"gap\":" << (a.gap() ? FormatFixed(*a.gap(), 4) : "null");
  if (timing) out << ",\"seconds\":" << FormatFixed(a.seconds, 6);
  out << "}\n";
}

void PrintCsvHeader(bool timing, std::ostream& out) {
  out << "frame,rays,nodes,rays_per_node,bound,peel_length,splits,peel_minus_bound,optimum,"
         "peel_minus_optimum,optimum_status,"
      << (timing ? "seconds," : "")
      << "peel_schedule,lower_bound,lower_bound_method,best_length,gap,best_method,"
         "best_schedule\n";
}

void PrintCsv(const FrameAnalysis& a, bool timing, std::ostream& out) {
  out << a.frame << ',' << a.rays << ',' << a.nodes << ',' << FormatFixed(a.rays_per_node(), 3)
      << ',' << a.bound << ',' << a.peel_length() << ',' << a.splits << ','
      << a.peel_length() - a.bound << ',' << OptionalNumber(a.optimum, "") << ',' << Gap(a) << ",\""
      << a.optimum_status << "\"," << (timing ? FormatFixed(a.seconds, 6) + "," : "") << '"'
      << Schedule(a.peel_schedule, " ") << "\"," << OptionalNumber(a.lower_bound, "") << ','
      << CsvField(a.lower_bound_method) << ',' << OptionalNumber(a.best_length, "") << ','
      << (a.gap() ? FormatFixed(*a.gap(), 4) : "") << ',' << CsvField(a.best_method) << ",\""
      << Schedule(a.best_schedule, " ") << "\"\n";
}

void PrintTableHeader(bool timing, bool bracket, std::ostream& out) {
  out << "   frame         rays      nodes  rays/node    bound     peel   splits peel-bound"
         "  optimum peel-opt"
      << (bracket ? "    lower     best      gap" : "") << (timing ? "     time" : "") << "\n";
}

void PrintRow(const FrameAnalysis& a, bool timing, bool bracket, std::ostream& out) {
  char line[256];
  std::snprintf(line, sizeof line, "%8d %12llu %10llu %10.1f %8llu %8llu %8llu %10llu %8s %8s",
                a.frame, (unsigned long long)a.rays, (unsigned long long)a.nodes, a.rays_per_node(),
                (unsigned long long)a.bound, (unsigned long long)a.peel_length(),
                (unsigned long long)a.splits, (unsigned long long)(a.peel_length() - a.bound),
                OptionalNumber(a.optimum, "-").c_str(), a.optimum ? Gap(a).c_str() : "-");
  out << line;
  if (bracket) {
    std::snprintf(line, sizeof line, " %8s %8s %7s%%", OptionalNumber(a.lower_bound, "-").c_str(),
                  OptionalNumber(a.best_length, "-").c_str(),
                  a.gap() ? FormatFixed(100 * *a.gap(), 1).c_str() : "-");
    out << line;
  }
  if (timing) {
    std::snprintf(line, sizeof line, " %7.3fs", a.seconds);
    out << line;
  }
  out << "\n";
}

void CheckFormat(const std::string& format) {
  if (format != "table" && format != "json" && format != "csv") {
    throw InputError("--format '" + format + "': expected table, json or csv");
  }
}

// Results only, unless --timing: then the output depends on the machine too. To stdout, or
// to a --part file.
class Printer {
 public:
  Printer(const std::string& format, bool timing, bool bracket, std::ostream& out)
      : format_(format), timing_(timing), bracket_(bracket), out_(out) {
    CheckFormat(format);
    if (format_ == "table") PrintTableHeader(timing_, bracket_, out_);
    if (format_ == "csv") PrintCsvHeader(timing_, out_);
  }
  void Print(const FrameAnalysis& a) {
    if (format_ == "json") PrintJson(a, timing_, out_);
    if (format_ == "csv") PrintCsv(a, timing_, out_);
    if (format_ == "table") {
      PrintRow(a, timing_, bracket_, out_);
      // The merge of parts (tools/analyze_part.cpp) knows this line by its start.
      if (!a.optimum && a.optimum_status != "not computed") {
        out_ << "         optimum " << a.optimum_status << "\n";
      }
    }
    out_.flush();
  }

 private:
  std::string format_;
  bool timing_, bracket_;
  std::ostream& out_;
};

// The options that change what analyze prints, in one canonical form: parts to merge must
// agree on it (--jobs, --quiet and --dot change nothing printed).
std::string OutputOptions(const AnalyzeArgs& a) {
  const AnalyzeOptions& o = a.options;
  std::string s = std::string(o.exact ? "--exact " : "") + (o.bracket ? "--bracket " : "") +
                  "--effort " + a.effort + " --max-states " + std::to_string(o.max_states) +
                  " --max-seconds " + FormatReal(o.max_seconds) + " --max-nodes " +
                  std::to_string(o.max_nodes);
  return s + (a.timing ? " --timing" : "");
}

// The tree as Graphviz DOT, with the cache-saving links of its Peel schedule, written to a
// temporary name and renamed when complete.
void WriteDotFile(const std::string& path, const CellTree& tree, const FrameAnalysis& a) {
  WriteFileAtomically(
      path, [&](std::ostream& out) { WriteDot(out, tree, LinksOf(tree, a.peel_schedule)); },
      "--dot " + path);
}

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Every frame of the file (or the one --frame names), one at a time; the time of a frame
// includes reading its lines.
void AnalyzePaths(const AnalyzeArgs& a, Printer& printer) {
  std::ifstream in(a.paths);
  if (!in) throw InputError(a.paths + ": cannot open");
  JsonlReader reader(in, a.paths);
  JsonlFrame frame;
  const std::vector<int> frames_wanted =
      a.frames.empty() ? std::vector<int>{} : ParseFrameRange(a.frames);
  std::optional<std::pair<CellTree, FrameAnalysis>> dot;
  std::size_t analysed = 0;
  for (auto t0 = std::chrono::steady_clock::now(); reader.Next(frame);
       t0 = std::chrono::steady_clock::now()) {
    if (a.frame && frame.frame != *a.frame) continue;
    if (!a.frames.empty() &&
        (frame.frame < frames_wanted.front() || frame.frame > frames_wanted.back())) {
      continue;
    }
    if (!a.dot.empty() && analysed > 0) {
      throw InputError("--dot writes one frame's tree, and " + a.paths +
                       " has several: choose one with --frame N");
    }
    CellTreeBuilder builder;
    builder.AddBatch(frame.rays);
    CellTree tree = builder.Finish();
    const double build = SecondsSince(t0);
    FrameAnalysis r = AnalyzeTree(tree, a.options);
    r.frame = frame.frame;
    r.seconds += build;
    printer.Print(r);
    ++analysed;
    if (!a.dot.empty()) dot.emplace(std::move(tree), std::move(r));
  }
  if (a.frame && analysed == 0) {
    throw InputError(a.paths + ": no frame " + std::to_string(*a.frame));
  }
  if (!a.frames.empty() && analysed == 0) {
    throw InputError(a.paths + ": no frame in --frames " + a.frames);
  }
  if (dot) WriteDotFile(a.dot, dot->first, dot->second);
}

std::vector<std::size_t> SelectFrames(const TraceReader& r, const AnalyzeArgs& a) {
  if (!a.frames.empty()) return SelectFrameRange(r, a.frames);
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < r.frames().size(); ++i) {
    if (!a.frame || r.frames()[i].frame == *a.frame) out.push_back(i);
  }
  if (a.frame && out.empty()) {
    throw InputError(r.path() + ": no frame " + std::to_string(*a.frame));
  }
  return out;
}

// The first line of a --part file: the trace by content, the frames asked for (all: the
// trace's first to last), the options.
std::string PartLine(const TraceReader& r, const AnalyzeArgs& a) {
  AnalyzePartInfo info;
  info.format = a.format;
  info.options = OutputOptions(a);
  info.trace = a.trace;
  info.trace_hash = TraceFingerprint(r);
  if (!a.frames.empty()) {
    const std::vector<int> range = ParseFrameRange(a.frames);
    info.first = range.front(), info.last = range.back();
  } else if (a.frame) {
    info.first = info.last = *a.frame;
  } else {
    if (r.frames().empty()) throw InputError(r.path() + ": no frames to analyse");
    const auto [lo, hi] = std::minmax_element(
        r.frames().begin(), r.frames().end(),
        [](const FrameSummary& x, const FrameSummary& y) { return x.frame < y.frame; });
    info.first = lo->frame, info.last = hi->frame;
  }
  return AnalyzePartLine(info);
}

void AnalyzeTrace(AnalyzeArgs a, std::ostream& out) {
  const TraceReader r = TraceReader::Open(a.trace, a.cells);
  // The lower bound takes blocks of neighbouring cells from the trace's cell grid.
  a.options.bracket_options.lower.grid = r.header().cells;
  if (!r.warning().empty()) std::cerr << "raycell: warning: " << r.warning() << "\n";
  const std::vector<std::size_t> frames = SelectFrames(r, a);
  if (!a.dot.empty() && frames.size() != 1) {
    throw InputError("--dot writes one frame's tree: choose it with --frame N");
  }
  if (!a.part.empty()) out << PartLine(r, a);
  Printer printer(a.format, a.timing, a.options.bracket, out);
  Progress progress(!a.quiet);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    progress.Update(double(k) / frames.size(),
                    "frame " + std::to_string(r.frames()[frames[k]].frame));
    const auto t0 = std::chrono::steady_clock::now();
    const CellTree tree = BuildFrameTree(r, frames[k]);
    const double build = SecondsSince(t0);
    FrameAnalysis fa = AnalyzeTree(tree, a.options);
    fa.frame = r.frames()[frames[k]].frame;
    fa.seconds += build;
    progress.Done();
    printer.Print(fa);
    if (!a.dot.empty()) WriteDotFile(a.dot, tree, fa);
  }
}

void Run(const AnalyzeArgs& a) {
  if (a.trace.empty() == a.paths.empty()) {
    throw InputError("give either a TRACE file or --paths FILE.jsonl");
  }
  if (a.frame && a.all) throw InputError("--frame and --all exclude each other");
  if (!a.frames.empty() && (a.frame || a.all)) {
    throw InputError(std::string("--frames and ") + (a.frame ? "--frame" : "--all") +
                     " exclude each other");
  }
  if (!a.frames.empty()) ParseFrameRange(a.frames);  // malformed: before any work
  if (!a.part.empty() && !a.paths.empty()) {
    throw InputError("--part needs a TRACE: parts of --paths files are not supported");
  }
  CheckFormat(a.format);
  AnalyzeArgs args = a;
  args.options.bracket_options = BracketEffort(a.effort);
  args.options.bracket_options.best.threads = a.jobs;
  if (!args.paths.empty()) {
    Printer printer(args.format, args.timing, args.options.bracket, std::cout);
    return AnalyzePaths(args, printer);
  }
  if (args.part.empty()) return AnalyzeTrace(args, std::cout);
  WriteFileAtomically(
      args.part, [&](std::ostream& out) { AnalyzeTrace(args, out); }, "--part " + args.part);
}

void AddMerge(CLI::App* cmd, const std::shared_ptr<AnalyzeArgs>& args) {
  CLI::App* merge = cmd->add_subcommand(
      "merge",
      "Join the parts of a sharded analysis (`raycell analyze TRACE --frames A..B --part FILE`) "
      "into the output of one run over all their frames.");
  merge->add_option("PARTS", args->merge_parts, "the part files, each frame in exactly one")
      ->required();
  merge
      ->add_option("--out", args->merge_out,
                   "file to write (through FILE.tmp): what `raycell analyze TRACE` with the "
                   "parts' options prints for the union of their frames")
      ->required();
  merge->footer(
      "Every part must name the same trace (by content), format and options; their frame\n"
      "ranges must neither overlap nor leave a gap. Otherwise the merge says which parts or\n"
      "frames are wrong, exits with 2 and writes nothing. The parts may come in any order.\n\n"
      "Example:\n"
      "  raycell analyze capture.rct --format csv --frames 0..14 --part p0\n"
      "  raycell analyze capture.rct --format csv --frames 15..29 --part p1\n"
      "  raycell analyze merge p1 p0 --out analysis.csv   # = raycell analyze capture.rct "
      "--format csv");
  merge->callback([args] { MergeAnalyzeParts(args->merge_parts, args->merge_out); });
}

}  // namespace

void AddAnalyzeCommand(CLI::App& app) {
  auto args = std::make_shared<AnalyzeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "analyze", "Each frame's Cell Tree: size, maxGen bound, Peel schedule, exact optimum.");
  cmd->footer(
      "Per frame: rays, Cell Tree nodes, rays per node (the paper: about 100), the bound\n"
      "sum over cells of maxGen (no schedule with a one-cell cache fetches fewer cells),\n"
      "the Peel schedule's length and split peels, Peel minus bound and, with --exact on\n"
      "small trees, the optimum and Peel minus optimum (past the search limits the optimum\n"
      "is reported unknown, never guessed), and with --timing the time taken.\n"
      "--format json prints one object per frame and line with the keys schema\n"
      "(\"raycell-analyze/1\"), frame, rays, nodes, rays_per_node, bound, peel_length,\n"
      "peel_schedule (cells in fetch order), splits, peel_minus_bound, optimum (null when\n"
      "not computed or unknown), optimum_status, and with --bracket lower_bound,\n"
      "lower_bound_method, best_length, best_schedule, best_method and gap ((best - lower)\n"
      "/ lower; all null without --bracket), and seconds with --timing; docs/schemas.md\n"
      "documents each. With --bracket the optimum is set when the best schedule meets the\n"
      "lower bound.\n"
      "--paths reads ray paths as JSON Lines from raycell (`raycell trace cat`) or any other\n"
      "tool: keys in any order, rays in any order within a frame, ids any non-negative\n"
      "integers; required \"id\", \"parent\", \"spawn\", \"cells\" (\"parent\" and \"spawn\"\n"
      "null for primary rays); optional \"kind\" (default primary without a parent,\n"
      "reflection with one), \"pixel\" (default [0,0], or the parent's), \"samples\"\n"
      "(default 1 per visit) and \"frame\" (each frame's lines together; without it the\n"
      "file is frame 0). Every frame is analysed (--frame N picks one). docs/jsonl.md has\n"
      "the details and the order in which rays are renumbered.\n"
      "Without --timing the output depends only on the input and the options, byte for\n"
      "byte, whatever --jobs, except where --max-seconds stops a search (its status says\n"
      "so); --max-states limits the search the same way on every machine.\n\n"
      "Sharding: frames are analysed one by one, so a run over frames A..B prints exactly\n"
      "the lines of those frames in a run over the whole trace. --frames A..B --part FILE\n"
      "writes them to FILE (through FILE.tmp) after a first line naming the trace (by its\n"
      "content: the frames' checksums), the format, the options that change the output and\n"
      "the frames A..B; `raycell analyze merge PART... --out FILE` checks that the parts\n"
      "come from one trace with one format and the same options, and that their ranges\n"
      "neither overlap nor leave a gap (exit 2 otherwise, naming the frames), then writes\n"
      "what one run over the union of the ranges prints, byte for byte: the CSV or table\n"
      "header once, the frames in order (parts may be given in any order).\n"
      "tools/slurm/submit_analyze.sh runs the parts as a Slurm job array.\n\n"
      "Examples:\n"
      "  raycell analyze capture.rct\n"
      "  raycell analyze capture.rct --frame 3 --exact --format json\n"
      "  raycell analyze capture.rct --bracket --format csv > bracket.csv\n"
      "  raycell analyze capture.rct --bracket --format csv --frames 0..14 --part p0\n"
      "  raycell analyze capture.rct --bracket --format csv --frames 15..29 --part p1\n"
      "  raycell analyze merge p0 p1 --out bracket.csv   # the same bytes as above\n"
      "  raycell trace cat capture.rct --frame 0 > rays.jsonl && raycell analyze --paths "
      "rays.jsonl\n"
      "  echo '{\"id\":0,\"parent\":null,\"spawn\":null,\"cells\":[0,1]}' > p.jsonl && "
      "raycell analyze --paths p.jsonl");
  cmd->add_option("TRACE", args->trace, "trace file written by `raycell record`");
  cmd->add_option("--cells", args->cells, kCellsSpecHelp);
  cmd->add_option("--frame", args->frame, "analyse only this frame number (of TRACE or --paths)");
  cmd->add_option("--frames", args->frames,
                  "analyse only the frames numbered A..B (inclusive; also A-B or A)");
  cmd->add_flag("--all", args->all, "analyse every frame (the default)");
  cmd->add_option("--part", args->part,
                  "write the output to this file as a part for `raycell analyze merge` (below), "
                  "instead of stdout");
  cmd->add_option("--paths", args->paths,
                  "ray paths as JSON Lines (the format of `raycell trace cat`, from any tool; "
                  "see below) instead of a trace");
  cmd->add_flag("--exact", args->options.exact,
                "also compute the optimum by A* search (small trees)");
  cmd->add_option("--max-states", args->options.max_states, "exact search: states to expand")
      ->capture_default_str();
  cmd->add_option("--max-seconds", args->options.max_seconds, "exact search: time per frame")
      ->capture_default_str();
  cmd->add_option("--max-nodes", args->options.max_nodes,
                  "exact search: larger trees are not searched")
      ->capture_default_str();
  cmd->add_flag("--bracket", args->options.bracket,
                "also bracket the optimum: the best lower bound (projections of the paths on "
                "groups of cells, combined by an integer program) and the best schedule found "
                "(beam and local search, exact search on small trees); the optimum when they "
                "meet");
  cmd->add_option("--effort", args->effort,
                  "--bracket's budget: quick, default (about a minute per 27-cell frame on 2 "
                  "cores) or thorough (about 4x); counted in states, so every machine reports "
                  "the same")
      ->capture_default_str();
  cmd->add_option("--format", args->format, "table, json or csv")->capture_default_str();
  cmd->add_option("--dot", args->dot,
                  "write the frame's Cell Tree as Graphviz DOT (one colour per cell; dashed "
                  "edges: the cache-saving links of the Peel schedule). Render with "
                  "`dot -Tsvg FILE > tree.svg` (Debian package graphviz)");
  cmd->add_option("--jobs", args->jobs,
                  "threads of --bracket's schedule search (default: the hardware's); the output "
                  "is the same for any number");
  cmd->add_flag("--timing", args->timing, "also print the time each frame took");
  cmd->add_flag("--quiet", args->quiet, "no progress bar");
  cmd->require_subcommand(0, 1);
  AddMerge(cmd, args);
  cmd->callback([cmd, args] {
    if (cmd->got_subcommand("merge")) return;
    Run(*args);
  });
}

}  // namespace raycell
