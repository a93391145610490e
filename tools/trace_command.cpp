// raycell trace: inspect a capture (info) and hand its rays to other tools (cat).
#include <iostream>
#include <memory>
#include <optional>

#include "tools/commands.h"
#include "traces/check.h"
#include "traces/trace_inspect.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

struct TraceArgs {
  std::string file;
  std::optional<int> frame;
  std::string format = "jsonl";
};

TraceReader OpenWithWarning(const std::string& file) {
  TraceReader r = TraceReader::Open(file);
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
  const TraceReader r = OpenWithWarning(a.file);
  std::optional<std::size_t> index;
  if (a.frame) index = FrameIndex(r, *a.frame);
  std::ios::sync_with_stdio(false);
  WriteJsonl(r, index, std::cout);
  std::cout.flush();
}

}  // namespace

void AddTraceCommand(CLI::App& app) {
  CLI::App* trace = app.add_subcommand("trace", "Inspect a capture and export its rays.");
  trace->require_subcommand(1);

  auto info = std::make_shared<TraceArgs>();
  CLI::App* i = trace->add_subcommand(
      "info", "Header, frames, rays by kind, visits, samples, bytes per visit and compression.");
  i->add_option("FILE", info->file, "trace file (.rct; an interrupted capture's .tmp reads too)")
      ->required();
  i->callback([info] {
    const TraceReader r = OpenWithWarning(info->file);
    PrintInfo(r, info->file, std::cout);
  });

  auto cat = std::make_shared<TraceArgs>();
  CLI::App* c = trace->add_subcommand(
      "cat",
      "Write rays as JSON Lines, one ray per line:\n"
      "  {\"id\":7,\"parent\":3,\"spawn\":2,\"kind\":\"reflection\",\"pixel\":[x,y],"
      "\"cells\":[5,4,1],\"samples\":[12,30,2]}\n"
      "parent and spawn are null for primary rays; spawn indexes the parent's cells, and\n"
      "cells[0] is that cell. Ids are frame-local. Without --frame every frame is written and\n"
      "each line starts with \"frame\":N. `raycell analyze --paths` reads this format.");
  c->add_option("FILE", cat->file, "trace file")->required();
  c->add_option("--frame", cat->frame, "frame number to write (default: all)");
  c->add_option("--format", cat->format, "output format")->capture_default_str();
  c->callback([cat] { RunCat(*cat); });
}

}  // namespace raycell
