#include "traces/cell_dims.h"

#include "base/check.h"

namespace raycell {
namespace {

[[noreturn]] void BadDims(std::string_view text, const std::string& what, const std::string& why) {
  throw InputError(what + " \"" + std::string(text) +
                   "\": expected NXxNYxNZ with three positive integers, e.g. \"3x3x3\" (" + why +
                   ")");
}

std::uint64_t ParseDim(std::string_view text, const std::string& what, std::string_view part) {
  if (part.empty() || part.size() > 10) BadDims(text, what, "\"" + std::string(part) + "\"");
  std::uint64_t v = 0;
  for (char c : part) {
    if (c < '0' || c > '9') BadDims(text, what, "\"" + std::string(part) + "\" is not a number");
    v = v * 10 + static_cast<std::uint64_t>(c - '0');
  }
  if (v == 0) BadDims(text, what, "0 is out of range: each count is at least 1");
  return v;
}

}  // namespace

std::array<std::uint32_t, 3> ParseCellDims(std::string_view text, const std::string& what,
                                           std::uint64_t max_cells) {
  std::array<std::uint64_t, 3> d{};
  std::size_t start = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t end = axis < 2 ? text.find_first_of("xX", start) : text.size();
    if (end == std::string_view::npos) BadDims(text, what, "three counts needed");
    d[axis] = ParseDim(text, what, text.substr(start, end - start));
    start = end + 1;
  }
  // With each factor at most max_cells < 2^32, every product below fits 64 bits.
  RAYCELL_CHECK_LE(max_cells, std::uint64_t{0xFFFFFFFFu});
  const bool fits =
      d[0] <= max_cells && d[1] <= max_cells && d[2] <= max_cells && d[0] * d[1] <= max_cells;
  if (!fits || d[0] * d[1] * d[2] > max_cells) {
    throw InputError(
        what + " \"" + std::string(text) + "\": " +
        (fits ? std::to_string(d[0] * d[1] * d[2]) + " cells" : std::string("too many cells")) +
        ", more than " + std::to_string(max_cells));
  }
  return {static_cast<std::uint32_t>(d[0]), static_cast<std::uint32_t>(d[1]),
          static_cast<std::uint32_t>(d[2])};
}

}  // namespace raycell
