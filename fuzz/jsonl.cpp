// Fuzz target: the JSON Lines path reader (`raycell analyze --paths`), then the tree it
// built. Bad lines must give an InputError naming the line, never a crash, a leak or a hang.
#include "traces/jsonl.h"

#include <cstdint>
#include <sstream>
#include <string>

#include "base/check.h"
#include "graph/cell_tree.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace raycell;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    JsonlReader reader(in, "fuzz.jsonl");
    JsonlFrame frame;
    while (reader.Next(frame)) {
      CellTreeBuilder builder;
      builder.AddBatch(frame.rays);
      const CellTree tree = builder.Finish();
      RAYCELL_CHECK_LE(std::size_t{1}, tree.size());  // the root
    }
  } catch (const InputError&) {
  }
  return 0;
}
