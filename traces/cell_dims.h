// The one parser of cell counts "NXxNYxNZ" (docs/design.md §1 "Scene and cells"): record's
// --cells, the uniform and grid: subdivision SPECs (traces/subdivision.h) and the fuzz target
// all read counts through it.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace raycell {

// Parses "NXxNYxNZ" (e.g. "3x3x3"; 'X' also accepted): three positive integers whose product
// is at most `max_cells`. Throws InputError `WHAT "TEXT": ...` saying what is wrong otherwise
// (a count of 0 is "out of range", a product over max_cells "more than MAX").
std::array<std::uint32_t, 3> ParseCellDims(std::string_view text,
                                           const std::string& what = "--cells",
                                           std::uint64_t max_cells = 0xFFFFFFFFu);

}  // namespace raycell
