#include "traces/trace_reader.h"

#include <capnp/message.h>
#include <capnp/serialize.h>
#include <fcntl.h>
#include <kj/exception.h>
#include <sys/stat.h>
#include <unistd.h>
#define ZSTD_STATIC_LINKING_ONLY  // ZSTD_getFrameHeader
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <utility>

#include "base/check.h"
#include "base/format.h"
#include "base/hash.h"
#include "traces/columns.h"
#include "traces/format.h"
#include "traces/frame_checksum.h"
#include "traces/regroup.h"
#include "traces/subdivision.h"
#include "traces/trace.capnp.h"

namespace raycell {
namespace {

// Bad bytes found while decoding; turned into an InputError naming the file and the part
// of it (header, frame, index) by Guarded() below.
using BadData = BadTraceData;

std::string Str(std::uint64_t v) { return std::to_string(v); }

// Runs `body`, turning BadData and Cap'n Proto exceptions into an InputError that starts
// with "<path>: <where()>: ".
template <typename Where, typename Body>
auto Guarded(const std::string& path, Where&& where, Body&& body) {
  try {
    return body();
  } catch (const BadData& e) {
    throw InputError(path + ": " + where() + ": " + e.what());
  } catch (const kj::Exception& e) {
    throw InputError(path + ": " + where() + ": malformed message: " + e.getDescription().cStr());
  }
}

// ---- Input file --------------------------------------------------------------------------

// The file's bytes, read with pread from a file or copied from memory.
class FileIn {
 public:
  explicit FileIn(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw InputError(path + ": cannot open: " + std::strerror(errno));
    struct stat st;
    if (::fstat(fd_, &st) != 0) {
      const int error = errno;
      ::close(fd_);
      throw InputError(path + ": cannot stat: " + std::strerror(error));
    }
    size_ = static_cast<std::uint64_t>(st.st_size);
  }
  // Reads `bytes` instead of a file.
  explicit FileIn(std::string&& bytes) : memory_(std::move(bytes)), size_(memory_.size()) {}
  FileIn(const FileIn&) = delete;
  FileIn& operator=(const FileIn&) = delete;
  ~FileIn() {
    if (fd_ >= 0) ::close(fd_);
  }

  std::uint64_t size() const { return size_; }

  // Reads exactly `n` bytes at `offset`; BadData when the file is shorter.
  void ReadAt(std::uint64_t offset, void* dst, std::size_t n) const {
    if (offset > size_ || n > size_ - offset) {
      throw BadData("truncated: needs bytes " + Str(offset) + ".." + Str(offset + n) +
                    " but the file has " + Str(size_));
    }
    if (fd_ < 0) {
      if (n > 0) std::memcpy(dst, memory_.data() + offset, n);
      return;
    }
    auto* p = static_cast<char*>(dst);
    while (n > 0) {
      const ssize_t got = ::pread(fd_, p, n, static_cast<off_t>(offset));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) throw BadData(std::string("read failed: ") + std::strerror(errno));
      p += got;
      offset += static_cast<std::uint64_t>(got);
      n -= static_cast<std::size_t>(got);
    }
  }

  // The bytes held in memory, moved out (the object reads nothing after).
  std::string TakeMemory() { return std::move(memory_); }

  std::uint32_t U32At(std::uint64_t offset) const {
    unsigned char b[4];
    ReadAt(offset, b, 4);
    return std::uint32_t{b[0]} | std::uint32_t{b[1]} << 8 | std::uint32_t{b[2]} << 16 |
           std::uint32_t{b[3]} << 24;
  }

 private:
  int fd_ = -1;
  std::string memory_;
  std::uint64_t size_ = 0;
};

std::uint64_t LoadU64(const unsigned char* b) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = v << 8 | b[i];
  return v;
}

// ---- One zstd frame, decompressed on demand ----------------------------------------------

// Decompression contexts kept per thread for reuse: creating one per frame costs a
// 100 KB allocation and, for each new frame, its window buffer again. A reader takes one
// (Acquire) and gives it back (Release), so nested readings on a thread each have their own.
class DCtxPool {
 public:
  static ZSTD_DCtx* Acquire() {
    std::vector<ZSTD_DCtx*>& free = Free().contexts;
    ZSTD_DCtx* dctx = nullptr;
    if (free.empty()) {
      dctx = ZSTD_createDCtx();
      RAYCELL_CHECK(dctx != nullptr);
    } else {
      dctx = free.back();
      free.pop_back();
      ZSTD_DCtx_reset(dctx, ZSTD_reset_session_and_parameters);
    }
    ZSTD_DCtx_setParameter(dctx, ZSTD_d_windowLogMax, kTraceMaxWindowLog);
    return dctx;
  }
  static void Release(ZSTD_DCtx* dctx) {
    std::vector<ZSTD_DCtx*>& free = Free().contexts;
    if (free.size() < kKept) {
      free.push_back(dctx);
    } else {
      ZSTD_freeDCtx(dctx);
    }
  }

 private:
  static constexpr std::size_t kKept = 4;
  struct List {
    std::vector<ZSTD_DCtx*> contexts;
    ~List() {
      for (ZSTD_DCtx* d : contexts) ZSTD_freeDCtx(d);
    }
  };
  static List& Free() {
    thread_local List list;
    return list;
  }
};

class ZstdFrameReader {
 public:
  ZstdFrameReader(const FileIn& file, std::uint64_t offset, std::uint64_t end)
      : file_(file), start_(offset), next_(offset), end_(std::min(end, file.size())) {
    if (file.U32At(offset) != ZSTD_MAGICNUMBER) {
      throw BadData("no zstd frame starts at offset " + Str(offset));
    }
    // No larger than the bytes there are to read (small frames are common).
    buffer_.resize(
        static_cast<std::size_t>(std::min<std::uint64_t>(ZSTD_DStreamInSize(), end_ - offset)));
    dctx_ = DCtxPool::Acquire();
  }
  ZstdFrameReader(const ZstdFrameReader&) = delete;
  ZstdFrameReader& operator=(const ZstdFrameReader&) = delete;
  ~ZstdFrameReader() { DCtxPool::Release(dctx_); }

  // Reads up to `n` bytes; fewer only when the zstd frame ends (its checksum then verified).
  std::size_t Read(void* dst, std::size_t n) {
    ZSTD_outBuffer out{dst, n, 0};
    while (out.pos < out.size && !done_) Step(out);
    return out.pos;
  }
  bool done() const { return done_; }
  // Compressed bytes of the frame; valid once done().
  std::uint64_t consumed() const { return next_ - (in_.size - in_.pos) - start_; }

 private:
  void Step(ZSTD_outBuffer& out) {
    const std::size_t out_before = out.pos, in_before = in_.pos;
    const std::size_t r = ZSTD_decompressStream(dctx_, &out, &in_);
    if (ZSTD_isError(r)) throw BadData(std::string("zstd: ") + ZSTD_getErrorName(r));
    if (r == 0) {
      done_ = true;
    } else if (in_.pos == in_.size && out.pos == out_before) {
      Refill();
    } else if (in_.pos == in_before && out.pos == out_before) {
      throw BadData("zstd: no progress");
    }
  }

  void Refill() {
    const std::size_t n =
        static_cast<std::size_t>(std::min<std::uint64_t>(buffer_.size(), end_ - next_));
    if (n == 0 && end_ == file_.size()) {
      throw BadData("truncated: the file ends at byte " + Str(end_) + " inside the zstd frame");
    }
    if (n == 0) throw BadData("the zstd frame runs past its end at byte " + Str(end_));
    file_.ReadAt(next_, buffer_.data(), n);
    next_ += n;
    in_ = ZSTD_inBuffer{buffer_.data(), n, 0};
  }

  const FileIn& file_;
  std::uint64_t start_, next_, end_;
  ZSTD_DCtx* dctx_ = nullptr;
  std::vector<char> buffer_;
  ZSTD_inBuffer in_{nullptr, 0, 0};
  bool done_ = false;
};

// ---- Messages ----------------------------------------------------------------------------

constexpr std::size_t kMaxSegments = 512;

capnp::ReaderOptions MessageOptions() {
  capnp::ReaderOptions options;
  options.traversalLimitInWords = kTraceMaxMessageBytes / sizeof(capnp::word);
  options.nestingLimit = 16;
  return options;
}

void ReadExactly(ZstdFrameReader& in, void* dst, std::size_t n, const char* what) {
  if (in.Read(dst, n) != n) throw BadData(std::string("zstd frame ends inside ") + what);
}

// Reads one message in standard framing; returns false at the end of the zstd frame.
bool ReadMessage(ZstdFrameReader& in, kj::Array<capnp::word>& words) {
  std::uint32_t first[2];
  const std::size_t got = in.Read(first, 4);
  if (got == 0) return false;
  if (got != 4) throw BadData("zstd frame ends inside a message's segment table");
  const std::size_t segments = std::size_t{first[0]} + 1;
  if (segments > kMaxSegments) throw BadData("message has " + Str(segments) + " segments");
  const std::size_t table_words = segments / 2 + 1;
  std::vector<std::uint32_t> table(table_words * 2);
  table[0] = first[0];
  ReadExactly(in, table.data() + 1, table.size() * 4 - 4, "a segment table");
  std::uint64_t body_words = 0;
  for (std::size_t s = 0; s < segments; ++s) body_words += table[1 + s];
  if (body_words * 8 > kTraceMaxMessageBytes) {
    throw BadData("message of " + Str(body_words * 8) + " bytes exceeds the limit");
  }
  words = kj::heapArray<capnp::word>(table_words + body_words);
  kj::byte* bytes = words.asBytes().begin();
  std::memcpy(bytes, table.data(), table_words * 8);
  ReadExactly(in, bytes + table_words * 8, body_words * 8, "a message");
  return true;
}

// ---- Header ------------------------------------------------------------------------------

std::string ToStd(capnp::Text::Reader t) { return std::string(t.begin(), t.size()); }

Vec3d ToVec3(schema::Vec3::Reader v) { return {v.getX(), v.getY(), v.getZ()}; }

RenderSettings ToSettings(schema::Settings::Reader s) {
  RenderSettings r;
  r.width = s.getWidth();
  r.height = s.getHeight();
  r.spp = s.getSpp();
  r.max_depth = s.getMaxDepth();
  r.primary_step = s.getPrimaryStep();
  r.shadow_step = s.getShadowStep();
  r.cutoff = s.getCutoff();
  r.store_t = s.getStoreT();
  r.single_precision = s.getSinglePrecision();
  r.zstd_level = s.getZstdLevel();
  return r;
}

GridInfo ToGrid(schema::Grid::Reader g) {
  return {ToStd(g.getName()), ToStd(g.getRole()), ToStd(g.getSource()), g.getVoxelSize(),
          g.getLeafCount()};
}

CameraKey ToCamera(schema::Camera::Reader c) {
  CameraKey k;
  k.frame = c.getFrame();
  k.eye = ToVec3(c.getEye());
  k.target = ToVec3(c.getTarget());
  k.up = ToVec3(c.getUp());
  k.fov_deg = c.getFovDeg();
  return k;
}

CameraPathInfo ToPath(schema::CameraPath::Reader r) {
  if (r.getKeys().size() > kTraceMaxFrames) {
    throw BadData("camera path with " + Str(r.getKeys().size()) + " key frames exceeds the " +
                  "trace format's limit of " + Str(kTraceMaxFrames) + " (kTraceMaxFrames)");
  }
  CameraPathInfo p;
  p.kind = ToStd(r.getKind());
  p.first_frame = r.getFirstFrame();
  p.frame_count = r.getFrameCount();
  p.eye = ToVec3(r.getEye());
  p.target = ToVec3(r.getTarget());
  p.up = ToVec3(r.getUp());
  p.fov_deg = r.getFovDeg();
  p.orbit_degrees = r.getOrbitDegrees();
  for (auto k : r.getKeys()) p.keys.push_back(ToCamera(k));
  return p;
}

// The subdivision of a regrouped trace, checked: a SPEC that parses, a fine grid, and per
// frame boxes that tile it, as many as the cells.
SubdivisionInfo ToSubdivision(schema::Subdivision::Reader r, const TraceHeader& h) {
  SubdivisionInfo s;
  s.spec = ToStd(r.getSpec());
  if (s.spec.empty()) throw BadData("a subdivision without a SPEC");
  if (s.spec.size() > kTraceMaxTextBytes) throw BadData("a subdivision SPEC over the text limit");
  SubdivisionSpec spec;
  try {
    spec = ParseSubdivisionSpec(s.spec, "subdivision");
  } catch (const InputError& e) {
    throw BadData(e.what());
  }
  s.fine = {r.getFineX(), r.getFineY(), r.getFineZ()};
  const std::string grid = TraceCellGridProblem(s.fine);
  if (!grid.empty()) throw BadData("the subdivision's fine grid: " + grid);
  if (r.getBoxes().size() > kTraceMaxBoxes) {
    throw BadData("a subdivision of " + Str(r.getBoxes().size()) + " boxes exceeds the " +
                  "limit of " + Str(kTraceMaxBoxes) + " (kTraceMaxBoxes)");
  }
  const std::uint64_t cells = TraceCellCount(h.cells);
  const bool dynamic = spec.kind == SubdivisionSpec::Kind::kDynamic;
  const std::uint64_t frames = dynamic ? h.cameras.size() : 1;
  if (r.getBoxes().size() != cells * frames) {
    throw BadData("a subdivision of " + Str(r.getBoxes().size()) + " boxes for " + Str(cells) +
                  " cells" + (dynamic ? " and " + Str(frames) + " frames" : std::string()));
  }
  if (spec.kind != SubdivisionSpec::Kind::kUniform && (h.cells[1] != 1 || h.cells[2] != 1)) {
    throw BadData("a subdivision '" + s.spec + "' of a cell grid that is not NX1x1");
  }
  std::vector<std::uint8_t> covered;
  for (std::uint64_t i = 0; i < r.getBoxes().size(); ++i) {
    if (i % cells == 0) covered.assign(TraceCellCount(s.fine), 0);
    const auto b = r.getBoxes()[unsigned(i)];
    FineBox box{{b.getLoX(), b.getLoY(), b.getLoZ()}, {b.getHiX(), b.getHiY(), b.getHiZ()}};
    for (int a = 0; a < 3; ++a) {
      if (!(box.lo[a] < box.hi[a] && box.hi[a] <= s.fine[a])) {
        throw BadData("subdivision box " + Str(i) + " is empty or outside the fine grid");
      }
    }
    for (std::uint32_t z = box.lo[2]; z < box.hi[2]; ++z)
      for (std::uint32_t y = box.lo[1]; y < box.hi[1]; ++y)
        for (std::uint32_t x = box.lo[0]; x < box.hi[0]; ++x) {
          if (covered[x + s.fine[0] * (y + std::uint64_t{s.fine[1]} * z)]++) {
            throw BadData("subdivision box " + Str(i) + " overlaps another");
          }
        }
    if (i % cells == cells - 1 && std::count(covered.begin(), covered.end(), 0) != 0) {
      throw BadData("the subdivision's boxes leave fine cells uncovered");
    }
    s.boxes.push_back(box);
  }
  const auto ff = r.getFrameFootprints();
  if (ff.size() != (dynamic ? r.getBoxes().size() : 0)) {
    throw BadData("a subdivision with " + Str(ff.size()) + " frame footprints for " +
                  Str(r.getBoxes().size()) + " boxes" + (dynamic ? "" : " (not dynamic)"));
  }
  for (std::uint64_t f : ff) s.frame_footprints.push_back(f);
  return s;
}

// The header's fields as read, checked against the format's limits (footprints not yet:
// version 2 stores them in the records after the header).
TraceHeader ToHeader(schema::Header::Reader r, std::uint64_t* leaf_count) {
  TraceHeader h;
  h.format_version = r.getFormatVersion();
  if (h.format_version < 1 || h.format_version > kTraceFormatVersion) {
    throw BadData("format version " + Str(h.format_version) + " is not supported (this reader " +
                  "reads 1.." + Str(kTraceFormatVersion) + ")");
  }
  // Lists of empty structs cost the message nothing: check their lengths before reading.
  if (r.getGrids().size() > kTraceMaxGrids) {
    throw BadData(Str(r.getGrids().size()) + " grids exceed the trace format's limit of " +
                  Str(kTraceMaxGrids) + " (kTraceMaxGrids)");
  }
  if (r.getCameras().size() > kTraceMaxFrames) {
    throw BadData(Str(r.getCameras().size()) + " cameras (frames) exceed the trace format's " +
                  "limit of " + Str(kTraceMaxFrames) + " (kTraceMaxFrames)");
  }
  h.producer = ToStd(r.getProducer());
  h.scene = ToStd(r.getScene());
  for (auto g : r.getGrids()) h.grids.push_back(ToGrid(g));
  h.box_min = ToVec3(r.getBoxMin());
  h.box_max = ToVec3(r.getBoxMax());
  h.cells = {r.getCellsX(), r.getCellsY(), r.getCellsZ()};
  h.footprint_mode = ToStd(r.getFootprintMode());
  for (auto c : r.getCameras()) h.cameras.push_back(ToCamera(c));
  h.settings = ToSettings(r.getSettings());
  if (h.format_version >= 3) h.path = ToPath(r.getPath());
  if (h.format_version >= 4) {
    h.regroupable = r.getRegroupable();
    if (r.getLeafCount() > kTraceMaxLeaves) {
      throw BadData(Str(r.getLeafCount()) + " leaves exceed the trace format's limit of " +
                    Str(kTraceMaxLeaves) + " (kTraceMaxLeaves)");
    }
    if (!h.regroupable && r.getLeafCount() != 0)
      throw BadData("leaves in a capture not regroupable");
    *leaf_count = r.getLeafCount();
    if (r.hasSubdivision()) h.subdivision = ToSubdivision(r.getSubdivision(), h);
  }
  const std::string problem = TraceHeaderProblem(h);
  if (!problem.empty()) throw BadData(problem);
  const auto footprints = r.getFootprints();
  if (h.format_version >= 2 && footprints.size() != 0) {
    throw BadData("version 2 header with footprints in it");
  }
  if (h.format_version == 1 && footprints.size() != TraceCellCount(h.cells)) {
    throw BadData(Str(footprints.size()) + " footprints for " + Str(TraceCellCount(h.cells)) +
                  " cells");
  }
  for (std::uint64_t f : footprints) h.footprints.push_back(f);
  return h;
}

// Appends the footprints of one `footprints` record (version 2) to `out`, which holds those
// of the records before it; at most `cells` in all.
void AppendFootprints(schema::Footprints::Reader r, std::uint64_t cells,
                      std::vector<std::uint64_t>& out) {
  if (r.getFirstCell() != out.size()) {
    throw BadData("footprints record starts at cell " + Str(r.getFirstCell()) + ", expected " +
                  Str(out.size()));
  }
  ColumnReader values(r.getValues(), "footprint values");
  ColumnReader runs(r.getRuns(), r.getValues().getNarrow().size(), "footprint runs");
  if (values.AtEnd()) throw BadData("footprints record without runs");
  while (!values.AtEnd()) {
    const std::uint64_t value = values.Next(), run = runs.Next();
    if (run >= cells - out.size())
      throw BadData("footprints for more than " + Str(cells) + " cells");
    out.insert(out.end(), run + 1, value);
  }
  values.Finish();
  runs.Finish();
}

// Appends the leaves per cell of one `cellLeaves` record to `out` (cells < `cells`, leaf
// numbers < `leaf_count`, increasing within a cell).
void AppendCellLeaves(schema::CellLeaves::Reader r, std::uint64_t cells, std::uint64_t leaf_count,
                      CellLeaves& out) {
  const std::uint64_t first = out.begin.size() - 1;
  if (r.getFirstCell() != first) {
    throw BadData("cellLeaves record starts at cell " + Str(r.getFirstCell()) + ", expected " +
                  Str(first));
  }
  ColumnReader counts(r.getCounts(), "leaf counts"), leaves(r.getLeaves(), "cell leaves");
  if (counts.AtEnd()) throw BadData("cellLeaves record without cells");
  while (!counts.AtEnd()) {
    if (out.begin.size() - 1 == cells)
      throw BadData("leaves for more than " + Str(cells) + " cells");
    const std::uint64_t n = counts.Next();
    if (n > leaf_count || out.leaves.size() + n > kTraceMaxLeafRefs) {
      throw BadData("more (cell, leaf) pairs than the trace format's limit or the leaves");
    }
    std::uint64_t leaf = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint64_t d = leaves.Next();
      leaf = i == 0 ? d : leaf + 1 + std::min<std::uint64_t>(d, leaf_count);
      if (leaf >= leaf_count)
        throw BadData("a cell's leaf number beyond the " + Str(leaf_count) + " leaves");
      out.leaves.push_back(std::uint32_t(leaf));
    }
    out.begin.push_back(out.leaves.size());
  }
  counts.Finish();
  leaves.Finish();
}

// Decodes the header frame at offset 0; returns the header and sets `length`.
TraceHeader ReadHeader(const FileIn& file, std::uint64_t& length) {
  ZstdFrameReader in(file, 0, file.size());
  kj::Array<capnp::word> words;
  if (!ReadMessage(in, words)) throw BadData("empty header frame");
  TraceHeader header;
  std::uint64_t leaf_count = 0;
  {
    capnp::FlatArrayMessageReader message(words, MessageOptions());
    const auto record = message.getRoot<schema::Record>();
    if (record.which() != schema::Record::HEADER) throw BadData("first record is not a header");
    header = ToHeader(record.getHeader(), &leaf_count);
  }
  const std::uint64_t cells = TraceCellCount(header.cells);
  if (header.regroupable) header.leaves.begin.push_back(0);
  // Records in order: footprints, then (regroupable) leafBytes, then cellLeaves.
  while (ReadMessage(in, words)) {
    if (header.format_version < 2) throw BadData("more than one message in the header frame");
    capnp::FlatArrayMessageReader message(words, MessageOptions());
    const auto record = message.getRoot<schema::Record>();
    const bool footprints_done = header.footprints.size() == cells;
    const bool leaves_done = header.leaves.bytes.size() == leaf_count;
    const bool cell_leaves_started = header.leaves.begin.size() > 1;
    if (record.which() == schema::Record::FOOTPRINTS && header.leaves.bytes.empty() &&
        !cell_leaves_started) {
      AppendFootprints(record.getFootprints(), cells, header.footprints);
    } else if (!header.regroupable) {
      throw BadData("a record other than footprints after the header");
    } else if (record.which() == schema::Record::LEAF_BYTES && footprints_done &&
               !cell_leaves_started) {
      AppendFootprints(record.getLeafBytes(), leaf_count, header.leaves.bytes);
    } else if (record.which() == schema::Record::CELL_LEAVES && footprints_done && leaves_done) {
      AppendCellLeaves(record.getCellLeaves(), cells, leaf_count, header.leaves);
    } else {
      throw BadData("a record out of place after the header (expected footprints, then a " +
                    std::string("regroupable capture's leafBytes and cellLeaves records)"));
    }
  }
  if (header.footprints.size() != cells) {
    throw BadData(Str(header.footprints.size()) + " footprints for " + Str(cells) + " cells");
  }
  const std::vector<std::uint64_t>& ff = header.subdivision.frame_footprints;
  for (std::uint64_t i = 0; i < ff.size(); ++i) {
    if (ff[i] > header.footprints[i % cells]) {
      throw BadData("frame footprint " + Str(i) + " above its cell's footprint");
    }
  }
  if (header.regroupable) {
    if (header.leaves.bytes.size() != leaf_count || header.leaves.begin.size() != cells + 1) {
      throw BadData("a regroupable capture's leaves are incomplete");
    }
    if (header.footprint_mode != "sparse")
      throw BadData("a regroupable capture's footprints are not sparse");
    for (std::uint64_t c = 0; c < cells; ++c) {
      std::uint64_t sum = 0;
      for (std::uint64_t i = header.leaves.begin[c]; i < header.leaves.begin[c + 1]; ++i) {
        sum += header.leaves.bytes[header.leaves.leaves[i]];
      }
      if (sum != header.footprints[c]) {
        throw BadData("cell " + Str(c) + "'s leaves hold " + Str(sum) + " bytes, its footprint " +
                      Str(header.footprints[c]));
      }
    }
  }
  length = in.consumed();
  return header;
}

// ---- Batches -----------------------------------------------------------------------------

struct BatchColumns {
  capnp::List<std::uint8_t>::Reader heads;
  ColumnReader head_runs, parents, spawns, pixels, primary_paths, secondary_paths;
  ZeroRunColumnReader primary_samples, secondary_samples;
  capnp::List<float>::Reader t_enter, t_exit;

  explicit BatchColumns(schema::Batch::Reader b)
      : heads(b.getHeads()),
        head_runs(b.getHeadRuns(), heads.size(), "headRuns"),
        parents(b.getParents(), "parents"),
        spawns(b.getSpawns(), "spawns"),
        pixels(b.getPixels(), "pixels"),
        primary_paths(b.getPrimaryPaths(), "primaryPaths"),
        secondary_paths(b.getSecondaryPaths(), "secondaryPaths"),
        primary_samples(b.getPrimarySamples(), "primarySamples"),
        secondary_samples(b.getSecondarySamples(), "secondarySamples"),
        t_enter(b.getTEnter()),
        t_exit(b.getTExit()) {}

  // The number of rays of the batch (the sum of the head runs), at most kTraceMaxBatchRays.
  std::size_t RayCount(schema::Batch::Reader b) const {
    ColumnReader runs(b.getHeadRuns(), "headRuns");
    std::uint64_t rays = 0;
    for (unsigned r = 0; r < heads.size(); ++r) {
      const std::uint64_t run = runs.Next();
      if (run >= kTraceMaxBatchRays || rays + run + 1 > kTraceMaxBatchRays) {
        throw BadData("batch has more than " + Str(kTraceMaxBatchRays) + " rays");
      }
      rays += run + 1;
    }
    return static_cast<std::size_t>(rays);
  }

  void Finish() const {
    for (const ColumnReader* c :
         {&head_runs, &parents, &spawns, &pixels, &primary_paths, &secondary_paths}) {
      c->Finish();
    }
    primary_samples.Finish();
    secondary_samples.Finish();
  }
};

// Decodes the batches of one frame in order, validating them against each other and the
// header, and accumulates the frame's summary.
class FrameDecoder {
 public:
  FrameDecoder(const TraceHeader& header, std::int32_t frame, const FrameSummary* expected)
      : header_(header), acc_(frame, header.settings.store_t), frame_(frame), expected_(expected) {}

  void Decode(schema::Batch::Reader b, RayBatch& out) {
    if (b.getFrame() != frame_) throw BadData("batch of frame " + Str(b.getFrame()));
    if (b.getFirstId() != acc_.rays()) {
      throw BadData("batch starts at ray " + Str(b.getFirstId()) + ", expected " +
                    Str(acc_.rays()));
    }
    BatchColumns c(b);
    CheckTimeLengths(c);
    const std::size_t rays = c.RayCount(b);
    out.Clear();
    out.set_first_id(b.getFirstId());
    out.Reserve(rays, header_.settings.store_t ? c.t_enter.size() : 0);
    last_primary_ = kNone;
    for (auto& starts : group_start_) std::fill(std::begin(starts), std::end(starts), kNone);
    last_non_shadow_ = kNoParent;
    prev_x_ = prev_y_ = 0;
    std::size_t i = 0;
    for (unsigned r = 0; r < c.heads.size(); ++r) {
      const std::uint8_t head = c.heads[r];
      for (std::uint64_t n = c.head_runs.Next() + 1; n > 0; --n) DecodeRay(c, head, i++, out);
    }
    c.Finish();
    if (header_.settings.store_t && c.t_enter.size() != out.visit_count()) {
      throw BadData("t columns have " + Str(c.t_enter.size()) + " values for " +
                    Str(out.visit_count()) + " visits");
    }
    CheckAgainstExpected();
  }

  FrameSummary Summary() const { return acc_.Summary(); }

 private:
  static constexpr std::size_t kNone = ~std::size_t{0};

  void CheckTimeLengths(const BatchColumns& c) const {
    const bool t = header_.settings.store_t;
    if (c.t_enter.size() != c.t_exit.size() || (!t && c.t_enter.size() != 0) ||
        c.t_enter.size() > kTraceMaxBatchVisits) {
      throw BadData("t columns have bad length");
    }
  }

  void DecodeRay(BatchColumns& c, std::uint8_t head, std::size_t i, RayBatch& out) {
    const RayId id = out.first_id() + i;
    const auto kind = static_cast<RayKind>(head & kHeadKindMask);
    const RayId parent = DecodeParent(c, head, id, kind, i, out);
    const bool sibling = i > 0 && out.parents()[i - 1] == parent;
    const std::uint32_t spawn = DecodeSpawn(c, head, id, sibling ? out.spawns()[i - 1] : 0);
    CheckSpawn(id, parent, spawn);
    if (head & kHeadNewPixel) {
      prev_x_ = ApplyDelta(prev_x_, c.pixels.Next(), "pixel x");
      prev_y_ = ApplyDelta(prev_y_, c.pixels.Next(), "pixel y");
    }
    const bool primary = parent == kNoParent;
    const std::size_t ref = ReferenceRay(out, kind, parent, i, sibling);
    out.BeginRay(kind, parent, spawn, prev_x_, prev_y_);
    DecodeVisits(c, head, id, primary, ref, out);
    const std::size_t count = out.visit_end(i) - out.visit_begin(i);
    Remember(id, static_cast<std::uint32_t>(count));
    acc_.AddRay(out.ray(i));
    if (primary) last_primary_ = i;
    if (kind != RayKind::kShadow) last_non_shadow_ = id;
  }

  // Index of the reference ray of ray i (see "Column encoding" in trace.capnp), or kNone.
  // Also records ray i as a group start.
  std::size_t ReferenceRay(const RayBatch& out, RayKind kind, RayId parent, std::size_t i,
                           bool sibling) {
    if (parent == kNoParent) return last_primary_;
    if (sibling) return i - 1;
    if (parent < out.first_id()) return kNone;
    const auto parent_kind = static_cast<int>(out.kinds()[parent - out.first_id()]);
    return std::exchange(group_start_[static_cast<int>(kind)][parent_kind], i);
  }

  RayId DecodeParent(BatchColumns& c, std::uint8_t head, RayId id, RayKind kind, std::size_t i,
                     const RayBatch& out) const {
    const unsigned code = (head >> kHeadParentShift) & 3;
    if (kind == RayKind::kPrimary) {
      if (code != kParentIsLastNonShadow) {
        throw BadData("ray " + Str(id) + ": primary ray with a parent");
      }
      return kNoParent;
    }
    RayId parent = kNoParent;
    if (code == kParentIsLastNonShadow) {
      parent = last_non_shadow_;
    } else if (code == kParentOfPreviousRay) {
      if (i > 0) parent = out.parents()[i - 1];
    } else if (code == kParentExplicit) {
      const std::uint64_t delta = c.parents.Next();
      if (delta != 0 && delta <= id) parent = id - delta;
    }
    if (parent == kNoParent) throw BadData("ray " + Str(id) + ": bad parent");
    return parent;
  }

  static std::uint32_t DecodeSpawn(BatchColumns& c, std::uint8_t head, RayId id,
                                   std::uint32_t predicted) {
    const unsigned code = (head >> kHeadSpawnShift) & 3;
    const std::uint64_t spawn =
        code == kSpawnExplicit ? c.spawns.Next() : std::uint64_t{predicted} + code;
    if (spawn > 0xFFFFFFFF) throw BadData("ray " + Str(id) + ": bad spawn");
    return static_cast<std::uint32_t>(spawn);
  }

  void CheckSpawn(RayId id, RayId parent, std::uint32_t spawn) const {
    if (parent == kNoParent) {
      if (spawn != 0) throw BadData("ray " + Str(id) + ": primary ray with a spawn index");
      return;
    }
    if (id - parent > kWindow) return;  // too far back to remember; not checked
    if (spawn >= counts_[parent % kWindow]) {
      throw BadData("ray " + Str(id) + ": spawn " + Str(spawn) + " >= visit count of parent " +
                    Str(parent));
    }
  }

  // Adds the visits of ray `id` (the last ray of `out`); `ref` is its reference ray.
  void DecodeVisits(BatchColumns& c, std::uint8_t head, RayId id, bool primary, std::size_t ref,
                    RayBatch& out) {
    ColumnReader& paths = primary ? c.primary_paths : c.secondary_paths;
    ZeroRunColumnReader& samples = primary ? c.primary_samples : c.secondary_samples;
    const bool new_path = head & kHeadNewPath;
    if (!new_path && ref == kNone) {
      throw BadData("ray " + Str(id) + ": repeats the path of a reference ray it does not have");
    }
    const std::size_t ref_begin = ref == kNone ? 0 : out.visit_begin(ref);
    const std::size_t ref_count = ref == kNone ? 0 : out.visit_end(ref) - ref_begin;
    const std::uint64_t count = new_path ? paths.Next() : ref_count;
    if (count > kTraceMaxRayVisits || count > kTraceMaxBatchVisits - out.visit_count()) {
      throw BadData("ray " + Str(id) + ": too many visits");
    }
    const bool t = header_.settings.store_t;
    std::uint32_t cell = 0;
    for (std::uint64_t v = 0; v < count; ++v) {
      if (!new_path) {
        cell = out.cells()[ref_begin + v].value();
      } else if (v == 0) {
        const std::uint64_t first = paths.Next();
        if (first >= header_.cell_count()) throw BadData("ray " + Str(id) + ": bad cell");
        cell = static_cast<std::uint32_t>(first);
      } else {
        cell = ApplyDelta(cell, paths.Next(), "cell");
        if (cell >= header_.cell_count()) throw BadData("ray " + Str(id) + ": bad cell");
      }
      const std::uint64_t code = samples.Next();
      std::uint64_t n = code;
      if (v < ref_count) {
        n = ApplyDelta(out.samples()[ref_begin + v], code, "samples");
      } else if (code > 0xFFFFFFFF) {
        throw BadData("ray " + Str(id) + ": bad samples");
      }
      const std::size_t k = out.visit_count();
      if (t && k >= c.t_enter.size()) throw BadData("t columns have bad length");
      out.AddVisit(CellId(cell), static_cast<std::uint32_t>(n), t ? c.t_enter[k] : 0.f,
                   t ? c.t_exit[k] : 0.f);
    }
  }

  void Remember(RayId id, std::uint32_t visit_count) {
    if (id < kWindow) {
      counts_.push_back(visit_count);
    } else {
      counts_[id % kWindow] = visit_count;
    }
  }

  void CheckAgainstExpected() const {
    if (!expected_) return;
    if (acc_.rays() > expected_->rays || acc_.visits() > expected_->visits) {
      throw BadData("more rays or visits than the index says");
    }
  }

  static constexpr RayId kWindow = RayId{1} << 20;  // parents checked this far back

  const TraceHeader& header_;
  FrameAccumulator acc_;
  std::int32_t frame_;
  const FrameSummary* expected_;
  std::uint32_t prev_x_ = 0, prev_y_ = 0;  // pixel of the previous ray of the batch
  std::size_t last_primary_ = kNone;       // index in the batch of the last primary ray
  // Index in the batch of the last group start, by [kind][kind of its parent].
  std::size_t group_start_[kRayKindCount][kRayKindCount];
  RayId last_non_shadow_ = kNoParent;  // id of the last ray that is not a shadow ray
  std::vector<std::uint32_t> counts_;  // visit counts of the last kWindow rays
};

// ---- Frames ------------------------------------------------------------------------------

// Where a frame is and what is known of it before reading it.
struct FrameSlot {
  std::size_t ordinal;           // position among the file's frames (0 = first)
  std::uint64_t offset, end;     // bytes to read: the zstd frame starts at offset, ends <= end
  const FrameSummary* expected;  // from the index or an earlier scan; null when scanning
};

FrameSummary ToSummary(schema::FrameEnd::Reader r) {
  FrameSummary s;
  s.frame = r.getFrame();
  s.rays = r.getRays();
  s.visits = r.getVisits();
  s.samples = r.getSamples();
  const auto kinds = r.getRaysByKind();
  if (kinds.size() != kRayKindCount) throw BadData("frameEnd has bad raysByKind");
  for (unsigned k = 0; k < kinds.size(); ++k) s.rays_by_kind[k] = kinds[k];
  s.checksum = r.getChecksum();
  return s;
}

std::string Hex(std::uint64_t v) { return "0x" + FormatHex64(v); }

std::string Describe(const FrameSummary& s) {
  std::string kinds;
  for (int k = 0; k < kRayKindCount; ++k) {
    kinds += (k ? ", " : "") + Str(s.rays_by_kind[k]) + " " + ToString(static_cast<RayKind>(k));
  }
  return "frame " + std::to_string(s.frame) + ": " + Str(s.rays) + " rays (" + kinds + "), " +
         Str(s.visits) + " visits, " + Str(s.samples) + " samples";
}

void CheckSummary(const FrameSummary& stored, const FrameSummary& decoded, const char* source) {
  if (stored.frame != decoded.frame || stored.rays != decoded.rays ||
      stored.visits != decoded.visits || stored.samples != decoded.samples ||
      stored.rays_by_kind != decoded.rays_by_kind) {
    throw BadData(std::string(source) + " says " + Describe(stored) + "; decoded " +
                  Describe(decoded));
  }
  if (stored.checksum != decoded.checksum) {
    throw BadData(std::string("checksum mismatch: ") + source + " says " + Hex(stored.checksum) +
                  ", decoded rays hash to " + Hex(decoded.checksum));
  }
}

using BatchFn = std::function<void(const RayBatch&)>;

class FrameReading {
 public:
  FrameReading(const FileIn& file, const TraceHeader& header, const FrameSlot& slot)
      : in_(file, slot.offset, slot.end),
        header_(header),
        slot_(slot),
        batch_(header.settings.store_t) {
    if (slot.expected) number_ = slot.expected->frame;
  }

  FrameSummary Run(const BatchFn* fn) {
    kj::Array<capnp::word> words;
    while (ReadMessage(in_, words)) {
      capnp::FlatArrayMessageReader message(words, MessageOptions());
      const auto record = message.getRoot<schema::Record>();
      if (record.which() == schema::Record::FRAME_END) return End(record.getFrameEnd());
      if (record.which() != schema::Record::BATCH) throw BadData("unexpected record in a frame");
      Batch(record.getBatch(), fn);
    }
    throw BadData("the zstd frame ends without a frameEnd record");
  }

  std::optional<std::int32_t> number() const { return number_; }

 private:
  FrameDecoder& Decoder(std::int32_t frame) {
    if (!number_) number_ = frame;
    if (!decoder_) decoder_.emplace(header_, *number_, slot_.expected);
    return *decoder_;
  }

  void Batch(schema::Batch::Reader b, const BatchFn* fn) {
    Decoder(b.getFrame()).Decode(b, batch_);
    if (fn) (*fn)(batch_);
  }

  FrameSummary End(schema::FrameEnd::Reader r) {
    const FrameSummary stored = ToSummary(r);
    FrameSummary decoded = Decoder(stored.frame).Summary();
    CheckSummary(stored, decoded, "frameEnd");
    char extra;
    if (in_.Read(&extra, 1) != 0) throw BadData("data after the frameEnd record");
    decoded.offset = slot_.offset;
    decoded.length = in_.consumed();
    if (slot_.expected) CheckSummary(*slot_.expected, decoded, "the index");
    if (slot_.expected && slot_.expected->length != decoded.length) {
      throw BadData("the zstd frame is " + Str(decoded.length) + " bytes, the index says " +
                    Str(slot_.expected->length));
    }
    return decoded;
  }

  ZstdFrameReader in_;
  const TraceHeader& header_;
  FrameSlot slot_;
  std::optional<std::int32_t> number_;
  std::optional<FrameDecoder> decoder_;
  RayBatch batch_;
};

std::string FrameLabel(const FrameSlot& slot, std::optional<std::int32_t> number) {
  const std::string where = "offset " + Str(slot.offset);
  if (!number) return "frame #" + Str(slot.ordinal) + " (" + where + ")";
  return "frame " + std::to_string(*number) + " (#" + Str(slot.ordinal) + ", " + where + ")";
}

// Reads and verifies one frame, calling `fn` (if any) with each batch.
FrameSummary ReadFrame(const FileIn& file, const std::string& path, const TraceHeader& header,
                       const FrameSlot& slot, const BatchFn* fn) {
  std::optional<FrameReading> reading;
  auto where = [&] { return FrameLabel(slot, reading ? reading->number() : std::nullopt); };
  return Guarded(path, where, [&] {
    reading.emplace(file, header, slot);
    return reading->Run(fn);
  });
}

// ---- Index -------------------------------------------------------------------------------

class IndexLocation {
 public:
  // Finds the Index message from the trailer; BadData when missing or inconsistent.
  IndexLocation(const FileIn& file, std::uint64_t header_length) {
    const std::uint64_t size = file.size();
    if (size < header_length + 8 + kTraceTrailerBytes) throw BadData(kMissing);
    unsigned char trailer[kTraceTrailerBytes];
    file.ReadAt(size - kTraceTrailerBytes, trailer, kTraceTrailerBytes);
    if (std::memcmp(trailer + 16, kTraceIndexTag, 8) != 0) throw BadData(kMissing);
    hash = LoadU64(trailer);
    length = LoadU64(trailer + 8);
    if (length % 8 != 0 || length > kTraceMaxMessageBytes ||
        length > size - header_length - 8 - kTraceTrailerBytes) {
      throw BadData("damaged: bad length " + Str(length));
    }
    frame_offset = size - kTraceTrailerBytes - length - 8;
    if (file.U32At(frame_offset) != kTraceIndexMagic ||
        file.U32At(frame_offset + 4) != length + kTraceTrailerBytes) {
      throw BadData("damaged: bad skippable frame header at offset " + Str(frame_offset));
    }
  }

  static constexpr const char* kMissing =
      "missing: the file does not end with an index (interrupted capture or truncated file)";
  std::uint64_t hash = 0, length = 0, frame_offset = 0;
};

FrameSummary ToSummary(schema::IndexEntry::Reader e) {
  FrameSummary s;
  s.frame = e.getFrame();
  s.offset = e.getOffset();
  s.length = e.getLength();
  s.rays = e.getRays();
  s.visits = e.getVisits();
  s.samples = e.getSamples();
  const auto kinds = e.getRaysByKind();
  if (kinds.size() != kRayKindCount) throw BadData("damaged: bad raysByKind");
  for (unsigned k = 0; k < kinds.size(); ++k) s.rays_by_kind[k] = kinds[k];
  s.checksum = e.getChecksum();
  s.stored_hash = e.getStoredHash();
  return s;
}

std::vector<FrameSummary> ToSummaries(schema::Index::Reader index, const TraceHeader& header,
                                      std::uint64_t header_length, std::uint64_t index_offset) {
  if (index.getFormatVersion() != header.format_version ||
      index.getHeaderLength() != header_length) {
    throw BadData("damaged: version or header length disagrees with the header");
  }
  if (index.getFrames().size() > kTraceMaxFrames) {
    throw BadData("damaged: more than " + Str(kTraceMaxFrames) + " frames");
  }
  std::vector<FrameSummary> frames;
  std::uint64_t next = header_length;
  for (auto entry : index.getFrames()) {
    frames.push_back(ToSummary(entry));
    const FrameSummary& s = frames.back();
    if (s.offset != next || s.length == 0 || s.length > index_offset - next) {
      throw BadData("damaged: entry " + Str(frames.size() - 1) + " has a bad byte range");
    }
    next += s.length;
  }
  if (next != index_offset) throw BadData("damaged: frames do not end where the index starts");
  return frames;
}

std::vector<FrameSummary> ReadIndex(const FileIn& file, const TraceHeader& header,
                                    std::uint64_t header_length) {
  const IndexLocation where(file, header_length);
  auto words = kj::heapArray<capnp::word>(where.length / 8);
  file.ReadAt(where.frame_offset + 8, words.begin(), where.length);
  Hash64 hash;
  hash.AddBytes(words.begin(), where.length);
  if (hash.Finish() != where.hash) throw BadData("damaged: checksum mismatch");
  capnp::FlatArrayMessageReader message(words, MessageOptions());
  return ToSummaries(message.getRoot<schema::Index>(), header, header_length, where.frame_offset);
}

// Checks the stored zstd frame of `slot` (see TraceReader::ReadEncodedFrame) without decoding
// its rays.
void CheckEncodedFrame(const FileIn& file, const FrameSlot& slot) {
  ZstdFrameReader in(file, slot.offset, slot.end);
  ZSTD_frameHeader zh;
  char head[ZSTD_FRAMEHEADERSIZE_MAX];
  const std::size_t head_bytes =
      static_cast<std::size_t>(std::min<std::uint64_t>(sizeof head, slot.end - slot.offset));
  file.ReadAt(slot.offset, head, head_bytes);
  if (ZSTD_getFrameHeader(&zh, head, head_bytes) != 0 || !zh.checksumFlag) {
    throw BadData("the zstd frame has no content checksum");
  }
  kj::Array<capnp::word> words;
  bool ended = false;
  while (ReadMessage(in, words)) {
    if (ended) throw BadData("data after the frameEnd record");
    capnp::FlatArrayMessageReader message(words, MessageOptions());
    const auto record = message.getRoot<schema::Record>();
    if (record.which() == schema::Record::BATCH) continue;
    if (record.which() != schema::Record::FRAME_END) throw BadData("unexpected record in a frame");
    FrameSummary stored = ToSummary(record.getFrameEnd());
    CheckSummary(*slot.expected, stored, "the index");
    ended = true;
  }
  if (!ended) throw BadData("the zstd frame ends without a frameEnd record");
  if (in.consumed() != slot.end - slot.offset) {
    throw BadData("the zstd frame is " + Str(in.consumed()) + " bytes, the index says " +
                  Str(slot.end - slot.offset));
  }
}

}  // namespace

// ---- TraceReader -------------------------------------------------------------------------

struct TraceReader::Impl {
  std::string path;
  FileIn file;
  TraceHeader header;
  std::uint64_t header_length = 0;
  std::vector<FrameSummary> frames;
  std::string warning;
  std::uint64_t readable_end = 0;

  explicit Impl(const std::string& p) : path(p), file(p) {}
  Impl(const std::string& name, std::string&& bytes) : path(name), file(std::move(bytes)) {}

  void ReadHeaderFrame() {
    header = Guarded(
        path, [] { return std::string("header"); },
        [&] { return ReadHeader(file, header_length); });
  }

  void ReadFrameList() {
    try {
      frames = Guarded(
          path, [] { return std::string("index"); },
          [&] { return ReadIndex(file, header, header_length); });
      readable_end = file.size();
    } catch (const InputError& e) {
      std::string stop;
      frames = Scan(stop);
      readable_end = frames.empty() ? header_length : frames.back().offset + frames.back().length;
      warning = std::string(e.what()) + "; scanned the file instead and kept " +
                Str(frames.size()) + " complete frame(s)" +
                (stop.empty() ? "" : "; the scan stopped at " + stop);
    }
  }

  // Reads frames one after the other from the header on, until the end, the index frame or
  // the first damage (described in `stop`).
  std::vector<FrameSummary> Scan(std::string& stop) const {
    std::vector<FrameSummary> found;
    std::uint64_t pos = header_length;
    while (pos < file.size()) {
      if (file.size() - pos < 4) {
        stop = "offset " + Str(pos) + ": " + Str(file.size() - pos) + " stray bytes (truncated)";
        break;
      }
      if ((file.U32At(pos) & ZSTD_MAGIC_SKIPPABLE_MASK) == ZSTD_MAGIC_SKIPPABLE_START) break;
      try {
        found.push_back(
            ReadFrame(file, path, header, {found.size(), pos, file.size(), nullptr}, nullptr));
      } catch (const InputError& e) {
        stop = e.what();
        break;
      }
      pos += found.back().length;
    }
    return found;
  }

  // ---- A regroupable capture's view (TraceReader::Open) --------------------------------
  // header and frames above stay the stored ones; the view's are these.
  bool view = false;
  TraceHeader view_header;
  std::vector<FrameSummary> view_frames;
  // Per fine cell, its cell in the view (kNoCell: an empty one); one map for every frame, or
  // one per frame (a dynamic subdivision).
  std::vector<std::vector<CellId>> maps;
  // A dynamic subdivision's footprints, per frame (empty otherwise): the shown header's
  // subdivision.frame_footprints cut per frame.
  std::vector<std::vector<std::uint64_t>> frame_footprints;
  void CutFrameFootprints() {
    const TraceHeader& h = view ? view_header : header;
    const std::vector<std::uint64_t>& ff = h.subdivision.frame_footprints;
    const std::size_t n = h.cell_count();
    for (std::size_t f = 0; n > 0 && f * n < ff.size(); ++f) {
      frame_footprints.emplace_back(ff.begin() + std::ptrdiff_t(f * n),
                                    ff.begin() + std::ptrdiff_t((f + 1) * n));
    }
  }

  void ForEachStored(std::size_t i, const BatchFn& fn) const {
    const FrameSummary& s = Frame(i);
    ReadFrame(file, path, header, {i, s.offset, s.offset + s.length, &s}, &fn);
  }
  const std::vector<CellId>& MapOf(std::size_t i) const { return maps[maps.size() == 1 ? 0 : i]; }
  // The batch regrouped; an InputError names the file and frame.
  RayBatch RegroupIn(RayRegrouper& regrouper, const RayBatch& b, std::int32_t frame) const {
    try {
      return regrouper.Regroup(b);
    } catch (const InputError& e) {
      throw InputError(path + ": frame " + std::to_string(frame) + ": cannot regroup: " + e.what());
    }
  }

  // The map of a subdivision (null: the fine grid itself) whose cells have `footprints`.
  static std::vector<CellId> Map(const Subdivision* sub, const std::vector<std::uint64_t>& fp,
                                 std::size_t fine_cells) {
    std::vector<CellId> m(fine_cells);
    for (std::size_t f = 0; f < fine_cells; ++f) {
      const CellId c = sub ? sub->coarse_of_fine[f] : CellId(std::uint32_t(f));
      m[f] = fp[c.value()] == 0 ? kNoCell : c;
    }
    return m;
  }

  // Samples per fine cell of frame i, or of every frame (i = npos).
  std::vector<std::uint64_t> FineSamples(std::size_t i) const {
    std::vector<std::uint64_t> samples(header.cell_count(), 0);
    auto add = [&](const RayBatch& b) {
      for (std::size_t v = 0; v < b.visit_count(); ++v) {
        samples[b.cells()[v].value()] += b.samples()[v];
      }
    };
    if (i != std::size_t(-1)) {
      ForEachStored(i, add);
    } else {
      for (std::size_t f = 0; f < frames.size(); ++f) ForEachStored(f, add);
    }
    return samples;
  }

  // What a subdivision of the stored fine grid is made from; kd:N:work's samples over every
  // frame.
  FineCells Fine(const SubdivisionSpec& spec) const {
    FineCells fine;
    fine.grid = header.cells;
    fine.union_footprint = [this](const std::vector<std::uint32_t>& c) {
      return header.leaves.UnionBytes(c);
    };
    if (spec.kind == SubdivisionSpec::Kind::kKdWork ||
        spec.kind == SubdivisionSpec::Kind::kKdSqrt) {
      fine.samples = FineSamples(std::size_t(-1));
    }
    if (spec.kind == SubdivisionSpec::Kind::kGridCrossings) {
      fine.crossings = FineCrossings();
      fine.has_crossings = true;
    }
    return fine;
  }
  // grid:N:crossings's weights (FineCells::crossings): over every frame, each ray's steps
  // from one non-empty fine cell to its next, |dx|, |dy|, |dz| of their coordinates (the
  // visits to empty cells that a regroupable capture keeps are skipped, so that the counts
  // are those of the rays as any command reads them).
  std::array<std::uint64_t, 3> FineCrossings() const {
    const auto g = header.cells;
    const auto at = [&](std::uint32_t c) {
      return std::array<std::uint32_t, 3>{c % g[0], c / g[0] % g[1], c / g[0] / g[1]};
    };
    std::array<std::uint64_t, 3> n{};
    auto add = [&](const RayBatch& b) {
      for (std::size_t r = 0; r < b.size(); ++r) {
        std::optional<std::array<std::uint32_t, 3>> last;
        for (std::size_t v = b.visit_begin(r); v < b.visit_end(r); ++v) {
          const std::uint32_t c = b.cells()[v].value();
          if (header.footprints[c] == 0) continue;
          const std::array<std::uint32_t, 3> now = at(c);
          for (int a = 0; last && a < 3; ++a) {
            n[a] += now[a] > (*last)[a] ? now[a] - (*last)[a] : (*last)[a] - now[a];
          }
          last = now;
        }
      }
    };
    for (std::size_t f = 0; f < frames.size(); ++f) ForEachStored(f, add);
    return n;
  }
  // Per cell of `sub`, the bytes of its fine cells' leaves, each once.
  std::vector<std::uint64_t> Footprints(const Subdivision& sub) const {
    std::vector<std::uint64_t> fp(sub.cells());
    for (std::uint32_t c = 0; c < sub.cells(); ++c) {
      fp[c] = header.leaves.UnionBytes(FineCellsOf(sub.boxes[c], header.cells));
    }
    return fp;
  }

  void MakeView(const std::string& cells) {
    const TraceHeader& h = header;
    view = true;
    view_header = h;
    view_header.regroupable = false;
    view_header.leaves = {};
    const std::size_t fine_cells = h.cell_count();
    if (cells.empty()) {  // the captured grid: only the visits to empty cells dropped
      maps.push_back(Map(nullptr, h.footprints, fine_cells));
    } else {
      const std::string what = "--cells '" + cells + "'";
      const SubdivisionSpec spec = ParseSubdivisionSpec(cells, what);
      FineCells fine = Fine(spec);
      const bool dynamic = spec.kind == SubdivisionSpec::Kind::kDynamic;
      view_header.subdivision.spec = spec.ToString();
      view_header.subdivision.fine = h.cells;
      view_header.footprints.clear();
      const std::size_t subdivisions = dynamic ? frames.size() : 1;
      if (dynamic && std::uint64_t{spec.cells} * subdivisions > kTraceMaxBoxes) {
        throw InputError(what + ": " + Str(spec.cells) + " cells in each of " + Str(subdivisions) +
                         " frames exceed the trace format's limit of " + Str(kTraceMaxBoxes) +
                         " boxes (kTraceMaxBoxes)");
      }
      for (std::size_t i = 0; i < std::max<std::size_t>(subdivisions, 1); ++i) {
        if (dynamic && i > 0) fine.samples = FineSamples(i - 1);
        const Subdivision sub = Subdivide(spec, fine);
        const std::vector<std::uint64_t> fp = Footprints(sub);
        maps.push_back(Map(&sub, fp, fine_cells));
        if (dynamic) {
          view_header.subdivision.frame_footprints.insert(
              view_header.subdivision.frame_footprints.end(), fp.begin(), fp.end());
        }
        view_header.subdivision.boxes.insert(view_header.subdivision.boxes.end(), sub.boxes.begin(),
                                             sub.boxes.end());
        if (view_header.footprints.empty()) view_header.footprints.assign(fp.size(), 0);
        for (std::size_t c = 0; c < fp.size(); ++c) {  // a dynamic one: the largest
          view_header.footprints[c] = std::max(view_header.footprints[c], fp[c]);
        }
        view_header.cells = spec.kind == SubdivisionSpec::Kind::kUniform
                                ? spec.grid
                                : std::array<std::uint32_t, 3>{sub.cells(), 1, 1};
      }
    }
    for (std::size_t i = 0; i < frames.size(); ++i) {
      RayRegrouper regrouper(MapOf(i));
      FrameAccumulator sum(frames[i].frame, h.settings.store_t);
      ForEachStored(i, [&](const RayBatch& b) {
        const RayBatch out = RegroupIn(regrouper, b, frames[i].frame);
        for (std::size_t r = 0; r < out.size(); ++r) sum.AddRay(out.ray(r));
      });
      FrameSummary s = sum.Summary();
      s.offset = frames[i].offset;
      s.length = frames[i].length;
      s.stored_hash = frames[i].stored_hash;
      view_frames.push_back(s);
    }
  }

  const FrameSummary& Frame(std::size_t i) const {
    if (i >= frames.size()) {
      throw InputError(path + ": no frame #" + Str(i) + " (the file has " + Str(frames.size()) +
                       " readable frames)");
    }
    return frames[i];
  }
};

TraceReader::TraceReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TraceReader::TraceReader(TraceReader&&) noexcept = default;
TraceReader& TraceReader::operator=(TraceReader&&) noexcept = default;
TraceReader::~TraceReader() = default;

TraceReader TraceReader::Open(const std::string& path, const std::string& cells) {
  auto impl = std::make_unique<Impl>(path);
  impl->ReadHeaderFrame();
  impl->ReadFrameList();
  if (!cells.empty() && !impl->header.regroupable) {
    throw InputError("--cells '" + cells + "': " + path + " is not a regroupable capture " +
                     "(record it with `raycell record --regroupable` on a fine grid, e.g. " +
                     "--cells 12x12x12 --regroupable)");
  }
  if (impl->header.regroupable) impl->MakeView(cells);
  impl->CutFrameFootprints();
  return TraceReader(std::move(impl));
}

TraceReader TraceReader::OpenStored(const std::string& path) {
  auto impl = std::make_unique<Impl>(path);
  impl->ReadHeaderFrame();
  impl->ReadFrameList();
  impl->CutFrameFootprints();
  return TraceReader(std::move(impl));
}

TraceReader TraceReader::OpenBytes(std::string bytes, const std::string& name) {
  auto impl = std::make_unique<Impl>(name, std::move(bytes));
  impl->ReadHeaderFrame();
  impl->ReadFrameList();
  impl->CutFrameFootprints();
  return TraceReader(std::move(impl));
}

const std::string& TraceReader::path() const { return impl_->path; }
const TraceHeader& TraceReader::header() const {
  return impl_->view ? impl_->view_header : impl_->header;
}
const std::vector<FrameSummary>& TraceReader::frames() const {
  return impl_->view ? impl_->view_frames : impl_->frames;
}
bool TraceReader::regrouped() const { return impl_->view; }
const std::vector<std::uint64_t>& TraceReader::FrameFootprints(std::size_t frame_index) const {
  impl_->Frame(frame_index);
  if (impl_->frame_footprints.empty()) return header().footprints;
  return impl_->frame_footprints[frame_index];
}
const std::vector<CellId>& TraceReader::CellMap(std::size_t frame_index) const {
  RAYCELL_CHECK(impl_->view);
  impl_->Frame(frame_index);
  return impl_->MapOf(frame_index);
}
TraceReader::CoarseCells TraceReader::CoarserCells(const std::string& cells,
                                                   const std::string& what) const {
  const Impl& m = *impl_;
  if (!m.view) {
    throw InputError(what + ": '" + cells + "' needs a regroupable capture (raycell record " +
                     "--regroupable): a coarse cell's footprint counts each leaf once, which " +
                     m.path + " cannot tell");
  }
  if (m.maps.size() != 1 || m.view_header.subdivision.spec.rfind("dynamic:", 0) == 0) {
    throw InputError(what + ": '" + cells + "' cannot hold the cells of " + m.path +
                     " shown as a dynamic subdivision (--cells " + m.view_header.subdivision.spec +
                     "): they are other boxes every frame");
  }
  const SubdivisionSpec spec = ParseSubdivisionSpec(cells, what);
  if (spec.kind == SubdivisionSpec::Kind::kDynamic) {
    throw InputError(what + ": '" + cells + "': a memory level's cells stay the same over the " +
                     "frames");
  }
  Subdivision sub;
  try {
    sub = Subdivide(spec, m.Fine(spec));
  } catch (const InputError& e) {
    throw InputError(what + ": " + e.what());
  }
  CoarseCells out;
  out.bytes = m.Footprints(sub);
  const std::vector<CellId>& view = m.maps[0];
  const std::uint32_t n = std::uint32_t(header().cell_count());
  std::vector<bool> seen(n, false);
  out.of_cell.assign(n, CellId(0));  // an empty cell, never fetched: 0
  for (std::size_t f = 0; f < view.size(); ++f) {
    if (view[f] == kNoCell) continue;
    const std::uint32_t v = view[f].value();
    const CellId c = sub.coarse_of_fine[f];
    if (seen[v] && out.of_cell[v] != c) {
      throw InputError(what + ": '" + cells + "' does not hold whole cells of the replay (" +
                       (m.view_header.subdivision.spec.empty() ? "the captured grid"
                                                               : m.view_header.subdivision.spec) +
                       "): its cells " + std::to_string(out.of_cell[v].value()) + " and " +
                       std::to_string(c.value()) + " share cell " + std::to_string(v) +
                       "; use a subdivision whose boundaries include the replay's");
    }
    seen[v] = true;
    out.of_cell[v] = c;
  }
  return out;
}
const std::string& TraceReader::warning() const { return impl_->warning; }
std::uint64_t TraceReader::file_size() const { return impl_->file.size(); }
std::uint64_t TraceReader::readable_end() const { return impl_->readable_end; }

void TraceReader::ForEachBatch(std::size_t frame_index, const BatchFn& fn) const {
  if (!impl_->view) {
    impl_->ForEachStored(frame_index, fn);
    return;
  }
  RayRegrouper regrouper(impl_->MapOf(frame_index));
  impl_->ForEachStored(frame_index, [&](const RayBatch& b) {
    const RayBatch out = impl_->RegroupIn(regrouper, b, impl_->frames[frame_index].frame);
    if (!out.empty()) fn(out);
  });
}

RayBatch TraceReader::LoadFrame(std::size_t frame_index) const {
  const FrameSummary& s = impl_->Frame(frame_index);
  constexpr std::uint64_t kMaxReserve = std::uint64_t{1} << 24;
  RayBatch all(header().settings.store_t);
  all.Reserve(std::min(s.rays, kMaxReserve), std::min(s.visits, kMaxReserve));
  ForEachBatch(frame_index, [&](const RayBatch& b) { all.AppendRebased(b); });
  return all;
}

std::string TraceReader::ReadEncodedFrame(std::size_t frame_index) const {
  if (impl_->view) {
    throw InputError(impl_->path + ": a regroupable capture opened regrouped has no stored " +
                     "bytes of its regrouped frames (TraceReader::OpenStored)");
  }
  const FrameSummary& s = impl_->Frame(frame_index);
  const FrameSlot slot{frame_index, s.offset, s.offset + s.length, &s};
  return Guarded(
      impl_->path, [&] { return FrameLabel(slot, s.frame); },
      [&] {
        std::string bytes(s.length, '\0');
        impl_->file.ReadAt(s.offset, bytes.data(), bytes.size());
        if (s.stored_hash != 0) {  // the index has the stored bytes' hash: no decoding
          Hash64 h;
          h.AddBytes(bytes.data(), bytes.size());
          if (h.Finish() != s.stored_hash) {
            throw BadData("its " + Str(s.length) +
                          " bytes do not match the index's hash of them (damaged)");
          }
          return bytes;
        }
        FileIn frame(std::move(bytes));  // checked in memory: the file is read once
        CheckEncodedFrame(frame, {frame_index, 0, s.length, &s});
        return frame.TakeMemory();
      });
}

}  // namespace raycell
