// Fuzz target: the parsers of command-line values, each on the whole input: frame ranges
// (--frames), cell grids (--cells, then the trace format's limit), resolutions (--res),
// lights (--light: vectors and colours), integers. Bad text must give an InputError, never a
// crash, a leak or a hang; what parses must satisfy the parser's contract.
#include <cmath>
#include <cstdint>
#include <string>

#include "base/check.h"
#include "base/parse.h"
#include "traces/format.h"
#include "traces/record/cell_grid.h"
#include "traces/record/recorder.h"
#include "traces/record/scene.h"

namespace raycell {
namespace {

template <typename F>
void Try(F f) {
  try {
    f();
  } catch (const InputError&) {
  }
}

}  // namespace
}  // namespace raycell

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace raycell;
  const std::string text(reinterpret_cast<const char*>(data), size);
  Try([&] {
    const std::vector<int> frames = ParseFrameRange(text);
    RAYCELL_CHECK(!frames.empty() && frames.size() <= 1000000);
    for (std::size_t i = 1; i < frames.size(); ++i) RAYCELL_CHECK_EQ(frames[i], frames[i - 1] + 1);
  });
  Try([&] {
    const auto cells = ParseCellDims(text);
    RAYCELL_CHECK(cells[0] >= 1 && cells[1] >= 1 && cells[2] >= 1);
    RAYCELL_CHECK_LE(TraceCellCount(cells), std::uint64_t{0xFFFFFFFF});
    CheckTraceCellGrid(cells, "--cells");
    RAYCELL_CHECK_LE(TraceCellCount(cells), kTraceMaxCells);
  });
  Try([&] {
    const auto wh = ParseResolution(text);
    RAYCELL_CHECK(wh[0] >= 1 && wh[0] <= 65536 && wh[1] >= 1 && wh[1] <= 65536);
  });
  Try([&] {
    const Light l = ParseLight(text);
    RAYCELL_CHECK(std::isfinite(l.v.x) && std::isfinite(l.v.y) && std::isfinite(l.v.z));
    RAYCELL_CHECK(l.color.r >= 0 && l.color.g >= 0 && l.color.b >= 0);
  });
  Try([&] { ParseInt(text, "--n", -1000, 1000000); });
  Try([&] { ParseUint(text, "--n"); });
  std::uint64_t v = 0;
  if (TryParseUint(text, &v)) RAYCELL_CHECK_EQ(ParseUint(text, "--n"), v);
  return 0;
}
