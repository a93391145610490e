#include "traces/trace_writer.h"

#include <capnp/message.h>
#include <capnp/serialize.h>
#include <fcntl.h>
#include <kj/io.h>
#include <unistd.h>
#define ZSTD_STATIC_LINKING_ONLY  // ZSTD_getCParams
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "base/check.h"
#include "base/file.h"
#include "base/hash.h"
#include "traces/columns.h"
#include "traces/path_coder.h"
#include "traces/sample_coder.h"
#include "traces/trace.capnp.h"

namespace raycell {

namespace {

// ---- Output file and zstd stream ---------------------------------------------------------

std::string ErrnoText() { return std::strerror(errno); }

// An owned file descriptor for writing `path`, with full writes and a byte count. The file
// gets its name only at Publish(): it is opened unnamed (O_TMPFILE) and linked to `path`
// then, so a process killed before leaves nothing and one killed after leaves `path` with at
// least what was written before Publish() (the complete header). Where O_TMPFILE is not
// supported it is written as `path.new.PID` and renamed by Publish() (a kill before leaves
// that file behind).
class FileOut {
 public:
  explicit FileOut(std::string path) : path_(std::move(path)) {
    const auto slash = path_.rfind('/');
    const std::string dir = slash == std::string::npos ? "." : path_.substr(0, slash + 1);
    fd_ = ::open(dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0644);
    if (fd_ < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
      staging_ = path_ + ".new." + std::to_string(::getpid());
      fd_ = ::open(staging_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    }
    if (fd_ < 0) throw InputError(path_ + ": cannot open for writing: " + ErrnoText());
  }
  FileOut(const FileOut&) = delete;
  FileOut& operator=(const FileOut&) = delete;
  ~FileOut() {
    if (fd_ >= 0) ::close(fd_);
    if (!published_ && !staging_.empty()) ::unlink(staging_.c_str());
  }

  // Gives the file its name `path`, replacing what was there.
  void Publish() {
    if (!staging_.empty()) {
      if (std::rename(staging_.c_str(), path_.c_str()) != 0) {
        throw InputError(path_ + ": cannot create: " + ErrnoText());
      }
      published_ = true;
      return;
    }
    if (Link() == 0) return;
    if (errno == EEXIST) {
      ::unlink(path_.c_str());
      if (Link() == 0) return;
    }
    throw InputError(path_ + ": cannot create: " + ErrnoText());
  }
  void Write(const void* data, std::size_t size) {
    const auto* p = static_cast<const char*>(data);
    while (size > 0) {
      const ssize_t n = ::write(fd_, p, size);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw InputError(path_ + ": write failed: " + ErrnoText());
      if (hashing_) hash_.Add(p, static_cast<std::size_t>(n));
      p += n;
      size -= static_cast<std::size_t>(n);
      bytes_ += static_cast<std::uint64_t>(n);
    }
  }
  // Hashes what is written from now until TakeHash (a frame's stored bytes).
  void StartHash() {
    hash_ = StreamHash64();
    hashing_ = true;
  }
  std::uint64_t TakeHash() {
    hashing_ = false;
    return hash_.Finish();
  }
  void SyncAndClose() {
    if (::fsync(fd_) != 0) throw InputError(path_ + ": fsync failed: " + ErrnoText());
    const int fd = std::exchange(fd_, -1);
    if (::close(fd) != 0) throw InputError(path_ + ": close failed: " + ErrnoText());
  }
  std::uint64_t bytes() const { return bytes_; }
  const std::string& path() const { return path_; }

 private:
  // Links the unnamed file to `path`: through /proc, else by descriptor. 0 on success (and
  // published_ set); otherwise -1 with errno set.
  int Link() {
    char proc[64];
    std::snprintf(proc, sizeof proc, "/proc/self/fd/%d", fd_);
    int r = ::linkat(AT_FDCWD, proc, AT_FDCWD, path_.c_str(), AT_SYMLINK_FOLLOW);
    if (r != 0 && errno == ENOENT) r = ::linkat(fd_, "", AT_FDCWD, path_.c_str(), AT_EMPTY_PATH);
    if (r == 0) published_ = true;
    return r;
  }

  std::string path_;
  std::string staging_;  // the fallback's named temporary, when O_TMPFILE is unsupported
  int fd_ = -1;
  bool published_ = false;
  std::uint64_t bytes_ = 0;
  StreamHash64 hash_;
  bool hashing_ = false;
};

// Compresses what Cap'n Proto writes into zstd frames of `out`, one frame per EndFrame().
// Long-distance matching finds the repeats between the columns of consecutive batches; the
// window stays the level's own (LDM alone would raise it to 128 MiB).
class ZstdSink : public kj::OutputStream {
 public:
  ZstdSink(FileOut& out, int level) : out_(out), buffer_(ZSTD_CStreamOutSize()) {
    cctx_ = ZSTD_createCCtx();
    RAYCELL_CHECK(cctx_ != nullptr);
    const unsigned window_log = ZSTD_getCParams(level, ZSTD_CONTENTSIZE_UNKNOWN, 0).windowLog;
    RAYCELL_CHECK_LE(window_log, static_cast<unsigned>(kTraceMaxWindowLog));
    ZSTD_CCtx_setParameter(cctx_, ZSTD_c_compressionLevel, level);
    ZSTD_CCtx_setParameter(cctx_, ZSTD_c_checksumFlag, 1);
    ZSTD_CCtx_setParameter(cctx_, ZSTD_c_enableLongDistanceMatching, 1);
    ZSTD_CCtx_setParameter(cctx_, ZSTD_c_windowLog, static_cast<int>(window_log));
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

// Heads run-length coded: one byte per run of equal heads, and the run's length - 1.
class HeadRunBuilder {
 public:
  void Add(std::uint8_t head) {
    if (!heads_.empty() && heads_.back() == head) {
      ++run_;
      return;
    }
    Flush();
    heads_.push_back(head);
    run_ = 1;
  }
  void Finish() { Flush(); }
  void Fill(schema::Batch::Builder out) const {
    auto heads = out.initHeads(static_cast<unsigned>(heads_.size()));
    for (unsigned i = 0; i < heads_.size(); ++i) heads.set(i, heads_[i]);
    runs_.Fill(out.initHeadRuns());
  }
  std::size_t bytes() const { return heads_.size() + runs_.bytes(); }
  double EntropyBits() const { return raycell::EntropyBits(heads_) + runs_.EntropyBits(); }

 private:
  void Flush() {
    if (run_ > 0) runs_.Add(run_ - 1);
    run_ = 0;
  }

  std::vector<std::uint8_t> heads_;
  ColumnBuilder runs_;
  std::uint64_t run_ = 0;
};

bool SameCells(const RayView& a, const RayView& b) {
  return a.visit_count == b.visit_count && std::equal(a.cells, a.cells + a.visit_count, b.cells);
}

// The columns of one Batch message, encoded ray by ray as trace.capnp's "Column encoding"
// describes (format version 5) with the reference rule `rule` (Batch.referenceRule). Every
// prediction looks only at earlier rays of the same batch.
struct BatchColumns {
  HeadRunBuilder heads;
  ColumnBuilder parents, spawns, pixels, primary_paths, secondary_paths;
  ZeroRunColumnBuilder primary_samples, secondary_samples, shadow_samples;
  SampleEncoder samples;                             // version 6 and 7: Batch.sampleCode
  std::optional<PathEncoder> path_code;              // version 8: Batch.pathCode
  std::unique_ptr<VisitTable> table;                 // version 7
  std::vector<VisitTable::Coordinates> coordinates;  // version 7: of the ray's cells
  static constexpr std::size_t kNone = ~std::size_t{0};
  CellGrid grid;
  unsigned rule;
  std::uint32_t version;             // 6 for a version 7 batch without the visit table
  bool uses_table;                   // Batch.visitTable
  bool code_paths;                   // version 8: new paths in path_code (else in the columns)
  std::size_t last_primary = kNone;  // index in the batch of the last primary ray
  // Sibling rule: index of the last group start by [kind][kind of its parent].
  std::size_t group_start[kRayKindCount][kRayKindCount];
  // By [kind][kind of its parent][ordinal]: the last ray of the batch with them whose parent
  // is in the batch.
  std::vector<std::size_t> corresponding[kRayKindCount][kRayKindCount];
  std::vector<std::uint32_t> ordinals;  // per ray of the batch
  RayId last_non_shadow = kNoParent;    // id of the last ray whose kind is not shadow
  std::uint32_t last_first_cell = 0;    // first cell of the last ray with a visit

  // `visit_table` (version 7): the samples predicted from the visit table too (Batch.visitTable);
  // else a version 7 batch's samples are coded as version 6's. `paths_from` (version 8): the
  // columns of the same rule, whose path code (it does not depend on the visit table) is taken
  // instead of coding the paths again.
  BatchColumns(const RayBatch& b, const CellGrid& g, unsigned reference_rule,
               std::uint32_t format_version, bool visit_table = true,
               const BatchColumns* paths_from = nullptr)
      : samples(format_version >= 7 && visit_table ? SampleContext::kCount7
                                                   : SampleContext::kCount),
        grid(g),
        rule(reference_rule),
        version(format_version >= 7 && !visit_table ? 6 : format_version),
        uses_table(format_version >= 7 && visit_table),
        code_paths(format_version >= 8 && paths_from == nullptr) {
    if (uses_table) table = std::make_unique<VisitTable>();
    if (code_paths) path_code.emplace(g);
    for (auto& starts : group_start) std::fill(std::begin(starts), std::end(starts), kNone);
    ordinals.reserve(b.size());
    for (std::size_t i = 0; i < b.size(); ++i) AddRay(b, i);
    heads.Finish();
    primary_samples.Finish();
    secondary_samples.Finish();
    shadow_samples.Finish();
    if (version >= 6) samples.Finish();
    if (code_paths) {
      // Version 8: the path code where it is smaller than zstd's code of the path columns
      // alone (in the frame's stream, mixed with the other columns, zstd does about as well).
      path_code->Finish();
      std::string columns;
      primary_paths.AppendTo(columns);
      secondary_paths.AppendTo(columns);
      std::string packed(ZSTD_compressBound(columns.size()), '\0');
      const std::size_t n =
          ZSTD_compress(packed.data(), packed.size(), columns.data(), columns.size(), 3);
      RAYCELL_CHECK(!ZSTD_isError(n));
      code_paths = path_code->bytes() < n;
    }
    if (paths_from != nullptr) {
      RAYCELL_CHECK_EQ(paths_from->rule, rule);
      code_paths = paths_from->code_paths;
      if (code_paths) path_code = paths_from->path_code;
    }
    if (code_paths) primary_paths = secondary_paths = ColumnBuilder();
  }

  void AddRay(const RayBatch& b, std::size_t i) {
    const RayView r = b.ray(i);
    const bool has_prev = i > 0;
    const RayView prev = has_prev ? b.ray(i - 1) : RayView{};
    const bool sibling = has_prev && prev.parent == r.parent;
    unsigned head = static_cast<unsigned>(r.kind);
    head |= ParentCode(r, has_prev, prev) << kHeadParentShift;
    head |= SpawnCode(r, sibling ? prev.spawn : 0) << kHeadSpawnShift;
    const std::uint32_t px = has_prev ? prev.pixel_x : 0, py = has_prev ? prev.pixel_y : 0;
    if (r.pixel_x != px || r.pixel_y != py) {
      head |= kHeadNewPixel;
      pixels.Add(ZigZag(Delta(r.pixel_x, px)));
      pixels.Add(ZigZag(Delta(r.pixel_y, py)));
    }
    ordinals.push_back(sibling && prev.kind == r.kind ? ordinals.back() + 1 : 0);
    const std::size_t ref = ReferenceRay(b, r, i, sibling);
    const RayView reference = ref != kNone ? b.ray(ref) : RayView{};
    const bool new_path = ref == kNone || !SameCells(r, reference);
    if (new_path) {
      head |= kHeadNewPath;
      const std::uint32_t first = PredictedFirstCell(b, r, ref, reference);
      if (code_paths) {  // both ways in version 8; the constructor keeps the smaller
        path_code->Add(SampleGroup(static_cast<unsigned>(r.kind)), first, r.cells, r.visit_count,
                       ParentHint(b, r.parent, r.spawn, grid), reference.cells,
                       reference.visit_count);
      }
      ColumnBuilder& paths = r.is_primary() ? primary_paths : secondary_paths;
      paths.Add(r.visit_count);
      AddSteps(r, first, paths);
    }
    ZeroRunColumnBuilder& v5_samples = r.is_primary()               ? primary_samples
                                       : r.kind == RayKind::kShadow ? shadow_samples
                                                                    : secondary_samples;
    // Each visit against the reference's visit of the same cell, searched from the one after
    // the last matched, at most kSampleMatchWindow visits on.
    std::size_t next = 0;
    SampleContext context(static_cast<unsigned>(r.kind), new_path);
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      const std::size_t end = std::min(reference.visit_count, next + kSampleMatchWindow);
      std::size_t k = next;
      while (k < end && reference.cells[k] != r.cells[v]) ++k;
      const bool matched = ref != kNone && k < end;
      const std::uint64_t value =
          matched ? ZigZag(Delta(r.samples[v], reference.samples[k])) : r.samples[v];
      if (matched) next = k + 1;
      if (version >= 7) {
        AddSamplesV7(r, v, matched, matched ? reference.samples[k] : 0, new_path, context);
      } else if (version == 6) {
        const unsigned c =
            context.Of(matched, matched ? reference.samples[k] : 0, v + 1 == r.visit_count);
        samples.Add(c, value);
        context.Next(matched, value, r.samples[v]);
      } else {
        v5_samples.Add(value);
      }
    }
    heads.Add(static_cast<std::uint8_t>(head));
    if (r.is_primary()) last_primary = i;
    if (r.kind != RayKind::kShadow) last_non_shadow = r.id;
    if (r.visit_count > 0) last_first_cell = r.cells[0].value();
  }

  // Version 7: codes visit v of ray r against its prediction (PredictSamples) and enters it in
  // the visit table.
  void AddSamplesV7(const RayView& r, std::size_t v, bool matched, std::uint64_t reference,
                    bool new_path, SampleContext& context) {
    const bool last = v + 1 == r.visit_count;
    const std::uint32_t cell = r.cells[v].value();
    if (v == 0) {
      coordinates.resize(r.visit_count);
      for (std::size_t u = 0; u < r.visit_count; ++u) {
        coordinates[u] = VisitTable::CoordinatesOf(r.cells[u].value(), grid);
      }
    }
    const std::uint64_t key = VisitTable::KeyOfVisit(SampleGroup(static_cast<unsigned>(r.kind)),
                                                     cell, coordinates.data(), v, r.visit_count);
    const std::size_t slot = table->SlotOf(key);
    std::uint64_t known = 0;
    const bool hit = table->Find(slot, key, known);
    const SamplePrediction p = PredictSamples(matched, reference, new_path, hit, known);
    const std::uint64_t n = r.samples[v];
    const std::uint64_t value = p.residual ? ZigZag(Delta(n, p.predicted)) : n;
    samples.Add(context.Of(p.residual, p.predicted, last, p.predictor), value);
    context.Next(p.residual, value, n);
    table->Set(slot, key, r.samples[v]);
  }

  // Index of the reference ray of ray i (see "Column encoding" in trace.capnp), or kNone.
  // Also records ray i as a group start (sibling rule) or as the corresponding ray of its
  // kind, parent kind and ordinal (corresponding rule).
  std::size_t ReferenceRay(const RayBatch& b, const RayView& r, std::size_t i, bool sibling) {
    if (r.is_primary()) return last_primary;
    if (rule == kReferenceSibling) {
      if (sibling) return i - 1;
      if (r.parent < b.first_id()) return kNone;
      const auto parent_kind = static_cast<int>(b.kinds()[r.parent - b.first_id()]);
      return std::exchange(group_start[static_cast<int>(r.kind)][parent_kind], i);
    }
    if (r.parent >= b.first_id()) {
      const auto parent_kind = static_cast<int>(b.kinds()[r.parent - b.first_id()]);
      std::vector<std::size_t>& slots = corresponding[static_cast<int>(r.kind)][parent_kind];
      if (slots.size() <= ordinals[i]) slots.resize(ordinals[i] + 1, kNone);
      const std::size_t found = std::exchange(slots[ordinals[i]], i);
      if (found != kNone) return found;
    }
    return sibling ? i - 1 : kNone;
  }

  // The cell a new path's first step starts from (see "Paths" in trace.capnp).
  std::uint32_t PredictedFirstCell(const RayBatch& b, const RayView& r, std::size_t ref,
                                   const RayView& reference) const {
    if (!r.is_primary() && r.parent >= b.first_id()) {
      const std::size_t p = r.parent - b.first_id();
      if (r.spawn < b.visit_end(p) - b.visit_begin(p)) {
        return b.cells()[b.visit_begin(p) + r.spawn].value();
      }
    }
    if (ref != kNone && reference.visit_count > 0) return reference.cells[0].value();
    return last_first_cell;
  }

  unsigned ParentCode(const RayView& r, bool has_prev, const RayView& prev) {
    if (r.is_primary()) return kParentIsLastNonShadow;
    if (r.parent == last_non_shadow) return kParentIsLastNonShadow;
    if (has_prev && !prev.is_primary() && prev.parent == r.parent) return kParentOfPreviousRay;
    parents.Add(r.id - r.parent);
    return kParentExplicit;
  }

  unsigned SpawnCode(const RayView& r, std::uint32_t predicted) {
    if (r.spawn >= predicted && r.spawn - predicted < kSpawnExplicit) return r.spawn - predicted;
    spawns.Add(r.spawn);
    return kSpawnExplicit;
  }

  void AddSteps(const RayView& r, std::uint32_t first, ColumnBuilder& paths) const {
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      AddStep(paths, v == 0 ? first : r.cells[v - 1].value(), r.cells[v].value(), grid);
    }
  }

  std::size_t bytes() const {
    std::size_t n = heads.bytes() + primary_samples.bytes() + secondary_samples.bytes() +
                    shadow_samples.bytes();
    for (const ColumnBuilder* c : {&parents, &spawns, &pixels, &primary_paths, &secondary_paths}) {
      n += c->bytes();
    }
    n += samples.bytes();
    if (code_paths) n += path_code->bytes();
    return n;
  }

  // The columns' order-0 entropy (ColumnBuilder::EntropyBits), summed.
  double EntropyBits() const {
    double n = heads.EntropyBits() + primary_samples.EntropyBits() +
               secondary_samples.EntropyBits() + shadow_samples.EntropyBits();
    for (const ColumnBuilder* c : {&parents, &spawns, &pixels, &primary_paths, &secondary_paths}) {
      n += c->EntropyBits();
    }
    n += 8.0 * static_cast<double>(samples.bytes());
    if (code_paths) n += 8.0 * static_cast<double>(path_code->bytes());
    return n;
  }
};

void FillFloats(capnp::List<float>::Builder list, const std::vector<float>& values) {
  for (unsigned i = 0; i < values.size(); ++i) list.set(i, values[i]);
}

void FillBatch(schema::Batch::Builder out, const RayBatch& b, const BatchColumns& c,
               std::int32_t frame, bool store_t) {
  out.setFrame(frame);
  out.setReferenceRule(static_cast<std::uint8_t>(c.rule));
  out.setFirstId(b.first_id());
  out.setVisitTable(c.uses_table);
  c.heads.Fill(out);
  c.parents.Fill(out.initParents());
  c.spawns.Fill(out.initSpawns());
  c.pixels.Fill(out.initPixels());
  c.primary_paths.Fill(out.initPrimaryPaths());
  c.secondary_paths.Fill(out.initSecondaryPaths());
  c.primary_samples.Fill(out.initPrimarySamples());
  c.secondary_samples.Fill(out.initSecondarySamples());
  c.shadow_samples.Fill(out.initShadowSamples());
  if (c.version >= 6) {
    const std::vector<std::uint8_t>& code = c.samples.code();
    out.setSampleCode(capnp::Data::Reader(code.data(), code.size()));
  }
  if (c.code_paths) {
    const std::vector<std::uint8_t>& code = c.path_code->code();
    out.setPathCode(capnp::Data::Reader(code.data(), code.size()));
  }
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
  out.setSinglePrecision(s.single_precision);
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

void FillPath(schema::CameraPath::Builder out, const CameraPathInfo& p) {
  out.setKind(p.kind);
  out.setFirstFrame(p.first_frame);
  out.setFrameCount(p.frame_count);
  FillVec3(out.initEye(), p.eye);
  FillVec3(out.initTarget(), p.target);
  FillVec3(out.initUp(), p.up);
  out.setFovDeg(p.fov_deg);
  out.setOrbitDegrees(p.orbit_degrees);
  FillCameras(out.initKeys(static_cast<unsigned>(p.keys.size())), p.keys);
}

// The header message; the footprints follow in footprints records.
void FillHeader(schema::Header::Builder out, const TraceHeader& h, std::uint32_t version) {
  out.setFormatVersion(version);
  out.setProducer(h.producer);
  out.setScene(h.scene);
  FillGrids(out.initGrids(static_cast<unsigned>(h.grids.size())), h.grids);
  FillVec3(out.initBoxMin(), h.box_min);
  FillVec3(out.initBoxMax(), h.box_max);
  out.setCellsX(h.cells[0]);
  out.setCellsY(h.cells[1]);
  out.setCellsZ(h.cells[2]);
  out.setFootprintMode(h.footprint_mode);
  FillCameras(out.initCameras(static_cast<unsigned>(h.cameras.size())), h.cameras);
  FillSettings(out.initSettings(), h.settings);
  FillPath(out.initPath(), h.path);
  out.setRegroupable(h.regroupable);
  out.setLeafCount(h.leaves.bytes.size());
  if (!h.subdivision.empty()) {
    auto sub = out.initSubdivision();
    sub.setSpec(h.subdivision.spec);
    sub.setFineX(h.subdivision.fine[0]);
    sub.setFineY(h.subdivision.fine[1]);
    sub.setFineZ(h.subdivision.fine[2]);
    auto boxes = sub.initBoxes(static_cast<unsigned>(h.subdivision.boxes.size()));
    for (unsigned i = 0; i < boxes.size(); ++i) {
      const FineBox& b = h.subdivision.boxes[i];
      auto o = boxes[i];
      o.setLoX(b.lo[0]), o.setLoY(b.lo[1]), o.setLoZ(b.lo[2]);
      o.setHiX(b.hi[0]), o.setHiY(b.hi[1]), o.setHiZ(b.hi[2]);
    }
    const auto& ff = h.subdivision.frame_footprints;
    auto out_ff = sub.initFrameFootprints(static_cast<unsigned>(ff.size()));
    for (unsigned i = 0; i < ff.size(); ++i) out_ff.set(i, ff[i]);
  }
}

// Footprints of cells [first, end) as runs of equal values, into a footprints record.
class FootprintRecord {
 public:
  explicit FootprintRecord(std::uint64_t first) : first_(first) {}
  void Add(std::uint64_t value, std::uint64_t run) {
    values_.Add(value);
    runs_.Add(run - 1);
    ++count_;
  }
  std::size_t runs() const { return count_; }
  void Fill(schema::Footprints::Builder out) const {
    out.setFirstCell(first_);
    values_.Fill(out.initValues());
    runs_.Fill(out.initRuns());
  }

 private:
  std::uint64_t first_;
  ColumnBuilder values_, runs_;
  std::size_t count_ = 0;
};

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

void FillIndex(schema::Index::Builder out, std::uint32_t version, std::uint64_t header_length,
               const std::vector<FrameSummary>& frames) {
  out.setFormatVersion(version);
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
    entries[i].setStoredHash(s.stored_hash);
  }
}

void PutU32(std::vector<unsigned char>& out, std::uint32_t v) {
  for (int b = 0; b < 4; ++b) out.push_back(static_cast<unsigned char>(v >> (8 * b)));
}

void PutU64(std::vector<unsigned char>& out, std::uint64_t v) {
  for (int b = 0; b < 8; ++b) out.push_back(static_cast<unsigned char>(v >> (8 * b)));
}

// The index as a skippable frame: magic, size, Index message, trailer.
std::vector<unsigned char> IndexFrame(std::uint32_t version, std::uint64_t header_length,
                                      const std::vector<FrameSummary>& frames) {
  capnp::MallocMessageBuilder message;
  FillIndex(message.initRoot<schema::Index>(), version, header_length, frames);
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
  std::size_t batch_rays;  // options.max_batch_rays, or the format's default
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
        batch_rays(o.max_batch_rays != 0   ? o.max_batch_rays
                   : o.format_version >= 6 ? kTraceCodedBatchRays
                                           : kTraceBatchRays),
        file(p + ".tmp"),
        sink(file, h.settings.zstd_level),
        pending(h.settings.store_t) {}

  void WriteRecord(capnp::MallocMessageBuilder& message) {
    RAYCELL_CHECK_LE(capnp::computeSerializedSizeInWords(message) * 8, kTraceMaxMessageBytes);
    capnp::writeMessage(sink, message);
  }

  void WriteHeader() {
    capnp::MallocMessageBuilder message;
    FillHeader(message.initRoot<schema::Record>().initHeader(), header, options.format_version);
    WriteRecord(message);
    WriteRuns(header.footprints, /*leaves=*/false);
    if (header.regroupable) {
      WriteRuns(header.leaves.bytes, /*leaves=*/true);
      WriteCellLeaves();
    }
    sink.EndFrame();
    header_length = file.bytes();
    if (!options.name_at_finish) file.Publish();  // the .tmp appears now, with the header
  }

  // The footprints (or a regroupable capture's leaf bytes) as records of at most
  // options.footprint_runs_per_record runs.
  void WriteRuns(const std::vector<std::uint64_t>& f, bool leaves) {
    FootprintRecord record(0);
    for (std::size_t begin = 0, end; begin < f.size(); begin = end) {
      for (end = begin + 1; end < f.size() && f[end] == f[begin];) ++end;
      record.Add(f[begin], end - begin);
      if (record.runs() == options.footprint_runs_per_record || end == f.size()) {
        capnp::MallocMessageBuilder message;
        auto root = message.initRoot<schema::Record>();
        record.Fill(leaves ? root.initLeafBytes() : root.initFootprints());
        WriteRecord(message);
        record = FootprintRecord(end);
      }
    }
  }

  // A regroupable capture's leaves per cell, in records of at most kTraceLeafCellsPerRecord
  // cells and kTraceLeafRefsPerRecord leaves.
  void WriteCellLeaves() {
    const CellLeaves& l = header.leaves;
    const std::size_t cells = l.begin.size() - 1;
    for (std::size_t first = 0; first < cells;) {
      std::size_t end = first;
      while (end < cells && end - first < kTraceLeafCellsPerRecord &&
             (end == first || l.begin[end + 1] - l.begin[first] <= kTraceLeafRefsPerRecord)) {
        ++end;
      }
      ColumnBuilder counts, leaves;
      for (std::size_t c = first; c < end; ++c) {
        counts.Add(l.begin[c + 1] - l.begin[c]);
        for (std::uint64_t i = l.begin[c]; i < l.begin[c + 1]; ++i) {
          leaves.Add(i == l.begin[c] ? l.leaves[i] : l.leaves[i] - l.leaves[i - 1] - 1);
        }
      }
      capnp::MallocMessageBuilder message;
      auto out = message.initRoot<schema::Record>().initCellLeaves();
      out.setFirstCell(first);
      counts.Fill(out.initCounts());
      leaves.Fill(out.initLeaves());
      WriteRecord(message);
      first = end;
    }
  }

  void FlushPending() {
    if (pending.empty()) return;
    // Each reference rule's columns; the batch keeps the one whose columns have the lower
    // order-0 entropy (which zstd's output follows; format 6: plus the sample code's bits),
    // the sibling rule on a tie.
    const std::uint32_t version = options.format_version;
    const BatchColumns sibling(pending, header.cells, kReferenceSibling, version);
    const BatchColumns corresponding(pending, header.cells, kReferenceCorresponding, version);
    const BatchColumns& chosen =
        corresponding.EntropyBits() < sibling.EntropyBits() ? corresponding : sibling;
    // Format 7: the chosen rule's samples also coded without the visit table; the batch keeps
    // the smaller sample code (the table on a tie).
    std::optional<BatchColumns> without_table;
    if (version >= 7) {
      without_table.emplace(pending, header.cells, chosen.rule, version, false, &chosen);
      if (without_table->samples.bytes() >= chosen.samples.bytes()) without_table.reset();
    }
    const BatchColumns& columns = without_table ? *without_table : chosen;
    const std::size_t t_bytes = header.settings.store_t ? 8 * pending.visit_count() : 0;
    capnp::MallocMessageBuilder message(MessageWordsHint(columns.bytes() + t_bytes));
    FillBatch(message.initRoot<schema::Record>().initBatch(), pending, columns,
              frame.Summary().frame, header.settings.store_t);
    WriteRecord(message);
    pending.set_first_id(pending.first_id() + pending.size());
    pending.Clear();
  }

  bool PendingFull() const {
    return pending.size() >= batch_rays || pending.visit_count() >= options.max_batch_visits;
  }

  void CheckRay(const RayView& r) const {
    if (!r.is_primary()) RAYCELL_CHECK_LT(r.parent, r.id);
    if (r.is_primary()) RAYCELL_CHECK_EQ(r.spawn, 0u);
    RAYCELL_CHECK_LE(r.visit_count, kTraceMaxRayVisits);
    if (header.settings.store_t) RAYCELL_CHECK(r.t_enter != nullptr);
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      RAYCELL_CHECK_LT(r.cells[v].value(), header.cell_count());
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
  const std::string problem = TraceHeaderProblem(header);
  if (!problem.empty()) throw InputError(path + ": " + problem);
  RAYCELL_CHECK(options.max_batch_visits > 0);
  RAYCELL_CHECK(options.footprint_runs_per_record > 0 &&
                options.footprint_runs_per_record <= kTraceFootprintRunsPerRecord);
  RAYCELL_CHECK_LE(options.max_frames, kTraceMaxFrames);
  RAYCELL_CHECK(options.format_version >= 3 && options.format_version <= kTraceFormatVersion);
  RAYCELL_CHECK_LE(options.max_batch_rays, kTraceMaxBatchRays);
  RAYCELL_CHECK_LE(options.max_batch_visits, kTraceMaxBatchVisits - kTraceMaxRayVisits);
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

namespace {

void CheckFrameLimit(const std::string& path, std::size_t frames, std::size_t max_frames) {
  if (frames >= max_frames) {
    throw InputError(path + ": more than " + std::to_string(max_frames) +
                     " frames, the trace format's limit (kTraceMaxFrames)");
  }
}

}  // namespace

void TraceWriter::BeginFrame(std::int32_t frame) {
  Impl& w = *impl_;
  RAYCELL_CHECK(!w.in_frame && !w.finished);
  CheckFrameLimit(w.path, w.frames.size(), w.options.max_frames);
  w.in_frame = true;
  w.frame = FrameAccumulator(frame, w.header.settings.store_t);
  w.frame_offset = w.file.bytes();
  w.file.StartHash();
  w.pending.Clear();
  w.pending.set_first_id(0);
}

void TraceWriter::Append(const RayBatch& rays) {
  Impl& w = *impl_;
  RAYCELL_CHECK(w.in_frame);
  RAYCELL_CHECK_LE(5u, w.options.format_version);  // encodes only versions 5 and later
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
  summary.stored_hash = w.file.TakeHash();
  w.frames.push_back(summary);
  w.in_frame = false;
  return summary;
}

FrameSummary TraceWriter::AppendEncodedFrame(const FrameSummary& summary,
                                             const std::string& encoded) {
  Impl& w = *impl_;
  RAYCELL_CHECK(!w.in_frame && !w.finished);
  RAYCELL_CHECK(!encoded.empty());
  CheckFrameLimit(w.path, w.frames.size(), w.options.max_frames);
  FrameSummary s = summary;
  s.offset = w.file.bytes();
  s.length = encoded.size();
  if (s.stored_hash != 0) {  // the bytes' hash, which the caller checked them against
    w.file.Write(encoded.data(), encoded.size());
  } else {
    w.file.StartHash();
    w.file.Write(encoded.data(), encoded.size());
    s.stored_hash = w.file.TakeHash();
  }
  w.frames.push_back(s);
  return s;
}

void TraceWriter::Finish() {
  Impl& w = *impl_;
  RAYCELL_CHECK(!w.in_frame && !w.finished);
  const std::vector<unsigned char> index =
      IndexFrame(w.options.format_version, w.header_length, w.frames);
  w.file.Write(index.data(), index.size());
  if (w.options.name_at_finish) w.file.Publish();
  w.file.SyncAndClose();
  RenameFile(w.path + ".tmp", w.path);
  w.finished = true;
}

const std::string& TraceWriter::path() const { return impl_->path; }
std::size_t TraceWriter::frames_written() const { return impl_->frames.size(); }

}  // namespace raycell
