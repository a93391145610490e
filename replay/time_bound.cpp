#include "replay/time_bound.h"

#include <algorithm>
#include <utility>

#include "base/check.h"
#include "base/checked.h"
#include "scheduling/scheduler.h"

namespace raycell {
namespace {

// ---- (c) The longest chain, and the cells used ----------------------------------------
// The work graph is a forest (each unit has one predecessor); each form is walked once,
// without recursion, carrying the samples of the path up to each unit's end. Path sums are at
// most the frame's samples, which fit 64 bits (WorkGraph::totals). Each walk marks the cells
// of the units it reaches in `used` (bytes, not bits: one store a unit, not a read and a
// store).

// The breadth-first records (work.h): entry x's successors are entries first_child[x] ..
// first_child[x + 1], the roots are entries 0 .. roots. Entries are numbered in the order a
// breadth-first walk reaches them, so parents come before their children, and an entry's
// parent is found by a second cursor that moves forward only: one sequential pass over the
// records, keeping the paths' samples of the entries between the two cursors (at most a
// breadth-first level or two: about the primary rays, 8 bytes each). A third of the time of
// the same walk depth first, whose reads jump about the records.
std::uint64_t LongestPackedChain(const WorkGraph& w, std::vector<std::uint8_t>* used) {
  const WorkGraph::Packed* p = w.packed.data();
  const std::size_t n = w.size(), roots = w.roots.size();
  std::uint64_t longest = 0;
  std::vector<std::uint64_t> done;  // done[k - base]: the path's samples up to entry k's end
  std::size_t parent = 0, base = 0;
  for (std::size_t x = 0; x < n; ++x) {
    std::uint64_t before = 0;
    if (x >= roots) {
      while (p[parent + 1].first_child <= x) ++parent;
      before = done[parent - base];
    }
    (*used)[p[x].cell.value()] = 1;
    done.push_back(before + p[x].samples);
    longest = std::max(longest, done.back());
    if (parent - base >= 4096 && 2 * (parent - base) >= done.size()) {  // drop passed parents
      done.erase(done.begin(), done.begin() + std::ptrdiff_t(parent - base));
      base = parent;
    }
  }
  return longest;
}

// The columns (kept only when some unit does not fit the records, so rarely worth more): unit
// u's successors are succ[succ_begin[u] .. succ_begin[u + 1]], walked depth first from each
// root in turn with a stack of (unit, samples of the path before it), which holds only the
// units waiting beside one root's path.
std::uint64_t LongestColumnChain(const WorkGraph& w, std::vector<std::uint8_t>* used) {
  std::uint64_t longest = 0;
  std::vector<std::pair<UnitId, std::uint64_t>> stack;
  for (UnitId root : w.roots) {
    stack.push_back({root, 0});
    while (!stack.empty()) {
      const auto [u, before] = stack.back();
      stack.pop_back();
      (*used)[w.cell[u].value()] = 1;
      const std::uint64_t done = before + w.samples[u];
      longest = std::max(longest, done);
      for (UnitId k = w.succ_begin[u]; k < w.succ_begin[u + 1]; ++k) {
        stack.push_back({w.succ[k], done});
      }
    }
  }
  return longest;
}

// The Compact form (work.h), walked depth first a ray at a time: a ray's visits one after the
// other, each ray spawned at a visit pushed with the path up to that visit's end. `spawned` is
// ordered by the visit spawned at, and a ray's first unit points at the first entry at or
// after its first visit, so one cursor follows the ray's visits (as CompactUnits in
// replayer.cpp).
std::uint64_t LongestCompactChain(const WorkGraph& w, std::vector<std::uint8_t>* used) {
  const WorkGraph::Compact& c = w.compact;
  const std::uint8_t* stream = c.stream.data();
  const std::size_t spawned = c.spawned.size();
  std::uint64_t longest = 0;
  std::vector<std::pair<WorkGraph::CompactUnit, std::uint64_t>> stack;
  for (const WorkGraph::CompactUnit& root : c.roots) {
    stack.push_back({root, 0});
    while (!stack.empty()) {
      const auto [first, before] = stack.back();
      stack.pop_back();
      std::uint64_t done = before;
      std::uint32_t at = first.offset;
      std::size_t k = first.spawned;
      for (bool last = false; !last;) {
        const std::uint32_t record = at;
        const std::uint32_t cell_last = ReadVarint(stream, &at);
        (*used)[cell_last >> 1] = 1;
        last = (cell_last & 1) != 0;
        done += ReadVarint(stream, &at);
        for (; k < spawned && c.spawned[k].at == record; ++k) {
          stack.push_back({c.spawned[k].unit, done});
        }
      }
      longest = std::max(longest, done);
    }
  }
  return longest;
}

// ---- (b) The links ----------------------------------------------------------------------

// Moving `bytes` across the link below `level`.
SimTime LinkCost(const LevelConfig& level, std::uint64_t bytes) {
  return level.latency_below + level.bandwidth_below.TransferTime(bytes);
}

// (b), and in `below_caches` the sum over the links below level 0 that (d) adds to the work.
SimTime LinksTerm(const std::vector<std::uint8_t>& used,
                  const std::vector<std::uint64_t>& footprints, const ReplayConfig& config,
                  const std::vector<std::vector<bool>>* held, const MemoryUnits* units,
                  unsigned __int128* below_caches_out) {
  const std::size_t cells = used.size();
  const bool given = units != nullptr && !units->empty();
  // nearer[c]: some copy of a level nearer than the one at hand holds c's unit at the start.
  std::vector<bool> nearer(cells, false);
  // Per unit of `level`, whether it must cross the link below it; then nearer updated.
  const auto needed = [&](std::size_t level) {
    const LevelUnits* own = given && !(*units)[level].identity() ? &(*units)[level] : nullptr;
    std::vector<bool> need(own ? own->bytes.size() : cells, false);
    for (std::size_t c = 0; c < cells; ++c) {
      const std::size_t u = own ? own->unit_of_cell[c].value() : c;
      const bool here = held != nullptr && (*held)[level][u];
      if (used[c] && !nearer[c] && !here) need[u] = true;
      nearer[c] = nearer[c] || here;
    }
    return std::make_pair(need, own);
  };
  // The links below level 0, one per processor: the sum over cells, shared out over them.
  // In 128 bits: P links may carry more than one SimTime's worth between them.
  unsigned __int128 below_caches = 0;
  {
    const auto [need, own] = needed(0);
    RAYCELL_CHECK(own == nullptr);  // the caches hold the cells
    for (std::size_t c = 0; c < cells; ++c) {
      if (need[c]) below_caches += LinkCost(config.levels[0], footprints[c]).picoseconds();
    }
  }
  *below_caches_out = below_caches;
  const std::uint32_t p = config.processors.count;
  const unsigned __int128 per_processor = below_caches / p + (below_caches % p != 0 ? 1 : 0);
  RAYCELL_CHECK(per_processor <= SimTime::Max().picoseconds());
  SimTime links = SimTime::Picoseconds(std::uint64_t(per_processor));
  for (std::size_t i = 1; i < config.levels.size(); ++i) {
    const auto [need, own] = needed(i);
    SimTime shared;
    for (std::size_t u = 0; u < need.size(); ++u) {
      if (need[u])
        shared = shared + LinkCost(config.levels[i], own ? own->bytes[u] : footprints[u]);
    }
    links = std::max(links, shared);
  }
  return links;
}

}  // namespace

WorkGraph::Shape ShapeOf(const WorkGraph& work) {
  WorkGraph::Shape shape;
  shape.used.assign(work.cells, 0);
  shape.chain_samples = work.compact.units != 0 ? LongestCompactChain(work, &shape.used)
                        : !work.packed.empty()  ? LongestPackedChain(work, &shape.used)
                                                : LongestColumnChain(work, &shape.used);
  return shape;
}

SimTime TimeBoundTerms::value() const { return std::max({work, links, chain, busy}); }

std::string TimeBoundTerms::ToString() const {
  return "work " + work.ToString() + ", links " + links.ToString() + ", chain " + chain.ToString() +
         ", busy " + busy.ToString();
}

TimeBoundTerms TimeLowerBoundTerms(const WorkGraph& work,
                                   const std::vector<std::uint64_t>& footprints,
                                   const ReplayConfig& config,
                                   const std::vector<std::vector<bool>>* held_at_start,
                                   const MemoryUnits* units) {
  RAYCELL_CHECK_EQ(footprints.size(), std::size_t(work.cells));
  RAYCELL_CHECK(!config.levels.empty() && config.processors.count > 0);
  if (held_at_start != nullptr) {
    RAYCELL_CHECK_EQ(held_at_start->size(), config.levels.size());
    for (std::size_t i = 0; i < held_at_start->size(); ++i) {
      RAYCELL_CHECK_EQ((*held_at_start)[i].size(), std::size_t(UnitCount(units, i, work.cells)));
    }
  }
  const SimTime tps = config.processors.time_per_sample;
  const WorkGraph::Shape walked = work.shape ? WorkGraph::Shape() : ShapeOf(work);
  const WorkGraph::Shape& shape = work.shape ? *work.shape : walked;
  const std::vector<std::uint8_t>& used = shape.used;
  const std::uint64_t chain = shape.chain_samples;
  TimeBoundTerms t;
  const std::uint64_t total = (tps * work.total_samples()).picoseconds();
  const std::uint32_t p = config.processors.count;
  t.work = SimTime::Picoseconds(total / p + (total % p != 0 ? 1 : 0));
  unsigned __int128 below_caches = 0;
  t.links = LinksTerm(used, footprints, config, held_at_start, units, &below_caches);
  t.chain = tps * chain;
  // (d): in 128 bits, as the sum of P processors' time may not fit one SimTime.
  const unsigned __int128 busy =
      (config.processors.prefetch ? 0 : below_caches) + static_cast<unsigned __int128>(total);
  const unsigned __int128 per_processor = busy / p + (busy % p != 0 ? 1 : 0);
  RAYCELL_CHECK(per_processor <= SimTime::Max().picoseconds());
  t.busy = SimTime::Picoseconds(std::uint64_t(per_processor));
  return t;
}

SimTime TimeLowerBound(const WorkGraph& work, const std::vector<std::uint64_t>& footprints,
                       const ReplayConfig& config,
                       const std::vector<std::vector<bool>>* held_at_start,
                       const MemoryUnits* units) {
  return TimeLowerBoundTerms(work, footprints, config, held_at_start, units).value();
}

}  // namespace raycell
