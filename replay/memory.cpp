#include "replay/memory.h"

#include <algorithm>

#include "engine/checked.h"
#include "traces/check.h"

namespace raycell {

CellStore::CellStore(const LevelConfig& level, const std::vector<std::uint64_t>* footprints)
    : level_(level), footprints_(footprints), stamp_(footprints->size(), 0) {}

std::uint64_t CellStore::Size(CellId cell) const {
  return level_.capacity_unit == LevelConfig::CapacityUnit::kCells ? 1 : (*footprints_)[cell];
}

bool CellStore::Lookup(CellId cell) {
  if (stamp_[cell] == 0) return false;
  if (level_.replacement == LevelConfig::Replacement::kLru) stamp_[cell] = ++clock_;
  return true;
}

void CellStore::EvictOne() {
  CellId victim = 0;
  std::uint64_t oldest = 0;
  for (CellId c = 0; c < stamp_.size(); ++c) {
    if (stamp_[c] != 0 && (oldest == 0 || stamp_[c] < oldest)) victim = c, oldest = stamp_[c];
  }
  RAYCELL_CHECK(oldest != 0);
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
                                 const std::vector<std::uint64_t>& footprints)
    : levels_(config.levels), footprints_(footprints) {
  RAYCELL_CHECK(!levels_.empty());
  for (std::size_t i = 0; i < levels_.size(); ++i) {
    if (levels_[i].replacement == LevelConfig::Replacement::kMin) {
      throw InputError("level '" + levels_[i].name +
                       "': replacement min (Belady) needs each level's future requests; this "
                       "replay does not run it yet: use lru or fifo");
    }
    const std::uint32_t copies = i == 0 ? config.processors.count : 1;
    stores_.emplace_back(copies, CellStore(levels_[i], &footprints_));
    link_free_.emplace_back(copies, SimTime::Zero());
    stats_.push_back({levels_[i].name, 0, 0});
  }
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
