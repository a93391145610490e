// Size and speed of a realistic trace (docs/design.md §3: bytes per visit at zstd level 3): a
// synthetic capture shaped like vdb_render's, written and read back (the round trip is
// checked), then the same rays with incompressible samples for comparison.
//
// A 96-voxel cube split into 3x3x3 cells, one primary ray per pixel of a SIZExSIZE image
// marching with step 1 for a smoothly varying number of samples (early termination), and at
// each primary sample a shadow ray towards a directional light marching with step 3 to the
// box exit. Samples per visit are counted. Deterministic: the same SIZE gives the same bytes.
//
// Usage: bench_trace_size [SIZE=256] [OUT=/tmp/bench_trace_size.rct]
//
// bench_trace_size --columns FILE: where a trace's bytes go. Each frame's batch columns
// (any format version) are gathered column by column, each compressed alone with zstd at the
// file's level, and their sizes printed per visit of the file, beside the file's own bytes
// per visit (which compresses the columns interleaved, batch by batch); format 6's range
// coded samples (sampleCode) count as one more column.
//
// bench_trace_size --recode IN OUT [VERSION]: IN's frames written anew by this build's writer
// as format VERSION (5, 6 or 7, default the current), to compare the formats on one capture: both
// files' bytes per visit, the encoding time, and each file's read time (every frame decoded
// and checked, as `raycell trace verify` does).
#include <capnp/serialize.h>
#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "base/check.h"
#include "traces/trace.capnp.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

struct V3 {
  double x, y, z;
  V3 operator+(const V3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  V3 operator*(double s) const { return {x * s, y * s, z * s}; }
};

V3 Normalized(V3 v) { return v * (1 / std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z)); }

class SyntheticScene {
 public:
  RayBatch Frame(int size) const {
    RayBatch b(false);
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) PrimaryWithShadows(x, y, size, b);
    }
    return b;
  }

 private:
  static constexpr double kN = 96, kCell = 32;

  int CellOf(V3 p) const {
    auto c = [](double v) { return std::clamp(static_cast<int>(v / kCell), 0, 2); };
    return c(p.x) + 3 * (c(p.y) + 3 * c(p.z));
  }
  bool Inside(V3 p) const {
    return p.x >= 0 && p.y >= 0 && p.z >= 0 && p.x < kN && p.y < kN && p.z < kN;
  }

  // Marches from p along d; appends visits and returns the visit index of each sample.
  std::vector<std::uint32_t> March(V3 p, V3 d, double step, int max_samples, RayBatch& b,
                                   std::vector<V3>* points) const {
    std::vector<std::uint32_t> visit_of_sample;
    int last = -1;
    const std::size_t first = b.visit_count();
    for (int i = 0; i < max_samples; ++i) {
      const V3 q = p + d * (step * i);
      if (!Inside(q)) break;
      const int c = CellOf(q);
      if (c != last)
        b.AddVisit(CellId(c), 0, static_cast<float>(step * i), static_cast<float>(step * i));
      b.AddSamplesToLastVisit(1);
      last = c;
      visit_of_sample.push_back(static_cast<std::uint32_t>(b.visit_count() - first - 1));
      if (points) points->push_back(q);
    }
    return visit_of_sample;
  }

  void PrimaryWithShadows(int x, int y, int size, RayBatch& b) const {
    const V3 eye{kN * 0.5, kN * 0.55, -3 * kN};
    const V3 target{kN * (0.02 + 0.96 * (x + 0.5) / size), kN * (0.02 + 0.96 * (y + 0.5) / size),
                    0};
    const V3 d = Normalized(target + eye * -1);
    const V3 entry = eye + d * (-eye.z / d.z + 1e-6);
    const int budget = static_cast<int>(62 + 18 * std::sin(x * 0.05) * std::cos(y * 0.037) +
                                        8 * std::sin((x + y) * 0.11));
    const RayId id = b.size();
    b.BeginRay(RayKind::kPrimary, kNoParent, 0, x, y);
    std::vector<V3> points;
    const std::vector<std::uint32_t> spawn = March(entry, d, 1.0, budget, b, &points);
    const V3 light = Normalized({0.35, 0.5, -1});
    for (std::size_t i = 0; i < points.size(); ++i) {
      b.BeginRay(RayKind::kShadow, id, spawn[i], x, y);
      March(points[i], light, 3.0, 1000, b, nullptr);
    }
  }
};

TraceHeader Header() {
  TraceHeader h;
  h.producer = "bench_trace_size";
  h.scene = "synthetic";
  h.cells = {3, 3, 3};
  h.footprints.assign(27, 32 * 32 * 32 * 4);
  h.cameras.push_back({});
  return h;
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Writes `frame` as a one-frame trace; returns its bytes per visit.
double BytesPerVisit(const std::string& path, const RayBatch& frame, double* write_s) {
  const auto t0 = std::chrono::steady_clock::now();
  TraceWriter w = TraceWriter::Create(path, Header());
  w.BeginFrame(0);
  w.Append(frame);
  const FrameSummary s = w.EndFrame();
  w.Finish();
  *write_s = Seconds(t0);
  return static_cast<double>(s.length) / static_cast<double>(s.visits);
}

int Main(int size, const std::string& path) {
  const RayBatch frame = SyntheticScene().Frame(size);
  std::uint64_t primaries = 0, primary_visits = 0, max_samples = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const RayView r = frame.ray(i);
    primaries += r.is_primary();
    if (r.is_primary()) primary_visits += r.visit_count;
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      max_samples = std::max<std::uint64_t>(max_samples, r.samples[v]);
    }
  }
  const std::uint64_t shadows = frame.size() - primaries;
  double write_s = 0;
  const double bpv = BytesPerVisit(path, frame, &write_s);
  const auto t0 = std::chrono::steady_clock::now();
  const bool same = TraceReader::Open(path).LoadFrame(0) == frame;
  const double read_s = Seconds(t0);
  std::printf(
      "synthetic frame %dx%d: %zu rays (%.1f shadow rays per primary), %zu visits "
      "(%.2f per primary, %.2f per shadow ray), samples <= %llu\n",
      size, size, frame.size(), shadows / double(primaries), frame.visit_count(),
      primary_visits / double(primaries),
      (frame.visit_count() - primary_visits) / static_cast<double>(shadows),
      static_cast<unsigned long long>(max_samples));
  std::printf("zstd level 3: %.4f bytes per visit; write %.2f s, read and verify %.2f s\n", bpv,
              write_s, read_s);
  if (!same) {
    std::printf("ERROR: the frame read back differs from the frame written\n");
    return 1;
  }
  // The same rays with samples replaced by independent uniform 1..40 draws (no spatial
  // coherence, so incompressible beyond their ~5.3 bits of entropy).
  std::mt19937_64 rng(12);
  RayBatch noisy(false);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const RayView r = frame.ray(i);
    noisy.BeginRay(r.kind, r.parent, r.spawn, r.pixel_x, r.pixel_y);
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      noisy.AddVisit(r.cells[v], 1 + rng() % 40, 0, 0);
    }
  }
  std::printf("same rays, uniform random samples 1..40: %.4f bytes per visit\n",
              BytesPerVisit(path, noisy, &write_s));
  std::remove(path.c_str());
  return 0;
}

// The content of one zstd frame.
std::string Decompress(const std::string& frame) {
  ZSTD_DCtx* dctx = ZSTD_createDCtx();
  std::string out;
  std::vector<char> buffer(ZSTD_DStreamOutSize());
  ZSTD_inBuffer in{frame.data(), frame.size(), 0};
  std::size_t left = 1;
  while (left != 0 && in.pos < in.size) {
    ZSTD_outBuffer o{buffer.data(), buffer.size(), 0};
    left = ZSTD_decompressStream(dctx, &o, &in);
    RAYCELL_CHECK(!ZSTD_isError(left));
    out.append(buffer.data(), o.pos);
  }
  ZSTD_freeDCtx(dctx);
  return out;
}

void AddColumn(std::string& to, schema::Column::Reader c) {
  for (const std::uint8_t b : c.getNarrow()) to.push_back(static_cast<char>(b));
  for (const std::uint64_t w : c.getWide()) {
    for (int k = 0; k < 8; ++k) to.push_back(static_cast<char>(w >> (8 * k)));
  }
}

// Each frame's batch columns, compressed column by column (see the file comment).
int Columns(const std::string& path) {
  const TraceReader reader = TraceReader::Open(path);
  const int level = static_cast<int>(reader.header().settings.zstd_level);
  std::map<std::string, std::uint64_t> packed, raw;
  std::uint64_t visits = 0, frame_bytes = 0;
  for (std::size_t f = 0; f < reader.frames().size(); ++f) {
    visits += reader.frames()[f].visits;
    const std::string encoded = reader.ReadEncodedFrame(f);
    frame_bytes += encoded.size();
    const std::string content = Decompress(encoded);
    kj::Array<capnp::word> words = kj::heapArray<capnp::word>(content.size() / 8);
    std::memcpy(words.begin(), content.data(), words.size() * 8);
    std::map<std::string, std::string> columns;
    capnp::ReaderOptions options;
    options.traversalLimitInWords = kTraceMaxMessageBytes / 8;
    for (kj::ArrayPtr<const capnp::word> rest = words; rest.size() > 0;) {
      capnp::FlatArrayMessageReader message(rest, options);
      rest = kj::arrayPtr(message.getEnd(), rest.end());
      const auto record = message.getRoot<schema::Record>();
      if (record.which() != schema::Record::BATCH) continue;
      const auto b = record.getBatch();
      std::string& heads = columns["heads"];
      for (const std::uint8_t h : b.getHeads()) heads.push_back(static_cast<char>(h));
      AddColumn(columns["headRuns"], b.getHeadRuns());
      AddColumn(columns["parents"], b.getParents());
      AddColumn(columns["spawns"], b.getSpawns());
      AddColumn(columns["pixels"], b.getPixels());
      AddColumn(columns["primaryPaths"], b.getPrimaryPaths());
      AddColumn(columns["secondaryPaths"], b.getSecondaryPaths());
      AddColumn(columns["primarySamples"], b.getPrimarySamples());
      AddColumn(columns["secondarySamples"], b.getSecondarySamples());
      AddColumn(columns["shadowSamples"], b.getShadowSamples());
      const auto code = b.getSampleCode();
      columns["sampleCode"].append(reinterpret_cast<const char*>(code.begin()), code.size());
      const auto paths = b.getPathCode();
      columns["pathCode"].append(reinterpret_cast<const char*>(paths.begin()), paths.size());
      std::string& t = columns["tEnter+tExit"];
      for (const float x : b.getTEnter()) t.append(reinterpret_cast<const char*>(&x), 4);
      for (const float x : b.getTExit()) t.append(reinterpret_cast<const char*>(&x), 4);
    }
    for (const auto& [name, bytes] : columns) {
      std::string out(ZSTD_compressBound(bytes.size()), '\0');
      const std::size_t n =
          ZSTD_compress(out.data(), out.size(), bytes.data(), bytes.size(), level);
      RAYCELL_CHECK(!ZSTD_isError(n));
      packed[name] += n;
      raw[name] += bytes.size();
    }
  }
  const double v = static_cast<double>(std::max<std::uint64_t>(visits, 1));
  std::printf("%s: format version %u, %zu frame(s), %llu visits, %.4f bytes per visit in frames\n",
              path.c_str(), reader.header().format_version, reader.frames().size(),
              static_cast<unsigned long long>(visits), frame_bytes / v);
  std::printf("%-18s %12s %12s\n", "column", "B/visit", "raw B/visit");
  std::uint64_t all = 0, all_raw = 0;
  for (const auto& [name, n] : packed) {
    std::printf("%-18s %12.4f %12.4f\n", name.c_str(), n / v, raw[name] / v);
    all += n;
    all_raw += raw[name];
  }
  std::printf("%-18s %12.4f %12.4f\n", "sum", all / v, all_raw / v);
  return 0;
}

// Rewrites the trace IN as OUT with this build's writer (format `version`), frame by frame,
// and prints both files' bytes per visit and the times: the write (encoding and compressing
// the rays read) and a verify-speed read of each file (every frame decoded and checked).
int Recode(const std::string& in, const std::string& out, std::uint32_t version) {
  const TraceReader reader = TraceReader::OpenStored(in);
  TraceWriterOptions options;
  options.format_version = version;
  std::uint64_t visits = 0, in_bytes = 0, out_bytes = 0;
  double write_s = 0;
  {
    TraceWriter w = TraceWriter::Create(out, reader.header(), options);
    for (std::size_t f = 0; f < reader.frames().size(); ++f) {
      const RayBatch rays = reader.LoadFrame(f);
      const auto t0 = std::chrono::steady_clock::now();
      w.BeginFrame(reader.frames()[f].frame);
      w.Append(rays);
      const FrameSummary s = w.EndFrame();
      write_s += Seconds(t0);
      RAYCELL_CHECK_EQ(s.checksum, reader.frames()[f].checksum);
      visits += s.visits;
      in_bytes += reader.frames()[f].length;
      out_bytes += s.length;
    }
    w.Finish();
  }
  auto read_time = [](const std::string& path) {
    const auto t0 = std::chrono::steady_clock::now();
    const TraceReader r = TraceReader::OpenStored(path);
    for (std::size_t f = 0; f < r.frames().size(); ++f) r.ForEachBatch(f, [](const RayBatch&) {});
    return Seconds(t0);
  };
  const double v = static_cast<double>(std::max<std::uint64_t>(visits, 1));
  std::printf("%s: version %u, %.4f B/visit; %s: version %u, %.4f B/visit, written in %.3f s\n",
              in.c_str(), reader.header().format_version, in_bytes / v, out.c_str(), version,
              out_bytes / v, write_s);
  std::fflush(stdout);
  const double read_in = read_time(in), read_out = read_time(out);
  std::printf("read (decode and check every frame): %s %.3f s, %s %.3f s\n", in.c_str(), read_in,
              out.c_str(), read_out);
  return 0;
}

}  // namespace
}  // namespace raycell

int main(int argc, char** argv) {
  if ((argc == 4 || argc == 5) && std::string(argv[1]) == "--recode") {
    const int version = argc == 5 ? std::atoi(argv[4]) : int{raycell::kTraceFormatVersion};
    if (version < 5 || version > int{raycell::kTraceFormatVersion}) {
      std::fprintf(stderr, "bench_trace_size: --recode writes format version 5 or %u\n",
                   raycell::kTraceFormatVersion);
      return 2;
    }
    try {
      return raycell::Recode(argv[2], argv[3], static_cast<std::uint32_t>(version));
    } catch (const raycell::InputError& e) {
      std::fprintf(stderr, "bench_trace_size: %s\n", e.what());
      return 2;
    }
  }
  if (argc == 3 && std::string(argv[1]) == "--columns") {
    try {
      return raycell::Columns(argv[2]);
    } catch (const raycell::InputError& e) {
      std::fprintf(stderr, "bench_trace_size: %s\n", e.what());
      return 2;
    }
  }
  const int size = argc > 1 ? std::atoi(argv[1]) : 256;
  const std::string out = argc > 2 ? argv[2] : "/tmp/bench_trace_size.rct";
  if (size < 1 || size > 4096) {
    std::fprintf(stderr, "usage: bench_trace_size [SIZE=256 (1..4096)] [OUT]\n");
    return 2;
  }
  try {
    return raycell::Main(size, out);
  } catch (const raycell::InputError& e) {
    std::fprintf(stderr, "bench_trace_size: %s\n", e.what());
    return 2;
  }
}
