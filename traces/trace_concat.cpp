#include "traces/trace_concat.h"

#include <algorithm>
#include <filesystem>
#include <utility>

#include "base/check.h"
#include "base/format.h"
#include "base/parse.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

std::string Grid(const std::array<std::uint32_t, 3>& c) {
  return std::to_string(c[0]) + "x" + std::to_string(c[1]) + "x" + std::to_string(c[2]);
}

// One input: its reader and the frames it holds.
struct Part {
  TraceReader reader;
  std::int32_t first = 0, last = 0;
  std::string name() const { return reader.path(); }
  std::string range() const { return FormatFrameRange(first, last); }
};

// Opens `path` and checks it is a complete capture of a recorded camera path whose frames
// are its cameras' (a range of consecutive frames).
Part OpenPart(const std::string& path) {
  Part p{TraceReader::OpenStored(path)};
  const TraceReader& r = p.reader;
  if (!r.warning().empty()) {
    throw InputError(path + ": damaged or incomplete, not joined: " + r.warning());
  }
  const TraceHeader& h = r.header();
  if (h.path.kind.empty()) {
    throw InputError(path + ": its camera path is not recorded (format version " +
                     std::to_string(h.format_version) +
                     ", or an imported trace): only captures of format version 3 or later, "
                     "which record it, can be joined");
  }
  if (h.cameras.empty()) throw InputError(path + ": holds no frames");
  const std::vector<FrameSummary>& frames = r.frames();
  for (std::size_t i = 0; i < h.cameras.size(); ++i) {
    const std::int64_t want = std::int64_t{h.cameras.front().frame} + std::int64_t(i);
    if (h.cameras[i].frame != want) {
      throw InputError(path + ": its cameras' frames are not consecutive (camera #" +
                       std::to_string(i) + " is frame " + std::to_string(h.cameras[i].frame) + ")");
    }
    if (i >= frames.size() || frames[i].frame != h.cameras[i].frame) {
      throw InputError(path + ": holds " + std::to_string(frames.size()) +
                       " frame(s), not the frames of its cameras " +
                       FormatFrameRange(h.cameras.front().frame, h.cameras.back().frame) +
                       " (an incomplete capture)");
    }
  }
  if (frames.size() != h.cameras.size()) {
    throw InputError(path + ": holds " + std::to_string(frames.size()) + " frames for " +
                     std::to_string(h.cameras.size()) + " cameras");
  }
  p.first = h.cameras.front().frame;
  p.last = h.cameras.back().frame;
  return p;
}

// The first difference of two renderer settings, e.g. "resolution: 32x32 vs 64x32"; empty
// when equal.
std::string SettingsDifference(const RenderSettings& a, const RenderSettings& b) {
  auto res = [](const RenderSettings& s) {
    return std::to_string(s.width) + "x" + std::to_string(s.height);
  };
  const std::pair<bool, std::string> checks[] = {
      {a.width != b.width || a.height != b.height,
       "resolution (--res): " + res(a) + " vs " + res(b)},
      {a.spp != b.spp,
       "samples per pixel (--spp): " + std::to_string(a.spp) + " vs " + std::to_string(b.spp)},
      {a.max_depth != b.max_depth, "maximum depth (--max-depth): " + std::to_string(a.max_depth) +
                                       " vs " + std::to_string(b.max_depth)},
      {a.primary_step != b.primary_step,
       "step (--step): " + FormatReal(a.primary_step) + " vs " + FormatReal(b.primary_step)},
      {a.shadow_step != b.shadow_step, "shadow step (--shadow-step): " + FormatReal(a.shadow_step) +
                                           " vs " + FormatReal(b.shadow_step)},
      {a.cutoff != b.cutoff,
       "cutoff (--cutoff): " + FormatReal(a.cutoff) + " vs " + FormatReal(b.cutoff)},
      {a.store_t != b.store_t, std::string("stored t (--store-t): ") + (a.store_t ? "yes" : "no") +
                                   " vs " + (b.store_t ? "yes" : "no")},
      {a.single_precision != b.single_precision,
       std::string("precision (--precision): ") + (a.single_precision ? "single" : "double") +
           " vs " + (b.single_precision ? "single" : "double")},
      {a.zstd_level != b.zstd_level, "zstd level (--zstd-level): " + std::to_string(a.zstd_level) +
                                         " vs " + std::to_string(b.zstd_level)},
  };
  for (const auto& [differs, what] : checks) {
    if (differs) return what;
  }
  return "";
}

// The first difference between two headers but their cameras, e.g. "cell grid: 2x2x2 vs
// 3x3x3"; empty when they describe captures of one animation.
std::string HeaderDifference(const TraceHeader& a, const TraceHeader& b) {
  if (a.scene != b.scene) return "scene: '" + a.scene + "' vs '" + b.scene + "'";
  if (a.grids != b.grids) return "grids (names, roles, sources, voxel sizes or leaf counts)";
  if (!(a.box_min == b.box_min) || !(a.box_max == b.box_max)) {
    return "scene box: " + FormatVec3(a.box_min) + " - " + FormatVec3(a.box_max) + " vs " +
           FormatVec3(b.box_min) + " - " + FormatVec3(b.box_max);
  }
  if (a.cells != b.cells) return "cell grid (--cells): " + Grid(a.cells) + " vs " + Grid(b.cells);
  if (a.footprint_mode != b.footprint_mode) {
    return "footprint mode (--footprint): " + a.footprint_mode + " vs " + b.footprint_mode;
  }
  if (a.footprints != b.footprints) {
    std::size_t c = 0;
    while (a.footprints[c] == b.footprints[c]) ++c;
    return "footprints: cell " + std::to_string(c) + " has " + std::to_string(a.footprints[c]) +
           " vs " + std::to_string(b.footprints[c]) + " bytes";
  }
  if (a.regroupable != b.regroupable) {
    return std::string("regroupable (--regroupable): ") + (a.regroupable ? "yes" : "no") + " vs " +
           (b.regroupable ? "yes" : "no");
  }
  if (!(a.leaves == b.leaves)) return "the leaves of a regroupable capture";
  if (a.cells_change() || b.cells_change()) {
    return "subdivision: a dynamic one has boxes per frame of each input (join the fine "
           "captures, then regroup the joined one)";
  }
  if (!(a.subdivision == b.subdivision)) {
    return "subdivision: '" + a.subdivision.spec + "' vs '" + b.subdivision.spec + "'";
  }
  std::string settings = SettingsDifference(a.settings, b.settings);
  if (!settings.empty()) return settings;
  if (a.path != b.path) return "camera path: " + a.path.ToString() + " vs " + b.path.ToString();
  if (a.producer != b.producer) return "producer: '" + a.producer + "' vs '" + b.producer + "'";
  if (a.format_version != b.format_version) {
    return "format version: " + std::to_string(a.format_version) + " vs " +
           std::to_string(b.format_version);
  }
  TraceHeader a_path = a, b_path = b;  // every field but the cameras was compared above
  a_path.cameras.clear();
  b_path.cameras.clear();
  RAYCELL_CHECK(a_path == b_path);
  return "";
}

// Sorts the parts by their first frame and checks they follow each other without overlap
// or gap, and describe one capture.
void CheckJoinable(std::vector<Part>& parts) {
  for (std::size_t i = 1; i < parts.size(); ++i) {
    const std::string d = HeaderDifference(parts[0].reader.header(), parts[i].reader.header());
    if (!d.empty()) {
      throw InputError(parts[0].name() + " and " + parts[i].name() + " differ in " + d +
                       ": not captures of one animation");
    }
  }
  std::stable_sort(parts.begin(), parts.end(),
                   [](const Part& a, const Part& b) { return a.first < b.first; });
  for (std::size_t i = 1; i < parts.size(); ++i) {
    const Part &a = parts[i - 1], &b = parts[i];
    const std::string both =
        a.name() + " holds frames " + a.range() + " and " + b.name() + " frames " + b.range();
    if (b.first <= a.last) {
      throw InputError("overlapping frame ranges: " + both + " (frames " +
                       FormatFrameRange(b.first, std::min(a.last, b.last)) + " are in both)");
    }
    if (std::int64_t{b.first} > std::int64_t{a.last} + 1) {
      throw InputError("frame ranges with a gap: " + both + " (frames " +
                       FormatFrameRange(std::int64_t{a.last} + 1, std::int64_t{b.first} - 1) +
                       " are in neither)");
    }
  }
}

}  // namespace

ConcatSummary ConcatTraces(const std::vector<std::string>& inputs, const std::string& out) {
  if (inputs.empty()) throw InputError("trace concat: no input traces");
  std::vector<Part> parts;
  for (const std::string& path : inputs) parts.push_back(OpenPart(path));
  CheckJoinable(parts);
  TraceHeader header = parts[0].reader.header();
  header.cameras.clear();
  for (const Part& p : parts) {
    const auto& c = p.reader.header().cameras;
    header.cameras.insert(header.cameras.end(), c.begin(), c.end());
  }
  TraceWriterOptions options;
  options.name_at_finish = true;
  options.format_version = header.format_version;  // the frames are copied as encoded
  TraceWriter writer = TraceWriter::Create(out, header, options);
  for (const Part& p : parts) {
    for (std::size_t i = 0; i < p.reader.frames().size(); ++i) {
      writer.AppendEncodedFrame(p.reader.frames()[i], p.reader.ReadEncodedFrame(i));
    }
  }
  writer.Finish();
  ConcatSummary s;
  s.inputs = parts.size();
  s.frames = header.cameras.size();
  s.first_frame = parts.front().first;
  s.last_frame = parts.back().last;
  s.bytes = std::filesystem::file_size(out);
  return s;
}

}  // namespace raycell
