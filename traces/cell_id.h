// A cell of the scene's grid (docs/design.md §1 "Cell and node ids"): cell = x + nx*(y + ny*z).
// A type of its own, not a plain number, so that a cell, a Cell Tree node (NodeId, also 32
// bits) and a count never convert into each other: a CellId is made from a number only
// explicitly, CellId(i), and gives it back only through value(). ++c steps to the next cell
// in that numbering, for loops over a grid's cells. Four bytes, trivially copyable: it costs
// nothing over the number it holds.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <ostream>
#include <type_traits>

namespace raycell {

class CellId {
 public:
  CellId() = default;  // uninitialised, as a plain number; CellId{} is cell 0
  constexpr explicit CellId(std::uint32_t value) : value_(value) {}
  constexpr std::uint32_t value() const { return value_; }
  constexpr CellId& operator++() {
    ++value_;
    return *this;
  }
  friend constexpr bool operator==(CellId a, CellId b) { return a.value_ == b.value_; }
  friend constexpr bool operator!=(CellId a, CellId b) { return a.value_ != b.value_; }
  friend constexpr bool operator<(CellId a, CellId b) { return a.value_ < b.value_; }
  friend constexpr bool operator>(CellId a, CellId b) { return a.value_ > b.value_; }
  friend constexpr bool operator<=(CellId a, CellId b) { return a.value_ <= b.value_; }
  friend constexpr bool operator>=(CellId a, CellId b) { return a.value_ >= b.value_; }
  friend std::ostream& operator<<(std::ostream& out, CellId c) { return out << c.value_; }

 private:
  std::uint32_t value_;
};
static_assert(sizeof(CellId) == sizeof(std::uint32_t) && std::is_trivially_copyable_v<CellId>);

// The cells 0 .. count-1 in order: for (CellId c : CellRange(count)).
class CellRange {
 public:
  class Iterator {
   public:
    constexpr explicit Iterator(std::uint32_t v) : v_(v) {}
    constexpr CellId operator*() const { return CellId(v_); }
    constexpr Iterator& operator++() {
      ++v_;
      return *this;
    }
    constexpr bool operator!=(Iterator o) const { return v_ != o.v_; }

   private:
    std::uint32_t v_;
  };
  constexpr explicit CellRange(std::uint32_t count) : count_(count) {}
  constexpr Iterator begin() const { return Iterator(0); }
  constexpr Iterator end() const { return Iterator(count_); }

 private:
  std::uint32_t count_;
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
