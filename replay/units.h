// Units for the replay configuration (CONTRIBUTING.md "Units parsed once at load"): durations,
// sizes and bandwidths are parsed from text such as "10ns", "256MiB" or "1.6GB/s" into typed,
// exact values, and formatted back so that format → parse round-trips exactly.
//
// Parsing is exact decimal arithmetic (no floating point): "1.5us" is 1'500'000 ps, "1.6GB/s"
// is 12'800'000'000 bit/s. A value that is not a whole number of the base unit (picoseconds,
// bytes, bits per second) is an input error rather than silently rounded.
//
// Prefixes: decimal k, M, G, T = 10^3, 10^6, 10^9, 10^12; binary Ki, Mi, Gi, Ti = 2^10 ... 2^40.
// "KB" is rejected as ambiguous (use "kB" or "KiB"). Upper-case B is bytes, lower-case b bits.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "base/units.h"
#include "engine/time.h"

namespace raycell {

// A transfer rate, held exactly as a whole number of bits per second (so both "10Gb/s" and
// "1.6GB/s" are exact), or unlimited. Never zero.
class Bandwidth {
 public:
  // Default: unlimited (the host memory below the last level).
  constexpr Bandwidth() = default;

  static constexpr Bandwidth Unlimited() { return Bandwidth(); }
  // CHECK-fails on zero; BytesPerSecond CHECK-fails on overflow of the bit count.
  static Bandwidth BitsPerSecond(std::uint64_t bits);
  static Bandwidth BytesPerSecond(std::uint64_t bytes);

  constexpr bool unlimited() const { return bits_per_second_ == 0; }
  // CHECK-fails when unlimited.
  std::uint64_t bits_per_second() const;
  // For reports only; +infinity when unlimited.
  double bytes_per_second() const;

  // Time to move `bytes` at this rate, rounded up to a whole picosecond:
  // ceil(bytes * 8 * 10^12 / bits_per_second), computed exactly in 128-bit integers.
  // Zero when unlimited or bytes == 0. CHECK-fails if the result exceeds SimTime::Max().
  SimTime TransferTime(std::uint64_t bytes) const;

  // Shortest exact form: "1.6GB/s", "133MB/s", "800MiB/s", "10.5Gb/s" (bits only when the rate
  // is not a whole number of bytes per second), "unlimited". Round-trips through ParseBandwidth.
  std::string ToString() const;

  friend constexpr bool operator==(Bandwidth a, Bandwidth b) {
    return a.bits_per_second_ == b.bits_per_second_;
  }
  friend constexpr bool operator!=(Bandwidth a, Bandwidth b) { return !(a == b); }

 private:
  constexpr explicit Bandwidth(std::uint64_t bits) : bits_per_second_(bits) {}
  std::uint64_t bits_per_second_ = 0;  // 0 = unlimited
};

// Parsers. `what` names the value for error messages, e.g. "replay.toml:12:5: level 'board'
// bandwidth"; every error is an InputError "WHAT: REASON: 'TEXT'". Whitespace is allowed
// around the text and between number and unit. Signs, exponents, NaN and infinities are
// rejected (except "inf"/"unlimited" for bandwidth).

// "250ps", "10ns", "1.5 us" (also "µs"), "2ms", "0.5s". A number without a unit is an error;
// zero is allowed; the value must be a whole number of picoseconds that fits SimTime.
SimTime ParseDuration(std::string_view text, const std::string& what);

// "1.6GB/s", "133MB/s", "800MiB/s", "10Gb/s", "inf", "unlimited". Zero is an error; the value
// must be a whole number of bits per second that fits 64 bits.
Bandwidth ParseBandwidth(std::string_view text, const std::string& what);

// Shortest exact form of a duration in the largest fitting unit: "40ns", "1us", "1.5us",
// "0ns". ParseDuration(FormatDuration(t)) == t for every t.
std::string FormatDuration(SimTime t);

}  // namespace raycell
