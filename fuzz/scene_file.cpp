// Fuzz target: scene files (record/scene_file.h), read and checked as `raycell record --scene
// FILE.toml` reads them, without building any grid. Bad text must give an InputError, never
// a crash, a leak or a hang; a scene that is accepted prints (--print-scene) to text that
// reads back to the same print.
#include "record/scene_file.h"

#include <cstdint>
#include <string>
#include <string_view>

#include "base/check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace raycell;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const SceneDescription d = ParseSceneDescription(text, "fuzz.toml", "/fuzz");
    const std::string printed = PrintSceneDescription(d);
    const SceneDescription again = ParseSceneDescription(printed, "printed.toml", "/fuzz");
    RAYCELL_CHECK(PrintSceneDescription(again) == printed);
    for (const GridDesc& g : d.grids) {
      if (!g.from_file()) ShapesAtFrame(g, 1);  // an animated grid's next frame, checked
    }
  } catch (const InputError&) {
  }
  return 0;
}
