// Lists of cells as tests write them: {0, 1, 2} or {A, B} (CellId is explicit, so a brace list of
// numbers does not make a std::vector<CellId>). A CellList is a std::vector<CellId>.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <utility>
#include <vector>

#include "traces/cell_id.h"

namespace raycell::testing {

struct CellList : std::vector<CellId> {
  CellList() = default;
  CellList(std::initializer_list<CellId> cells) : std::vector<CellId>(cells) {}
  CellList(std::initializer_list<std::uint32_t> cells) {
    for (std::uint32_t c : cells) push_back(CellId(c));
  }
  CellList(std::vector<CellId> cells) : std::vector<CellId>(std::move(cells)) {}
  template <typename It>
  CellList(It first, It last) : std::vector<CellId>(first, last) {}
};

}  // namespace raycell::testing
