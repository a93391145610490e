// Fuzz target: the parsers of command-line values, each on the whole input: frame ranges
// (--frames), cell grids (--cells, then the trace format's limit), resolutions (--res),
// lights (--light: vectors and colours), integers, cell subdivisions (--cells SPEC on a fine
// capture: parsed, printed back, and applied to a small fine grid). Bad text must give an
// InputError, never a crash, a leak or a hang; what parses must satisfy the parser's contract.
#include <cmath>
#include <cstdint>
#include <string>

#include "base/check.h"
#include "base/parse.h"
#include "record/cell_grid.h"
#include "record/recorder.h"
#include "record/scene.h"
#include "traces/cell_dims.h"
#include "traces/format.h"
#include "traces/subdivision.h"

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
  Try([&] {
    const SubdivisionSpec spec = ParseSubdivisionSpec(text, "--cells");
    RAYCELL_CHECK(ParseSubdivisionSpec(spec.ToString(), "--cells") == spec);
    // On a 6x4x3 fine grid of uneven footprints (an InputError where the spec does not fit
    // it): every fine cell in exactly one coarse cell.
    FineCells fine;
    fine.grid = {6, 4, 3};
    for (std::uint32_t f = 0; f < fine.count(); ++f) fine.samples.push_back(f * 37 % 11);
    fine.union_footprint = [](const std::vector<std::uint32_t>& cells) {
      std::uint64_t bytes = 0;
      for (std::uint32_t f : cells) bytes += (f * 7919 % 13) * 512;
      return bytes;
    };
    const Subdivision s = Subdivide(spec, fine);
    RAYCELL_CHECK_EQ(s.coarse_of_fine.size(), std::size_t{fine.count()});
    std::uint64_t covered = 0;
    for (const FineBox& b : s.boxes) covered += b.volume();
    RAYCELL_CHECK_EQ(covered, std::uint64_t{fine.count()});
    for (CellId c : s.coarse_of_fine) RAYCELL_CHECK_LT(c.value(), s.cells());
  });
  Try([&] { ParseInt(text, "--n", -1000, 1000000); });
  Try([&] { ParseUint(text, "--n"); });
  std::uint64_t v = 0;
  if (TryParseUint(text, &v)) RAYCELL_CHECK_EQ(ParseUint(text, "--n"), v);
  return 0;
}
