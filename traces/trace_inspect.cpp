#include "traces/trace_inspect.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <iomanip>
#include <set>
#include <sstream>
#include <vector>

#include "base/format.h"

namespace raycell {
namespace {

// Naive uncompressed encoding the compression ratio is measured against.
constexpr std::uint64_t kNaiveBytesPerRay = 24;
constexpr std::uint64_t kNaiveBytesPerVisit = 16;
constexpr std::size_t kMaxFootprintsShown = 32;

std::string Vec(const Vec3d& v) {
  std::ostringstream s;
  s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return s.str();
}

void PrintGrids(const TraceHeader& h, std::ostream& out) {
  out << "grids:          " << h.grids.size() << "\n";
  for (const GridInfo& g : h.grids) {
    out << "  " << g.name << " (" << g.role << ", " << g.source << ", voxel size " << g.voxel_size
        << ", " << g.leaf_count << " leaves)\n";
  }
}

void PrintFootprints(const TraceHeader& h, std::ostream& out) {
  std::uint64_t total = 0;
  for (std::uint64_t f : h.footprints) total += f;
  out << "footprints:     " << h.footprint_mode << ", " << total << " bytes in all:";
  for (std::size_t i = 0; i < h.footprints.size() && i < kMaxFootprintsShown; ++i) {
    out << " " << h.footprints[i];
  }
  out << (h.footprints.size() > kMaxFootprintsShown ? " ...\n" : "\n");
  std::vector<std::uint64_t> full;
  for (std::uint64_t f : h.footprints) {
    if (f != 0) full.push_back(f);
  }
  if (full.empty()) return;
  std::sort(full.begin(), full.end());
  out << "footprint spread: " << full.size() << " non-empty cells, min " << full.front()
      << ", median " << full[(full.size() - 1) / 2] << ", max " << full.back() << " bytes, max/min "
      << FormatFixed(double(full.back()) / double(full.front()), 2) << "\n";
}

void PrintSettings(const RenderSettings& s, std::ostream& out) {
  out << "settings:       " << s.width << "x" << s.height << ", " << s.spp << " spp, max depth "
      << s.max_depth << ", primary step " << s.primary_step << ", shadow step " << s.shadow_step
      << ", cutoff " << s.cutoff << ", " << (s.single_precision ? "single" : "double")
      << " precision, t " << (s.store_t ? "stored" : "not stored") << ", zstd level "
      << s.zstd_level << "\n";
}

void PrintHeader(const TraceReader& reader, const std::string& path, std::ostream& out) {
  const TraceHeader& h = reader.header();
  out << "trace:          " << path << " (" << reader.file_size() << " bytes)\n"
      << "format version: " << h.format_version << "\n"
      << "producer:       " << h.producer << "\n"
      << "scene:          " << h.scene << "\n";
  PrintGrids(h, out);
  out << "box:            " << Vec(h.box_min) << " - " << Vec(h.box_max) << "\n"
      << "cell grid:      " << h.cells[0] << "x" << h.cells[1] << "x" << h.cells[2] << " = "
      << h.cell_count() << " cells\n";
  if (!h.subdivision.empty()) {
    const auto& f = h.subdivision.fine;
    out << "subdivision:    " << h.subdivision.spec;
    if (h.subdivision.spec.rfind("grid:", 0) == 0 && !h.cells_change()) {
      // A grid's counts: its boxes' distinct lower corners per axis (grid:N:crossings chose).
      std::array<std::set<std::uint32_t>, 3> lo;
      for (const FineBox& b : h.subdivision.boxes) {
        for (int a = 0; a < 3; ++a) lo[a].insert(b.lo[a]);
      }
      out << " (" << lo[0].size() << "x" << lo[1].size() << "x" << lo[2].size() << ")";
    }
    out << " of a fine grid " << f[0] << "x" << f[1] << "x" << f[2]
        << (h.cells_change() ? " (boxes per frame)" : "") << "\n";
  }
  if (h.regroupable) {
    out << "regroupable:    yes (" << h.leaves.bytes.size() << " leaves, " << h.leaves.leaves.size()
        << " cell-leaf pairs; rays also visit empty cells)\n";
  }
  PrintFootprints(h, out);
  out << "cameras:        " << h.cameras.size();
  if (!h.cameras.empty()) {
    out << " (frames " << h.cameras.front().frame << ".." << h.cameras.back().frame << ")";
  }
  out << "\n"
      << "path:           " << h.path.ToString() << "\n";
  PrintSettings(h.settings, out);
  if (!reader.warning().empty()) out << "warning:        " << reader.warning() << "\n";
}

void PrintRow(const std::string& label, const FrameSummary& s, std::ostream& out) {
  out << std::setw(8) << label;
  for (std::uint64_t n : s.rays_by_kind) out << std::setw(12) << n;
  out << std::setw(12) << s.rays << std::setw(13) << s.visits << std::setw(14) << s.samples
      << std::setw(13) << s.length << std::setw(9) << std::fixed << std::setprecision(3)
      << (s.visits ? static_cast<double>(s.length) / static_cast<double>(s.visits) : 0.0) << "\n";
  out.unsetf(std::ios::floatfield);
}

FrameSummary Total(const std::vector<FrameSummary>& frames) {
  FrameSummary t;
  for (const FrameSummary& s : frames) {
    t.rays += s.rays;
    t.visits += s.visits;
    t.samples += s.samples;
    t.length += s.length;
    for (int k = 0; k < kRayKindCount; ++k) t.rays_by_kind[k] += s.rays_by_kind[k];
  }
  return t;
}

void PrintTable(const TraceReader& reader, std::ostream& out) {
  out << "\n" << std::setw(8) << "frame";
  for (int k = 0; k < kRayKindCount; ++k) out << std::setw(12) << ToString(RayKind(k));
  out << std::setw(12) << "rays" << std::setw(13) << "visits" << std::setw(14) << "samples"
      << std::setw(13) << "bytes" << std::setw(9) << "B/visit"
      << "\n";
  for (const FrameSummary& s : reader.frames()) PrintRow(std::to_string(s.frame), s, out);
  PrintRow("total", Total(reader.frames()), out);
}

void PrintRatio(const TraceReader& reader, std::ostream& out) {
  const FrameSummary t = Total(reader.frames());
  const std::uint64_t raw = t.rays * kNaiveBytesPerRay + t.visits * kNaiveBytesPerVisit;
  out << "\nframes:         " << reader.frames().size() << "\n"
      << "raw size:       " << raw << " bytes (naive uncompressed encoding: " << kNaiveBytesPerRay
      << " B per ray + " << kNaiveBytesPerVisit << " B per visit)\n"
      << "compressed:     " << t.length << " bytes in frames, " << reader.file_size()
      << " bytes in the file\n"
      << "ratio:          " << std::fixed << std::setprecision(1)
      << (t.length ? static_cast<double>(raw) / static_cast<double>(t.length) : 0.0)
      << "x (raw / compressed frames)\n";
  out.unsetf(std::ios::floatfield);
}

}  // namespace

void PrintInfo(const TraceReader& reader, const std::string& path, std::ostream& out) {
  PrintHeader(reader, path, out);
  PrintTable(reader, out);
  PrintRatio(reader, out);
}

}  // namespace raycell
