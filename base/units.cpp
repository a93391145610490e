#include "base/units.h"

#include <cctype>
#include <limits>

#include "base/check.h"
#include "base/parse.h"

namespace raycell {
namespace units_internal {

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

static std::string ToDecimal(U128 v) {
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

static bool IsNonFiniteWord(std::string_view s) {
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

}  // namespace units_internal

using namespace units_internal;

std::string Bytes::ToString() const { return ShortestWithPrefix(count_) + "B"; }

Bytes ParseBytes(std::string_view text, const std::string& what) {
  const std::string_view t = Trim(text);
  std::string_view unit;
  const Decimal d = ParseNumber(t, what, &unit);
  const SizeUnit u = ParseSizeUnit(unit, what, text, "B, kB, MB, GB, TB, KiB, MiB, GiB or TiB");
  if (u.bits) Fail(what, "a size is in bytes (B), not bits (b)", text);
  return Bytes(Scale(d, u.multiplier, "bytes", what, text));
}

}  // namespace raycell
