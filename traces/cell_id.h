// A cell of the scene's grid (docs/design.md §1 "Cell and node ids"): cell = x + nx*(y + ny*z).
// A type of its own (base/typed_id.h), so that a cell, a Cell Tree node (NodeId) and a count
// never convert into each other: a CellId is made from a number only explicitly, CellId(i),
// and gives it back only through value(). ++c steps to the next cell in that numbering.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <ostream>
#include <type_traits>

#include "base/typed_id.h"

namespace raycell {

class CellId : public TypedId<CellId> {
 public:
  using TypedId::TypedId;
  constexpr std::uint32_t value() const { return number(); }
  constexpr CellId& operator++() {
    Increment();
    return *this;
  }
};
static_assert(sizeof(CellId) == sizeof(std::uint32_t) && std::is_trivially_copyable_v<CellId>);

// The cells 0 .. count-1 in order: for (CellId c : CellRange(count)).
class CellRange : public IdRange<CellId> {
 public:
  constexpr explicit CellRange(std::uint32_t count) : IdRange(0, count) {}
};

// No cell: the Cell Tree root's, and a separator where lists of cells are flattened.
inline constexpr CellId kNoCell{std::numeric_limits<std::uint32_t>::max()};

}  // namespace raycell

template <>
struct std::hash<raycell::CellId> {
  std::size_t operator()(raycell::CellId c) const noexcept {
    return std::hash<std::uint32_t>()(c.value());
  }
};
