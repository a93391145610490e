// A regroupable capture shown regrouped (internal to traces/: TraceReader::Open's view, not
// for its users; docs/design.md §1 "The regroupable capture", "Regrouping"). Built from the
// stored capture's header and frames, it holds the view's header (its cells, footprints and
// subdivision), its frames (totals and checksums of the regrouped rays), per frame the map of
// fine cells to the view's cells, and regroups a stored frame's batches as they are read.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "traces/cell_id.h"
#include "traces/ray_batch.h"
#include "traces/regroup.h"
#include "traces/subdivision.h"
#include "traces/trace_header.h"
#include "traces/trace_reader.h"

namespace raycell {

class RegroupedView {
 public:
  using BatchFn = std::function<void(const RayBatch&)>;
  // Calls its BatchFn with each batch of stored frame i (an index into the stored frames), as
  // stored, in ray order.
  using StoredFrames = std::function<void(std::size_t, const BatchFn&)>;

  // The view of the regroupable capture `path` (its header `stored`, its readable frames
  // `frames`, read by `read`; all three must outlive the view) regrouped into the subdivision
  // `cells` names (a SPEC), or, with `cells` empty, into its own grid (its visits to empty
  // cells dropped). Reads every frame once, and once more for kd:N:work's, kd:N:sqrt's,
  // dynamic's and grid:N:crossings's weights. InputError "--cells 'SPEC': ..." for a bad SPEC
  // or a subdivision the fine grid cannot make, "<path>: frame N: cannot regroup: ..." for a
  // frame that cannot be regrouped, and the reader's own for a damaged one.
  RegroupedView(const std::string& path, const TraceHeader& stored,
                const std::vector<FrameSummary>& frames, StoredFrames read,
                const std::string& cells);

  const TraceHeader& header() const { return header_; }
  const std::vector<FrameSummary>& frames() const { return frames_; }
  // Per fine cell, its cell in the view (kNoCell: an empty one) in frame i (i < frames()).
  const std::vector<CellId>& CellMap(std::size_t i) const {
    return maps_[maps_.size() == 1 ? 0 : i];
  }
  // Calls `fn` with each batch of frame i (i < frames()) regrouped, in ray order (batches
  // left empty skipped).
  void ForEachBatch(std::size_t i, const BatchFn& fn) const;
  // See TraceReader::SubdivideFineGrid.
  FineSubdivision SubdivideFineGrid(const SubdivisionSpec& spec) const;

 private:
  // The batch regrouped; an InputError names the file and frame.
  RayBatch RegroupIn(RayRegrouper& regrouper, const RayBatch& b, std::int32_t frame) const;
  // Samples per fine cell of frame i, or of every frame (i = npos).
  std::vector<std::uint64_t> FineSamples(std::size_t i) const;
  // What a subdivision of the stored fine grid is made from; kd:N:work's samples over every
  // frame.
  FineCells Fine(const SubdivisionSpec& spec) const;
  // grid:N:crossings's weights (FineCells::crossings), over every frame.
  std::array<std::uint64_t, 3> FineCrossings() const;
  // Per cell of `sub`, the bytes of its fine cells' leaves, each once.
  std::vector<std::uint64_t> Footprints(const Subdivision& sub) const;

  std::string path_;
  const TraceHeader& stored_;
  const std::vector<FrameSummary>& stored_frames_;
  StoredFrames read_;
  TraceHeader header_;
  std::vector<FrameSummary> frames_;
  // Per fine cell, its cell in the view (kNoCell: an empty one); one map for every frame, or
  // one per frame (a dynamic subdivision).
  std::vector<std::vector<CellId>> maps_;
};

}  // namespace raycell
