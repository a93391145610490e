#include "replay/memory.h"

#include <algorithm>

#include "engine/checked.h"
#include "traces/check.h"

namespace raycell {

CellStore::CellStore(const LevelConfig& level, const std::vector<std::uint64_t>* footprints,
                     std::vector<CellId> future)
    : level_(level), footprints_(footprints), stamp_(footprints->size(), 0),
      future_(std::move(future)), uses_(footprints->size()) {
  for (std::size_t i = 0; i < future_.size(); ++i) uses_[future_[i]].push_back(i);
}

std::size_t CellStore::NextUse(CellId cell) const {
  const auto& u = uses_[cell];
  const auto it = std::lower_bound(u.begin(), u.end(), pos_);
  return it == u.end() ? SIZE_MAX : *it;
}

CellId CellStore::MinVictim() const {
  CellId victim = 0;
  std::size_t farthest = 0;
  bool found = false;
  for (CellId c = 0; c < stamp_.size(); ++c) {
    if (stamp_[c] == 0) continue;
    const std::size_t next = NextUse(c);
    if (!found || next > farthest) victim = c, farthest = next, found = true;
  }
  RAYCELL_CHECK(found);
  return victim;
}

std::uint64_t CellStore::Size(CellId cell) const {
  return level_.capacity_unit == LevelConfig::CapacityUnit::kCells ? 1 : (*footprints_)[cell];
}

bool CellStore::Lookup(CellId cell) {
  requests_.push_back(cell);
  if (level_.replacement == LevelConfig::Replacement::kMin) {
    if (pos_ < future_.size() && future_[pos_] == cell) {
      ++pos_;
    } else {
      diverged_ = true;  // resynchronise on this cell's next request, if any
      const std::size_t next = NextUse(cell);
      if (next != SIZE_MAX) pos_ = next + 1;
    }
  }
  if (stamp_[cell] == 0) return false;
  if (level_.replacement == LevelConfig::Replacement::kLru) stamp_[cell] = ++clock_;
  return true;
}

void CellStore::EvictOne() {
  CellId victim = 0;
  if (level_.replacement == LevelConfig::Replacement::kMin) {
    victim = MinVictim();
  } else {
    std::uint64_t oldest = 0;
    for (CellId c = 0; c < stamp_.size(); ++c) {
      if (stamp_[c] != 0 && (oldest == 0 || stamp_[c] < oldest)) victim = c, oldest = stamp_[c];
    }
    RAYCELL_CHECK(oldest != 0);
  }
  stamp_[victim] = 0;
  used_ -= Size(victim);
}

void CellStore::Insert(CellId cell) {
  if (stamp_[cell] != 0 || Size(cell) > level_.capacity) return;
  while (used_ + Size(cell) > level_.capacity) EvictOne();
  stamp_[cell] = ++clock_;
  used_ += Size(cell);
}

MemoryHierarchy::MemoryHierarchy(const ReplayConfig& config,
                                 const std::vector<std::uint64_t>& footprints,
                                 const Requests& futures)
    : levels_(config.levels), footprints_(footprints) {
  RAYCELL_CHECK(!levels_.empty());
  for (std::size_t i = 0; i < levels_.size(); ++i) {
    const bool min = levels_[i].replacement == LevelConfig::Replacement::kMin;
    LevelConfig level = levels_[i];
    if (min && futures.empty()) level.replacement = LevelConfig::Replacement::kLru;
    const std::uint32_t copies = i == 0 ? config.processors.count : 1;
    stores_.emplace_back();
    for (std::uint32_t k = 0; k < copies; ++k) {
      stores_.back().emplace_back(level, &footprints_,
                                  min && !futures.empty() ? futures[i][k] : std::vector<CellId>{});
    }
    link_free_.emplace_back(copies, SimTime::Zero());
    stats_.push_back({levels_[i].name, 0, 0});
  }
}

MemoryHierarchy::Requests MemoryHierarchy::requests() const {
  Requests r(stores_.size());
  for (std::size_t i = 0; i < stores_.size(); ++i) {
    for (const CellStore& s : stores_[i]) r[i].push_back(s.requests());
  }
  return r;
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

SimTime MemoryHierarchy::Fetch(std::uint32_t processor, CellId cell, SimTime now) {
  std::size_t from = 0;  // the nearest level holding the cell; levels_.size() = host
  while (from < levels_.size() && !Store(from, processor).Lookup(cell)) ++from;
  SimTime t = now;
  for (std::size_t i = from; i-- > 0;) {  // down through every level above `from`
    SimTime& free = LinkFree(i, processor);
    const SimTime start = std::max(t, free);
    t = start + levels_[i].latency_below +
        levels_[i].bandwidth_below.TransferTime(footprints_[cell]);
    free = t;
    Store(i, processor).Insert(cell);
    CheckedIncrement(stats_[i].fetches);
    CheckedIncrement(stats_[i].bytes, footprints_[cell]);
  }
  return t;
}

}  // namespace raycell
