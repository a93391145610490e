// raycell trace: inspect a capture (info) and hand its rays to other tools (cat).
#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "base/check.h"
#include "tools/commands.h"
#include "traces/trace_inspect.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

struct TraceArgs {
  std::string file;
  bool cameras = false;
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
  const TraceReader r = TraceReader::Open(a.file);
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

}  // namespace

void AddTraceCommand(CLI::App& app) {
  CLI::App* trace = app.add_subcommand("trace", "Inspect a capture and export its rays.");
  trace->require_subcommand(1);

  auto info = std::make_shared<TraceArgs>();
  CLI::App* i = trace->add_subcommand(
      "info", "Header, frames, rays by kind, visits, samples, bytes per visit and compression.");
  i->add_option("FILE", info->file, "trace file (.rct; an interrupted capture's .tmp reads too)")
      ->required();
  i->add_flag("--cameras", info->cameras,
              "also print each frame's camera as 'camera FRAME eye X,Y,Z target X,Y,Z fov F' "
              "(e.g. to render the same views with vdb_render -translate/-lookat/-fov)");
  i->callback([info] {
    const TraceReader r = OpenWithWarning(info->file);
    PrintInfo(r, info->file, std::cout);
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
      "each line starts with \"frame\":N. This is the format the Cell Tree analysis\n(`raycell "
      "analyze --paths`, issue 3) is specified to read.");
  c->add_option("FILE", cat->file, "trace file")->required();
  c->add_option("--frame", cat->frame, "frame number to write (default: all)");
  c->add_option("--format", cat->format, "output format")->capture_default_str();
  c->callback([cat] { RunCat(*cat); });
}

}  // namespace raycell
