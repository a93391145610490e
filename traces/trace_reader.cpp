#include "traces/trace_reader.h"

#include <capnp/message.h>
#include <capnp/serialize.h>

#include <algorithm>
#include <cstring>
#include <optional>
#include <utility>

#include "base/check.h"
#include "base/hash.h"
#include "traces/format.h"
#include "traces/regrouped_view.h"
#include "traces/trace.capnp.h"
#include "traces/trace_decode.h"
#include "traces/trace_file.h"

namespace raycell {
namespace {

using trace_io::BadData;
using trace_io::BatchFn;
using trace_io::FileIn;
using trace_io::FrameSlot;
using trace_io::Guarded;
using trace_io::Str;

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
    hash = trace_io::LoadU64(trailer);
    length = trace_io::LoadU64(trailer + 8);
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
  capnp::FlatArrayMessageReader message(words, trace_io::MessageOptions());
  return ToSummaries(message.getRoot<schema::Index>(), header, header_length, where.frame_offset);
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
        [&] { return trace_io::ReadHeader(file, header_length); });
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
        found.push_back(trace_io::ReadFrame(file, path, header,
                                            {found.size(), pos, file.size(), nullptr}, nullptr));
      } catch (const InputError& e) {
        stop = e.what();
        break;
      }
      pos += found.back().length;
    }
    return found;
  }

  // A regroupable capture's view (TraceReader::Open); header and frames above stay the
  // stored ones.
  std::optional<RegroupedView> view;
  // A dynamic subdivision's footprints, per frame (empty otherwise): the shown header's
  // subdivision.frame_footprints cut per frame.
  std::vector<std::vector<std::uint64_t>> frame_footprints;

  void MakeView(const std::string& cells) {
    view.emplace(
        path, header, frames, [this](std::size_t i, const BatchFn& fn) { ForEachStored(i, fn); },
        cells);
  }
  const TraceHeader& Shown() const { return view ? view->header() : header; }

  void CutFrameFootprints() {
    const TraceHeader& h = Shown();
    const std::vector<std::uint64_t>& ff = h.subdivision.frame_footprints;
    const std::size_t n = h.cell_count();
    for (std::size_t f = 0; n > 0 && f * n < ff.size(); ++f) {
      frame_footprints.emplace_back(ff.begin() + std::ptrdiff_t(f * n),
                                    ff.begin() + std::ptrdiff_t((f + 1) * n));
    }
  }

  void ForEachStored(std::size_t i, const BatchFn& fn) const {
    const FrameSummary& s = Frame(i);
    trace_io::ReadFrame(file, path, header, {i, s.offset, s.offset + s.length, &s}, &fn);
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
const TraceHeader& TraceReader::header() const { return impl_->Shown(); }
const std::vector<FrameSummary>& TraceReader::frames() const {
  return impl_->view ? impl_->view->frames() : impl_->frames;
}
bool TraceReader::regrouped() const { return impl_->view.has_value(); }
const std::vector<std::uint64_t>& TraceReader::FrameFootprints(std::size_t frame_index) const {
  impl_->Frame(frame_index);
  if (impl_->frame_footprints.empty()) return header().footprints;
  return impl_->frame_footprints[frame_index];
}
const std::vector<CellId>& TraceReader::CellMap(std::size_t frame_index) const {
  RAYCELL_CHECK(impl_->view);
  impl_->Frame(frame_index);
  return impl_->view->CellMap(frame_index);
}
FineSubdivision TraceReader::SubdivideFineGrid(const SubdivisionSpec& spec) const {
  RAYCELL_CHECK(impl_->view);
  return impl_->view->SubdivideFineGrid(spec);
}
const std::string& TraceReader::warning() const { return impl_->warning; }
std::uint64_t TraceReader::file_size() const { return impl_->file.size(); }
std::uint64_t TraceReader::readable_end() const { return impl_->readable_end; }

void TraceReader::ForEachBatch(std::size_t frame_index, const BatchFn& fn) const {
  if (!impl_->view) {
    impl_->ForEachStored(frame_index, fn);
    return;
  }
  impl_->Frame(frame_index);
  impl_->view->ForEachBatch(frame_index, fn);
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
      impl_->path, [&] { return trace_io::FrameLabel(slot, s.frame); },
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
        trace_io::CheckEncodedFrame(frame, {frame_index, 0, s.length, &s});
        return frame.TakeMemory();
      });
}

}  // namespace raycell
