#include "traces/subdivision.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "base/check.h"
#include "base/parse.h"
#include "base/units.h"
#include "traces/cell_dims.h"

namespace raycell {
namespace {

std::uint32_t ParseCount(std::string_view text, const std::string& what, const char* of) {
  return std::uint32_t(ParseUint(text, what + ": " + of, 1, kMaxSubdivisionCells));
}

std::uint64_t ParseBudget(std::string_view text, const std::string& what) {
  const std::uint64_t b = ParseBytes(text, what + ": byte budget").count();
  if (b == 0)
    throw InputError(what + ": byte budget must be greater than zero: '" + std::string(text) + "'");
  return b;
}

// What a k-d split balances: a box's footprint (the union's bytes), its samples, or its
// footprint over the square root of its samples plus one (kd:N:sqrt, which gives each cell a
// footprint in proportion to the square root of its work). Doubles: footprints are exact up
// to 2^53 bytes.
class Weigher {
 public:
  enum class By { kFootprint, kWork, kSqrt };
  Weigher(const FineCells& fine, By by) : fine_(fine), by_(by) {}
  double operator()(const FineBox& b) const {
    const std::vector<std::uint32_t> cells = FineCellsOf(b, fine_.grid);
    std::uint64_t samples = 0;
    if (by_ != By::kFootprint) {
      for (std::uint32_t c : cells) samples += fine_.samples[c];
    }
    if (by_ == By::kWork) return double(samples);
    const double bytes = double(fine_.union_footprint(cells));
    return by_ == By::kFootprint ? bytes : bytes / std::sqrt(double(samples) + 1.0);
  }

 private:
  const FineCells& fine_;
  By by_;
};

// A box split in two, and the weight of each half.
struct BoxSplit {
  FineBox lower, upper;
  double lower_weight = 0, upper_weight = 0;
};

// Splits `b` (more than one fine cell) at the fine boundary whose larger half weighs least;
// ties: axis x before y before z, then the lowest boundary.
BoxSplit BestSplit(const FineBox& b, const Weigher& weigh) {
  bool found = false;
  BoxSplit best;
  for (int axis = 0; axis < 3; ++axis) {
    for (std::uint32_t at = b.lo[axis] + 1; at < b.hi[axis]; ++at) {
      BoxSplit s{b, b};
      s.lower.hi[axis] = at;
      s.upper.lo[axis] = at;
      s.lower_weight = weigh(s.lower);
      s.upper_weight = weigh(s.upper);
      if (!found || std::max(s.lower_weight, s.upper_weight) <
                        std::max(best.lower_weight, best.upper_weight)) {
        found = true, best = s;
      }
    }
  }
  RAYCELL_CHECK(found);
  return best;
}

// A k-d tree: splits the heaviest splittable box (the first on ties) while `more(boxes,
// weights)` asks for another cell and one is splittable.
template <typename More>
std::vector<FineBox> KdTree(const FineBox& whole, const Weigher& weigh, More more) {
  std::vector<FineBox> boxes{whole};
  std::vector<double> weights{weigh(whole)};
  while (more(boxes, weights)) {
    std::size_t pick = boxes.size();
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (boxes[i].volume() < 2) continue;
      if (pick == boxes.size() || weights[i] > weights[pick]) pick = i;
    }
    if (pick == boxes.size()) break;  // every box is one fine cell
    const BoxSplit split = BestSplit(boxes[pick], weigh);
    boxes[pick] = split.lower;
    weights[pick] = split.lower_weight;
    boxes.push_back(split.upper);
    weights.push_back(split.upper_weight);
  }
  return boxes;
}

void Octree(const FineBox& b, const Weigher& weigh, std::uint64_t budget,
            std::vector<FineBox>* out) {
  if (b.volume() < 2 || weigh(b) <= double(budget)) {
    out->push_back(b);
    return;
  }
  // Halves along every axis longer than one fine cell (the lower half the smaller).
  std::array<std::vector<std::pair<std::uint32_t, std::uint32_t>>, 3> halves;
  for (int a = 0; a < 3; ++a) {
    if (b.hi[a] - b.lo[a] < 2) {
      halves[a] = {{b.lo[a], b.hi[a]}};
    } else {
      const std::uint32_t mid = b.lo[a] + (b.hi[a] - b.lo[a]) / 2;
      halves[a] = {{b.lo[a], mid}, {mid, b.hi[a]}};
    }
  }
  for (const auto& z : halves[2]) {
    for (const auto& y : halves[1]) {
      for (const auto& x : halves[0]) {
        Octree(FineBox{{x.first, y.first, z.first}, {x.second, y.second, z.second}}, weigh, budget,
               out);
      }
    }
  }
}

}  // namespace

std::uint64_t FineBox::volume() const {
  std::uint64_t v = 1;
  for (int a = 0; a < 3; ++a) v *= hi[a] > lo[a] ? hi[a] - lo[a] : 0;
  return v;
}

std::vector<std::uint32_t> FineCellsOf(const FineBox& b, const std::array<std::uint32_t, 3>& g) {
  std::vector<std::uint32_t> out;
  out.reserve(b.volume());
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z) {
    for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y) {
      for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x) out.push_back(x + g[0] * (y + g[1] * z));
    }
  }
  return out;
}

std::vector<CellId> CellOfFine(const std::vector<FineBox>& boxes,
                               const std::array<std::uint32_t, 3>& g) {
  std::vector<CellId> of(std::size_t{g[0]} * g[1] * g[2], kNoCell);
  for (std::uint32_t c = 0; c < boxes.size(); ++c) {
    for (std::uint32_t f : FineCellsOf(boxes[c], g)) {
      RAYCELL_CHECK_LT(f, of.size());
      RAYCELL_CHECK(of[f] == kNoCell);
      of[f] = CellId(c);
    }
  }
  return of;
}

std::string SubdivisionSpec::ToString() const {
  switch (kind) {
    case Kind::kUniform:
    case Kind::kGrid:
      return std::string(kind == Kind::kGrid ? "grid:" : "") + std::to_string(grid[0]) + "x" +
             std::to_string(grid[1]) + "x" + std::to_string(grid[2]);
    case Kind::kGridCrossings:
      return "grid:" + std::to_string(cells) + ":crossings";
    case Kind::kKdFootprint:
      return "kd:" + std::to_string(cells) + ":footprint";
    case Kind::kKdWork:
      return "kd:" + std::to_string(cells) + ":work";
    case Kind::kKdSqrt:
      return "kd:" + std::to_string(cells) + ":sqrt";
    case Kind::kKdBudget:
      return "kd:budget:" + Bytes(budget).ToString();
    case Kind::kOctree:
      return "octree:" + Bytes(budget).ToString();
    case Kind::kDynamic:
      return "dynamic:" + std::to_string(cells) + (sqrt ? ":sqrt" : "");
    case Kind::kAuto:
      return "auto:" + std::to_string(cells);
  }
  RAYCELL_CHECK(false);
  return {};
}

SubdivisionSpec ParseSubdivisionSpec(std::string_view text, const std::string& what) {
  const std::string t(Trim(text));
  const std::vector<std::string> parts = Split(t, ':');
  const std::string expected =
      " (expected NXxNYxNZ, grid:NXxNYxNZ, grid:N:crossings, kd:N:footprint, kd:N:work, "
      "kd:N:sqrt, kd:budget:BYTES, octree:BYTES, dynamic:N, dynamic:N:sqrt or auto:N)";
  SubdivisionSpec s;
  const bool grid = parts.size() == 2 && parts[0] == "grid";
  if (parts.size() == 1 || grid) {
    const std::string& counts = grid ? parts[1] : t;
    const std::vector<std::string> dims = Split(counts, 'x');
    if (dims.size() != 3) {
      throw InputError(what + ": '" + t + "' is not a cell subdivision" + expected);
    }
    s.kind = grid ? SubdivisionSpec::Kind::kGrid : SubdivisionSpec::Kind::kUniform;
    s.grid = ParseCellDims(counts, what, kMaxSubdivisionCells);
    return s;
  }
  const std::string& kind = parts[0];
  if (kind == "grid" && parts.size() == 3) {
    s.kind = SubdivisionSpec::Kind::kGridCrossings;
    if (parts[2] != "crossings") {
      throw InputError(what + ": a grid of N cells is chosen by 'crossings' (grid:N:crossings), " +
                       "not '" + parts[2] + "'");
    }
    s.cells = ParseCount(parts[1], what, "grid cell count");
  } else if (kind == "kd" && parts.size() == 3 && parts[1] == "budget") {
    s.kind = SubdivisionSpec::Kind::kKdBudget;
    s.budget = ParseBudget(parts[2], what);
  } else if (kind == "kd" && parts.size() == 3) {
    s.cells = ParseCount(parts[1], what, "kd cell count");
    if (parts[2] == "footprint") {
      s.kind = SubdivisionSpec::Kind::kKdFootprint;
    } else if (parts[2] == "work") {
      s.kind = SubdivisionSpec::Kind::kKdWork;
    } else if (parts[2] == "sqrt") {
      s.kind = SubdivisionSpec::Kind::kKdSqrt;
    } else {
      throw InputError(what + ": kd balances 'footprint', 'work' or 'sqrt', not '" + parts[2] +
                       "'");
    }
  } else if (kind == "octree" && parts.size() == 2) {
    s.kind = SubdivisionSpec::Kind::kOctree;
    s.budget = ParseBudget(parts[1], what);
  } else if (kind == "dynamic" && (parts.size() == 2 || parts.size() == 3)) {
    s.kind = SubdivisionSpec::Kind::kDynamic;
    s.cells = ParseCount(parts[1], what, "dynamic cell count");
    if (parts.size() == 3 && parts[2] != "sqrt") {
      throw InputError(what + ": dynamic balances work (dynamic:N) or 'sqrt' (dynamic:N:sqrt), " +
                       "not '" + parts[2] + "'");
    }
    s.sqrt = parts.size() == 3;
  } else if (kind == "auto" && parts.size() == 2) {
    s.kind = SubdivisionSpec::Kind::kAuto;
    s.cells = ParseCount(parts[1], what, "auto cell count");
  } else {
    throw InputError(what + ": '" + t + "' is not a cell subdivision" + expected);
  }
  return s;
}

namespace {

// grid:N:crossings's counts (subdivision.h): over every NX x NY x NZ = N with each count at most
// the fine grid's, the least sum of crossings[a] (NA - 1) / (FA - 1), compared exactly over the
// common denominator (FX - 1)(FY - 1)(FZ - 1) in 128 bits (an axis of one fine cell has no
// boundary inside and counts 1 there); ties to the lowest NX, then NY.
std::array<std::uint32_t, 3> GridByCrossings(std::uint32_t n, const FineCells& fine,
                                             const std::string& what) {
  if (!fine.has_crossings) {
    throw InputError(what + ": needs the rays' steps between the fine cells, by axis");
  }
  using Wide = unsigned __int128;
  std::optional<std::array<std::uint32_t, 3>> best;
  Wide best_cost = 0;
  for (std::uint32_t x = 1; x <= std::min(n, fine.grid[0]); ++x) {
    if (n % x != 0) continue;
    for (std::uint32_t y = 1; y <= std::min(n / x, fine.grid[1]); ++y) {
      if ((n / x) % y != 0 || n / x / y > fine.grid[2]) continue;
      const std::array<std::uint32_t, 3> c{x, y, n / x / y};
      Wide cost = 0;
      for (int a = 0; a < 3; ++a) {
        Wide term = Wide{fine.crossings[a]} * (c[a] - 1);
        for (int b = 0; b < 3; ++b) {
          if (b != a) term *= std::max<std::uint32_t>(fine.grid[b] - 1, 1);
        }
        cost += term;
      }
      if (!best || cost < best_cost) best = c, best_cost = cost;
    }
  }
  if (!best) {
    throw InputError(what + ": no grid of " + std::to_string(n) + " cells fits the fine grid's " +
                     std::to_string(fine.grid[0]) + "x" + std::to_string(fine.grid[1]) + "x" +
                     std::to_string(fine.grid[2]));
  }
  return *best;
}

// The boxes of a grid of `counts` cells on the fine grid `g`, numbered x + NX (y + NY z): along
// each axis of F fine cells cut into N, boundary i at round(i F / N), halves up (i F / N itself
// when N divides F), strictly increasing as N <= F.
std::vector<FineBox> GridBoxes(const std::array<std::uint32_t, 3>& counts,
                               const std::array<std::uint32_t, 3>& g, const std::string& what) {
  std::array<std::vector<std::uint32_t>, 3> at;
  for (int a = 0; a < 3; ++a) {
    const std::uint64_t f = g[a], c = counts[a];
    if (c > f) {
      throw InputError(what + ": its " + std::to_string(c) + " cells along " + "xyz"[a] +
                       " are more than the fine grid's " + std::to_string(f));
    }
    for (std::uint64_t i = 0; i <= c; ++i) {
      at[a].push_back(std::uint32_t((2 * i * f + c) / (2 * c)));
    }
  }
  std::vector<FineBox> boxes;
  for (std::uint32_t z = 0; z < counts[2]; ++z) {
    for (std::uint32_t y = 0; y < counts[1]; ++y) {
      for (std::uint32_t x = 0; x < counts[0]; ++x) {
        boxes.push_back(
            {{at[0][x], at[1][y], at[2][z]}, {at[0][x + 1], at[1][y + 1], at[2][z + 1]}});
      }
    }
  }
  return boxes;
}

}  // namespace

std::array<std::uint32_t, 3> CubicGrid(std::uint32_t n, const std::array<std::uint32_t, 3>& fine,
                                       const std::string& what) {
  std::optional<std::array<std::uint32_t, 3>> best;
  const auto key = [](const std::array<std::uint32_t, 3>& g) {
    const auto [lo, hi] = std::minmax({g[0], g[1], g[2]});
    return std::pair<std::uint32_t, std::uint32_t>(hi, std::uint32_t(-1) - lo);
  };
  for (std::uint32_t x = 1; x <= std::min(n, fine[0]); ++x) {
    if (n % x != 0) continue;
    for (std::uint32_t y = 1; y <= std::min(n / x, fine[1]); ++y) {
      if (n / x % y != 0 || n / x / y > fine[2]) continue;
      const std::array<std::uint32_t, 3> g{x, y, n / x / y};
      if (!best || key(g) < key(*best)) best = g;
    }
  }
  if (!best) {
    throw InputError(what + ": no grid of " + std::to_string(n) + " cells (NX NY NZ = " +
                     std::to_string(n) + ") fits the fine grid " + std::to_string(fine[0]) + "x" +
                     std::to_string(fine[1]) + "x" + std::to_string(fine[2]));
  }
  return *best;
}

Subdivision Subdivide(const SubdivisionSpec& spec, const FineCells& fine) {
  using Kind = SubdivisionSpec::Kind;
  const std::uint32_t n = fine.count();
  RAYCELL_CHECK(n > 0);
  const std::string what = "cell subdivision '" + spec.ToString() + "'";
  const FineBox whole{{0, 0, 0}, fine.grid};
  const bool dynamic_work = spec.kind == Kind::kDynamic && !fine.samples.empty();
  const bool by_work = spec.kind == Kind::kKdWork || (dynamic_work && !spec.sqrt);
  const bool by_sqrt = spec.kind == Kind::kKdSqrt || (dynamic_work && spec.sqrt);
  if ((by_work || by_sqrt) && fine.samples.size() != n) {
    throw InputError(what + ": needs the samples of each of the " + std::to_string(n) +
                     " fine cells");
  }
  const bool grid = spec.kind == Kind::kUniform || spec.kind == Kind::kGrid ||
                    spec.kind == Kind::kGridCrossings || spec.kind == Kind::kAuto;
  if (!by_work && !grid) RAYCELL_CHECK(fine.union_footprint != nullptr);
  const Weigher weigh(fine, by_work   ? Weigher::By::kWork
                            : by_sqrt ? Weigher::By::kSqrt
                                      : Weigher::By::kFootprint);
  Subdivision out;
  switch (spec.kind) {
    case Kind::kUniform: {
      for (int a = 0; a < 3; ++a) {
        if (fine.grid[a] % spec.grid[a] != 0) {
          throw InputError(what + ": its " + std::to_string(spec.grid[a]) + " cells along " +
                           "xyz"[a] + " do not divide the fine grid's " +
                           std::to_string(fine.grid[a]) +
                           " (a cell boundary must be a fine-cell boundary)");
        }
      }
      out.boxes = GridBoxes(spec.grid, fine.grid, what);
      break;
    }
    case Kind::kGrid:
      out.boxes = GridBoxes(spec.grid, fine.grid, what);
      break;
    case Kind::kGridCrossings:
      out.boxes = GridBoxes(GridByCrossings(spec.cells, fine, what), fine.grid, what);
      break;
    case Kind::kAuto:
      out.boxes = GridBoxes(CubicGrid(spec.cells, fine.grid, what), fine.grid, what);
      break;
    case Kind::kKdFootprint:
    case Kind::kKdWork:
    case Kind::kKdSqrt:
    case Kind::kDynamic:
      if (spec.cells > n) {
        throw InputError(what + ": " + std::to_string(spec.cells) + " cells from " +
                         std::to_string(n) + " fine cells");
      }
      out.boxes = KdTree(whole, weigh,
                         [&](const auto& boxes, const auto&) { return boxes.size() < spec.cells; });
      break;
    case Kind::kKdBudget:
      out.boxes = KdTree(whole, weigh, [&](const auto& boxes, const auto& weights) {
        for (std::size_t i = 0; i < boxes.size(); ++i) {
          if (boxes[i].volume() > 1 && weights[i] > double(spec.budget)) return true;
        }
        return false;
      });
      break;
    case Kind::kOctree:
      Octree(whole, weigh, spec.budget, &out.boxes);
      break;
  }
  std::sort(out.boxes.begin(), out.boxes.end(), [](const FineBox& a, const FineBox& b) {
    return std::array{a.lo[2], a.lo[1], a.lo[0]} < std::array{b.lo[2], b.lo[1], b.lo[0]};
  });
  out.coarse_of_fine = CellOfFine(out.boxes, fine.grid);
  return out;
}

}  // namespace raycell
