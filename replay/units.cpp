#include "replay/units.h"

#include <limits>

#include "base/check.h"
#include "base/checked.h"
#include "base/parse.h"

namespace raycell {
namespace {

using namespace units_internal;

constexpr std::uint64_t kPsPerS = 1000'000'000'000;

}  // namespace

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
