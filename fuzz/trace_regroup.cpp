// Fuzz target: `raycell trace regroup` (and --cells SPEC) of a damaged or mismatched fine
// capture. Input layout: byte 0 picks the SPEC (below; byte 0 >= 16: the text of bytes 1..k,
// up to the first 0 byte, is the SPEC); the rest is the capture's bytes. Seeds are the valid
// fine capture fuzz/data/regroup_fine.rct (frames 0-1 of the built-in scene's orbit 2:20 at
// 8x8, 4x4x4 cells, --regroupable), whole and damaged. Properties: a refusal is an InputError
// and leaves no output; a regrouped trace opens without warning, has the subdivision's cell
// count, keeps every sample of the capture (regrouping moves samples, never drops them) and
// no more rays, and every frame builds a Cell Tree.
#include "traces/trace_regroup.h"

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "base/check.h"
#include "graph/frame_tree.h"
#include "traces/trace_reader.h"

namespace {

namespace fs = std::filesystem;

const fs::path& WorkDir() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() /
                       ("raycell_fuzz_regroup_" + std::to_string(static_cast<long>(::getpid())));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

constexpr const char* kSpecs[] = {"4x4x4",          "2x2x2",      "2x1x4",      "1x1x1",
                                  "kd:5:footprint", "kd:7:work",  "kd:64:work", "kd:budget:4KiB",
                                  "octree:8KiB",    "octree:1",   "dynamic:3",  "dynamic:64",
                                  "3x3x3",          "kd:65:work", "",           "kd:1:footprint"};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace raycell;
  if (size < 1) return 0;
  std::string spec;
  std::size_t begin = 1;
  if (data[0] < 16) {
    spec = kSpecs[data[0]];
  } else {
    while (begin < size && data[begin] != 0 && begin < 64) spec += char(data[begin++]);
    if (begin < size) ++begin;
  }
  const std::string in = (WorkDir() / "in.rct").string(), out = (WorkDir() / "out.rct").string();
  std::ofstream(in, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data + begin),
             static_cast<std::streamsize>(size - begin));
  RAYCELL_CHECK(!fs::exists(out));
  try {
    const RegroupSummary s = RegroupTrace(in, spec, out);
    const TraceReader stored = TraceReader::OpenStored(in);
    const TraceReader regrouped = TraceReader::Open(out);
    RAYCELL_CHECK(regrouped.warning().empty());
    RAYCELL_CHECK_EQ(regrouped.header().cell_count(), s.cells);
    RAYCELL_CHECK_EQ(regrouped.frames().size(), stored.frames().size());
    for (std::size_t i = 0; i < stored.frames().size(); ++i) {
      RAYCELL_CHECK_EQ(regrouped.frames()[i].samples, stored.frames()[i].samples);
      RAYCELL_CHECK_LE(regrouped.frames()[i].rays, stored.frames()[i].rays);
      BuildFrameTree(regrouped, i);
    }
    fs::remove(out);
  } catch (const InputError&) {
    RAYCELL_CHECK(!fs::exists(out));
  }
  return 0;
}
