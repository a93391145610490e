// The scene's cell grid and the traversal of a ray through it (docs/design.md §1 "Scene and
// cells", "Rays and visits").
//
// CellGrid: a world-space box [lo, hi] split uniformly into nx*ny*nz cells,
// cell = x + nx*(y + ny*z). Cell planes along an axis are lo + k*(hi-lo)/n for k < n, and
// exactly hi for k = n; a cell owns its lower planes (plane k belongs to cell k), and the
// last cell also owns hi.
//
// CellDDA: the cells a ray crosses, one segment at a time, modelled on pbrt-v4's
// DDAMajorantIterator. Crossing parameters are computed from each plane's position, never
// accumulated. Crossings whose parameters agree up to rounding (a ray through an edge or a
// corner, or leaving the box there) are taken together, so the ray steps diagonally and no
// sliver segment appears. "Up to rounding": each crossing parameter is uncertain by 16 ulps
// of the coordinates on its axis divided by the direction's component there; two crossings
// are together when they differ by less than the sum of their uncertainties, and taking
// them together never moves the ray by more than 1e-3 of a cell.
//
// Semantics of the edge cases:
//  - The box is closed. A ray lying in a face of the box (or along an edge) is inside it
//    and visits the cells on the inner side. A ray lying in an interior cell plane visits
//    the cells above the plane (the plane's owner). A ray starting on a cell plane or on the
//    box surface starts in the cell it moves into; a direction component of +-0 means
//    parallel, any other one (even denormal) means moving to that side.
//  - A ray whose chord through box ∩ [tmin, tmax] has length 0 (it only touches the box,
//    points away from it, starts on its surface pointing out, or tmin >= tmax) yields no
//    segment.
//  - Direction (0,0,0), a non-finite origin or direction, or a NaN tmin/tmax is an
//    InputError. So is a chord that is unbounded (a finite t range was not given and the
//    direction is so small that t overflows).
//  - Forced start cell (spawned rays): the ray starts at tmin (which must be finite), not at
//    the box entry, and the first segment is always the given cell, from tmin to where the
//    ray leaves that cell (clamped to [tmin, min(tmax, box exit)]). It is the one segment
//    that may have zero length: when the start point lies on the face the ray leaves by,
//    or when the ray leaves the box right away. A start point outside the given cell by at
//    most 1e-6 of the box's extent on each axis (rounding; a fraction of the box, not of a
//    cell, so that nested grids decide alike) counts as inside it. A start point farther
//    out (a ray spawned half a voxel off a surface) is reached at once: the first segment
//    is the given cell with zero length, and the ray goes on from the cell holding its
//    start point as if it had no start cell, but on the axes where the point is within that
//    margin, where it keeps the given cell's index. When that cell is the given one again
//    the two are one segment; when the ray only enters the box later, the given cell's
//    segment lasts until it does.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "traces/ray_batch.h"
#include "traces/trace_header.h"

namespace raycell {

// Axis-aligned box, e.g. the bounds of one cell.
struct Box3d {
  Vec3d lo, hi;
  bool operator==(const Box3d& o) const { return lo == o.lo && hi == o.hi; }
  std::string ToString() const;
};

// "(x, y, z)" with round-trip precision.
std::string ToString(const Vec3d& v);

class CellGrid {
 public:
  // Throws InputError unless lo and hi are finite, lo < hi on every axis, every dim >= 1,
  // nx*ny*nz fits a CellId, and every cell is wide enough to be resolved at the box's
  // coordinates (at least 2^-40 of the largest coordinate magnitude on its axis, and a
  // normal double).
  static CellGrid Create(const Vec3d& lo, const Vec3d& hi, std::array<std::uint32_t, 3> dims);

  const Vec3d& lo() const { return lo_; }
  const Vec3d& hi() const { return hi_; }
  const std::array<std::uint32_t, 3>& dims() const { return dims_; }
  std::uint32_t dim(int axis) const { return dims_[axis]; }
  std::uint32_t cell_count() const { return dims_[0] * dims_[1] * dims_[2]; }
  // Nominal cell size (hi-lo)/n along each axis.
  const std::array<double, 3>& cell_size() const { return size_; }

  // Position of plane k (0 <= k <= n) on `axis`: strictly increasing in k, lo at 0, hi at n,
  // lo + (hi - lo) * (k / n) otherwise, so that nested grids share their planes exactly.
  double Plane(int axis, std::uint32_t k) const;
  // The index along `axis` of the cell holding coordinate c: plane(i) <= c < plane(i+1),
  // clamped to [0, n-1] for coordinates outside the box. c must not be NaN.
  std::uint32_t AxisCell(int axis, double c) const;
  // The cell holding p, clamped to the grid for points on or outside the boundary.
  CellId CellOf(const Vec3d& p) const;
  CellId CellIndex(const std::array<std::uint32_t, 3>& xyz) const;
  std::array<std::uint32_t, 3> CellCoords(CellId cell) const;
  // [plane(x), plane(x+1)] x [...] x [...]; consistent with CellOf.
  Box3d CellBounds(CellId cell) const;

  // "CellGrid[(lo) - (hi), 3x3x3 cells]".
  std::string ToString() const;

 private:
  CellGrid() = default;
  Vec3d lo_, hi_;
  std::array<std::uint32_t, 3> dims_{1, 1, 1};
  std::array<double, 3> lo_a_{}, hi_a_{}, size_{};
};

// One piece of a ray inside one cell: parameters [t0, t1] in units of the ray's direction.
struct CellSegment {
  CellId cell{0};
  double t0 = 0, t1 = 0;
  bool operator==(const CellSegment& o) const { return cell == o.cell && t0 == o.t0 && t1 == o.t1; }
  // "{cell 3, t [0.25, 0.5]}".
  std::string ToString() const;
};

// Iterates the cells that the ray origin + t*dir, t in [tmin, tmax], crosses inside the
// grid's box (see the semantics at the top of this file). Segments come in order of t; the
// first starts at max(tmin, box entry) (tmin with a forced start cell), the last ends at
// min(tmax, box exit), each starts exactly where the previous one ended, consecutive
// segments are to different cells, and none but a forced first one has zero length.
//
//   CellDDA dda(grid, o, d);
//   for (CellSegment s; dda.Next(&s);) ...
//
// A small value type: it holds a copy of the grid, no pointers.
class CellDDA {
 public:
  using Segment = CellSegment;
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();

  CellDDA(const CellGrid& grid, const Vec3d& origin, const Vec3d& dir, double tmin = 0,
          double tmax = kInfinity, std::optional<CellId> start_cell = std::nullopt);

  // Writes the next segment and returns true, or returns false when the ray has left the
  // box or reached tmax.
  bool Next(CellSegment* segment);
  bool done() const { return done_ && !pending_; }

  // The iterator's state, for logging.
  std::string ToString() const;

 private:
  void InitAxes(const Vec3d& origin, const Vec3d& dir);
  void InitFree(double tmin, double tmax);
  void InitForced(CellId start, double tmin, double tmax);
  // True when the point at parameter tmin lies outside the cell `xyz` by more than
  // start_cap_ on some axis: before the cell's entry plane on an axis the ray moves along,
  // or off its slab on an axis the ray is parallel to; `out` says on which axes.
  bool StartsOutside(const std::array<std::uint32_t, 3>& xyz, double tmin,
                     std::array<bool, 3>* out) const;
  // Parameter range [entry, exit] of the slab of `axis`; empty (entry > exit) when the ray
  // is parallel to it and outside.
  void Slab(int axis, double* entry, double* exit) const;
  double CrossingT(int axis, std::uint32_t plane) const;
  // Parameter of the next interior plane the ray crosses on `axis`, +inf if none.
  double NextCrossing(int axis) const;
  // True when the crossing of `axis` at tc is at or before t (whose own uncertainty is ut),
  // up to rounding: tc - t is within the two uncertainties and moves the ray by at most
  // kTolCellFraction of a cell along `axis`.
  bool Near(int axis, double tc, double t, double ut) const;
  // The cell index on `axis` just after parameter t (crossings near t taken).
  std::int64_t NaturalIndex(int axis, double t, double ut) const;
  // Steps every axis whose next crossing is near t_.
  void Advance();
  CellId Cell() const;

  CellGrid grid_;
  std::array<double, 3> o_{}, d_{}, abs_d_{}, t_next_{};
  // Rounding uncertainty of a crossing parameter on each axis, and the largest distance
  // along the axis by which taking crossings together may move the ray.
  std::array<double, 3> u_{}, cap_{};
  // How far a forced start point may lie outside its cell on each axis and count as in it.
  std::array<double, 3> start_cap_{};
  std::array<std::int64_t, 3> idx_{};
  std::array<int, 3> step_{};
  double t_ = 0, t_end_ = 0, t_u_ = 0, end_u_ = 0;  // current and last parameter, uncertainties
  bool done_ = true;
  // A forced start cell away from the start point: its segment, not emitted yet.
  std::optional<CellSegment> pending_;
  std::uint32_t emitted_ = 0, max_segments_ = 0;
};

// Runs `dda` to the end and returns its segments.
std::vector<CellSegment> CollectSegments(CellDDA dda);

}  // namespace raycell
