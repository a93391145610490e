// Simulated time (docs/design.md §2): an integer count of picoseconds in 64 bits, so 10^12
// samples at 1 ps each (10^12 ps = 1 s) are exact and the range is about 213 days.
// Typed and explicit: no implicit conversion from or to integers; arithmetic is checked.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <ostream>
#include <string>

#include "base/checked.h"

namespace raycell {

class SimTime {
 public:
  constexpr SimTime() = default;

  static constexpr SimTime Zero() { return SimTime(0); }
  static constexpr SimTime Max() { return SimTime(std::numeric_limits<std::uint64_t>::max()); }
  static constexpr SimTime Picoseconds(std::uint64_t ps) { return SimTime(ps); }
  static SimTime Nanoseconds(std::uint64_t ns) { return SimTime(CheckedMul(ns, 1000)); }
  static SimTime Microseconds(std::uint64_t us) { return SimTime(CheckedMul(us, 1000'000)); }
  static SimTime Milliseconds(std::uint64_t ms) { return SimTime(CheckedMul(ms, kPsPerMs)); }
  static SimTime Seconds(std::uint64_t s) { return SimTime(CheckedMul(s, kPsPerS)); }
  // Seconds as a double, rounded to the nearest picosecond. CHECK-fails unless `seconds` is
  // finite, non-negative and below SimTime::Max(); TryFromSeconds returns nullopt instead
  // (for values read from configs, which are input errors, not bugs).
  static SimTime FromSeconds(double seconds);
  static std::optional<SimTime> TryFromSeconds(double seconds);

  constexpr std::uint64_t picoseconds() const { return ps_; }
  double seconds() const { return double(ps_) / double(kPsPerS); }

  // "1234567ps".
  std::string ToString() const { return std::to_string(ps_) + "ps"; }

  SimTime& operator+=(SimTime d) { return *this = *this + d; }
  friend SimTime operator+(SimTime a, SimTime b) { return SimTime(CheckedAdd(a.ps_, b.ps_)); }
  friend SimTime operator-(SimTime a, SimTime b) { return SimTime(CheckedSub(a.ps_, b.ps_)); }
  friend SimTime operator*(SimTime a, std::uint64_t n) { return SimTime(CheckedMul(a.ps_, n)); }
  friend SimTime operator*(std::uint64_t n, SimTime a) { return a * n; }

  friend constexpr bool operator==(SimTime a, SimTime b) { return a.ps_ == b.ps_; }
  friend constexpr bool operator!=(SimTime a, SimTime b) { return a.ps_ != b.ps_; }
  friend constexpr bool operator<(SimTime a, SimTime b) { return a.ps_ < b.ps_; }
  friend constexpr bool operator<=(SimTime a, SimTime b) { return a.ps_ <= b.ps_; }
  friend constexpr bool operator>(SimTime a, SimTime b) { return a.ps_ > b.ps_; }
  friend constexpr bool operator>=(SimTime a, SimTime b) { return a.ps_ >= b.ps_; }

  friend std::ostream& operator<<(std::ostream& os, SimTime t) { return os << t.ToString(); }

 private:
  static constexpr std::uint64_t kPsPerMs = 1000'000'000;
  static constexpr std::uint64_t kPsPerS = 1000'000'000'000;
  constexpr explicit SimTime(std::uint64_t ps) : ps_(ps) {}
  std::uint64_t ps_ = 0;
};

}  // namespace raycell
