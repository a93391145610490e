// A 32-bit id that is a type of its own (docs/design.md §1 "Cell and node ids"): made from a
// number only explicitly, compared only with ids of its own kind, printed as its number. The
// kinds derive from it and name the accessor that gives the number back (CellId::value(),
// NodeId::index()). Four bytes, trivially copyable: it costs nothing over the number.
#pragma once

#include <cstdint>
#include <ostream>

namespace raycell {

template <typename Kind>
class TypedId {
 public:
  TypedId() = default;  // uninitialised, as a plain number; Kind{} is 0
  constexpr explicit TypedId(std::uint32_t number) : number_(number) {}

  friend constexpr bool operator==(Kind a, Kind b) { return a.number_ == b.number_; }
  friend constexpr bool operator!=(Kind a, Kind b) { return a.number_ != b.number_; }
  friend constexpr bool operator<(Kind a, Kind b) { return a.number_ < b.number_; }
  friend constexpr bool operator>(Kind a, Kind b) { return a.number_ > b.number_; }
  friend constexpr bool operator<=(Kind a, Kind b) { return a.number_ <= b.number_; }
  friend constexpr bool operator>=(Kind a, Kind b) { return a.number_ >= b.number_; }
  friend std::ostream& operator<<(std::ostream& out, Kind a) { return out << a.number_; }

 protected:
  constexpr std::uint32_t number() const { return number_; }
  constexpr void Increment() { ++number_; }

 private:
  std::uint32_t number_;
};

// The ids first .. end-1 of one kind, in order: for (CellId c : CellRange(n)).
template <typename Id>
class IdRange {
 public:
  class Iterator {
   public:
    constexpr explicit Iterator(std::uint32_t number) : number_(number) {}
    constexpr Id operator*() const { return Id(number_); }
    constexpr Iterator& operator++() {
      ++number_;
      return *this;
    }
    constexpr bool operator!=(Iterator o) const { return number_ != o.number_; }

   private:
    std::uint32_t number_;
  };
  constexpr IdRange(std::uint32_t first, std::uint32_t end) : first_(first), end_(end) {}
  constexpr Iterator begin() const { return Iterator(first_); }
  constexpr Iterator end() const { return Iterator(end_); }

 private:
  std::uint32_t first_, end_;
};

}  // namespace raycell
