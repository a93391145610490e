#include "replay/units.h"

#include <cctype>
#include <limits>

#include "base/check.h"
#include "base/parse.h"

namespace raycell {
namespace {

using U128 = unsigned __int128;

constexpr U128 kU64Max = std::numeric_limits<std::uint64_t>::max();
constexpr std::uint64_t kPsPerS = 1000'000'000'000;

[[noreturn]] void Fail(const std::string& what, const std::string& reason, std::string_view text) {
  throw InputError(what + ": " + reason + ": '" + std::string(text) + "'");
}

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

U128 Pow(U128 base, int n) {
  U128 r = 1;
  while (n-- > 0) r *= base;
  return r;
}

std::string ToDecimal(U128 v) {
  std::string s;
  do {
    s.insert(s.begin(), char('0' + int(v % 10)));
    v /= 10;
  } while (v != 0);
  return s;
}

// value / scale as an exact decimal ("1.5"); scale is a power of 10 or of 2, so it terminates.
std::string ExactQuotient(U128 value, U128 scale) {
  std::string s = ToDecimal(value / scale);
  U128 rem = value % scale;
  if (rem != 0) s += '.';
  while (rem != 0) {
    rem *= 10;
    s += char('0' + int(rem / scale));
    rem %= scale;
  }
  return s;
}

// A decimal number without sign or exponent: mantissa / 10^frac_digits.
struct Decimal {
  U128 mantissa = 0;
  int frac_digits = 0;
};

bool IsNonFiniteWord(std::string_view s) {
  const std::string l = Lower(s);
  for (const char* w : {"nan", "inf"}) {
    if (l.rfind(w, 0) == 0 || l.rfind(std::string("+") + w, 0) == 0 ||
        l.rfind(std::string("-") + w, 0) == 0) {
      return true;
    }
  }
  return false;
}

// Parses the number at the start of `text` (already trimmed); returns it and the unit text
// after it (trimmed).
Decimal ParseNumber(std::string_view text, const std::string& what, std::string_view* unit) {
  if (text.empty()) Fail(what, "expected a number with a unit", text);
  if (IsNonFiniteWord(text)) Fail(what, "not a finite number", text);
  if (text.front() == '-') Fail(what, "negative values are not allowed", text);
  if (text.front() == '+') Fail(what, "a sign is not allowed", text);
  Decimal d;
  std::size_t i = 0;
  int digits = 0;
  bool in_fraction = false;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '.' && !in_fraction) {
      in_fraction = true;
      continue;
    }
    if (c < '0' || c > '9') break;
    ++digits;
    if (d.mantissa > U128(1) << 100) Fail(what, "too many digits", text);
    d.mantissa = d.mantissa * 10 + U128(c - '0');
    if (in_fraction) ++d.frac_digits;
  }
  if (digits == 0) Fail(what, "expected a number", text);
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    Fail(what, "exponents are not supported; use a unit prefix", text);
  }
  while (d.frac_digits > 0 && d.mantissa % 10 == 0) {
    d.mantissa /= 10;
    --d.frac_digits;
  }
  // Keeps mantissa * multiplier (< 2^44) and 10^frac_digits inside 128 bits.
  if (d.mantissa >= Pow(10, 25) || d.frac_digits > 36) {
    Fail(what, "too many significant digits", text);
  }
  *unit = Trim(text.substr(i));
  return d;
}

// mantissa * multiplier / 10^frac_digits, which must be a whole number that fits 64 bits.
std::uint64_t Scale(const Decimal& d, U128 multiplier, const char* base, const std::string& what,
                    std::string_view text) {
  const U128 num = d.mantissa * multiplier;
  const U128 den = Pow(10, d.frac_digits);
  if (num % den != 0) Fail(what, std::string("not a whole number of ") + base, text);
  const U128 q = num / den;
  if (q > kU64Max) Fail(what, "value too large", text);
  return std::uint64_t(q);
}

// A size unit: a prefix and B (bytes) or b (bits).
struct SizeUnit {
  U128 multiplier = 1;
  bool bits = false;
};

constexpr const char* kSizeUnits = "B, kB, MB, GB, TB, KiB, MiB, GiB or TiB";

SizeUnit ParseSizeUnit(std::string_view unit, const std::string& what, std::string_view text,
                       const char* expected) {
  if (unit.empty()) Fail(what, std::string("missing unit (expected ") + expected + ")", text);
  SizeUnit u;
  const char last = unit.back();
  if (last != 'B' && last != 'b') {
    Fail(what, "unknown unit '" + std::string(unit) + "' (expected " + expected + ")", text);
  }
  u.bits = last == 'b';
  const std::string_view prefix = unit.substr(0, unit.size() - 1);
  static const struct {
    const char* name;
    U128 multiplier;
  } kPrefixes[] = {{"", 1},
                   {"k", Pow(10, 3)},
                   {"M", Pow(10, 6)},
                   {"G", Pow(10, 9)},
                   {"T", Pow(10, 12)},
                   {"Ki", U128(1) << 10},
                   {"Mi", U128(1) << 20},
                   {"Gi", U128(1) << 30},
                   {"Ti", U128(1) << 40}};
  for (const auto& p : kPrefixes) {
    if (prefix == p.name) {
      u.multiplier = p.multiplier;
      return u;
    }
  }
  if (prefix == "K") {
    Fail(what, "ambiguous unit '" + std::string(unit) + "': use k (1000) or Ki (1024)", text);
  }
  Fail(what, "unknown unit '" + std::string(unit) + "' (expected " + expected + ")", text);
}

// The shortest exact rendering of `value` with a decimal or (when whole) binary prefix;
// ties go to the decimal form.
std::string ShortestWithPrefix(U128 value) {
  static const struct {
    const char* prefix;
    U128 scale;
    bool binary;
  } kCandidates[] = {{"T", Pow(10, 12), false},
                     {"G", Pow(10, 9), false},
                     {"M", Pow(10, 6), false},
                     {"k", Pow(10, 3), false},
                     {"", 1, false},
                     {"Ti", U128(1) << 40, true},
                     {"Gi", U128(1) << 30, true},
                     {"Mi", U128(1) << 20, true},
                     {"Ki", U128(1) << 10, true}};
  std::string best = ToDecimal(value);
  for (const auto& c : kCandidates) {
    if (value < c.scale || (c.binary && value % c.scale != 0)) continue;
    std::string s = ExactQuotient(value, c.scale) + c.prefix;
    if (s.size() < best.size()) best = std::move(s);
  }
  return best;
}

}  // namespace

std::string Bytes::ToString() const { return ShortestWithPrefix(count_) + "B"; }

Bandwidth Bandwidth::BitsPerSecond(std::uint64_t bits) {
  RAYCELL_CHECK(bits > 0);
  return Bandwidth(bits);
}

Bandwidth Bandwidth::BytesPerSecond(std::uint64_t bytes) {
  return BitsPerSecond(CheckedMul(bytes, 8));
}

std::uint64_t Bandwidth::bits_per_second() const {
  RAYCELL_CHECK(!unlimited());
  return bits_per_second_;
}

double Bandwidth::bytes_per_second() const {
  if (unlimited()) return std::numeric_limits<double>::infinity();
  return double(bits_per_second_) / 8.0;
}

SimTime Bandwidth::TransferTime(std::uint64_t bytes) const {
  if (unlimited() || bytes == 0) return SimTime::Zero();
  const U128 num = U128(bytes) * 8 * kPsPerS;  // < 2^64 * 2^43: fits
  const U128 ps = (num + bits_per_second_ - 1) / bits_per_second_;
  if (ps > kU64Max) {
    detail::CheckFailed("Bandwidth::TransferTime overflows SimTime", __FILE__, __LINE__,
                        detail::Values(bytes, ToString()));
  }
  return SimTime::Picoseconds(std::uint64_t(ps));
}

std::string Bandwidth::ToString() const {
  if (unlimited()) return "unlimited";
  if (bits_per_second_ % 8 == 0) return ShortestWithPrefix(bits_per_second_ / 8) + "B/s";
  return ShortestWithPrefix(bits_per_second_) + "b/s";
}

SimTime ParseDuration(std::string_view text, const std::string& what) {
  const std::string_view t = Trim(text);
  std::string_view unit;
  const Decimal d = ParseNumber(t, what, &unit);
  static const struct {
    const char* name;
    std::uint64_t ps;
  } kUnits[] = {{"ps", 1},
                {"ns", 1000},
                {"us", 1000'000},
                {"\xC2\xB5s", 1000'000},  // µs (micro sign)
                {"\xCE\xBCs", 1000'000},  // μs (Greek mu)
                {"ms", 1000'000'000},
                {"s", kPsPerS}};
  if (unit.empty()) Fail(what, "missing unit (expected ps, ns, us, ms or s)", text);
  for (const auto& u : kUnits) {
    if (unit == u.name) {
      return SimTime::Picoseconds(Scale(d, u.ps, "picoseconds", what, text));
    }
  }
  Fail(what, "unknown unit '" + std::string(unit) + "' (expected ps, ns, us, ms or s)", text);
}

Bytes ParseBytes(std::string_view text, const std::string& what) {
  const std::string_view t = Trim(text);
  std::string_view unit;
  const Decimal d = ParseNumber(t, what, &unit);
  const SizeUnit u = ParseSizeUnit(unit, what, text, kSizeUnits);
  if (u.bits) Fail(what, "a size is in bytes (B), not bits (b)", text);
  return Bytes(Scale(d, u.multiplier, "bytes", what, text));
}

Bandwidth ParseBandwidth(std::string_view text, const std::string& what) {
  const std::string_view t = Trim(text);
  const std::string l = Lower(t);
  if (l == "inf" || l == "unlimited") return Bandwidth::Unlimited();
  std::string_view unit;
  const Decimal d = ParseNumber(t, what, &unit);
  constexpr const char* kExpected = "B/s, kB/s, MB/s, GB/s, MiB/s, ..., or b/s, Mb/s, Gb/s, ...";
  if (unit.size() < 2 || unit.substr(unit.size() - 2) != "/s") {
    Fail(what,
         unit.empty() ? std::string("missing unit (expected ") + kExpected + ")"
                      : "unknown unit '" + std::string(unit) + "' (expected " + kExpected + ")",
         text);
  }
  const SizeUnit u = ParseSizeUnit(Trim(unit.substr(0, unit.size() - 2)), what, text, kExpected);
  const U128 multiplier = u.multiplier * (u.bits ? 1 : 8);
  const std::uint64_t bits = Scale(d, multiplier, "bits per second", what, text);
  if (bits == 0) Fail(what, "bandwidth must be greater than zero", text);
  return Bandwidth::BitsPerSecond(bits);
}

std::string FormatDuration(SimTime t) {
  static const struct {
    const char* name;
    std::uint64_t ps;
  } kUnits[] = {{"s", kPsPerS}, {"ms", 1000'000'000}, {"us", 1000'000}, {"ns", 1000}};
  const std::uint64_t ps = t.picoseconds();
  if (ps == 0) return "0ns";
  for (const auto& u : kUnits) {
    if (ps >= u.ps) return ExactQuotient(ps, u.ps) + u.name;
  }
  return std::to_string(ps) + "ps";
}

}  // namespace raycell
