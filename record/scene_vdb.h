// Scene internals with OpenVDB types. Include only from the renderer's translation units
// (scene.cpp, renderer.cpp): OpenVDB headers are heavy.
#pragma once

#include <openvdb/openvdb.h>

#include <string>
#include <vector>

#include "record/scene.h"

namespace raycell {

struct FogLayer {
  openvdb::FloatGrid::ConstPtr grid;
  FogMaterial material;
};

struct SurfaceLayer {
  openvdb::FloatGrid::ConstPtr grid;
  SurfaceMaterial material;
};

struct Scene::Impl {
  std::vector<FogLayer> fogs;
  std::vector<SurfaceLayer> surfaces;
  std::vector<GridInfo> infos;           // the rendered grids
  std::vector<std::string> float_grids;  // every float grid of the source (for messages)
  std::vector<Light> lights;
  Rgb sky_top{0, 0, 0}, sky_bottom{0, 0, 0};  // background gradient by direction.y
  openvdb::Vec3d lo, hi;
};

}  // namespace raycell
