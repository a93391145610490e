// What a trace file says about the capture as a whole (docs/design.md §3): the scene, its cell
// grid and footprints, the camera of every frame and the renderer's settings. Plain values;
// traces/trace.capnp stores them field by field.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "traces/format.h"
#include "traces/subdivision.h"

namespace raycell {

struct Vec3d {
  double x = 0, y = 0, z = 0;
  bool operator==(const Vec3d& o) const { return x == o.x && y == o.y && z == o.z; }
};

// "x,y,z", each the shortest text that reads back the same double (FormatReal).
std::string FormatVec3(const Vec3d& v);

struct GridInfo {
  std::string name;    // grid name in the .vdb file ("density", "surface", ...)
  std::string role;    // "fog" or "surface"
  std::string source;  // file it came from, or "builtin"
  double voxel_size = 0;
  std::uint64_t leaf_count = 0;
  bool operator==(const GridInfo& o) const {
    return name == o.name && role == o.role && source == o.source && voxel_size == o.voxel_size &&
           leaf_count == o.leaf_count;
  }
};

struct CameraKey {
  std::int32_t frame = 0;  // frame number (e.g. 150 for fluid_data_0150.vdb)
  Vec3d eye, target, up{0, 1, 0};
  double fov_deg = 45;
  bool operator==(const CameraKey& o) const {
    return frame == o.frame && eye == o.eye && target == o.target && up == o.up &&
           fov_deg == o.fov_deg;
  }
};

// How the camera of every frame of a capture is made (docs/design.md §3 "The trace"): the
// whole camera path, of which a capture holds a range of frames (its cameras). Two captures
// with equal paths and settings hold frames of one animation; `raycell trace concat` joins
// them.
struct CameraPathInfo {
  // "still": one camera (eye, target, up, fov) for every frame. "orbit": frame f's eye is
  // `eye` turned by orbit_degrees * (f - first_frame) / frame_count about `up` through
  // `target`, for the path's frames first_frame..first_frame + frame_count - 1. "keyframes":
  // interpolated linearly between `keys` (their frame, eye, target and fov; `up` for all),
  // clamped to the first and last key. Empty: not recorded (files before format version 3,
  // imported traces).
  std::string kind;
  std::int32_t first_frame = 0;
  std::uint32_t frame_count = 0;  // orbit: the path's frames; otherwise 0 (every frame)
  Vec3d eye, target, up{0, 1, 0};
  double fov_deg = 0;
  double orbit_degrees = 0;
  std::vector<CameraKey> keys;  // keyframes only
  bool operator==(const CameraPathInfo& o) const {
    return kind == o.kind && first_frame == o.first_frame && frame_count == o.frame_count &&
           eye == o.eye && target == o.target && up == o.up && fov_deg == o.fov_deg &&
           orbit_degrees == o.orbit_degrees && keys == o.keys;
  }
  bool operator!=(const CameraPathInfo& o) const { return !(*this == o); }
  // One line, e.g. "orbit of 90 degrees over frames 0..7 (eye 0,1.2,4 target 0,0,0 up
  // 0,1,0 fov 40)"; "not recorded" when kind is empty.
  std::string ToString() const;
};

struct RenderSettings {
  std::uint32_t width = 256, height = 256, spp = 1;
  std::uint32_t max_depth = 3;
  double primary_step = 1.0;  // in voxels of the finest fog grid, as vdb_render's --step
  double shadow_step = 3.0;
  double cutoff = 0.005;          // early-termination threshold on transmittance
  bool store_t = false;           // visits carry t_enter/t_exit
  bool single_precision = false;  // the marcher computed in float rather than double
  std::uint32_t zstd_level = 3;
  bool operator==(const RenderSettings& o) const {
    return width == o.width && height == o.height && spp == o.spp && max_depth == o.max_depth &&
           primary_step == o.primary_step && shadow_step == o.shadow_step && cutoff == o.cutoff &&
           store_t == o.store_t && single_precision == o.single_precision &&
           zstd_level == o.zstd_level;
  }
};

// A regroupable capture's leaves (`record --regroupable`; docs/design.md §1 "Subdivisions"):
// the scene's allocated leaf nodes and active tiles that overlap a cell, the bytes of each,
// and per cell the ones it overlaps, so that the footprint of any union of cells counts each
// leaf once. Sparse footprints only: a cell's footprint is the bytes of its leaves.
struct CellLeaves {
  std::vector<std::uint64_t> bytes;   // per leaf
  std::vector<std::uint64_t> begin;   // cell c's leaves are leaves[begin[c]..begin[c + 1])
  std::vector<std::uint32_t> leaves;  // leaf numbers, increasing within each cell
  bool empty() const { return begin.empty(); }
  // The bytes of the leaves of any of `cells` (fine cell numbers), each leaf once.
  std::uint64_t UnionBytes(const std::vector<std::uint32_t>& cells) const;
  bool operator==(const CellLeaves& o) const {
    return bytes == o.bytes && begin == o.begin && leaves == o.leaves;
  }
};

// What the cells of a trace are made of when they are not the uniform grid it was captured
// on: a subdivision of a fine capture (`trace regroup`, or `--cells SPEC` on a fine capture).
struct SubdivisionInfo {
  std::string spec;  // the SPEC (traces/subdivision.h); empty: the uniform grid `cells`
  std::array<std::uint32_t, 3> fine{0, 0, 0};  // the fine grid the boxes are made of
  // Per cell its box of fine cells; `dynamic:N`: per frame the file holds, in frame order,
  // cell_count() boxes each (each frame has its own subdivision).
  std::vector<FineBox> boxes;
  // `dynamic:N` only: per box, that cell's footprint in that frame (footprints are each
  // cell's largest over the frames); empty otherwise.
  std::vector<std::uint64_t> frame_footprints;
  bool empty() const { return spec.empty(); }
  // Whether each frame has its own boxes (`dynamic:N`, `auto:N`).
  bool dynamic() const { return spec.rfind("dynamic:", 0) == 0 || spec.rfind("auto:", 0) == 0; }
  // Per fine cell, its cell in frame `frame` (an index into the trace's frames) of a trace of
  // `cells` cells each frame: the boxes of that frame (`dynamic:N`) or the only ones.
  std::vector<CellId> CellOfFine(std::size_t frame, std::uint32_t cells) const;
  // Whether frames `a` and `b` (indices into the trace's frames) have the same cells: true but
  // for a dynamic subdivision whose boxes differ between them.
  bool SameCells(std::size_t a, std::size_t b, std::uint32_t cells) const;
  bool operator==(const SubdivisionInfo& o) const {
    return spec == o.spec && fine == o.fine && boxes == o.boxes &&
           frame_footprints == o.frame_footprints;
  }
};

struct TraceHeader {
  std::uint32_t format_version = kTraceDefaultVersion;
  std::string producer;  // "raycell 0.1.0"
  std::string scene;     // what --scene was
  std::vector<GridInfo> grids;
  Vec3d box_min, box_max;  // world-space scene box that the cells split
  std::array<std::uint32_t, 3> cells{2, 2, 2};
  std::vector<std::uint64_t> footprints;  // bytes per cell, cell = x + nx*(y + ny*z)
  std::string footprint_mode = "sparse";
  std::vector<CameraKey> cameras;  // one per frame the capture holds, in frame order
  CameraPathInfo path;             // the whole camera path; cameras are a range of it
  RenderSettings settings;
  // A fine capture that any coarser subdivision can be made of (`record --regroupable`,
  // format version 4): its rays also visit the empty cells they cross (samples 0), and
  // `leaves` holds each cell's leaves. Readers show it as the captured grid unless asked for
  // another subdivision (TraceReader::Open).
  bool regroupable = false;
  CellLeaves leaves;            // regroupable only
  SubdivisionInfo subdivision;  // the cells' shapes when not the uniform grid `cells`
  std::uint32_t cell_count() const { return cells[0] * cells[1] * cells[2]; }
  // Whether the volume changes from frame to frame: a sequence of files, one per frame (the
  // recorder's --scene pattern with '%'). The trace keeps one footprint per cell, the largest
  // over the frames, not which cells changed: warm memory keeps nothing between the frames of
  // such a capture (docs/design.md §2 "Memory").
  bool volume_changes() const { return scene.find('%') != std::string::npos; }
  // Whether a cell is a different box from one frame to the next (a dynamic subdivision):
  // warm memory carries what it held over through the fine cells (replay/memory.h CarryOver).
  bool cells_change() const { return subdivision.dynamic(); }
  bool operator==(const TraceHeader& o) const {
    return format_version == o.format_version && producer == o.producer && scene == o.scene &&
           grids == o.grids && box_min == o.box_min && box_max == o.box_max && cells == o.cells &&
           footprints == o.footprints && footprint_mode == o.footprint_mode &&
           cameras == o.cameras && path == o.path && settings == o.settings &&
           regroupable == o.regroupable && leaves == o.leaves && subdivision == o.subdivision;
  }
};

// Per-frame totals, stored at the end of each frame and in the index.
struct FrameSummary {
  std::int32_t frame = 0;
  std::uint64_t rays = 0, visits = 0, samples = 0;
  std::array<std::uint64_t, 4> rays_by_kind{};  // indexed by RayKind
  std::uint64_t checksum = 0;                   // of the frame's rays, see trace.capnp
  std::uint64_t offset = 0, length = 0;         // byte range of the frame's zstd frame
  // hash64 of those stored bytes (IndexEntry.storedHash); 0: not recorded.
  std::uint64_t stored_hash = 0;
  bool operator==(const FrameSummary& o) const {
    return frame == o.frame && rays == o.rays && visits == o.visits && samples == o.samples &&
           rays_by_kind == o.rays_by_kind && checksum == o.checksum;
  }
};

}  // namespace raycell
