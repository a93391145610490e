#include "replay/memory.h"

#include <algorithm>
#include <cstdint>
#include <utility>

#include "base/check.h"
#include "base/checked.h"

namespace raycell {

CellStore::CellStore(const LevelConfig& level, const std::vector<std::uint64_t>* footprints,
                     std::vector<CellId> future)
    : level_(level),
      footprints_(footprints),
      policy_(MakeReplacement(*level.replacement, std::uint32_t(footprints->size()),
                              std::move(future))),
      held_(footprints->size(), false) {}

std::uint64_t CellStore::Size(CellId cell) const {
  return level_.capacity_unit == LevelConfig::CapacityUnit::kCells ? 1
                                                                   : (*footprints_)[cell.value()];
}

bool CellStore::Lookup(CellId cell) {
  requests_.push_back(cell);
  policy_->Requested(cell);
  if (!held_[cell.value()]) return false;
  policy_->Hit(cell);
  return true;
}

bool CellStore::Fits(CellId cell, std::optional<CellId> pinned) const {
  const std::uint64_t keep = pinned && held_[pinned->value()] ? Size(*pinned) : 0;
  return held_[cell.value()] || keep + Size(cell) <= level_.capacity;
}

bool CellStore::Insert(CellId cell, std::optional<CellId> pinned) {
  if (held_[cell.value()]) return true;
  if (!Fits(cell, pinned)) return false;
  while (used_ + Size(cell) > level_.capacity) {
    const std::optional<CellId> victim = policy_->Victim(pinned);
    RAYCELL_CHECK(victim.has_value());
    held_[victim->value()] = false;
    used_ -= Size(*victim);
    policy_->Evicted(*victim);
  }
  held_[cell.value()] = true;
  used_ += Size(cell);
  policy_->Inserted(cell);
  return true;
}

void CellStore::Restore(const std::vector<CellId>& cells) {
  for (const CellId c : cells) RAYCELL_CHECK(Insert(c));
}

MemoryState CarryOver(const MemoryState& state, const FrameCells& from, const FrameCells& to) {
  RAYCELL_CHECK(from.of_fine && from.footprints && to.of_fine && to.footprints);
  RAYCELL_CHECK_EQ(from.of_fine->size(), to.of_fine->size());
  const std::size_t fine = to.of_fine->size(), cells = to.footprints->size();
  constexpr std::size_t kNone = SIZE_MAX;
  MemoryState out;
  for (const auto& level : state.held) {
    out.held.emplace_back();
    for (const std::vector<CellId>& copy : level) {
      // Position of each cell of `from` in the copy's eviction order; kNone: not held.
      std::vector<std::size_t> position(from.footprints->size(), kNone);
      for (std::size_t i = 0; i < copy.size(); ++i) {
        RAYCELL_CHECK_LT(copy[i].value(), position.size());
        position[copy[i].value()] = i;
      }
      // Per cell of `to`: the earliest victim holding part of its data; kNone and `missing`
      // when part of its data is held by no cell of the copy.
      std::vector<std::size_t> first(cells, kNone);
      std::vector<bool> missing(cells, false);
      for (std::size_t f = 0; f < fine; ++f) {
        const CellId c = (*to.of_fine)[f], o = (*from.of_fine)[f];
        if (c == kNoCell) continue;
        RAYCELL_CHECK_LT(c.value(), cells);
        if (o == kNoCell || (*from.footprints)[o.value()] == 0) continue;  // no data there
        const std::size_t p = position[o.value()];
        if (p == kNone) {
          missing[c.value()] = true;
        } else {
          first[c.value()] = std::min(first[c.value()], p);
        }
      }
      std::vector<std::pair<std::size_t, std::uint32_t>> kept;
      for (std::uint32_t c = 0; c < cells; ++c) {
        if (!missing[c] && first[c] != kNone && (*to.footprints)[c] > 0)
          kept.push_back({first[c], c});
      }
      std::sort(kept.begin(), kept.end());
      out.held.back().emplace_back();
      for (const auto& [p, c] : kept) out.held.back().back().push_back(CellId(c));
    }
  }
  return out;
}

std::uint32_t UnitCount(const MemoryUnits* units, std::size_t level, std::uint32_t cells) {
  if (units == nullptr || units->empty() || (*units)[level].identity()) return cells;
  return std::uint32_t((*units)[level].bytes.size());
}

MemoryHierarchy::MemoryHierarchy(const ReplayConfig& config,
                                 const std::vector<std::uint64_t>& footprints,
                                 const Requests& futures, const MemoryState& start,
                                 const MemoryUnits* units)
    : levels_(config.levels), footprints_(footprints) {
  RAYCELL_CHECK(!levels_.empty());
  const bool given = units != nullptr && !units->empty();
  RAYCELL_CHECK(!given || units->size() == levels_.size());
  for (std::size_t i = 0; i < levels_.size(); ++i) {
    const bool own = given && !(*units)[i].identity();
    RAYCELL_CHECK(!own || i > 0);  // the processors' caches hold the cells they work
    if (own) RAYCELL_CHECK_EQ((*units)[i].unit_of_cell.size(), footprints.size());
    unit_of_.push_back(own ? &(*units)[i].unit_of_cell : nullptr);
    bytes_.push_back(own ? &(*units)[i].bytes : &footprints_);
  }
  for (std::size_t i = 0; i < levels_.size(); ++i) {
    // A policy that needs the future runs as LRU until a run has made the requests.
    const bool min = levels_[i].replacement->needs_future;
    LevelConfig level = levels_[i];
    if (min && futures.empty()) level.replacement = &kLruReplacement;
    const std::uint32_t copies = i == 0 ? config.processors.count : 1;
    stores_.emplace_back();
    for (std::uint32_t k = 0; k < copies; ++k) {
      stores_.back().emplace_back(level, bytes_[i],
                                  min && !futures.empty() ? futures[i][k] : std::vector<CellId>{});
    }
    link_free_.emplace_back(copies, SimTime::Zero());
    stats_.push_back({levels_[i].name, 0, 0});
  }
  if (!start.empty()) {
    RAYCELL_CHECK_EQ(start.held.size(), stores_.size());
    for (std::size_t i = 0; i < stores_.size(); ++i) {
      RAYCELL_CHECK_EQ(start.held[i].size(), stores_[i].size());
      for (std::size_t k = 0; k < stores_[i].size(); ++k) stores_[i][k].Restore(start.held[i][k]);
    }
  }
  arrival_.assign(config.processors.count, std::vector<SimTime>(footprints.size()));
  arrives_.assign(levels_.size(), std::vector<SimTime>());
  for (std::size_t i = 1; i < levels_.size(); ++i) arrives_[i].assign(bytes_[i]->size(), SimTime());
  prefetched_.assign(config.processors.count, std::vector<bool>(footprints.size(), false));
}

MemoryHierarchy::Requests MemoryHierarchy::requests() const {
  Requests r(stores_.size());
  for (std::size_t i = 0; i < stores_.size(); ++i) {
    for (const CellStore& s : stores_[i]) r[i].push_back(s.requests());
  }
  return r;
}

MemoryState MemoryHierarchy::State() const {
  MemoryState state;
  for (const auto& level : stores_) {
    state.held.emplace_back();
    for (const CellStore& s : level) state.held.back().push_back(s.Held());
  }
  return state;
}

MemoryState MemoryHierarchy::Fitted(const ReplayConfig& config,
                                    const std::vector<std::uint64_t>& footprints,
                                    const MemoryState& state) {
  MemoryHierarchy h(config, footprints);
  RAYCELL_CHECK_EQ(state.held.size(), h.stores_.size());
  for (std::size_t i = 0; i < h.stores_.size(); ++i) {
    RAYCELL_CHECK_EQ(state.held[i].size(), h.stores_[i].size());
    for (std::size_t k = 0; k < h.stores_[i].size(); ++k) {
      for (const CellId c : state.held[i][k]) h.stores_[i][k].Insert(c);
    }
  }
  return h.State();
}

std::vector<std::vector<bool>> HeldAnywhere(const MemoryState& state, std::uint32_t cells,
                                            const MemoryUnits* units) {
  std::vector<std::vector<bool>> held;
  for (const auto& level : state.held) {
    held.emplace_back(UnitCount(units, held.size(), cells), false);
    for (const auto& copy : level) {
      for (const CellId c : copy) held.back()[c.value()] = true;
    }
  }
  return held;
}

bool MemoryHierarchy::diverged() const {
  for (const auto& level : stores_) {
    for (const CellStore& s : level) {
      if (s.diverged()) return true;
    }
  }
  return false;
}

CellStore& MemoryHierarchy::Store(std::size_t level, std::uint32_t processor) {
  return stores_[level][level == 0 ? processor : 0];
}

SimTime& MemoryHierarchy::LinkFree(std::size_t level, std::uint32_t processor) {
  return link_free_[level][level == 0 ? processor : 0];
}

SimTime MemoryHierarchy::Transfer(std::uint32_t processor, CellId cell, std::size_t from, SimTime t,
                                  std::optional<CellId> pinned) {
  // A shared level holds a cell from when it is asked for there, but can pass it on only
  // once it has arrived (another processor's transfer of it may still be on its way).
  // Each link carries its level's unit of the cell.
  if (from >= 1 && from < levels_.size()) {
    t = std::max(t, arrives_[from][UnitOf(from, cell).value()]);
  }
  for (std::size_t i = from; i-- > 0;) {  // down through every level above `from`
    const CellId unit = UnitOf(i, cell);
    const std::uint64_t bytes = Bytes(i, unit);
    SimTime& free = LinkFree(i, processor);
    const SimTime start = std::max(t, free);
    t = start + levels_[i].latency_below + levels_[i].bandwidth_below.TransferTime(bytes);
    free = t;
    if (observer_) {  // a prefetch keeps the cell being worked: only it passes `pinned`
      observer_->Transfer(i, i == 0 ? processor : 0, unit, bytes, start, t, processor,
                          pinned.has_value());
    }
    Store(i, processor).Insert(unit, i == 0 ? pinned : std::nullopt);
    if (i >= 1) arrives_[i][unit.value()] = t;
    CheckedIncrement(stats_[i].fetches);
    CheckedIncrement(stats_[i].bytes, bytes);
  }
  return t;
}

SimTime MemoryHierarchy::Fetch(std::uint32_t processor, CellId cell, SimTime now) {
  std::size_t from = 0;  // the nearest level holding the cell; levels_.size() = host
  while (from < levels_.size() && !Store(from, processor).Lookup(UnitOf(from, cell))) ++from;
  if (from == 0) {
    if (prefetched_[processor][cell.value()]) CheckedIncrement(prefetch_hits_);
    prefetched_[processor][cell.value()] = false;
    return std::max(now, arrival_[processor][cell.value()]);
  }
  prefetched_[processor][cell.value()] = false;
  return Transfer(processor, cell, from, now, std::nullopt);
}

bool MemoryHierarchy::Prefetch(std::uint32_t processor, CellId cell, SimTime now, CellId working) {
  CellStore& cache = Store(0, processor);
  if (cache.Contains(cell) || !cache.Fits(cell, working)) return false;
  std::size_t from = 1;
  while (from < levels_.size() && !Store(from, processor).Lookup(UnitOf(from, cell))) ++from;
  arrival_[processor][cell.value()] = Transfer(processor, cell, from, now, working);
  prefetched_[processor][cell.value()] = true;
  CheckedIncrement(prefetches_);
  return true;
}

}  // namespace raycell
