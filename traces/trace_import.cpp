#include "traces/trace_import.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "base/check.h"
#include "traces/jsonl.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

// The trace reader's limit on each axis of the cell grid (so at most 2^30 cells).
constexpr std::uint32_t kMaxCellsPerAxis = 1024;

std::string Dims(const std::array<std::uint32_t, 3>& c) {
  return std::to_string(c[0]) + "x" + std::to_string(c[1]) + "x" + std::to_string(c[2]);
}

void Validate(const ImportOptions& o) {
  for (std::uint32_t n : o.cells) {
    if (n == 0 || n > kMaxCellsPerAxis) {
      throw InputError("--cells " + Dims(o.cells) + ": each dimension must be in 1.." +
                       std::to_string(kMaxCellsPerAxis) + " (the trace format's limit)");
    }
  }
  if (o.footprint == 0) {
    throw InputError(
        "--footprint: must be more than 0 bytes (a cell of footprint 0 is empty "
        "and may not appear in any path)");
  }
  if (o.box) {
    const auto& [lo, hi] = *o.box;
    const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(l[a]) || !std::isfinite(h[a]) || !(l[a] < h[a])) {
        throw InputError("--box: expected finite X0,Y0,Z0,X1,Y1,Z1 with X0 < X1, Y0 < Y1, Z0 < Z1");
      }
    }
  }
  if (o.zstd_level < 1 || o.zstd_level > kTraceMaxZstdLevel) {
    throw InputError("--zstd-level " + std::to_string(o.zstd_level) + ": must be in 1.." +
                     std::to_string(kTraceMaxZstdLevel));
  }
  if (o.out.empty()) throw InputError("--out: give the trace file to write");
}

JsonlReadOptions ReadOptions(const ImportOptions& o) {
  JsonlReadOptions r;
  r.cell_count = std::uint64_t{o.cells[0]} * o.cells[1] * o.cells[2];
  r.cells_what = "--cells " + Dims(o.cells);
  return r;
}

std::ifstream Open(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open");
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    throw InputError(path + ": not a regular file (trace import reads it twice: first to " +
                     "check it, then to write the trace); save the paths to a file first");
  }
  return in;
}

// What the first reading finds: the frames in order and the largest pixel.
struct Survey {
  std::vector<std::int32_t> frames;
  std::uint64_t max_x = 0, max_y = 0;
};

Survey SurveyFile(const ImportOptions& o) {
  std::ifstream in = Open(o.paths);
  JsonlReader reader(in, o.paths, ReadOptions(o));
  Survey s;
  JsonlFrame f;
  while (reader.Next(f)) {
    s.frames.push_back(f.frame);
    for (std::uint32_t x : f.rays.pixel_xs()) s.max_x = std::max<std::uint64_t>(s.max_x, x);
    for (std::uint32_t y : f.rays.pixel_ys()) s.max_y = std::max<std::uint64_t>(s.max_y, y);
  }
  if (s.frames.empty()) throw InputError(o.paths + ": no rays");
  return s;
}

std::uint32_t ImageSize(std::uint64_t max_pixel, const std::string& what) {
  if (max_pixel + 1 > std::numeric_limits<std::uint32_t>::max()) {
    throw InputError("a pixel " + what + " of " + std::to_string(max_pixel) +
                     " leaves no room for the image size in 32 bits");
  }
  return static_cast<std::uint32_t>(max_pixel + 1);
}

ImportSummary WriteFrames(const ImportOptions& o, const Survey& s, TraceWriter& writer) {
  std::ifstream in = Open(o.paths);
  JsonlReader reader(in, o.paths, ReadOptions(o));
  ImportSummary summary;
  JsonlFrame f;
  while (reader.Next(f)) {
    if (summary.frames >= s.frames.size() || s.frames[summary.frames] != f.frame) {
      throw InputError(o.paths + ": changed while it was imported");
    }
    writer.BeginFrame(f.frame);
    writer.Append(f.rays);
    const FrameSummary written = writer.EndFrame();
    ++summary.frames;
    summary.renumbered_frames += f.renumbered ? 1 : 0;
    summary.rays += written.rays;
    summary.visits += written.visits;
  }
  if (summary.frames != s.frames.size()) {
    throw InputError(o.paths + ": changed while it was imported");
  }
  return summary;
}

}  // namespace

TraceHeader ImportHeader(const ImportOptions& o, const std::vector<std::int32_t>& frames,
                         std::uint32_t width, std::uint32_t height) {
  TraceHeader h;
  h.producer = "raycell 0.1.0 (trace import)";
  h.scene = "import:" + o.paths;
  if (o.box) {
    h.box_min = o.box->first;
    h.box_max = o.box->second;
  } else {
    h.box_max = {double(o.cells[0]), double(o.cells[1]), double(o.cells[2])};
  }
  h.cells = o.cells;
  h.footprints.assign(h.cell_count(), o.footprint);
  h.footprint_mode = "uniform";
  for (std::int32_t f : frames) {
    CameraKey c;
    c.frame = f;
    h.cameras.push_back(c);
  }
  h.settings.width = width;
  h.settings.height = height;
  h.settings.zstd_level = o.zstd_level;
  return h;
}

ImportSummary ImportJsonl(const ImportOptions& o) {
  Validate(o);
  const Survey s = SurveyFile(o);
  const TraceHeader header =
      ImportHeader(o, s.frames, ImageSize(s.max_x, "x"), ImageSize(s.max_y, "y"));
  TraceWriter writer = TraceWriter::Create(o.out, header);
  try {
    const ImportSummary summary = WriteFrames(o, s, writer);
    writer.Finish();
    return summary;
  } catch (...) {
    std::remove(writer.tmp_path().c_str());
    throw;
  }
}

}  // namespace raycell
