// Sizes in bytes, parsed from text such as "256MiB" or "1.5GB" into exact values and formatted
// back so that format -> parse round-trips exactly (CONTRIBUTING.md "Units parsed once at
// load"). The replay's durations and bandwidths (replay/units.h) are parsed with the same
// numbers and prefixes, so every module that reads a size (the replay's levels, a cell
// subdivision's byte budget) reads it one way.
//
// Parsing is exact decimal arithmetic (no floating point). A value that is not a whole number
// of bytes is an input error rather than silently rounded. Prefixes: decimal k, M, G, T = 10^3,
// 10^6, 10^9, 10^12; binary Ki, Mi, Gi, Ti = 2^10 ... 2^40. "KB" is rejected as ambiguous (use
// "kB" or "KiB"). Upper-case B is bytes, lower-case b bits.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace raycell {

// A number of bytes. Explicit construction only, so a count of cells or records cannot be
// passed where a size is meant.
class Bytes {
 public:
  constexpr Bytes() = default;
  constexpr explicit Bytes(std::uint64_t count) : count_(count) {}

  constexpr std::uint64_t count() const { return count_; }

  // Shortest exact form: "512B", "1.5GB", "256MiB". ParseBytes(ToString()) == *this.
  std::string ToString() const;

  friend constexpr bool operator==(Bytes a, Bytes b) { return a.count_ == b.count_; }
  friend constexpr bool operator!=(Bytes a, Bytes b) { return a.count_ != b.count_; }
  friend constexpr bool operator<(Bytes a, Bytes b) { return a.count_ < b.count_; }

 private:
  std::uint64_t count_ = 0;
};

// Parsers. `what` names the value for error messages; every error is an InputError "WHAT:
// REASON: 'TEXT'". Whitespace is allowed around the text and between number and unit. Signs,
// exponents, NaN and infinities are rejected.

// "512B", "4KiB", "64MiB", "1.5GB". A unit is required; zero is allowed; bits are rejected;
// the value must be a whole number of bytes that fits 64 bits.
Bytes ParseBytes(std::string_view text, const std::string& what);

// The number and unit parsing shared with replay/units.cpp (durations and bandwidths); not
// for other callers.
namespace units_internal {

using U128 = unsigned __int128;

inline constexpr U128 kU64Max = ~std::uint64_t{0};

// Throws InputError "WHAT: REASON: 'TEXT'".
[[noreturn]] void Fail(const std::string& what, const std::string& reason, std::string_view text);
std::string Lower(std::string_view s);
U128 Pow(U128 base, int n);
// value / scale as an exact decimal ("1.5"); scale is a power of 10 or of 2, so it terminates.
std::string ExactQuotient(U128 value, U128 scale);

// A decimal number without sign or exponent: mantissa / 10^frac_digits.
struct Decimal {
  U128 mantissa = 0;
  int frac_digits = 0;
};
// Parses the number at the start of `text` (already trimmed); returns it and the unit text
// after it (trimmed).
Decimal ParseNumber(std::string_view text, const std::string& what, std::string_view* unit);
// mantissa * multiplier / 10^frac_digits, which must be a whole number that fits 64 bits.
std::uint64_t Scale(const Decimal& d, U128 multiplier, const char* base, const std::string& what,
                    std::string_view text);

// A size unit: a prefix and B (bytes) or b (bits).
struct SizeUnit {
  U128 multiplier = 1;
  bool bits = false;
};
SizeUnit ParseSizeUnit(std::string_view unit, const std::string& what, std::string_view text,
                       const char* expected);
// The shortest exact rendering of `value` with a decimal or (when whole) binary prefix; ties go
// to the decimal form.
std::string ShortestWithPrefix(U128 value);

}  // namespace units_internal
}  // namespace raycell
