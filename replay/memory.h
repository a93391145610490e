// The memory levels between the block processors and host memory (DESIGN.md §2): level 0 is
// each processor's own cell cache, the others are shared (board memory), and host memory
// below the last level holds every cell. Moving a cell across the link below a level takes
// that link's latency plus footprint / bandwidth; a link carries one transfer at a time.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/time.h"
#include "replay/config.h"
#include "traces/ray_batch.h"

namespace raycell {

// One level's contents, with LRU or FIFO replacement. Capacity in cells or bytes; a cell
// larger than the whole capacity passes through without being kept.
class CellStore {
 public:
  CellStore(const LevelConfig& level, const std::vector<std::uint64_t>* footprints);
  // True if `cell` is held; a hit refreshes it under LRU.
  bool Lookup(CellId cell);
  // Keeps `cell`, evicting the least recently used (LRU) or oldest (FIFO) cells to make room.
  void Insert(CellId cell);
  bool Contains(CellId cell) const { return stamp_[cell] != 0; }
  std::uint64_t used() const { return used_; }

 private:
  std::uint64_t Size(CellId cell) const;
  void EvictOne();

  LevelConfig level_;
  const std::vector<std::uint64_t>* footprints_;
  std::vector<std::uint64_t> stamp_;  // 0: absent; else last use (LRU) or arrival (FIFO)
  std::uint64_t clock_ = 0, used_ = 0;
};

struct LevelStats {
  std::string name;
  std::uint64_t fetches = 0;  // cells brought into this level from the one below
  std::uint64_t bytes = 0;    // their footprints
};

class MemoryHierarchy {
 public:
  // InputError for a replacement policy the replay cannot run.
  MemoryHierarchy(const ReplayConfig& config, const std::vector<std::uint64_t>& footprints);
  // Brings `cell` into processor p's cache, asked at `now`; returns when it is there (now on
  // a hit). Deterministic: the same calls give the same times.
  SimTime Fetch(std::uint32_t processor, CellId cell, SimTime now);
  const std::vector<LevelStats>& stats() const { return stats_; }

 private:
  CellStore& Store(std::size_t level, std::uint32_t processor);
  SimTime& LinkFree(std::size_t level, std::uint32_t processor);

  std::vector<LevelConfig> levels_;
  const std::vector<std::uint64_t>& footprints_;
  std::vector<std::vector<CellStore>> stores_;   // [level][processor, or 0 when shared]
  std::vector<std::vector<SimTime>> link_free_;  // the link below each level, likewise
  std::vector<LevelStats> stats_;
};

}  // namespace raycell
