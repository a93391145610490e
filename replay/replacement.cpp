#include "replay/replacement.h"

#include <algorithm>
#include <cstdint>
#include <utility>

#include "base/check.h"

namespace raycell {

constexpr ReplacementEntry kLruReplacement = [] {
  ReplacementEntry e;
  e.name = "lru";
  e.note = nullptr;
  e.needs_future = false;
  e.make = [](std::uint32_t cells, std::vector<CellId>) -> std::unique_ptr<ReplacementPolicy> {
    return std::make_unique<RecencyReplacement>(cells, true);
  };
  return e;
}();

constexpr ReplacementEntry kFifoReplacement = [] {
  ReplacementEntry e;
  e.name = "fifo";
  e.note = nullptr;
  e.needs_future = false;
  e.make = [](std::uint32_t cells, std::vector<CellId>) -> std::unique_ptr<ReplacementPolicy> {
    return std::make_unique<RecencyReplacement>(cells, false);
  };
  return e;
}();

constexpr ReplacementEntry kMinReplacement = [] {
  ReplacementEntry e;
  e.name = "min";
  e.note = "Belady's MIN, a bound";
  e.needs_future = true;
  e.make = [](std::uint32_t cells,
              std::vector<CellId> future) -> std::unique_ptr<ReplacementPolicy> {
    return std::make_unique<MinReplacement>(cells, std::move(future));
  };
  return e;
}();

const std::vector<std::reference_wrapper<const ReplacementEntry>>& ReplacementRegistry() {
  // The order of the key's meaning and of its error message.
  static const std::vector<std::reference_wrapper<const ReplacementEntry>> registry = {
      kLruReplacement, kFifoReplacement, kMinReplacement};
  return registry;
}

std::unique_ptr<ReplacementPolicy> MakeReplacement(const ReplacementEntry& entry,
                                                   std::uint32_t cells,
                                                   std::vector<CellId> future) {
  return entry.make(cells, std::move(future));
}

std::vector<CellId> ReplacementPolicy::EvictionOrder(const std::vector<bool>& held) const {
  std::vector<CellId> order;
  for (std::uint32_t c = 0; c < held.size(); ++c) {
    if (held[c]) order.push_back(CellId(c));
  }
  return order;
}

// ---- LRU and FIFO ------------------------------------------------------------------------

RecencyReplacement::RecencyReplacement(std::uint32_t cells, bool move_on_hit)
    : move_on_hit_(move_on_hit), pos_(cells) {}

void RecencyReplacement::Hit(CellId cell) {
  if (move_on_hit_) order_.splice(order_.end(), order_, pos_[cell.value()]);
}

void RecencyReplacement::Inserted(CellId cell) {
  pos_[cell.value()] = order_.insert(order_.end(), cell);
}

void RecencyReplacement::Evicted(CellId cell) { order_.erase(pos_[cell.value()]); }

std::optional<CellId> RecencyReplacement::Victim(std::optional<CellId> pinned) const {
  for (const CellId c : order_) {
    if (c != pinned) return c;
  }
  return std::nullopt;
}

std::vector<CellId> RecencyReplacement::EvictionOrder(const std::vector<bool>&) const {
  return {order_.begin(), order_.end()};
}

// ---- MIN ---------------------------------------------------------------------------------

MinReplacement::MinReplacement(std::uint32_t cells, std::vector<CellId> future)
    : future_(std::move(future)), uses_(cells), held_(cells, false) {
  for (std::size_t i = 0; i < future_.size(); ++i) uses_[future_[i].value()].push_back(i);
}

std::size_t MinReplacement::NextUse(CellId cell) const {
  const auto& u = uses_[cell.value()];
  const auto it = std::lower_bound(u.begin(), u.end(), pos_);
  return it == u.end() ? SIZE_MAX : *it;
}

void MinReplacement::Requested(CellId cell) {
  if (pos_ < future_.size() && future_[pos_] == cell) {
    ++pos_;
    return;
  }
  diverged_ = true;  // resynchronise on this cell's next request, if any
  const std::size_t next = NextUse(cell);
  if (next != SIZE_MAX) pos_ = next + 1;
}

std::optional<CellId> MinReplacement::Victim(std::optional<CellId> pinned) const {
  std::optional<CellId> victim;
  std::size_t farthest = 0;
  for (CellId c : CellRange(held_.size())) {
    if (!held_[c.value()] || c == pinned) continue;
    const std::size_t next = NextUse(c);
    if (!victim || next > farthest) victim = c, farthest = next;
  }
  return victim;
}

}  // namespace raycell
