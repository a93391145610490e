// Parsing of command-line and configuration values, one way everywhere: the same text gives
// the same result (or the same kind of error) whichever option or file it came from.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace raycell {

// `s` without leading and trailing white space (std::isspace).
std::string_view Trim(std::string_view s);
// The fields between separators, empty ones kept: "" -> {""}, "a,,b" -> {"a", "", "b"},
// "a," -> {"a", ""}.
std::vector<std::string> Split(std::string_view s, char sep);
// The parts with `sep` between each two: {"a", "b"} and ", " -> "a, b"; {} -> "".
std::string Join(const std::vector<std::string>& parts, std::string_view sep);
// The names as a list for messages: {"a", "b", "c"} -> "a, b or c"; {"a"} -> "a".
std::string JoinOr(const std::vector<std::string>& names);

// A whole decimal integer: digits with an optional leading '-', nothing else (no white
// space, no '+', no trailing text), within [lo, hi]. InputError "WHAT: 'TEXT' is not an
// integer" or "WHAT: TEXT is out of range LO..HI" otherwise.
std::int64_t ParseInt(std::string_view text, const std::string& what,
                      std::int64_t lo = std::numeric_limits<std::int64_t>::min(),
                      std::int64_t hi = std::numeric_limits<std::int64_t>::max());
// The same without a sign.
std::uint64_t ParseUint(std::string_view text, const std::string& what, std::uint64_t lo = 0,
                        std::uint64_t hi = std::numeric_limits<std::uint64_t>::max());
// As ParseUint, but false instead of an error (for reading back files this program wrote).
bool TryParseUint(std::string_view text, std::uint64_t* out);

// Frame numbers "A..B", "A-B" (B >= 0) or "A", inclusive, in order; at most 10^6 frames.
// InputError naming `what` when malformed, inverted or too long.
std::vector<int> ParseFrameRange(const std::string& text, const std::string& what = "--frames");
// Frames first..last as ParseFrameRange reads them back: "A..B".
std::string FormatFrameRange(std::int64_t first, std::int64_t last);

}  // namespace raycell
