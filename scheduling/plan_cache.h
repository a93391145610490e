// Plans shared across the configurations of a sweep (issue 43; docs/design.md §5 "Sharing
// plans"): what a scheduler computes in BeginFrame from earlier frames' trees and a few
// configuration values (a plan, the union of two trees, a plan's run, stand-ins, statistics of
// a tree) is a function of those alone, so the runner gives every configuration replayed on a
// frame one PlanCache (FrameInfo::plans), and each such value is computed once per frame for
// all of them, whatever the processors, memory levels or bandwidths. A value is named by a key
// that holds everything it depends on: the trees' contents (TreeKey), the seed, the values it
// reads; never a tree's address, which a scheduler that makes trees of its own may reuse.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

class PlanCache {
 public:
  // memo: plan through the process-wide memo of plans (PlanFor), which also serves other
  // frames and schedulers; false: every plan is searched again (a configuration planning
  // alone, which the sharing test compares with).
  explicit PlanCache(bool memo = true) : memo_(memo) {}
  PlanCache(const PlanCache&) = delete;
  PlanCache& operator=(const PlanCache&) = delete;

  // The value of `key`, made by make() (a T) the first time it is asked for; callers asking
  // for it meanwhile on other threads wait for that one. The cache keeps it until released
  // (the runner releases all once every configuration of the frame began, ReleaseAll): a
  // scheduler holds the shared_ptr of what it reads after BeginFrame, so that the value goes
  // with the last configuration holding it (issue 43). Every caller of a key must ask for the
  // same T and make the same value (the key names all it depends on).
  template <typename T, typename Make>
  std::shared_ptr<const T> Get(std::uint64_t key, Make make) {
    std::shared_ptr<Slot> slot;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      std::shared_ptr<Slot>& s = slots_[key];
      if (!s) s = std::make_shared<Slot>();
      slot = s;
    }
    std::call_once(slot->once, [&] {
      slot->value = std::make_shared<const T>(make());
      std::lock_guard<std::mutex> lock(mutex_);
      ++made_;
    });
    return std::static_pointer_cast<const T>(slot->value);
  }

  // Forgets every value (the runner, once every configuration of the frame began): each goes
  // when its last holder drops it, so a scheduler holds (shared_ptr) what it reads after
  // BeginFrame; asked for again, a value is made again.
  void ReleaseAll() {
    std::lock_guard<std::mutex> lock(mutex_);
    slots_.clear();
  }

  bool memo() const { return memo_; }
  // Values made so far (for tests: each key once).
  std::size_t made() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return made_;
  }

 private:
  struct Slot {
    std::once_flag once;
    std::shared_ptr<const void> value;
  };
  bool memo_;
  mutable std::mutex mutex_;
  std::map<std::uint64_t, std::shared_ptr<Slot>> slots_;
  std::size_t made_ = 0;
};

// A hash of the tree's contents: every node's cell and parent (O(nodes)).
std::uint64_t TreeKey(const CellTree& tree);
// A hash of a map of cells to board cells (FrameInfo::board_cell_of, BoardCellOf).
std::uint64_t BoardKey(const std::vector<CellId>& board_cell_of);
// A key for a value of kind `kind` (a distinct constant per kind of value) over `parts`.
std::uint64_t PlanKey(std::uint64_t kind, std::initializer_list<std::uint64_t> parts);

// `cache`'s value for `key` (made once), or, without a cache (a scheduler asked outside a
// runner), make()'s own.
template <typename T, typename Make>
std::shared_ptr<const T> Shared(PlanCache* cache, std::uint64_t key, Make make) {
  if (cache == nullptr) return std::make_shared<const T>(make());
  return cache->Get<T>(key, std::move(make));
}

// Kinds of shared values (PlanKey's first argument), one per kind of value.
enum PlanKind : std::uint64_t {
  kPeelPlan = 1,
  kUnionTree,
  kBestPlan,
  kTwoLevelPeelPlan,
  kTwoLevelBestPlan,
  kAdaptiveStart,
  kTreeStats,
  kHeights,
  kStandIns,
  kSeenWork,  // a tree's work per node, for the replays of frames seen (replay/)
};

// Peel's schedule of `tree` (graph/peel.h), and the union of two trees (its shape, UnionShape:
// what the planners and celltree-adaptive's prediction read of it), shared through `cache`
// (null: made here).
std::shared_ptr<const std::vector<CellId>> SharedPeel(PlanCache* cache, const CellTree& tree);
std::shared_ptr<const CellTree> SharedUnion(PlanCache* cache, const CellTree& before,
                                            const CellTree& previous);

}  // namespace raycell
