// Replacement policies of a memory level (docs/design.md §2; CONTRIBUTING.md: policies plug in
// through small interfaces, after ChampSim's replacement modules). A CellStore keeps which
// cells it holds and their bytes; its policy is told every request, hit, insertion and
// eviction, and picks the victim when room is needed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <optional>
#include <vector>

#include "graph/cell_tree.h"  // CellId
#include "replay/config.h"

namespace raycell {

class ReplacementPolicy {
 public:
  virtual ~ReplacementPolicy() = default;
  // Every lookup, hit or miss, in request order (MIN follows its future with it).
  virtual void Requested(CellId /*cell*/) {}
  // A lookup that found `cell` held.
  virtual void Hit(CellId cell) = 0;
  // `cell` was brought in / thrown out.
  virtual void Inserted(CellId cell) = 0;
  virtual void Evicted(CellId cell) = 0;
  // The held cell to evict, never `pinned`; nullopt when there is none.
  virtual std::optional<CellId> Victim(std::optional<CellId> pinned) const = 0;
  // MIN only: whether the requests strayed from the future it was given.
  virtual bool diverged() const { return false; }
  // The held cells (held[c]) in the order this policy would evict them, first victim first,
  // so that inserting them into a new policy in this order gives it the same state (memory
  // kept across frames). Default: by cell number, for policies whose victims do not depend on
  // the order cells came in (MIN).
  virtual std::vector<CellId> EvictionOrder(const std::vector<bool>& held) const;
};

// A replacement policy's registry entry, as the schedulers' (scheduling/scheduler.h
// SchedulerEntry): each is defined in replacement.cpp with every field set by name, and a
// memory level holds its policy's entry (LevelConfig::replacement), resolved from its name
// once, where the configuration is read.
struct ReplacementEntry {
  const char* name = nullptr;  // as in configs: "lru"
  const char* note = nullptr;  // for the key's meaning, or null: "Belady's MIN, a bound"
  // Whether it needs the level's future requests (Belady's MIN): a replay first runs the
  // frame with LRU at that level to learn them (MemoryHierarchy), then again with the policy
  // (ReplayFrame).
  bool needs_future = false;
  // The policy for a store of `cells` cells; `future`: the requests a previous run of the
  // same frame made at this store (needs_future only).
  std::unique_ptr<ReplacementPolicy> (*make)(std::uint32_t cells,
                                             std::vector<CellId> future) = nullptr;
};
// Least recently used, first in first out, Belady's MIN.
extern const ReplacementEntry kLruReplacement;
extern const ReplacementEntry kFifoReplacement;
extern const ReplacementEntry kMinReplacement;

// Every replacement policy: the one list that configurations (parsing, printing, the key's
// meaning and its messages) derive from. A new policy is an entry in replacement.cpp and a
// line in this list.
const std::vector<std::reference_wrapper<const ReplacementEntry>>& ReplacementRegistry();

// The policy of `entry` for a store of `cells` cells (entry.make). A policy that needs a
// future given none is a CHECK failure.
std::unique_ptr<ReplacementPolicy> MakeReplacement(const ReplacementEntry& entry,
                                                   std::uint32_t cells,
                                                   std::vector<CellId> future = {});

// Least recently used (move_on_hit) or first in, first out: held cells in a list, oldest use
// or arrival first; the victim is the first that is not pinned.
class RecencyReplacement : public ReplacementPolicy {
 public:
  RecencyReplacement(std::uint32_t cells, bool move_on_hit);
  void Hit(CellId cell) override;
  void Inserted(CellId cell) override;
  void Evicted(CellId cell) override;
  std::optional<CellId> Victim(std::optional<CellId> pinned) const override;
  std::vector<CellId> EvictionOrder(const std::vector<bool>& held) const override;

 private:
  bool move_on_hit_;
  std::list<CellId> order_;                       // oldest first
  std::vector<std::list<CellId>::iterator> pos_;  // per cell, valid while held
};

// Belady's MIN: evicts the held cell whose next request lies farthest in the future (never
// requested again first; lowest cell number on ties).
class MinReplacement : public ReplacementPolicy {
 public:
  MinReplacement(std::uint32_t cells, std::vector<CellId> future);
  void Requested(CellId cell) override;
  void Hit(CellId) override {}
  void Inserted(CellId cell) override { held_[cell.value()] = true; }
  void Evicted(CellId cell) override { held_[cell.value()] = false; }
  std::optional<CellId> Victim(std::optional<CellId> pinned) const override;
  bool diverged() const override { return diverged_; }

 private:
  // Position in future_ of the next request of `cell` at or after pos_; SIZE_MAX if none.
  std::size_t NextUse(CellId cell) const;

  std::vector<CellId> future_;
  std::vector<std::vector<std::size_t>> uses_;  // per cell: its positions in future_
  std::vector<bool> held_;
  std::size_t pos_ = 0;
  bool diverged_ = false;
};

}  // namespace raycell
