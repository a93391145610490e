// Fuzz target: --material values (GRID:key=value:...), applied as `raycell record` applies
// them, to a scene loaded from a tiny .vdb file (fuzz/data/tiny.vdb: a level set "ball" and a
// fog volume "density"). One material per input line. Bad text must give an InputError,
// never a crash, a leak or a hang.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/parse.h"
#include "record/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace raycell;
  // The file is read once (Scene::Load, 30 ms); each input's materials are applied to it as
  // Load applies spec.materials (Scene::WithMaterials: the same ApplyMaterial).
  static const std::unique_ptr<Scene> base = [] {
    SceneSpec spec;
    spec.source = RAYCELL_FUZZ_DATA "/tiny.vdb";
    spec.all_grids = true;  // both grids, so that a material may name either
    return Scene::Load(spec, 0);
  }();
  const std::vector<std::string> materials =
      Split(std::string(reinterpret_cast<const char*>(data), size), '\n');
  try {
    const auto scene = base->WithMaterials(materials, RAYCELL_FUZZ_DATA "/tiny.vdb");
    RAYCELL_CHECK_EQ(scene->grids().size(), std::size_t{2});
  } catch (const InputError&) {
  }
  return 0;
}
