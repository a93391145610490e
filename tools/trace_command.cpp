// raycell trace: inspect a capture (info, verify), hand its rays to other tools (cat) and make
// a capture from another tool's ray paths (import).
#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/character.h"
#include "base/check.h"
#include "base/parallel.h"
#include "base/parse.h"
#include "replay/units.h"
#include "tools/commands.h"
#include "traces/cell_dims.h"
#include "traces/jsonl.h"
#include "traces/trace_concat.h"
#include "traces/trace_import.h"
#include "traces/trace_inspect.h"
#include "traces/trace_reader.h"
#include "traces/trace_regroup.h"

namespace raycell {
namespace {

struct TraceArgs {
  std::string file, cells;
  bool cameras = false, no_character = false;
  std::optional<int> frame;
  std::string format = "jsonl";
};

// The trace as analyses see it (a regroupable capture regrouped into `cells`, or its own
// grid), or as stored.
TraceReader OpenWithWarning(const std::string& file, const std::string& cells, bool stored) {
  TraceReader r = stored ? TraceReader::OpenStored(file) : TraceReader::Open(file, cells);
  if (!r.warning().empty()) std::cerr << "raycell: warning: " << r.warning() << "\n";
  return r;
}

// Index into frames() of frame number `frame`; InputError listing what there is if absent.
std::size_t FrameIndex(const TraceReader& r, int frame) {
  std::string have;
  for (std::size_t i = 0; i < r.frames().size(); ++i) {
    if (r.frames()[i].frame == frame) return i;
    have += (i ? ", " : "") + std::to_string(r.frames()[i].frame);
  }
  throw InputError(r.path() + ": no frame " + std::to_string(frame) + " (frames: " + have + ")");
}

void RunCat(const TraceArgs& a) {
  if (a.format != "jsonl") throw InputError("--format '" + a.format + "': only jsonl is supported");
  const TraceReader r = OpenWithWarning(a.file, a.cells, false);
  std::optional<std::size_t> index;
  if (a.frame) index = FrameIndex(r, *a.frame);
  std::ios::sync_with_stdio(false);
  WriteJsonl(r, index, std::cout);
  std::cout.flush();
}

std::string Csv(const Vec3d& v) {
  std::ostringstream s;
  s << std::defaultfloat << std::setprecision(10) << v.x << "," << v.y << "," << v.z;
  return s.str();
}

void PrintCameras(const TraceHeader& h, std::ostream& out) {
  for (const CameraKey& c : h.cameras) {
    out << "camera " << c.frame << " eye " << Csv(c.eye) << " target " << Csv(c.target) << " fov "
        << std::defaultfloat << std::setprecision(10) << c.fov_deg << "\n";
  }
}

// What Open() could not read, when it scanned instead of reading the index: the index and
// the bytes after the last intact frame, with the reader's reason.
std::string Unreadable(const TraceReader& r) {
  std::string lost = "the index";
  const std::uint64_t begin = r.readable_end(), end = r.file_size();
  if (begin < end) {
    const std::size_t n = r.frames().size();
    const std::string after = n == 0 ? "the header"
                                     : "the last intact frame (frame " +
                                           std::to_string(r.frames()[n - 1].frame) + ", #" +
                                           std::to_string(n - 1) + ")";
    lost += " and bytes " + std::to_string(begin) + ".." + std::to_string(end) + " (" +
            std::to_string(end - begin) + " bytes) after " + after;
  }
  return lost + (begin < end ? " are" : " is") + " unreadable: " + r.warning();
}

// Reads and checks every frame (zstd and frame checksums, content), streaming, and reports
// the read speed. Any damage fails the verification (InputError, exit 2) after every frame
// was tried: a missing or damaged index, bytes that are not part of an intact frame, a bad
// frame. (The other commands warn and use the intact frames.)
void RunVerify(const TraceArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  const TraceReader r = TraceReader::OpenStored(a.file);
  std::vector<std::string> damage;
  if (!r.warning().empty()) damage.push_back(Unreadable(r));
  std::uint64_t rays = 0, visits = 0;
  std::size_t verified = 0;
  for (std::size_t i = 0; i < r.frames().size(); ++i) {
    std::uint64_t frame_rays = 0, frame_visits = 0;
    try {
      r.ForEachBatch(i, [&](const RayBatch& b) {
        frame_rays += b.size();
        frame_visits += b.visit_count();
      });
    } catch (const InputError& e) {
      std::cout << "frame " << r.frames()[i].frame << ": DAMAGED\n";
      damage.push_back(e.what());
      continue;
    }
    rays += frame_rays;
    visits += frame_visits;
    ++verified;
    std::cout << "frame " << r.frames()[i].frame << ": ok, " << frame_visits << " visits\n";
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << std::fixed << std::setprecision(3) << verified << " frame(s), " << rays << " rays, "
            << visits << " visits verified in " << s << " s (" << std::setprecision(1)
            << visits / std::max(s, 1e-9) / 1e6 << " M visits/s)\n";
  std::cout.flush();
  if (damage.empty()) return;
  std::string message =
      a.file + ": verification failed (" + std::to_string(damage.size()) + " problem(s)): ";
  for (std::size_t i = 0; i < damage.size(); ++i) message += (i ? "; " : "") + damage[i];
  throw InputError(message);
}

struct ImportArgs {
  ImportOptions options;
  std::string cells, footprint, box;
};

// "X0,Y0,Z0,X1,Y1,Z1".
std::pair<Vec3d, Vec3d> ParseBox(const std::string& text) {
  const std::vector<std::string> f = Split(text, ',');
  double v[6];
  for (std::size_t i = 0; i < 6 && f.size() == 6; ++i) {
    char* end = nullptr;
    v[i] = std::strtod(f[i].c_str(), &end);
    if (f[i].empty() || *end) break;
    if (i == 5) return {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
  }
  throw InputError("--box '" + text + "': expected six numbers X0,Y0,Z0,X1,Y1,Z1");
}

void RunImport(ImportArgs& a) {
  ImportOptions& o = a.options;
  o.cells = ParseCellDims(a.cells);
  if (!a.footprint.empty()) o.footprint = ParseBytes(a.footprint, "--footprint").count();
  if (!a.box.empty()) o.box = ParseBox(a.box);
  const ImportSummary s = ImportJsonl(o);
  std::cerr << "imported " << s.frames << " frame(s), " << s.rays << " rays, " << s.visits
            << " visits from " << o.paths << " -> " << o.out << "\n";
  if (s.renumbered_frames) {
    std::cerr << "note: ray ids renumbered in " << s.renumbered_frames
              << " frame(s) (ray trees by their primary ray's id, parents before children; "
                 "`raycell trace cat` shows the new ids)\n";
  }
}

void AddImport(CLI::App& trace) {
  auto args = std::make_shared<ImportArgs>();
  ImportOptions& o = args->options;
  CLI::App* c = trace.add_subcommand(
      "import", "Make a trace from ray paths in JSON Lines, e.g. written by another renderer.");
  c->footer(
      "Reads the format `raycell trace cat` writes, with keys in any order and rays in any\n"
      "order within a frame; the least a line needs is\n"
      "  {\"id\":7,\"parent\":3,\"spawn\":2,\"cells\":[5,4,1]}\n"
      "(\"parent\" and \"spawn\" null for primary rays). Defaults: \"kind\" primary without\n"
      "a parent, reflection with one; \"pixel\" [0,0] for a primary ray, its parent's for a\n"
      "spawned one; \"samples\" 1 per visit. Lines with a \"frame\" key make one trace frame\n"
      "per frame number (each frame's lines together, as `trace cat` writes them); without\n"
      "it the file is frame 0. Ids may be any non-negative integers: each frame is renumbered\n"
      "0, 1, 2, ... taking ray trees by their primary ray's id and, within a tree, the\n"
      "smallest id whose parent is placed (ids already in that order are kept).\n"
      "What the paths do not say gets a default: scene box 0,0,0 to NX,NY,NZ (--box),\n"
      "every cell --footprint bytes (the bytes a replay fetches), cameras at the origin,\n"
      "image size the largest pixel + 1. The file is read twice (checked, then written),\n"
      "so nothing is written when a line is bad. docs/jsonl.md has the details.\n\n"
      "Example:\n"
      "  raycell trace import rays.jsonl --cells 3x3x3 --out rays.rct && raycell replay "
      "rays.rct");
  c->add_option("PATHS", o.paths, "ray paths as JSON Lines (a file; it is read twice)")->required();
  c->add_option("--cells", args->cells,
                "cell grid NXxNYxNZ the paths' cells number (cell = x + NX*(y + NY*z)); every "
                "cell of the paths must be below NX*NY*NZ")
      ->required();
  c->add_option("--out", o.out, "trace file to write")->required();
  c->add_option("--footprint", args->footprint,
                "bytes of every cell, with a unit (e.g. 512KiB, 4MiB); default 1MiB, a dense "
                "64^3 brick of 4-byte voxels");
  c->add_option("--box", args->box,
                "scene box X0,Y0,Z0,X1,Y1,Z1 the cells split; default 0,0,0,NX,NY,NZ");
  c->add_option("--zstd-level", o.zstd_level, "zstd compression level 1..19")
      ->capture_default_str();
  c->callback([args] { RunImport(*args); });
}

struct RegroupArgs {
  std::string input, cells, out;
};

void RunRegroup(const RegroupArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  const RegroupSummary s = RegroupTrace(a.input, a.cells, a.out);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cerr << "regrouped " << s.frames << " frame(s) into " << s.cells
            << " cells: " << s.fine_visits << " stored visits -> " << s.visits << " visits of "
            << s.rays << " rays (" << s.bytes << " bytes) -> " << a.out << " in " << std::fixed
            << std::setprecision(3) << secs << " s\n";
}

void AddRegroup(CLI::App& trace) {
  auto args = std::make_shared<RegroupArgs>();
  CLI::App* c = trace.add_subcommand(
      "regroup", "Make a capture on any coarser subdivision from one fine regroupable capture.");
  c->footer(
      "The input is a fine capture recorded with `raycell record --regroupable` (its rays\n"
      "also visit the empty cells they cross, and it holds each cell's leaves). Each visit's\n"
      "cell becomes the cell of the subdivision holding it; consecutive visits in one cell\n"
      "merge (samples added), visits to empty cells and rays left with none are dropped, and a\n"
      "cell's footprint is the bytes of its leaves, each once. The output is the trace a\n"
      "capture on those cells would be, with the subdivision in its header. analyze, replay,\n"
      "sweep and `trace cat` take the same SPEC as --cells on the fine capture, writing no "
      "file.\n\n"
      "SPEC (cells are boxes of whole fine cells; docs/design.md §1 \"Subdivisions\"):\n"
      "  NXxNYxNZ          uniform; each count divides the fine grid's\n"
      "  grid:NXxNYxNZ     any counts up to the fine grid's: along each axis the fine boundaries\n"
      "                    nearest to an even split (grid:1x3x9 on 12x12x12: cells long in x)\n"
      "  grid:N:crossings  the grid of N cells whose boundaries the rays' steps cross least\n"
      "                    (cells long along the axes rays travel); `trace info --cells` names\n"
      "                    its counts\n"
      "  kd:N:footprint    k-d tree of N cells, footprints as equal as possible\n"
      "  kd:N:work         k-d tree of N cells, samples (over all frames) as equal as possible\n"
      "  kd:N:sqrt         k-d tree of N cells, footprint / sqrt(samples + 1) as equal as\n"
      "                    possible: footprints in proportion to the square root of the work\n"
      "  kd:budget:BYTES   k-d tree until every cell fits BYTES (e.g. 256KiB) or is one fine cell\n"
      "  octree:BYTES      octree: halve every axis while a cell is over BYTES\n"
      "  dynamic:N         kd:N:work on the previous frame's samples, per frame (frame 0 by\n"
      "                    footprint); warm memory keeps the new cells whose fine cells it\n"
      "                    held\n"
      "  dynamic:N:sqrt    the same with kd:N:sqrt on the previous frame's samples\n"
      "  auto:N            the recommended N cells: per frame, from the frames before it only,\n"
      "                    the uniform grid nearest a cube (3x3x3 for 27), or an adaptive\n"
      "                    candidate once its estimated savings on the frames seen pay for\n"
      "                    changing the cells (a frame scheduled without an earlier tree)\n\n"
      "Examples:\n"
      "  raycell record --cells 12x12x12 --regroupable --no-images --out fine.rct\n"
      "  raycell trace regroup fine.rct --cells 3x3x3 --out c3.rct   # = record --cells 3x3x3\n"
      "  raycell trace regroup fine.rct --cells kd:27:footprint --out kd.rct\n"
      "  raycell analyze fine.rct --cells octree:256KiB");
  c->add_option("CAPTURE", args->input, "a capture recorded with --regroupable")->required();
  c->add_option("--cells", args->cells, "the subdivision's SPEC")->required();
  c->add_option("--out", args->out, "trace file to write")->required();
  c->callback([args] { RunRegroup(*args); });
}

struct ConcatArgs {
  std::vector<std::string> inputs;
  std::string out;
};

void RunConcat(const ConcatArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  const ConcatSummary s = ConcatTraces(a.inputs, a.out);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cerr << "joined " << s.inputs << " trace(s): frames " << s.first_frame << ".."
            << s.last_frame << " (" << s.frames << " frames, " << s.bytes << " bytes) -> " << a.out
            << " in " << std::fixed << std::setprecision(3) << secs << " s\n";
}

void AddConcat(CLI::App& trace) {
  auto args = std::make_shared<ConcatArgs>();
  CLI::App* c = trace.add_subcommand(
      "concat", "Join captures of consecutive frame ranges of one camera path into one trace.");
  c->footer(
      "The inputs, in any order, must be complete captures of one scene with the same\n"
      "settings, cell grid, footprints and camera path (format version 3 or later), whose\n"
      "frame ranges follow each other without overlap or gap once sorted: e.g. made by\n"
      "`raycell record --orbit 30:360 --frames A..B` on several machines. The output is the\n"
      "trace one `record` of the whole range writes, byte for byte. Each frame is copied as\n"
      "stored after checking it against the hash of its bytes the index keeps (captures\n"
      "from before that hash: its zstd checksum and totals; not its rays: `trace verify`\n"
      "does); only the header and index are written anew. Anything else (overlap, gap, a\n"
      "difference, a damaged or incomplete input) exits 2 naming it, and writes nothing.\n\n"
      "Example:\n"
      "  raycell record --orbit 8:90 --frames 0..3 --no-images --out a.rct\n"
      "  raycell record --orbit 8:90 --frames 4..7 --no-images --out b.rct\n"
      "  raycell trace concat b.rct a.rct --out all.rct   # = record --orbit 8:90");
  c->add_option("TRACES", args->inputs, "captures to join, in any order")->required();
  c->add_option("--out", args->out, "trace file to write")->required();
  c->callback([args] { RunConcat(*args); });
}

}  // namespace

void AddTraceCommand(CLI::App& app) {
  CLI::App* trace = app.add_subcommand("trace", "Inspect a capture and export its rays.");
  trace->require_subcommand(1);

  auto info = std::make_shared<TraceArgs>();
  CLI::App* i = trace->add_subcommand(
      "info",
      "Header, frames, rays by kind, visits, samples, bytes per visit and compression, then the "
      "capture's character: rays per pixel, the share of secondary rays, and the mean and "
      "largest maxGen per cell (every frame's Cell Tree built once).");
  i->add_option("FILE", info->file, "trace file (.rct; an interrupted capture's .tmp reads too)")
      ->required();
  i->add_option("--cells", info->cells,
                "a regroupable capture regrouped into this subdivision (SPEC as `trace "
                "regroup`): its cells, footprints and totals; default: the file as stored");
  i->add_flag("--cameras", info->cameras,
              "also print each frame's camera as 'camera FRAME eye X,Y,Z target X,Y,Z fov F' "
              "(e.g. to render the same views with vdb_render -translate/-lookat/-fov)");
  i->add_flag("--no-character", info->no_character,
              "skip the character (which reads every frame): only what the header and the "
              "frame index hold, at once whatever the capture's size");
  i->callback([info] {
    // As stored, unless asked for a regroupable capture's subdivision.
    const TraceReader r = OpenWithWarning(info->file, info->cells, info->cells.empty());
    PrintInfo(r, info->file, std::cout);
    if (!info->no_character) {
      std::cout << "\n";
      PrintCharacter(Characterize(r, HardwareThreads()), std::cout);
    }
    if (info->cameras) PrintCameras(r.header(), std::cout);
  });

  auto verify = std::make_shared<TraceArgs>();
  CLI::App* v = trace->add_subcommand(
      "verify",
      "Read every frame, check checksums and content, and report the read speed. Exits 2 on "
      "any damage (a missing or damaged index, a truncated file, a bad frame), naming what is "
      "lost; the other commands warn and use the intact frames instead.");
  v->add_option("FILE", verify->file, "trace file")->required();
  v->callback([verify] { RunVerify(*verify); });

  auto cat = std::make_shared<TraceArgs>();
  CLI::App* c = trace->add_subcommand("cat", "Write rays as JSON Lines, one ray per line.");
  c->footer(
      "Each line:\n"
      "  {\"id\":7,\"parent\":3,\"spawn\":2,\"kind\":\"reflection\",\"pixel\":[x,y],"
      "\"cells\":[5,4,1],\"samples\":[12,30,2]}\n"
      "parent and spawn are null for primary rays; spawn indexes the parent's cells, and\n"
      "cells[0] is that cell. Ids are frame-local. Without --frame every frame is written and\n"
      "each line starts with \"frame\":N when the file has more than one frame. `raycell\n"
      "analyze --paths` and `raycell trace import` read this format (docs/jsonl.md).");
  c->add_option("FILE", cat->file, "trace file")->required();
  c->add_option("--frame", cat->frame, "frame number to write (default: all)");
  c->add_option("--cells", cat->cells,
                "a regroupable capture's rays in this subdivision (SPEC as `trace regroup`); "
                "default: its own grid");
  c->add_option("--format", cat->format, "output format")->capture_default_str();
  c->callback([cat] { RunCat(*cat); });

  AddImport(*trace);
  AddConcat(*trace);
  AddRegroup(*trace);
}

}  // namespace raycell
