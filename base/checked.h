// Checked 64-bit arithmetic for counters and simulated time (CONTRIBUTING.md "Typed time"):
// an overflow is a broken invariant, so it is a CHECK failure that prints both operands.
#pragma once

#include <cstdint>

#include "base/check.h"

namespace raycell {

// a + b; CHECK-fails on overflow.
inline std::uint64_t CheckedAdd(std::uint64_t a, std::uint64_t b) {
  std::uint64_t sum;
  if (__builtin_add_overflow(a, b, &sum)) {
    detail::CheckFailed("CheckedAdd overflow", __FILE__, __LINE__, detail::Values(a, b));
  }
  return sum;
}

// a * b; CHECK-fails on overflow.
inline std::uint64_t CheckedMul(std::uint64_t a, std::uint64_t b) {
  std::uint64_t product;
  if (__builtin_mul_overflow(a, b, &product)) {
    detail::CheckFailed("CheckedMul overflow", __FILE__, __LINE__, detail::Values(a, b));
  }
  return product;
}

// a - b; CHECK-fails if b > a.
inline std::uint64_t CheckedSub(std::uint64_t a, std::uint64_t b) {
  if (b > a) detail::CheckFailed("CheckedSub underflow", __FILE__, __LINE__, detail::Values(a, b));
  return a - b;
}

// counter += by, checked. For statistics counters: `CheckedIncrement(stats.fetches);`.
inline void CheckedIncrement(std::uint64_t& counter, std::uint64_t by = 1) {
  counter = CheckedAdd(counter, by);
}

}  // namespace raycell
