#include "record/cell_grid.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include "base/check.h"
#include "record/vec3.h"

namespace raycell {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Rounding uncertainty of a crossing: this many ulps of the coordinates on its axis (plane
// and origin), divided by the direction's component.
constexpr double kTolUlps = 16 * DBL_EPSILON;
// Crossings taken together never move the ray by more than this fraction of a cell.
constexpr double kTolCellFraction = 1e-3;
// A forced start point this close to its cell on an axis, as a fraction of the box's extent
// there, is in it (rounding). A fraction of the box, not of a cell, so that grids nested in one
// box decide alike (docs/design.md §1 "Subdivisions").
constexpr double kStartTolBoxFraction = 1e-6;
// A cell must be at least this fraction of the largest coordinate magnitude on its axis.
constexpr double kMinCellRelative = 0x1p-40;

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::array<double, 3> ToArray(const Vec3d& v) { return {v.x, v.y, v.z}; }

// Replaces the bound *t (uncertainty *u) by v (uncertainty uv) when v is tighter (`tighter`
// is greater<> for a lower bound, less<> for an upper one); on a tie keeps the larger
// uncertainty.
template <typename Tighter>
void KeepBound(double v, double uv, Tighter tighter, double* t, double* u) {
  if (tighter(v, *t)) {
    *t = v;
    *u = uv;
  } else if (v == *t) {
    *u = std::max(*u, uv);
  }
}

const char* AxisName(int axis) { return axis == 0 ? "x" : axis == 1 ? "y" : "z"; }

void CheckCellCount(const std::array<std::uint64_t, 3>& d, const std::string& what) {
  const std::uint64_t max = std::numeric_limits<std::uint32_t>::max();
  if (d[0] > max || d[1] > max || d[0] * d[1] > max || d[0] * d[1] * d[2] > max)
    throw InputError(what + ": cell count " + std::to_string(d[0]) + "*" + std::to_string(d[1]) +
                     "*" + std::to_string(d[2]) + " exceeds " + std::to_string(max));
}

}  // namespace

std::string ToString(const Vec3d& v) {
  return "(" + Num(v.x) + ", " + Num(v.y) + ", " + Num(v.z) + ")";
}

std::string Box3d::ToString() const {
  return "[" + raycell::ToString(lo) + " - " + raycell::ToString(hi) + "]";
}

// ---------------------------------------------------------------------------- CellGrid

CellGrid CellGrid::Create(const Vec3d& lo, const Vec3d& hi, std::array<std::uint32_t, 3> dims) {
  const std::string box = "cell grid box " + raycell::ToString(lo) + " - " + raycell::ToString(hi);
  if (!IsFinite(lo) || !IsFinite(hi)) throw InputError(box + ": coordinates must be finite");
  CheckCellCount({dims[0], dims[1], dims[2]}, box);
  CellGrid g;
  g.lo_ = lo;
  g.hi_ = hi;
  g.dims_ = dims;
  g.lo_a_ = ToArray(lo);
  g.hi_a_ = ToArray(hi);
  for (int a = 0; a < 3; ++a) {
    const std::string axis = std::string(" along ") + AxisName(a);
    if (dims[a] == 0) throw InputError(box + ": cell count" + axis + " must be at least 1");
    if (!(g.lo_a_[a] < g.hi_a_[a])) throw InputError(box + ": min must be below max" + axis);
    g.size_[a] = (g.hi_a_[a] - g.lo_a_[a]) / dims[a];
    const double mag = std::max(std::abs(g.lo_a_[a]), std::abs(g.hi_a_[a]));
    if (!std::isfinite(g.size_[a]) || g.size_[a] < DBL_MIN || g.size_[a] < kMinCellRelative * mag)
      throw InputError(box + ": cell size " + Num(g.size_[a]) + axis +
                       " is too small to resolve at coordinates of magnitude " + Num(mag));
  }
  return g;
}

double CellGrid::Plane(int axis, std::uint32_t k) const {
  RAYCELL_CHECK_LE(k, dims_[axis]);
  // (k / n) first: the fraction of a plane shared by two nested grids (k / n == j / m) is the
  // same double, so their planes are the same numbers and a grid's cells are unions of a
  // finer one's, exactly (docs/design.md §1 "Subdivisions").
  return k == dims_[axis] ? hi_a_[axis]
                          : lo_a_[axis] + (hi_a_[axis] - lo_a_[axis]) * (double(k) / dims_[axis]);
}

std::uint32_t CellGrid::AxisCell(int axis, double c) const {
  RAYCELL_CHECK(!std::isnan(c));
  const std::uint32_t n = dims_[axis];
  if (c <= lo_a_[axis]) return 0;
  if (c >= hi_a_[axis]) return n - 1;
  const double guess = std::floor((c - lo_a_[axis]) / size_[axis]);
  std::uint32_t i = static_cast<std::uint32_t>(std::clamp(guess, 0.0, double(n - 1)));
  while (i > 0 && c < Plane(axis, i)) --i;
  while (i + 1 < n && c >= Plane(axis, i + 1)) ++i;
  return i;
}

CellId CellGrid::CellOf(const Vec3d& p) const {
  return CellIndex({AxisCell(0, p.x), AxisCell(1, p.y), AxisCell(2, p.z)});
}

CellId CellGrid::CellIndex(const std::array<std::uint32_t, 3>& xyz) const {
  for (int a = 0; a < 3; ++a) RAYCELL_CHECK_LT(xyz[a], dims_[a]);
  return CellId(xyz[0] + dims_[0] * (xyz[1] + dims_[1] * xyz[2]));
}

std::array<std::uint32_t, 3> CellGrid::CellCoords(CellId cell) const {
  const std::uint32_t c = cell.value();
  RAYCELL_CHECK_LT(c, cell_count());
  return {c % dims_[0], (c / dims_[0]) % dims_[1], c / (dims_[0] * dims_[1])};
}

Box3d CellGrid::CellBounds(CellId cell) const {
  const auto c = CellCoords(cell);
  return {{Plane(0, c[0]), Plane(1, c[1]), Plane(2, c[2])},
          {Plane(0, c[0] + 1), Plane(1, c[1] + 1), Plane(2, c[2] + 1)}};
}

std::string CellGrid::ToString() const {
  return "CellGrid[" + raycell::ToString(lo_) + " - " + raycell::ToString(hi_) + ", " +
         std::to_string(dims_[0]) + "x" + std::to_string(dims_[1]) + "x" +
         std::to_string(dims_[2]) + " cells]";
}

// ----------------------------------------------------------------------------- CellDDA

std::string CellSegment::ToString() const {
  return "{cell " + std::to_string(cell.value()) + ", t [" + Num(t0) + ", " + Num(t1) + "]}";
}

CellDDA::CellDDA(const CellGrid& grid, const Vec3d& origin, const Vec3d& dir, double tmin,
                 double tmax, std::optional<CellId> start_cell)
    : grid_(grid) {
  // Built only on error: this constructor runs once per traced ray.
  auto ray = [&] { return "ray " + raycell::ToString(origin) + " + t*" + raycell::ToString(dir); };
  if (!IsFinite(origin) || !IsFinite(dir)) throw InputError(ray() + ": must be finite");
  if (dir.x == 0 && dir.y == 0 && dir.z == 0) throw InputError(ray() + ": direction is zero");
  if (std::isnan(tmin) || std::isnan(tmax)) throw InputError(ray() + ": t range is NaN");
  InitAxes(origin, dir);
  if (start_cell) {
    if (start_cell->value() >= grid_.cell_count())
      throw InputError(ray() + ": start cell " + std::to_string(start_cell->value()) + " outside " +
                       grid_.ToString());
    InitForced(*start_cell, tmin, tmax);
  } else {
    InitFree(tmin, tmax);
  }
  if (!done_ && !(std::isfinite(t_) && std::isfinite(t_end_)))
    throw InputError(ray() + ": t range in the box [" + Num(t_) + ", " + Num(t_end_) +
                     "] is unbounded (direction too small)");
  max_segments_ = grid_.dim(0) + grid_.dim(1) + grid_.dim(2) + 2;
}

void CellDDA::InitAxes(const Vec3d& origin, const Vec3d& dir) {
  o_ = ToArray(origin);
  d_ = ToArray(dir);
  for (int a = 0; a < 3; ++a) {
    abs_d_[a] = std::abs(d_[a]);
    step_[a] = d_[a] > 0 ? 1 : d_[a] < 0 ? -1 : 0;
    const double mag =
        std::max(std::abs(grid_.Plane(a, 0)), std::abs(grid_.Plane(a, grid_.dim(a))));
    u_[a] = step_[a] == 0 ? 0 : kTolUlps * (mag + std::abs(o_[a])) / abs_d_[a];
    cap_[a] = kTolCellFraction * grid_.cell_size()[a];
    start_cap_[a] = kStartTolBoxFraction * (grid_.Plane(a, grid_.dim(a)) - grid_.Plane(a, 0));
  }
}

void CellDDA::Slab(int axis, double* entry, double* exit) const {
  if (step_[axis] == 0) {
    const bool inside =
        grid_.Plane(axis, 0) <= o_[axis] && o_[axis] <= grid_.Plane(axis, grid_.dim(axis));
    *entry = inside ? -kInf : kInf;
    *exit = inside ? kInf : -kInf;
    return;
  }
  const double t_lo = CrossingT(axis, 0), t_hi = CrossingT(axis, grid_.dim(axis));
  *entry = std::min(t_lo, t_hi);
  *exit = std::max(t_lo, t_hi);
}

void CellDDA::InitFree(double tmin, double tmax) {
  t_ = tmin;
  t_end_ = tmax;
  for (int a = 0; a < 3; ++a) {
    double entry, exit;
    Slab(a, &entry, &exit);
    KeepBound(entry, u_[a], std::greater<>(), &t_, &t_u_);
    KeepBound(exit, u_[a], std::less<>(), &t_end_, &end_u_);
  }
  done_ = !(t_ < t_end_);
  if (done_ || !std::isfinite(t_)) return;
  for (int a = 0; a < 3; ++a) {
    idx_[a] = NaturalIndex(a, t_, t_u_);
    t_next_[a] = NextCrossing(a);
  }
}

void CellDDA::InitForced(CellId start, double tmin, double tmax) {
  if (!std::isfinite(tmin))
    throw InputError("ray with forced start cell " + std::to_string(start.value()) +
                     ": tmin must be finite, not " + Num(tmin));
  const auto xyz = grid_.CellCoords(start);
  std::array<bool, 3> out{};
  if (StartsOutside(xyz, tmin, &out)) {
    InitFree(tmin, tmax);
    if (!done_ && t_ == tmin) {
      // The start point's cell, but on the axes where it is within the margin of the given
      // cell's slab: the given cell's index there.
      for (int a = 0; a < 3; ++a) {
        if (!out[a]) idx_[a] = xyz[a], t_next_[a] = NextCrossing(a);
      }
    }
    if (!done_ && Cell() == start) {  // the ray enters the box in the given cell
      t_ = tmin;
    } else {
      pending_ = CellSegment{start, tmin, done_ ? tmin : t_};
    }
    return;
  }
  // Axes the ray is parallel to do not clip: the start cell says where the ray lies.
  t_ = tmin;
  t_end_ = tmax;
  for (int a = 0; a < 3; ++a) {
    double entry, exit;
    Slab(a, &entry, &exit);
    if (step_[a] != 0) KeepBound(exit, u_[a], std::less<>(), &t_end_, &end_u_);
  }
  t_end_ = std::max(t_, t_end_);
  done_ = false;
  for (int a = 0; a < 3; ++a) {
    idx_[a] = xyz[a];
    t_next_[a] = NextCrossing(a);
  }
}

bool CellDDA::StartsOutside(const std::array<std::uint32_t, 3>& xyz, double tmin,
                            std::array<bool, 3>* out) const {
  bool any = false;
  for (int a = 0; a < 3; ++a) {
    if (step_[a] == 0) {
      (*out)[a] = grid_.Plane(a, xyz[a]) - o_[a] > start_cap_[a] ||
                  o_[a] - grid_.Plane(a, xyz[a] + 1) > start_cap_[a];
    } else {
      // Past the cell's exit plane is fine: the ray leaves the cell at once (Advance).
      const double t_in = CrossingT(a, step_[a] > 0 ? xyz[a] : xyz[a] + 1);
      (*out)[a] = (t_in - tmin) * abs_d_[a] > start_cap_[a];
    }
    any |= (*out)[a];
  }
  return any;
}

double CellDDA::CrossingT(int axis, std::uint32_t plane) const {
  return (grid_.Plane(axis, plane) - o_[axis]) / d_[axis];
}

double CellDDA::NextCrossing(int axis) const {
  const std::int64_t plane = step_[axis] > 0 ? idx_[axis] + 1 : idx_[axis];
  if (step_[axis] == 0 || plane <= 0 || plane >= grid_.dim(axis)) return kInf;
  return CrossingT(axis, static_cast<std::uint32_t>(plane));
}

bool CellDDA::Near(int axis, double tc, double t, double ut) const {
  const double dt = tc - t;
  return dt <= u_[axis] + ut && dt * abs_d_[axis] <= cap_[axis];
}

std::int64_t CellDDA::NaturalIndex(int axis, double t, double ut) const {
  const std::int64_t n = grid_.dim(axis);
  if (step_[axis] == 0) return grid_.AxisCell(axis, o_[axis]);
  // Interior crossing j (0 <= j < n-1) is plane j+1 going up, plane n-1-j going down; their
  // parameters never decrease with j. Count the passed ones by bisection.
  auto crossing = [&](std::int64_t j) {
    return CrossingT(axis, static_cast<std::uint32_t>(step_[axis] > 0 ? j + 1 : n - 1 - j));
  };
  std::int64_t passed = 0, count = n - 1;
  while (count > 0) {
    const std::int64_t half = count / 2;
    if (Near(axis, crossing(passed + half), t, ut)) {
      passed += half + 1;
      count -= half + 1;
    } else {
      count = half;
    }
  }
  return step_[axis] > 0 ? passed : n - 1 - passed;
}

bool CellDDA::Next(CellSegment* segment) {
  if (pending_) {
    *segment = *pending_;
    pending_.reset();
    ++emitted_;
    return true;
  }
  if (done_) return false;
  RAYCELL_CHECK_LT(emitted_, max_segments_);
  ++emitted_;
  const auto a = std::min_element(t_next_.begin(), t_next_.end()) - t_next_.begin();
  const double tn = t_next_[a];
  double end = std::max(t_, tn);
  if (tn >= t_end_ || Near(int(a), t_end_, tn, end_u_)) {  // last cell; a sliver is merged
    end = t_end_;
    done_ = true;
  }
  *segment = {Cell(), t_, end};
  RAYCELL_CHECK_LE(t_, end);
  if (end == tn) t_u_ = u_[a];
  t_ = end;
  if (!done_) Advance();
  return true;
}

void CellDDA::Advance() {
  for (int a = 0; a < 3; ++a) {
    // NextCrossing is +inf once the last interior plane is crossed, so each axis steps at
    // most n-1 times over the whole ray.
    while (t_next_[a] != kInf && Near(a, t_next_[a], t_, t_u_)) {
      idx_[a] += step_[a];
      RAYCELL_CHECK(idx_[a] >= 0 && idx_[a] < grid_.dim(a));
      t_next_[a] = NextCrossing(a);
    }
  }
}

CellId CellDDA::Cell() const {
  std::array<std::uint32_t, 3> xyz;
  for (int a = 0; a < 3; ++a) {
    RAYCELL_CHECK(idx_[a] >= 0 && idx_[a] < grid_.dim(a));
    xyz[a] = static_cast<std::uint32_t>(idx_[a]);
  }
  return grid_.CellIndex(xyz);
}

std::string CellDDA::ToString() const {
  std::ostringstream s;
  s << "CellDDA[" << grid_.ToString() << ", o " << raycell::ToString({o_[0], o_[1], o_[2]})
    << ", d " << raycell::ToString({d_[0], d_[1], d_[2]}) << ", cell (" << idx_[0] << ", "
    << idx_[1] << ", " << idx_[2] << "), t " << Num(t_) << ", end " << Num(t_end_) << ", next ("
    << Num(t_next_[0]) << ", " << Num(t_next_[1]) << ", " << Num(t_next_[2]) << "), segments "
    << emitted_ << (pending_ ? ", first " + pending_->ToString() : "") << (done_ ? ", done]" : "]");
  return s.str();
}

std::vector<CellSegment> CollectSegments(CellDDA dda) {
  std::vector<CellSegment> out;
  for (CellSegment s; dda.Next(&s);) out.push_back(s);
  return out;
}

}  // namespace raycell
