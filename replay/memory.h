// The memory levels between the block processors and host memory (docs/design.md §2): level 0 is
// each processor's own cell cache, the others are shared (board memory), and host memory
// below the last level holds every cell. Moving a cell across the link below a level takes
// that link's latency plus footprint / bandwidth; a link carries one transfer at a time.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/time.h"
#include "replay/config.h"
#include "replay/observer.h"
#include "replay/replacement.h"
#include "traces/ray_batch.h"

namespace raycell {

// One level's contents: which cells it holds and their bytes; its replacement policy
// (replay/replacement.h: LRU, FIFO or Belady's MIN) picks the victims. Capacity in cells or
// bytes; a cell larger than the whole capacity passes through without being kept.
//
// MIN needs this store's future requests: `future`, the requests a previous run of the same
// frame made (see ReplayFrame). Every Lookup is recorded in requests(), and diverged() tells
// whether they strayed from `future`.
class CellStore {
 public:
  CellStore(const LevelConfig& level, const std::vector<std::uint64_t>* footprints,
            std::vector<CellId> future = {});
  // True if `cell` is held; the policy is told of the request and the hit.
  bool Lookup(CellId cell);
  // Keeps `cell`, evicting the policy's victims to make room, never `pinned` (the cell a
  // processor is working). False if it cannot be kept.
  bool Insert(CellId cell, std::optional<CellId> pinned = std::nullopt);
  // Whether Insert(cell, pinned) would keep the cell.
  bool Fits(CellId cell, std::optional<CellId> pinned) const;
  bool Contains(CellId cell) const { return held_[cell.value()]; }
  std::uint64_t used() const { return used_; }
  const std::vector<CellId>& requests() const { return requests_; }
  bool diverged() const { return policy_->diverged(); }
  // The held cells, first victim first (ReplacementPolicy::EvictionOrder).
  std::vector<CellId> Held() const { return policy_->EvictionOrder(held_); }
  // Keeps `cells` (as Held() listed them) without counting them as requests or fetches: the
  // state a frame starts from. They fit by construction (the same level held them, or
  // MemoryHierarchy::Fitted kept them).
  void Restore(const std::vector<CellId>& cells);

 private:
  std::uint64_t Size(CellId cell) const;

  LevelConfig level_;
  const std::vector<std::uint64_t>* footprints_;
  std::unique_ptr<ReplacementPolicy> policy_;
  std::vector<bool> held_;
  std::uint64_t used_ = 0;
  std::vector<CellId> requests_;
};

// What a memory level stores, moves and counts (docs/design.md §2 "Levels of coarser cells"):
// the replay's cells, or, with `level.NAME.cells` (a SPEC of a regroupable capture's fine
// grid), coarser cells, each a union of the replay's (a board that loads 3x3x3 cells for
// caches that hold 6x6x6 ones). A unit is numbered as a cell of its own subdivision; the link
// below a level carries that level's units, at their bytes.
struct LevelUnits {
  std::vector<CellId> unit_of_cell;  // per replay cell; empty: the replay's cells
  std::vector<std::uint64_t> bytes;  // per unit, its footprint (each leaf once)
  bool identity() const { return unit_of_cell.empty(); }
};
// Per level (nearest first); empty, or a level's identity(): that level holds the replay's
// cells. A level's units nest in the next level's (each unit lies in one unit below it).
using MemoryUnits = std::vector<LevelUnits>;
// The units of level `level` under `units` (null or empty: the replay's cells): `cells` or
// that level's unit count.
std::uint32_t UnitCount(const MemoryUnits* units, std::size_t level, std::uint32_t cells);

// What the levels hold: per level and copy (processor for level 0, else one), the held cells
// in the order the copy's policy would evict them. A frame with warm memory starts from the
// state the previous frame ended with (docs/design.md §2 "Memory"); empty: every level empty.
struct MemoryState {
  std::vector<std::vector<std::vector<CellId>>> held;  // [level][copy]
  bool empty() const { return held.empty(); }
};

// One frame's cells as unions of a fine grid's cells (a dynamic subdivision, whose cells are
// other boxes every frame): per fine cell its cell (kNoCell: none), and per cell its
// footprint in that frame (0: empty, no data).
struct FrameCells {
  const std::vector<CellId>* of_fine = nullptr;
  const std::vector<std::uint64_t>* footprints = nullptr;
};
// What `state`, left by a frame of cells `from`, holds of the next frame's cells `to`
// (docs/design.md §2 "Across frames"): a level copy holds a non-empty cell of `to` when each
// of its fine cells lies in a cell of `from` that the copy held, or in an empty one (no
// data); a cell only partly held is not held. Each copy lists its cells first victim first,
// by the earliest victim among the cells of `from` that hold its data, ties by cell number.
// The list may not fit the level (a cell larger than it, or more cells than it holds):
// MemoryHierarchy::Fitted keeps what the policies keep. Every level must hold the replay's
// cells (no LevelUnits).
MemoryState CarryOver(const MemoryState& state, const FrameCells& from, const FrameCells& to);
// Per level of `state`, per unit of the level (`cells` of the replay, units as UnitCount
// gives them): whether some copy of the level holds it.
std::vector<std::vector<bool>> HeldAnywhere(const MemoryState& state, std::uint32_t cells,
                                            const MemoryUnits* units = nullptr);

struct LevelStats {
  std::string name;
  std::uint64_t fetches = 0;  // cells brought into this level from the one below
  std::uint64_t bytes = 0;    // their footprints
};

class MemoryHierarchy {
 public:
  // Requests per level and copy (processor for level 0, else one), as requests() returns.
  using Requests = std::vector<std::vector<std::vector<CellId>>>;
  // `futures`: for levels with MIN replacement, the requests of a previous run; empty on the
  // first run, when MIN levels run LRU to learn them.
  // `start`: what the levels hold when the frame starts (empty: nothing), as State() gave it
  // for the same configuration and footprints. `units` (null: every level the replay's cells)
  // must outlive the hierarchy.
  MemoryHierarchy(const ReplayConfig& config, const std::vector<std::uint64_t>& footprints,
                  const Requests& futures = {}, const MemoryState& start = {},
                  const MemoryUnits* units = nullptr);
  // What the levels hold now.
  MemoryState State() const;
  // What levels of `config` keep of `state` (as CarryOver gives it) when each copy inserts its
  // cells in their order, the policy evicting as it must (a policy that needs its future runs
  // as LRU, as on a first run): a state that fits, for the next frame's start.
  static MemoryState Fitted(const ReplayConfig& config,
                            const std::vector<std::uint64_t>& footprints, const MemoryState& state);
  Requests requests() const;
  // True when a MIN level's requests strayed from its future (run again with requests()).
  bool diverged() const;
  // Brings `cell` into processor p's cache, asked at `now`; returns when it is there (now on
  // a hit). Deterministic: the same calls give the same times.
  SimTime Fetch(std::uint32_t processor, CellId cell, SimTime now);
  // Starts bringing `cell` into processor p's cache at `now` while the processor works
  // `working` (which stays): double buffering. A later Fetch of the cell waits only for what
  // is left of the transfer. Returns false, doing nothing, if the cell is already there or
  // the cache has no room beside `working`.
  bool Prefetch(std::uint32_t processor, CellId cell, SimTime now, CellId working);
  const std::vector<LevelStats>& stats() const { return stats_; }
  std::uint64_t prefetches() const { return prefetches_; }
  std::uint64_t prefetch_hits() const { return prefetch_hits_; }
  // Told of every transfer (ReplayObserver::Transfer); null (the default): none.
  void set_observer(ReplayObserver* observer) { observer_ = observer; }

 private:
  CellStore& Store(std::size_t level, std::uint32_t processor);
  // Moves `cell` down from level `from` (levels_.size(): host) into p's cache, starting at
  // `t`; returns when it arrives.
  SimTime Transfer(std::uint32_t processor, CellId cell, std::size_t from, SimTime t,
                   std::optional<CellId> pinned);
  SimTime& LinkFree(std::size_t level, std::uint32_t processor);
  // Level `level`'s unit holding `cell`, and a unit's bytes.
  CellId UnitOf(std::size_t level, CellId cell) const {
    return unit_of_[level] ? (*unit_of_[level])[cell.value()] : cell;
  }
  std::uint64_t Bytes(std::size_t level, CellId unit) const {
    return (*bytes_[level])[unit.value()];
  }

  std::vector<LevelConfig> levels_;
  const std::vector<std::uint64_t>& footprints_;
  std::vector<const std::vector<CellId>*> unit_of_;       // per level; null: the cells
  std::vector<const std::vector<std::uint64_t>*> bytes_;  // per level, per unit
  std::vector<std::vector<CellStore>> stores_;            // [level][processor, or 0 when shared]
  std::vector<std::vector<SimTime>> link_free_;           // the link below each level, likewise
  std::vector<LevelStats> stats_;
  std::vector<std::vector<SimTime>> arrival_;  // [processor][cell]: when a prefetch lands
  std::vector<std::vector<bool>> prefetched_;  // [processor][cell]: not yet used
  std::vector<std::vector<SimTime>> arrives_;  // [shared level][unit]: when it gets there
  std::uint64_t prefetches_ = 0, prefetch_hits_ = 0;
  ReplayObserver* observer_ = nullptr;
};

}  // namespace raycell
