// Streaming writer of trace files (docs/design.md §3; the format is documented in
// traces/trace.capnp). Memory is bounded by one batch of rays plus zstd's window, never by
// the capture. The file is written to `path + ".tmp"` and renamed to `path` by Finish();
// each frame is flushed to the .tmp as a complete zstd frame at EndFrame(), so an
// interrupted capture leaves a .tmp whose finished frames TraceReader can still read.
// The format's constants and limits are in traces/format.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "traces/format.h"
#include "traces/frame_checksum.h"
#include "traces/ray_batch.h"
#include "traces/trace_header.h"

namespace raycell {

// ---- Writer ------------------------------------------------------------------------------

struct TraceWriterOptions {
  // Rays per batch message (at most kTraceMaxBatchRays); 0: the format's default
  // (kTraceBatchRays, or kTraceCodedBatchRays for the range-coded formats 6 and later). Every
  // message stays far below Cap'n Proto's 64 MiB limit.
  std::size_t max_batch_rays = 0;
  // A batch also ends once it holds this many visits (at most kTraceMaxBatchVisits -
  // kTraceMaxRayVisits).
  std::size_t max_batch_visits = std::size_t{1} << 20;
  // Runs of equal footprints per footprints record (at most kTraceFootprintRunsPerRecord).
  std::size_t footprint_runs_per_record = kTraceFootprintRunsPerRecord;
  // Most frames in the file (at most kTraceMaxFrames; lower only to test the limit).
  std::size_t max_frames = kTraceMaxFrames;
  // false (a capture): `path.tmp` appears once the header is written and keeps every ended
  // frame if the writer is dropped. true (`trace concat`): the file has no name until
  // Finish(), so a writer dropped before it leaves nothing.
  bool name_at_finish = false;
  // The format version the header and index say (3..kTraceFormatVersion). Rays are encoded
  // (Append) in 5 (the default, kTraceDefaultVersion: the faster to read) or 6 (samples range
  // coded: smaller files); an earlier one is for copying encoded frames of files of that
  // version (AppendEncodedFrame: `trace concat`).
  std::uint32_t format_version = kTraceDefaultVersion;
};

class TraceWriter {
 public:
  // Opens `path + ".tmp"` and writes the header (format version options.format_version,
  // whatever header.format_version says). The zstd level is header.settings.zstd_level (1..19);
  // visits carry t when header.settings.store_t. Throws InputError naming the path when the file
  // cannot be written or the header exceeds a limit of the format (TraceHeaderProblem in
  // traces/format.h), before anything is written.
  static TraceWriter Create(const std::string& path, const TraceHeader& header,
                            const TraceWriterOptions& options = {});
  // As above with header.settings.zstd_level replaced by `zstd_level`.
  static TraceWriter Create(const std::string& path, const TraceHeader& header, int zstd_level);

  TraceWriter(TraceWriter&&) noexcept;
  TraceWriter& operator=(TraceWriter&&) noexcept;
  // Without Finish(), closes and leaves the .tmp file (holding every ended frame).
  ~TraceWriter();

  // Starts frame number `frame` (a camera's frame number, e.g. 150). InputError when the file
  // already has kTraceMaxFrames (options.max_frames) frames.
  void BeginFrame(std::int32_t frame);
  // Appends rays to the current frame. `rays.first_id()` must equal the number of rays
  // appended to this frame so far (ids are frame-local and continue across calls); parents
  // are frame-local ids smaller than the ray's own, primary rays have spawn 0, a ray has at
  // most kTraceMaxRayVisits visits, cells are < header.cell_count().
  // Violations are bugs of the caller and fail a RAYCELL_CHECK.
  void Append(const RayBatch& rays);
  // Writes the frame's last batch and its frameEnd record, completes its zstd frame and
  // hands it to the OS. Returns its summary (with offset and length in the file).
  FrameSummary EndFrame();
  // Appends a frame already encoded: `encoded` is the complete zstd frame of frame
  // `summary.frame` as another trace stored it, and `summary` its totals and checksum (its
  // offset and length are ignored) and, when not 0, the hash of `encoded` (stored_hash), kept
  // as it is; else the bytes are hashed as they are written. The bytes are written as they
  // are, so the caller checks them first (TraceReader::ReadEncodedFrame, against that hash).
  // Returns the summary with offset and length in this file. InputError as BeginFrame.
  FrameSummary AppendEncodedFrame(const FrameSummary& summary, const std::string& encoded);
  // Writes the index, fsyncs, closes and renames the .tmp file to `path`.
  void Finish();

  const std::string& path() const;
  std::string tmp_path() const { return path() + ".tmp"; }
  std::size_t frames_written() const;

 private:
  struct Impl;
  explicit TraceWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace raycell
