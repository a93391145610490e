// Reader of trace files (docs/design.md §3; the format is documented in traces/trace.capnp).
//
// Open() decodes the header and the index at the end of the file; a frame is then read by
// seeking to its offset, without decoding the others. When the index is missing (a .tmp
// left by an interrupted capture, a truncated file) or damaged, Open() scans the zstd frames
// from the start instead, keeps every complete, valid frame before the first damage and
// says so in warning().
//
// Everything read is checked: zstd and frame checksums, message sizes against a fixed limit
// and the file size, and the content (parent < id, spawn < the parent's visit count, cells
// < cell count, every column holding exactly the values its rays use, rays and visits of a
// batch within the format's limits, totals consistent with the frame's summary). Every
// failure is an InputError whose message names the file and the frame (or the header or
// index) and what was wrong, e.g.
//   "out/a.rct: frame 150 (#3, offset 12345): zstd: Restored data doesn't match checksum".
// Const methods read with pread and keep no shared state, so several threads may read
// frames of one TraceReader at once.
//
// Its parts, internal to traces/: the file, its zstd frames and their messages
// (trace_file.h), decoding and checking the header and the frames (trace_decode.h), and a
// regroupable capture's regrouped view (regrouped_view.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "traces/ray_batch.h"
#include "traces/subdivision.h"
#include "traces/trace_header.h"

namespace raycell {

// A subdivision of a regroupable capture's stored fine grid, with what a trace knows of it
// (TraceReader::SubdivideFineGrid).
struct FineSubdivision {
  // Its boxes and, per fine cell, the cell holding it.
  Subdivision subdivision;
  // Per cell of it, the bytes of its fine cells' leaves, each leaf once (0: an empty cell).
  std::vector<std::uint64_t> footprints;
  // Per fine cell, its cell in the reader's view (kNoCell: an empty one); TraceReader::CellMap.
  std::vector<CellId> view_of_fine;
};

class TraceReader {
 public:
  // Throws InputError when the file cannot be opened or its header is unreadable.
  //
  // A regroupable capture (`raycell record --regroupable`; docs/design.md §1 "Subdivisions")
  // is shown regrouped: into the subdivision `cells` names (a SPEC, traces/subdivision.h), or,
  // with `cells` empty, into its own grid (its visits to empty cells dropped), as a capture
  // recorded on those cells would be. header() and frames() are then the regrouped trace's
  // (its cells, footprints and subdivision; frame totals and checksums of the regrouped rays:
  // Open reads every frame once to make them, and once more for kd:N:work's weights), and
  // ForEachBatch and LoadFrame regroup as they read. InputError for a `cells` given with a
  // trace that is not regroupable, a bad SPEC, or a subdivision the fine grid cannot make.
  static TraceReader Open(const std::string& path, const std::string& cells = "");
  // The trace as stored, a regroupable capture with its visits to empty cells (for `trace
  // regroup` and `trace concat`).
  static TraceReader OpenStored(const std::string& path);
  // The same for a trace held in memory; `name` stands for the path in messages.
  static TraceReader OpenBytes(std::string bytes, const std::string& name);

  TraceReader(TraceReader&&) noexcept;
  TraceReader& operator=(TraceReader&&) noexcept;
  ~TraceReader();

  const std::string& path() const;
  // Whether a regroupable capture is shown regrouped (Open), not as stored.
  bool regrouped() const;
  // When regrouped: per stored cell, its cell in the view (kNoCell: an empty one) in frame
  // `frame_index` (RayRegrouper's map).
  const std::vector<CellId>& CellMap(std::size_t frame_index) const;
  // The cells' footprints in frame `frame_index`: a dynamic subdivision's own (its cells are
  // other boxes every frame; header() has each cell's largest), else header().footprints.
  const std::vector<std::uint64_t>& FrameFootprints(std::size_t frame_index) const;
  // A subdivision of a regroupable capture's stored fine grid beside this view (Open; what a
  // replay's levels of coarser cells are made from, docs/design.md §2): the subdivision `spec`
  // makes of the fine grid (Subdivide with the fine cells' data, as Open with --cells SPEC:
  // the union footprints of their leaves, every frame's samples for kd:N:work and kd:N:sqrt,
  // the crossings for grid:N:crossings; dynamic:N: frame 0's), each of its cells' footprint
  // (its fine cells' leaves, each once) and the view's own fine-to-cell map. Only when
  // regrouped() and the view's cells stay the same over the frames (header().subdivision is
  // not dynamic; a RAYCELL_CHECK). InputError (Subdivide's) when the fine grid cannot make
  // `spec`, the reader's own when a frame read for its weights is damaged.
  FineSubdivision SubdivideFineGrid(const SubdivisionSpec& spec) const;
  const TraceHeader& header() const;
  // Summaries of the readable frames in file order, with their offset and length.
  const std::vector<FrameSummary>& frames() const;
  // Empty when the index was read; otherwise why it was not and what the scan recovered.
  const std::string& warning() const;
  std::uint64_t file_size() const;
  // Where the part of the file Open() could read ends: file_size() when the index was read;
  // otherwise the end of the last complete, valid frame the scan kept (or of the header).
  // What follows (a partial or damaged frame, the frames after it, the index) was not read.
  std::uint64_t readable_end() const;

  // Calls `fn` with each batch of frame `frame_index` (an index into frames()) in ray order.
  // Batch ray ids are frame-local; parents may point into earlier batches. Only one batch is
  // held in memory. Damage may be detected after some batches were delivered (the zstd and
  // frame checksums are checked at the end): an InputError means the frame is bad.
  void ForEachBatch(std::size_t frame_index, const std::function<void(const RayBatch&)>& fn) const;
  // The whole frame as one batch (first_id 0), returned only when fully verified.
  RayBatch LoadFrame(std::size_t frame_index) const;
  // The frame's zstd frame as stored, for copying it into another trace without decoding its
  // rays (`raycell trace concat`). Checked first: where the index has the stored bytes' hash
  // (IndexEntry.storedHash), against it, at the speed of reading; else at the speed of
  // decompression: exactly one zstd frame, of the index's length, with a content checksum that
  // holds, holding Records that are batches followed by one frameEnd equal to the index's
  // summary. (The rays are not decoded: ForEachBatch checks them.) InputError naming the file
  // and frame if not, or when the trace is shown regrouped.
  std::string ReadEncodedFrame(std::size_t frame_index) const;

 private:
  struct Impl;
  explicit TraceReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace raycell
