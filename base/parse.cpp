#include "base/parse.h"

#include <cctype>
#include <charconv>

#include "base/check.h"

namespace raycell {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::vector<std::string> Split(std::string_view s, char sep) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (std::size_t p; (p = s.find(sep, start)) != std::string_view::npos; start = p + 1) {
    out.emplace_back(s.substr(start, p - start));
  }
  out.emplace_back(s.substr(start));
  return out;
}

std::string Join(const std::vector<std::string>& parts, std::string_view sep) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (i > 0) out += sep;
    out += parts[i];
  }
  return out;
}

std::string JoinOr(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  }
  return out;
}

namespace {

template <typename T>
T ParseInteger(std::string_view text, const std::string& what, T lo, T hi) {
  T v{};
  const char* end = text.data() + text.size();
  const auto r = std::from_chars(text.data(), end, v);
  if (text.empty() || r.ptr != end || r.ec == std::errc::invalid_argument) {
    throw InputError(what + ": '" + std::string(text) + "' is not an integer");
  }
  if (r.ec == std::errc::result_out_of_range || v < lo || v > hi) {
    throw InputError(what + ": " + std::string(text) + " is out of range " + std::to_string(lo) +
                     ".." + std::to_string(hi));
  }
  return v;
}

}  // namespace

std::int64_t ParseInt(std::string_view text, const std::string& what, std::int64_t lo,
                      std::int64_t hi) {
  return ParseInteger<std::int64_t>(text, what, lo, hi);
}

std::uint64_t ParseUint(std::string_view text, const std::string& what, std::uint64_t lo,
                        std::uint64_t hi) {
  if (!text.empty() && text.front() == '-') {
    throw InputError(what + ": '" + std::string(text) + "' is not a whole number");
  }
  return ParseInteger<std::uint64_t>(text, what, lo, hi);
}

bool TryParseUint(std::string_view text, std::uint64_t* out) {
  const char* end = text.data() + text.size();
  const auto r = std::from_chars(text.data(), end, *out);
  return !text.empty() && text.front() != '-' && r.ec == std::errc() && r.ptr == end;
}

std::string FormatFrameRange(std::int64_t first, std::int64_t last) {
  return std::to_string(first) + ".." + std::to_string(last);
}

std::vector<int> ParseFrameRange(const std::string& text, const std::string& what) {
  std::size_t sep = text.find("..");
  std::size_t skip = 2;
  if (sep == std::string::npos) {
    sep = text.find('-', 1);
    skip = 1;
  }
  constexpr std::int64_t kMin = std::numeric_limits<int>::min();
  constexpr std::int64_t kMax = std::numeric_limits<int>::max();
  const std::string label = what + " '" + text + "'";
  const std::string_view t = text;
  const auto a = int(ParseInt(sep == std::string::npos ? t : t.substr(0, sep), label, kMin, kMax));
  const auto b =
      sep == std::string::npos ? a : int(ParseInt(t.substr(sep + skip), label, kMin, kMax));
  if (b < a) throw InputError(label + ": the range ends before it starts");
  if (std::int64_t(b) - a >= 1000000) throw InputError(label + ": too many frames (at most 10^6)");
  std::vector<int> frames;
  for (int f = a; f <= b; ++f) frames.push_back(f);
  return frames;
}

}  // namespace raycell
