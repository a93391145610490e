#include "traces/trace_writer.h"

#include <capnp/message.h>
#include <capnp/serialize.h>
#include <fcntl.h>
#include <kj/io.h>
#include <unistd.h>
#include <zstd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

#include "traces/check.h"
#include "traces/trace.capnp.h"

namespace raycell {

// ---- Hash64, FrameAccumulator ------------------------------------------------------------

void Hash64::AddBytes(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; i += 8) {
    std::uint64_t w = 0;
    for (std::size_t b = 0; b < 8 && i + b < size; ++b) w |= std::uint64_t{p[i + b]} << (8 * b);
    Add(w);
  }
  Add(size);
}

std::uint64_t Hash64::Finish() const {
  std::uint64_t h = h_;
  h ^= h >> 33;
  h *= kP2;
  h ^= h >> 29;
  h *= kP3;
  h ^= h >> 32;
  return h;
}

FrameAccumulator::FrameAccumulator(std::int32_t frame, bool store_t) : store_t_(store_t) {
  summary_.frame = frame;
}

namespace {
std::uint64_t FloatBits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}
}  // namespace

void FrameAccumulator::AddRay(const RayView& r) {
  hash_.Add(static_cast<std::uint64_t>(r.kind));
  hash_.Add(r.parent);
  hash_.Add(r.spawn);
  hash_.Add(r.pixel_x);
  hash_.Add(r.pixel_y);
  hash_.Add(r.visit_count);
  for (std::size_t i = 0; i < r.visit_count; ++i) {
    hash_.Add(r.cells[i]);
    hash_.Add(r.samples[i]);
    if (store_t_) hash_.Add(FloatBits(r.t_enter[i]) << 32 | FloatBits(r.t_exit[i]));
    summary_.samples += r.samples[i];
  }
  ++summary_.rays;
  ++summary_.rays_by_kind[static_cast<int>(r.kind)];
  summary_.visits += r.visit_count;
}

FrameSummary FrameAccumulator::Summary() const {
  FrameSummary s = summary_;
  s.checksum = hash_.Finish();
  return s;
}

namespace {

// ---- Output file and zstd stream ---------------------------------------------------------

std::string ErrnoText() { return std::strerror(errno); }

// An owned file descriptor opened for writing, with full writes and a byte count.
class FileOut {
 public:
  explicit FileOut(std::string path) : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) throw InputError(path_ + ": cannot open for writing: " + ErrnoText());
  }
  FileOut(const FileOut&) = delete;
  FileOut& operator=(const FileOut&) = delete;
  ~FileOut() {
    if (fd_ >= 0) ::close(fd_);
  }

  void Write(const void* data, std::size_t size) {
    const auto* p = static_cast<const char*>(data);
    while (size > 0) {
      const ssize_t n = ::write(fd_, p, size);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw InputError(path_ + ": write failed: " + ErrnoText());
      p += n;
      size -= static_cast<std::size_t>(n);
      bytes_ += static_cast<std::uint64_t>(n);
    }
  }
  void SyncAndClose() {
    if (::fsync(fd_) != 0) throw InputError(path_ + ": fsync failed: " + ErrnoText());
    const int fd = std::exchange(fd_, -1);
    if (::close(fd) != 0) throw InputError(path_ + ": close failed: " + ErrnoText());
  }
  std::uint64_t bytes() const { return bytes_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t bytes_ = 0;
};

// Compresses what Cap'n Proto writes into zstd frames of `out`, one frame per EndFrame().
class ZstdSink : public kj::OutputStream {
 public:
  ZstdSink(FileOut& out, int level) : out_(out), buffer_(ZSTD_CStreamOutSize()) {
    cctx_ = ZSTD_createCCtx();
    RAYCELL_CHECK(cctx_ != nullptr);
    ZSTD_CCtx_setParameter(cctx_, ZSTD_c_compressionLevel, level);
    ZSTD_CCtx_setParameter(cctx_, ZSTD_c_checksumFlag, 1);
  }
  ZstdSink(const ZstdSink&) = delete;
  ZstdSink& operator=(const ZstdSink&) = delete;
  ~ZstdSink() { ZSTD_freeCCtx(cctx_); }

  void write(const void* data, std::size_t size) override { Compress(data, size, ZSTD_e_continue); }
  void EndFrame() { Compress(nullptr, 0, ZSTD_e_end); }

 private:
  void Compress(const void* data, std::size_t size, ZSTD_EndDirective mode) {
    ZSTD_inBuffer in{data, size, 0};
    bool done = false;
    while (!done) {
      ZSTD_outBuffer out{buffer_.data(), buffer_.size(), 0};
      const std::size_t left = ZSTD_compressStream2(cctx_, &out, &in, mode);
      if (ZSTD_isError(left)) {
        throw InputError(out_.path() + ": zstd: " + ZSTD_getErrorName(left));
      }
      out_.Write(buffer_.data(), out.pos);
      done = mode == ZSTD_e_end ? left == 0 : in.pos == in.size;
    }
  }

  FileOut& out_;
  std::vector<char> buffer_;
  ZSTD_CCtx* cctx_ = nullptr;
};

// ---- Encoding ----------------------------------------------------------------------------

std::uint64_t ZigZag(std::int64_t v) {
  return (static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63);
}

std::int64_t Delta(std::uint64_t value, std::uint64_t previous) {
  return static_cast<std::int64_t>(value - previous);
}

// A Column being built: narrow bytes with 255 escaping into `wide`.
class ColumnBuilder {
 public:
  void Reserve(std::size_t n) { narrow_.reserve(n); }
  void Add(std::uint64_t v) {
    if (v < 255) {
      narrow_.push_back(static_cast<std::uint8_t>(v));
    } else {
      narrow_.push_back(255);
      wide_.push_back(v);
    }
  }
  void Fill(schema::Column::Builder column) const {
    auto narrow = column.initNarrow(static_cast<unsigned>(narrow_.size()));
    for (unsigned i = 0; i < narrow_.size(); ++i) narrow.set(i, narrow_[i]);
    auto wide = column.initWide(static_cast<unsigned>(wide_.size()));
    for (unsigned i = 0; i < wide_.size(); ++i) wide.set(i, wide_[i]);
  }
  std::size_t bytes() const { return narrow_.size() + 8 * wide_.size(); }

 private:
  std::vector<std::uint8_t> narrow_;
  std::vector<std::uint64_t> wide_;
};

// The columns of one Batch message, encoded ray by ray.
struct BatchColumns {
  std::vector<std::uint8_t> kinds;
  ColumnBuilder parents, spawns, xs, ys, counts, cells, samples;
  std::uint64_t prev_spawn = 0, prev_x = 0, prev_y = 0;  // of the previous ray

  explicit BatchColumns(const RayBatch& b) {
    for (ColumnBuilder* c : {&parents, &spawns, &xs, &ys, &counts}) c->Reserve(b.size());
    cells.Reserve(b.visit_count());
    samples.Reserve(b.visit_count());
    for (std::size_t i = 0; i < b.size(); ++i) AddRay(b.ray(i));
  }

  void AddRay(const RayView& r) {
    kinds.push_back(static_cast<std::uint8_t>(r.kind));
    parents.Add(r.is_primary() ? 0 : r.id - r.parent);
    spawns.Add(ZigZag(Delta(r.spawn, prev_spawn)));
    xs.Add(ZigZag(Delta(r.pixel_x, prev_x)));
    ys.Add(ZigZag(Delta(r.pixel_y, prev_y)));
    prev_spawn = r.spawn;
    prev_x = r.pixel_x;
    prev_y = r.pixel_y;
    counts.Add(r.visit_count);
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      cells.Add(v == 0 ? r.cells[0] : ZigZag(Delta(r.cells[v], r.cells[v - 1])));
      samples.Add(r.samples[v]);
    }
  }

  std::size_t bytes() const {
    std::size_t n = kinds.size();
    for (const ColumnBuilder* c : {&parents, &spawns, &xs, &ys, &counts, &cells, &samples}) {
      n += c->bytes();
    }
    return n;
  }
};

void FillFloats(capnp::List<float>::Builder list, const std::vector<float>& values) {
  for (unsigned i = 0; i < values.size(); ++i) list.set(i, values[i]);
}

void FillBatch(schema::Batch::Builder out, const RayBatch& b, const BatchColumns& c,
               std::int32_t frame, bool store_t) {
  out.setFrame(frame);
  out.setFirstId(b.first_id());
  auto kinds = out.initKinds(static_cast<unsigned>(c.kinds.size()));
  for (unsigned i = 0; i < c.kinds.size(); ++i) kinds.set(i, c.kinds[i]);
  c.parents.Fill(out.initParents());
  c.spawns.Fill(out.initSpawns());
  c.xs.Fill(out.initPixelsX());
  c.ys.Fill(out.initPixelsY());
  c.counts.Fill(out.initVisitCounts());
  c.cells.Fill(out.initCells());
  c.samples.Fill(out.initSamples());
  if (!store_t) return;
  FillFloats(out.initTEnter(static_cast<unsigned>(b.visit_count())), b.t_enters());
  FillFloats(out.initTExit(static_cast<unsigned>(b.visit_count())), b.t_exits());
}

void FillVec3(schema::Vec3::Builder out, const Vec3d& v) {
  out.setX(v.x);
  out.setY(v.y);
  out.setZ(v.z);
}

void FillSettings(schema::Settings::Builder out, const RenderSettings& s) {
  out.setWidth(s.width);
  out.setHeight(s.height);
  out.setSpp(s.spp);
  out.setMaxDepth(s.max_depth);
  out.setPrimaryStep(s.primary_step);
  out.setShadowStep(s.shadow_step);
  out.setCutoff(s.cutoff);
  out.setStoreT(s.store_t);
  out.setZstdLevel(s.zstd_level);
}

void FillGrids(capnp::List<schema::Grid>::Builder out, const std::vector<GridInfo>& grids) {
  for (unsigned i = 0; i < grids.size(); ++i) {
    out[i].setName(grids[i].name);
    out[i].setRole(grids[i].role);
    out[i].setSource(grids[i].source);
    out[i].setVoxelSize(grids[i].voxel_size);
    out[i].setLeafCount(grids[i].leaf_count);
  }
}

void FillCameras(capnp::List<schema::Camera>::Builder out, const std::vector<CameraKey>& cams) {
  for (unsigned i = 0; i < cams.size(); ++i) {
    out[i].setFrame(cams[i].frame);
    FillVec3(out[i].initEye(), cams[i].eye);
    FillVec3(out[i].initTarget(), cams[i].target);
    FillVec3(out[i].initUp(), cams[i].up);
    out[i].setFovDeg(cams[i].fov_deg);
  }
}

void FillHeader(schema::Header::Builder out, const TraceHeader& h) {
  out.setFormatVersion(h.format_version);
  out.setProducer(h.producer);
  out.setScene(h.scene);
  FillGrids(out.initGrids(static_cast<unsigned>(h.grids.size())), h.grids);
  FillVec3(out.initBoxMin(), h.box_min);
  FillVec3(out.initBoxMax(), h.box_max);
  out.setCellsX(h.cells[0]);
  out.setCellsY(h.cells[1]);
  out.setCellsZ(h.cells[2]);
  auto footprints = out.initFootprints(static_cast<unsigned>(h.footprints.size()));
  for (unsigned i = 0; i < h.footprints.size(); ++i) footprints.set(i, h.footprints[i]);
  out.setFootprintMode(h.footprint_mode);
  FillCameras(out.initCameras(static_cast<unsigned>(h.cameras.size())), h.cameras);
  FillSettings(out.initSettings(), h.settings);
}

void FillKindCounts(capnp::List<std::uint64_t>::Builder out, const FrameSummary& s) {
  for (unsigned k = 0; k < s.rays_by_kind.size(); ++k) out.set(k, s.rays_by_kind[k]);
}

void FillFrameEnd(schema::FrameEnd::Builder out, const FrameSummary& s) {
  out.setFrame(s.frame);
  out.setRays(s.rays);
  out.setVisits(s.visits);
  out.setSamples(s.samples);
  FillKindCounts(out.initRaysByKind(kRayKindCount), s);
  out.setChecksum(s.checksum);
}

void FillIndex(schema::Index::Builder out, std::uint64_t header_length,
               const std::vector<FrameSummary>& frames) {
  out.setFormatVersion(kTraceFormatVersion);
  out.setHeaderLength(header_length);
  auto entries = out.initFrames(static_cast<unsigned>(frames.size()));
  for (unsigned i = 0; i < frames.size(); ++i) {
    const FrameSummary& s = frames[i];
    entries[i].setFrame(s.frame);
    entries[i].setOffset(s.offset);
    entries[i].setLength(s.length);
    entries[i].setRays(s.rays);
    entries[i].setVisits(s.visits);
    entries[i].setSamples(s.samples);
    FillKindCounts(entries[i].initRaysByKind(kRayKindCount), s);
    entries[i].setChecksum(s.checksum);
  }
}

void PutU32(std::vector<unsigned char>& out, std::uint32_t v) {
  for (int b = 0; b < 4; ++b) out.push_back(static_cast<unsigned char>(v >> (8 * b)));
}

void PutU64(std::vector<unsigned char>& out, std::uint64_t v) {
  for (int b = 0; b < 8; ++b) out.push_back(static_cast<unsigned char>(v >> (8 * b)));
}

// The index as a skippable frame: magic, size, Index message, trailer.
std::vector<unsigned char> IndexFrame(std::uint64_t header_length,
                                      const std::vector<FrameSummary>& frames) {
  capnp::MallocMessageBuilder message;
  FillIndex(message.initRoot<schema::Index>(), header_length, frames);
  const kj::Array<capnp::word> words = capnp::messageToFlatArray(message);
  const kj::ArrayPtr<const kj::byte> bytes = words.asBytes();
  RAYCELL_CHECK_LT(bytes.size() + kTraceTrailerBytes, std::size_t{0xFFFFFFFF});
  Hash64 hash;
  hash.AddBytes(bytes.begin(), bytes.size());
  std::vector<unsigned char> out;
  PutU32(out, kTraceIndexMagic);
  PutU32(out, static_cast<std::uint32_t>(bytes.size() + kTraceTrailerBytes));
  out.insert(out.end(), bytes.begin(), bytes.end());
  PutU64(out, hash.Finish());
  PutU64(out, bytes.size());
  out.insert(out.end(), kTraceIndexTag, kTraceIndexTag + 8);
  return out;
}

std::size_t MessageWordsHint(std::size_t payload_bytes) { return payload_bytes / 8 + 256; }

}  // namespace

// ---- TraceWriter -------------------------------------------------------------------------

struct TraceWriter::Impl {
  std::string path;
  TraceHeader header;
  TraceWriterOptions options;
  FileOut file;
  ZstdSink sink;
  std::uint64_t header_length = 0;
  std::vector<FrameSummary> frames;
  bool in_frame = false;
  bool finished = false;
  FrameAccumulator frame{0, false};
  std::uint64_t frame_offset = 0;
  RayBatch pending;

  Impl(const std::string& p, const TraceHeader& h, const TraceWriterOptions& o)
      : path(p),
        header(h),
        options(o),
        file(p + ".tmp"),
        sink(file, h.settings.zstd_level),
        pending(h.settings.store_t) {}

  void WriteRecord(capnp::MallocMessageBuilder& message) {
    RAYCELL_CHECK_LE(capnp::computeSerializedSizeInWords(message) * 8, kTraceMaxMessageBytes);
    capnp::writeMessage(sink, message);
  }

  void WriteHeader() {
    capnp::MallocMessageBuilder message;
    FillHeader(message.initRoot<schema::Record>().initHeader(), header);
    WriteRecord(message);
    sink.EndFrame();
    header_length = file.bytes();
  }

  void FlushPending() {
    if (pending.empty()) return;
    const BatchColumns columns(pending);
    const std::size_t t_bytes = header.settings.store_t ? 8 * pending.visit_count() : 0;
    capnp::MallocMessageBuilder message(MessageWordsHint(columns.bytes() + t_bytes));
    FillBatch(message.initRoot<schema::Record>().initBatch(), pending, columns,
              frame.Summary().frame, header.settings.store_t);
    WriteRecord(message);
    pending.set_first_id(pending.first_id() + pending.size());
    pending.Clear();
  }

  bool PendingFull() const {
    return pending.size() >= options.max_batch_rays ||
           pending.visit_count() >= options.max_batch_visits;
  }

  void CheckRay(const RayView& r) const {
    if (!r.is_primary()) RAYCELL_CHECK_LT(r.parent, r.id);
    if (header.settings.store_t) RAYCELL_CHECK(r.t_enter != nullptr);
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      RAYCELL_CHECK_LT(r.cells[v], header.cell_count());
    }
  }

  void AddRay(const RayView& r) {
    CheckRay(r);
    frame.AddRay(r);
    pending.BeginRay(r.kind, r.parent, r.spawn, r.pixel_x, r.pixel_y);
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      const Visit visit = r.visit(v);
      pending.AddVisit(visit.cell, visit.samples, visit.t_enter, visit.t_exit);
    }
    if (PendingFull()) FlushPending();
  }
};

TraceWriter::TraceWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TraceWriter::TraceWriter(TraceWriter&&) noexcept = default;
TraceWriter& TraceWriter::operator=(TraceWriter&&) noexcept = default;
TraceWriter::~TraceWriter() = default;

TraceWriter TraceWriter::Create(const std::string& path, const TraceHeader& header,
                                const TraceWriterOptions& options) {
  const int level = static_cast<int>(header.settings.zstd_level);
  if (level < 1 || level > kTraceMaxZstdLevel) {
    throw InputError(path + ": zstd level " + std::to_string(level) + " is not in 1.." +
                     std::to_string(kTraceMaxZstdLevel));
  }
  RAYCELL_CHECK(options.max_batch_rays > 0 && options.max_batch_visits > 0);
  RAYCELL_CHECK_EQ(header.footprints.size(), std::size_t{header.cell_count()});
  auto impl = std::make_unique<Impl>(path, header, options);
  impl->WriteHeader();
  return TraceWriter(std::move(impl));
}

TraceWriter TraceWriter::Create(const std::string& path, const TraceHeader& header,
                                int zstd_level) {
  TraceHeader h = header;
  h.settings.zstd_level = static_cast<std::uint32_t>(zstd_level < 0 ? 0 : zstd_level);
  return Create(path, h, TraceWriterOptions{});
}

void TraceWriter::BeginFrame(std::int32_t frame) {
  Impl& w = *impl_;
  RAYCELL_CHECK(!w.in_frame && !w.finished);
  w.in_frame = true;
  w.frame = FrameAccumulator(frame, w.header.settings.store_t);
  w.frame_offset = w.file.bytes();
  w.pending.Clear();
  w.pending.set_first_id(0);
}

void TraceWriter::Append(const RayBatch& rays) {
  Impl& w = *impl_;
  RAYCELL_CHECK(w.in_frame);
  RAYCELL_CHECK_EQ(rays.first_id(), w.frame.rays());
  for (std::size_t i = 0; i < rays.size(); ++i) w.AddRay(rays.ray(i));
}

FrameSummary TraceWriter::EndFrame() {
  Impl& w = *impl_;
  RAYCELL_CHECK(w.in_frame);
  w.FlushPending();
  FrameSummary summary = w.frame.Summary();
  capnp::MallocMessageBuilder message;
  FillFrameEnd(message.initRoot<schema::Record>().initFrameEnd(), summary);
  w.WriteRecord(message);
  w.sink.EndFrame();
  summary.offset = w.frame_offset;
  summary.length = w.file.bytes() - w.frame_offset;
  w.frames.push_back(summary);
  w.in_frame = false;
  return summary;
}

void TraceWriter::Finish() {
  Impl& w = *impl_;
  RAYCELL_CHECK(!w.in_frame && !w.finished);
  const std::vector<unsigned char> index = IndexFrame(w.header_length, w.frames);
  w.file.Write(index.data(), index.size());
  w.file.SyncAndClose();
  const std::string tmp = w.path + ".tmp";
  if (std::rename(tmp.c_str(), w.path.c_str()) != 0) {
    throw InputError(w.path + ": cannot rename " + tmp + " to it: " + ErrnoText());
  }
  w.finished = true;
}

const std::string& TraceWriter::path() const { return impl_->path; }
std::size_t TraceWriter::frames_written() const { return impl_->frames.size(); }

}  // namespace raycell
