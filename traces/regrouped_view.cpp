#include "traces/regrouped_view.h"

#include <algorithm>
#include <optional>
#include <utility>

#include "base/check.h"
#include "traces/auto_cells.h"
#include "traces/format.h"
#include "traces/frame_checksum.h"

namespace raycell {
namespace {

// The map of a subdivision (null: the fine grid itself) whose cells have `fp` as footprints:
// per fine cell, its cell, kNoCell where that is empty.
std::vector<CellId> ViewMapOf(const Subdivision* sub, const std::vector<std::uint64_t>& fp,
                              std::size_t fine_cells) {
  std::vector<CellId> m(fine_cells);
  for (std::size_t f = 0; f < fine_cells; ++f) {
    const CellId c = sub ? sub->coarse_of_fine[f] : CellId(std::uint32_t(f));
    m[f] = fp[c.value()] == 0 ? kNoCell : c;
  }
  return m;
}

}  // namespace

RegroupedView::RegroupedView(const std::string& path, const TraceHeader& stored,
                             const std::vector<FrameSummary>& frames, StoredFrames read,
                             const std::string& cells)
    : path_(path), stored_(stored), stored_frames_(frames), read_(std::move(read)) {
  const TraceHeader& h = stored_;
  header_ = h;
  header_.regroupable = false;
  header_.leaves = {};
  const std::size_t fine_cells = h.cell_count();
  if (cells.empty()) {  // the captured grid: only the visits to empty cells dropped
    maps_.push_back(ViewMapOf(nullptr, h.footprints, fine_cells));
  } else {
    const std::string what = "--cells '" + cells + "'";
    const SubdivisionSpec spec = ParseSubdivisionSpec(cells, what);
    FineCells fine = Fine(spec);
    const bool dynamic = spec.per_frame();
    std::optional<AutoCells> auto_cells;
    if (spec.kind == SubdivisionSpec::Kind::kAuto) auto_cells.emplace(spec.cells, fine, what);
    header_.subdivision.spec = spec.ToString();
    header_.subdivision.fine = h.cells;
    header_.footprints.clear();
    const std::size_t subdivisions = dynamic ? frames.size() : 1;
    if (dynamic && std::uint64_t{spec.cells} * subdivisions > kTraceMaxBoxes) {
      throw InputError(what + ": " + std::to_string(spec.cells) + " cells in each of " +
                       std::to_string(subdivisions) +
                       " frames exceed the trace format's limit of " +
                       std::to_string(kTraceMaxBoxes) + " boxes (kTraceMaxBoxes)");
    }
    for (std::size_t i = 0; i < std::max<std::size_t>(subdivisions, 1); ++i) {
      if (spec.kind == SubdivisionSpec::Kind::kDynamic && i > 0) fine.samples = FineSamples(i - 1);
      const Subdivision sub = auto_cells ? auto_cells->next() : Subdivide(spec, fine);
      if (auto_cells && i < frames.size()) {  // auto:N learns frame i for the frames after it
        read_(i, [&](const RayBatch& b) {
          try {
            auto_cells->AddBatch(b);
          } catch (const InputError& e) {
            throw InputError(path_ + ": frame " + std::to_string(frames[i].frame) +
                             ": cannot regroup: " + e.what());
          }
        });
        auto_cells->EndFrame();
      }
      const std::vector<std::uint64_t> fp = Footprints(sub);
      maps_.push_back(ViewMapOf(&sub, fp, fine_cells));
      if (dynamic) {
        header_.subdivision.frame_footprints.insert(header_.subdivision.frame_footprints.end(),
                                                    fp.begin(), fp.end());
      }
      header_.subdivision.boxes.insert(header_.subdivision.boxes.end(), sub.boxes.begin(),
                                       sub.boxes.end());
      if (header_.footprints.empty()) header_.footprints.assign(fp.size(), 0);
      for (std::size_t c = 0; c < fp.size(); ++c) {  // a dynamic one: the largest
        header_.footprints[c] = std::max(header_.footprints[c], fp[c]);
      }
      header_.cells = spec.kind == SubdivisionSpec::Kind::kUniform
                          ? spec.grid
                          : std::array<std::uint32_t, 3>{sub.cells(), 1, 1};
    }
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    RayRegrouper regrouper(CellMap(i));
    FrameAccumulator sum(frames[i].frame, h.settings.store_t);
    read_(i, [&](const RayBatch& b) {
      const RayBatch out = RegroupIn(regrouper, b, frames[i].frame);
      for (std::size_t r = 0; r < out.size(); ++r) sum.AddRay(out.ray(r));
    });
    FrameSummary s = sum.Summary();
    s.offset = frames[i].offset;
    s.length = frames[i].length;
    s.stored_hash = frames[i].stored_hash;
    frames_.push_back(s);
  }
}

void RegroupedView::ForEachBatch(std::size_t i, const BatchFn& fn) const {
  RayRegrouper regrouper(CellMap(i));
  read_(i, [&](const RayBatch& b) {
    const RayBatch out = RegroupIn(regrouper, b, stored_frames_[i].frame);
    if (!out.empty()) fn(out);
  });
}

FineSubdivision RegroupedView::SubdivideFineGrid(const SubdivisionSpec& spec) const {
  RAYCELL_CHECK(maps_.size() == 1 && !header_.subdivision.dynamic());
  FineSubdivision out;
  out.subdivision = Subdivide(spec, Fine(spec));
  out.footprints = Footprints(out.subdivision);
  out.view_of_fine = maps_[0];
  return out;
}

RayBatch RegroupedView::RegroupIn(RayRegrouper& regrouper, const RayBatch& b,
                                  std::int32_t frame) const {
  try {
    return regrouper.Regroup(b);
  } catch (const InputError& e) {
    throw InputError(path_ + ": frame " + std::to_string(frame) + ": cannot regroup: " + e.what());
  }
}

std::vector<std::uint64_t> RegroupedView::FineSamples(std::size_t i) const {
  std::vector<std::uint64_t> samples(stored_.cell_count(), 0);
  auto add = [&](const RayBatch& b) {
    for (std::size_t v = 0; v < b.visit_count(); ++v) {
      samples[b.cells()[v].value()] += b.samples()[v];
    }
  };
  if (i != std::size_t(-1)) {
    read_(i, add);
  } else {
    for (std::size_t f = 0; f < stored_frames_.size(); ++f) read_(f, add);
  }
  return samples;
}

FineCells RegroupedView::Fine(const SubdivisionSpec& spec) const {
  FineCells fine;
  fine.grid = stored_.cells;
  fine.union_footprint = [this](const std::vector<std::uint32_t>& c) {
    return stored_.leaves.UnionBytes(c);
  };
  if (spec.kind == SubdivisionSpec::Kind::kKdWork || spec.kind == SubdivisionSpec::Kind::kKdSqrt) {
    fine.samples = FineSamples(std::size_t(-1));
  }
  if (spec.kind == SubdivisionSpec::Kind::kGridCrossings) {
    fine.crossings = FineCrossings();
    fine.has_crossings = true;
  }
  return fine;
}

// Each ray's steps from one non-empty fine cell to its next, |dx|, |dy|, |dz| of their
// coordinates (the visits to empty cells that a regroupable capture keeps are skipped, so
// that the counts are those of the rays as any command reads them).
std::array<std::uint64_t, 3> RegroupedView::FineCrossings() const {
  const auto g = stored_.cells;
  const auto at = [&](std::uint32_t c) {
    return std::array<std::uint32_t, 3>{c % g[0], c / g[0] % g[1], c / g[0] / g[1]};
  };
  std::array<std::uint64_t, 3> n{};
  auto add = [&](const RayBatch& b) {
    for (std::size_t r = 0; r < b.size(); ++r) {
      std::optional<std::array<std::uint32_t, 3>> last;
      for (std::size_t v = b.visit_begin(r); v < b.visit_end(r); ++v) {
        const std::uint32_t c = b.cells()[v].value();
        if (stored_.footprints[c] == 0) continue;
        const std::array<std::uint32_t, 3> now = at(c);
        for (int a = 0; last && a < 3; ++a) {
          n[a] += now[a] > (*last)[a] ? now[a] - (*last)[a] : (*last)[a] - now[a];
        }
        last = now;
      }
    }
  };
  for (std::size_t f = 0; f < stored_frames_.size(); ++f) read_(f, add);
  return n;
}

std::vector<std::uint64_t> RegroupedView::Footprints(const Subdivision& sub) const {
  std::vector<std::uint64_t> fp(sub.cells());
  for (std::uint32_t c = 0; c < sub.cells(); ++c) {
    fp[c] = stored_.leaves.UnionBytes(FineCellsOf(sub.boxes[c], stored_.cells));
  }
  return fp;
}

}  // namespace raycell
