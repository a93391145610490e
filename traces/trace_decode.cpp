#include "traces/trace_decode.h"

#include <capnp/message.h>
#include <capnp/serialize.h>

#include <algorithm>
#include <cstring>
#include <iterator>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "base/check.h"
#include "base/format.h"
#include "traces/columns.h"
#include "traces/format.h"
#include "traces/frame_checksum.h"
#include "traces/path_coder.h"
#include "traces/sample_coder.h"
#include "traces/subdivision.h"
#include "traces/trace.capnp.h"

namespace raycell {
namespace trace_io {
namespace {

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
  const bool dynamic = spec.per_frame();
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

}  // namespace

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

namespace {

// ---- Batches -----------------------------------------------------------------------------

struct BatchColumns {
  capnp::List<std::uint8_t>::Reader heads;
  ColumnReader head_runs, parents, spawns, pixels, primary_paths, secondary_paths;
  ZeroRunColumnReader primary_samples, secondary_samples, shadow_samples;
  capnp::List<float>::Reader t_enter, t_exit;
  std::optional<SampleDecoder> sample_code;  // version 6 and later
  std::optional<PathDecoder> path_code;      // version 8

  // `table`: a version 7 batch with Batch.visitTable (its contexts are SampleContext::kCount7);
  // `v8`: a batch of version 8 (its new paths in Batch.pathCode, on `grid`, unless empty).
  BatchColumns(schema::Batch::Reader b, bool v6, bool table, bool v8, const CellGrid& grid)
      : heads(b.getHeads()),
        head_runs(b.getHeadRuns(), heads.size(), "headRuns"),
        parents(b.getParents(), "parents"),
        spawns(b.getSpawns(), "spawns"),
        pixels(b.getPixels(), "pixels"),
        primary_paths(b.getPrimaryPaths(), "primaryPaths"),
        secondary_paths(b.getSecondaryPaths(), "secondaryPaths"),
        primary_samples(b.getPrimarySamples(), "primarySamples"),
        secondary_samples(b.getSecondarySamples(), "secondarySamples"),
        shadow_samples(b.getShadowSamples(), "shadowSamples"),
        t_enter(b.getTEnter()),
        t_exit(b.getTExit()) {
    const capnp::Data::Reader code = b.getSampleCode();
    if (v6) {
      sample_code.emplace(code.begin(), code.size(),
                          table ? SampleContext::kCount7 : SampleContext::kCount);
    } else if (code.size() != 0) {
      throw BadData("sampleCode in a batch of format version 5 or earlier");
    }
    const capnp::Data::Reader paths = b.getPathCode();
    if (v8 && paths.size() != 0) {
      path_code.emplace(paths.begin(), paths.size(), grid);
    } else if (paths.size() != 0) {
      throw BadData("pathCode in a batch of format version 7 or earlier");
    }
  }

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
    shadow_samples.Finish();
    if (sample_code) sample_code->Finish();
    if (path_code) path_code->Finish();
  }
};

// Decodes the batches of one frame in order, validating them against each other and the
// header, and accumulates the frame's summary.
class FrameDecoder {
 public:
  FrameDecoder(const TraceHeader& header, std::int32_t frame, const FrameSummary* expected)
      : header_(header),
        acc_(frame, header.settings.store_t),
        frame_(frame),
        expected_(expected),
        v5_(header.format_version >= 5),
        v6_(header.format_version >= 6),
        v7_(header.format_version >= 7),
        v8_(header.format_version >= 8) {}

  void Decode(schema::Batch::Reader b, RayBatch& out) {
    if (b.getFrame() != frame_) throw BadData("batch of frame " + Str(b.getFrame()));
    if (b.getFirstId() != acc_.rays()) {
      throw BadData("batch starts at ray " + Str(b.getFirstId()) + ", expected " +
                    Str(acc_.rays()));
    }
    if (b.getVisitTable() && !v7_) {
      throw BadData("visitTable in a batch of format version 6 or earlier");
    }
    use_table_ = v7_ && b.getVisitTable();
    BatchColumns c(b, v6_, use_table_, v8_, header_.cells);
    if (use_table_) {
      if (!table_) table_ = std::make_unique<VisitTable>();
      table_->Clear();
    }
    CheckTimeLengths(c);
    const std::size_t rays = c.RayCount(b);
    out.Clear();
    out.set_first_id(b.getFirstId());
    out.Reserve(rays, header_.settings.store_t ? c.t_enter.size() : 0);
    last_primary_ = kNone;
    for (auto& starts : group_start_) std::fill(std::begin(starts), std::end(starts), kNone);
    last_non_shadow_ = kNoParent;
    prev_x_ = prev_y_ = 0;
    ordinals_.clear();
    for (auto& by_parent : corresponding_) {
      for (std::vector<std::size_t>& slots : by_parent) slots.clear();
    }
    last_first_cell_ = 0;
    corresponding_rule_ = v5_ && b.getReferenceRule() == kReferenceCorresponding;
    if (b.getReferenceRule() > (v5_ ? kReferenceCorresponding : kReferenceSibling)) {
      throw BadData("bad reference rule " + Str(unsigned{b.getReferenceRule()}));
    }
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
    std::size_t ref;
    if (v5_) {
      ordinals_.push_back(sibling && out.kinds()[i - 1] == kind ? ordinals_.back() + 1 : 0);
      ref = corresponding_rule_ ? ReferenceRayV5(out, kind, parent, i, sibling)
                                : ReferenceRay(out, kind, parent, i, sibling);
    } else {
      ref = ReferenceRay(out, kind, parent, i, sibling);
    }
    out.BeginRay(kind, parent, spawn, prev_x_, prev_y_);
    if (v5_) {
      DecodeVisitsV5(c, head, id, kind, ref, out);
    } else {
      DecodeVisits(c, head, id, primary, ref, out);
    }
    const std::size_t count = out.visit_end(i) - out.visit_begin(i);
    if (count > 0) last_first_cell_ = out.cells()[out.visit_begin(i)].value();
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

  // Version 5, the corresponding rule: the reference ray of ray i (see "Column encoding" in
  // trace.capnp), or kNone. Also records ray i as the corresponding ray of its kind, parent
  // kind and ordinal.
  std::size_t ReferenceRayV5(const RayBatch& out, RayKind kind, RayId parent, std::size_t i,
                             bool sibling) {
    if (parent == kNoParent) return last_primary_;
    if (parent >= out.first_id()) {
      const auto parent_kind = static_cast<int>(out.kinds()[parent - out.first_id()]);
      std::vector<std::size_t>& slots = corresponding_[static_cast<int>(kind)][parent_kind];
      if (slots.size() <= ordinals_[i]) slots.resize(ordinals_[i] + 1, kNone);
      const std::size_t found = std::exchange(slots[ordinals_[i]], i);
      if (found != kNone) return found;
    }
    return sibling ? i - 1 : kNone;
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

  // What every version reads before a ray's visits: whether it has a path of its own (else it
  // repeats its reference's), its reference's visits in `out`, and its visit count, checked.
  struct PathHead {
    bool new_path = false;
    std::size_t ref_begin = 0, ref_count = 0;
    std::uint64_t count = 0;
  };
  // `paths` is null in version 8, where a new path's count is its cells' (path_, read first).
  PathHead ReadPathHead(ColumnReader* paths, std::uint8_t head, RayId id, std::size_t ref,
                        const RayBatch& out) const {
    PathHead h;
    h.new_path = head & kHeadNewPath;
    if (!h.new_path && ref == kNone) {
      throw BadData("ray " + Str(id) + ": repeats the path of a reference ray it does not have");
    }
    h.ref_begin = ref == kNone ? 0 : out.visit_begin(ref);
    h.ref_count = ref == kNone ? 0 : out.visit_end(ref) - h.ref_begin;
    h.count = !h.new_path ? h.ref_count : paths ? paths->Next() : path_.size();
    if (h.count > kTraceMaxRayVisits || h.count > kTraceMaxBatchVisits - out.visit_count()) {
      throw BadData("ray " + Str(id) + ": too many visits");
    }
    return h;
  }

  // Adds the visits of ray `id` (the last ray of `out`); `ref` is its reference ray.
  void DecodeVisits(BatchColumns& c, std::uint8_t head, RayId id, bool primary, std::size_t ref,
                    RayBatch& out) {
    ColumnReader& paths = primary ? c.primary_paths : c.secondary_paths;
    ZeroRunColumnReader& samples = primary ? c.primary_samples : c.secondary_samples;
    const PathHead h = ReadPathHead(&paths, head, id, ref, out);
    const bool new_path = h.new_path;
    const std::size_t ref_begin = h.ref_begin, ref_count = h.ref_count;
    const std::uint64_t count = h.count;
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

  // Version 5: adds the visits of ray `id` (the last ray of `out`, index i in the batch);
  // `ref` is its reference ray (see "Paths" and "Samples" in trace.capnp).
  void DecodeVisitsV5(BatchColumns& c, std::uint8_t head, RayId id, RayKind kind, std::size_t ref,
                      RayBatch& out) {
    const bool primary = kind == RayKind::kPrimary;
    ColumnReader& paths = primary ? c.primary_paths : c.secondary_paths;
    ZeroRunColumnReader& samples = primary                    ? c.primary_samples
                                   : kind == RayKind::kShadow ? c.shadow_samples
                                                              : c.secondary_samples;
    const CellGrid grid = header_.cells;
    const bool coded_path = c.path_code && (head & kHeadNewPath);
    if (coded_path) ReadCodedPath(c, id, ref, out);
    const PathHead h = ReadPathHead(c.path_code ? nullptr : &paths, head, id, ref, out);
    const bool new_path = h.new_path;
    const std::size_t ref_begin = h.ref_begin, ref_count = h.ref_count;
    const std::uint64_t count = h.count;
    std::uint32_t cell = 0;
    if (new_path && count > 0) cell = PredictedFirstCell(out, ref, ref_begin, ref_count);
    const bool t = header_.settings.store_t;
    std::size_t next = 0;  // the reference's visit after the last matched
    SampleContext context(static_cast<unsigned>(kind), new_path);
    if (use_table_) {
      // The whole path first: a visit's samples are predicted from its step out too.
      path_.resize(count);
      coordinates_.resize(count);
      for (std::uint64_t v = 0; v < count; ++v) {
        cell = coded_path ? path_[v]
               : new_path ? ReadStep(paths, cell, grid)
                          : out.cells()[ref_begin + v].value();
        if (cell == kBadStep) throw BadData("ray " + Str(id) + ": bad cell");
        path_[v] = cell;
        coordinates_[v] = VisitTable::CoordinatesOf(cell, grid);
      }
    }
    const unsigned group = SampleGroup(static_cast<unsigned>(kind));
    // Two loops, the table's and versions 5-6's: one loop with the table's lookup under a
    // branch made every read of a version 5 trace ~10% slower (trace verify of b512).
    for (std::uint64_t v = 0; v < count; ++v) {
      if (use_table_) {
        cell = path_[v];
        const std::size_t end = std::min(ref_count, next + kSampleMatchWindow);
        std::size_t k = next;
        while (k < end && out.cells()[ref_begin + k].value() != cell) ++k;
        const bool matched = k < end;
        const bool last = v + 1 == count;
        const std::uint64_t key =
            VisitTable::KeyOfVisit(group, cell, coordinates_.data(), v, count);
        const std::size_t slot = table_->SlotOf(key);
        std::uint64_t known = 0;
        const bool hit = table_->Find(slot, key, known);
        const SamplePrediction p = PredictSamples(
            matched, matched ? out.samples()[ref_begin + k] : 0, new_path, hit, known);
        const std::uint64_t code =
            c.sample_code->Next(context.Of(p.residual, p.predicted, last, p.predictor));
        std::uint64_t n = code;
        if (p.residual) {
          n = ApplyDelta(p.predicted, code, "samples");
        } else if (code > 0xFFFFFFFF) {
          throw BadData("ray " + Str(id) + ": bad samples");
        }
        if (matched) next = k + 1;
        context.Next(p.residual, code, n);
        table_->Set(slot, key, static_cast<std::uint32_t>(n));
        const std::size_t at = out.visit_count();
        if (t && at >= c.t_enter.size()) throw BadData("t columns have bad length");
        out.AddVisit(CellId(cell), static_cast<std::uint32_t>(n), t ? c.t_enter[at] : 0.f,
                     t ? c.t_exit[at] : 0.f);
        continue;
      }
      cell = coded_path ? path_[v]
             : new_path ? ReadStep(paths, cell, grid)
                        : out.cells()[ref_begin + v].value();
      if (cell == kBadStep) throw BadData("ray " + Str(id) + ": bad cell");
      const std::size_t end = std::min(ref_count, next + kSampleMatchWindow);
      std::size_t k = next;
      while (k < end && out.cells()[ref_begin + k].value() != cell) ++k;
      const bool matched = k < end;
      const std::uint64_t predicted = matched ? out.samples()[ref_begin + k] : 0;
      const std::uint64_t code =
          c.sample_code ? c.sample_code->Next(context.Of(matched, predicted, v + 1 == count))
                        : samples.Next();
      std::uint64_t n = code;
      if (matched) {
        n = ApplyDelta(predicted, code, "samples");
        next = k + 1;
      } else if (code > 0xFFFFFFFF) {
        throw BadData("ray " + Str(id) + ": bad samples");
      }
      context.Next(matched, code, n);
      const std::size_t at = out.visit_count();
      if (t && at >= c.t_enter.size()) throw BadData("t columns have bad length");
      out.AddVisit(CellId(cell), static_cast<std::uint32_t>(n), t ? c.t_enter[at] : 0.f,
                   t ? c.t_exit[at] : 0.f);
    }
  }

  // Version 8: reads the new path of ray `id` (the last ray of `out`, its visits not yet
  // added; `ref` its reference ray) from the batch's pathCode into path_.
  void ReadCodedPath(BatchColumns& c, RayId id, std::size_t ref, RayBatch& out) {
    const std::size_t i = out.size() - 1;
    const std::size_t ref_begin = ref == kNone ? 0 : out.visit_begin(ref);
    const std::size_t ref_count = ref == kNone ? 0 : out.visit_end(ref) - ref_begin;
    const std::uint32_t from = PredictedFirstCell(out, ref, ref_begin, ref_count);
    const unsigned hint = ParentHint(out, out.parents()[i], out.spawns()[i], header_.cells);
    const std::size_t most = std::min(kTraceMaxRayVisits, kTraceMaxBatchVisits - out.visit_count());
    const unsigned group = SampleGroup(static_cast<unsigned>(out.kinds()[i]));
    if (!c.path_code->Next(group, from, hint, out.cells().data() + ref_begin, ref_count, most,
                           path_)) {
      throw BadData("ray " + Str(id) + ": bad path");
    }
  }

  // Version 5: the cell a new path's first step starts from (the last ray of `out` is the
  // one being decoded, its visits not yet added).
  std::uint32_t PredictedFirstCell(const RayBatch& out, std::size_t ref, std::size_t ref_begin,
                                   std::size_t ref_count) const {
    const std::size_t i = out.size() - 1;
    const RayId parent = out.parents()[i];
    if (parent != kNoParent && parent >= out.first_id()) {
      const std::size_t p = parent - out.first_id();
      const std::uint32_t spawn = out.spawns()[i];
      if (spawn < out.visit_end(p) - out.visit_begin(p)) {
        return out.cells()[out.visit_begin(p) + spawn].value();
      }
    }
    if (ref != kNone && ref_count > 0) return out.cells()[ref_begin].value();
    return last_first_cell_;
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
  // Version 5 (see "Column encoding" in trace.capnp): whether the frame is coded so; per ray
  // of the batch, its ordinal; by [kind][kind of its parent][ordinal], the last ray of the
  // batch with them whose parent is in the batch; the first cell of the last ray with a visit.
  bool v5_;
  bool v6_;                            // samples in Batch.sampleCode
  bool v7_;                            // ... predicted from the visit table too
  bool v8_;                            // new paths in Batch.pathCode
  bool use_table_ = false;             // in this batch (Batch.visitTable)
  std::unique_ptr<VisitTable> table_;  // version 7, cleared for every batch
  std::vector<std::uint32_t> path_;    // version 7: the cells of the ray being decoded
  std::vector<VisitTable::Coordinates> coordinates_;  // ... and their coordinates
  std::vector<std::uint32_t> ordinals_;
  std::vector<std::size_t> corresponding_[kRayKindCount][kRayKindCount];
  std::uint32_t last_first_cell_ = 0;
  bool corresponding_rule_ = false;  // the batch's referenceRule is the corresponding rule
};

// ---- Frames ------------------------------------------------------------------------------

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

}  // namespace

std::string FrameLabel(const FrameSlot& slot, std::optional<std::int32_t> number) {
  const std::string where = "offset " + Str(slot.offset);
  if (!number) return "frame #" + Str(slot.ordinal) + " (" + where + ")";
  return "frame " + std::to_string(*number) + " (#" + Str(slot.ordinal) + ", " + where + ")";
}

FrameSummary ReadFrame(const FileIn& file, const std::string& path, const TraceHeader& header,
                       const FrameSlot& slot, const BatchFn* fn) {
  std::optional<FrameReading> reading;
  auto where = [&] { return FrameLabel(slot, reading ? reading->number() : std::nullopt); };
  return Guarded(path, where, [&] {
    reading.emplace(file, header, slot);
    return reading->Run(fn);
  });
}

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

}  // namespace trace_io
}  // namespace raycell
