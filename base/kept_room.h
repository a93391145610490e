// Room kept by per-cell lists that empty and fill again within a frame (a board's ray queues, a
// scheduler's queued nodes; docs/design.md §2 "What a replay holds"). An emptied list keeps its
// room for the next fill, as std::vector does, but only up to a share of a budget for all the
// lists together: kept in every cell, the high-water rooms of thousands of cells held more
// than the queued items themselves (360 MB of queues at 4096 cells and 8 processors).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace raycell {

// The budget of each kind of list (a board's queues, a scheduler's queued nodes).
inline constexpr std::size_t kKeptRoomBytes = std::size_t{32} << 20;

// The room, in items of `item_bytes`, each of `lists` lists may keep so that together they
// keep at most `budget_bytes`; never less than `floor` items (a short list's room, which is
// worth keeping), never more than `ceiling`.
inline std::size_t KeptRoom(std::size_t budget_bytes, std::size_t item_bytes, std::size_t lists,
                            std::size_t floor, std::size_t ceiling) {
  const std::size_t per_list = budget_bytes / (item_bytes * std::max<std::size_t>(lists, 1));
  return std::clamp(per_list, floor, std::max(floor, ceiling));
}

// Empties `v` and frees its room. (`v = {}` does not: it is the initializer-list assignment,
// which clears and keeps the capacity.)
template <typename T, typename A>
void FreeRoom(std::vector<T, A>& v) {
  std::vector<T, A>().swap(v);
}

// Frees the room of `v` (empty or not) when it exceeds `kept` items: a std::vector, or any list
// with a FreeRoom of its own (base/mapped_array.h).
template <typename V>
void ReleaseRoomAbove(V& v, std::size_t kept) {
  if (v.capacity() > kept) FreeRoom(v);
}

}  // namespace raycell
