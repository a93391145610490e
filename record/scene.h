// A scene to record: OpenVDB float grids (fog volumes and level-set surfaces) with their
// materials, the lights and the background. OpenVDB types stay behind Scene::Impl, so this
// header is cheap to include.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "record/image.h"
#include "traces/trace_header.h"

namespace raycell {

// Fog coefficients are per voxel of optical path, as in OpenVDB's vdb_render.
struct FogMaterial {
  Rgb absorption{0.1, 0.1, 0.1};
  Rgb scattering{1.5, 1.5, 1.5};
  double shadow_gain = 0.2;  // in-scattering along shadow rays, vdb_render's -gain
};

struct SurfaceMaterial {
  Rgb color{0.8, 0.8, 0.8};
  double reflectivity = 0;  // fraction of light mirrored
  double transparency = 0;  // fraction of light refracted
  double ior = 1.5;         // index of refraction
};

struct Light {
  enum class Type { kDirectional, kPoint } type = Type::kDirectional;
  Vec3d v{0.3, 0.3, 0};      // direction towards the light, or its position
  Rgb color{0.7, 0.7, 0.7};  // vdb_render's default light
};

struct SceneDescription;  // record/scene_file.h

struct SceneSpec {
  // "builtin" (the embedded scenes/builtin.toml), a scene file (.toml), one .vdb file, or a
  // printf pattern such as fluid_data_%04d.vdb (one file per frame number).
  std::string source = "builtin";
  // The scene file read and resolved (ToRecordOptions: the flags applied); null: Load reads
  // `source` itself, and applies the fields below to it.
  std::shared_ptr<const SceneDescription> description;
  // The grids rendered, by name. Empty: vdb_render's choice, the first float grid of the file
  // (every grid of the built-in scene). Each named grid must be a float grid of the file.
  std::vector<std::string> grids;
  bool all_grids = false;  // every float grid of the file (then `grids` must be empty)
  // "GRID:key=value:key=value", e.g. "density:absorb=0.2:scatter=1,1,1" or
  // "ball:color=1,0,0:reflect=0.5:transparent=0:ior=1.5" (see ParseMaterial).
  std::vector<std::string> materials;
  std::vector<Light> lights;              // empty: the scene's own lights
  std::string footprint_mode = "sparse";  // or "dense"
};

// Parses "dir:X,Y,Z[:R,G,B]" or "point:X,Y,Z[:R,G,B]".
Light ParseLight(const std::string& text);
// Checks a light: finite, a non-zero direction, colour in [0, 1e30] (so that radiance fits a
// float). InputError naming `what` otherwise.
void ValidateLight(const Light& l, const std::string& what);
bool IsSequencePattern(const std::string& source);
// Whether the volume changes from frame to frame: a sequence pattern, or an animated scene
// file (a grid with `animate`, or read from a pattern of files). Loads the description when
// `spec` has none.
bool VolumeChanges(const SceneSpec& spec);
// The trace header's scene: the description's name, followed by "@%d" when the scene is
// animated (so TraceHeader::volume_changes holds, as for a sequence pattern), or the source.
std::string SceneLabel(const SceneSpec& spec);
// The file of one frame: the pattern formatted with the frame number, or the file itself.
std::string FrameFile(const std::string& source, int frame);

class Scene {
 public:
  struct Impl;  // OpenVDB grids and materials, see scene_vdb.h
  // Loads (or builds) the scene of one frame: only the grids chosen by spec.grids /
  // spec.all_grids are read. Throws InputError for a missing file, a file with no float grid,
  // a chosen grid it lacks, an unknown material key, and so on.
  static std::unique_ptr<Scene> Load(const SceneSpec& spec, int frame);
  // This scene (its grids shared, not copied) with `materials` applied on top, each as a
  // --material value is in Load (`source` names the scene in messages): the same checks and
  // InputErrors. Cheap: no file is read.
  std::unique_ptr<Scene> WithMaterials(const std::vector<std::string>& materials,
                                       const std::string& source) const;
  ~Scene();

  const std::vector<GridInfo>& grids() const;
  // World box that holds every sample with a non-zero value: the union of the grids' active
  // voxel bounding boxes, padded by one voxel (the trilinear kernel's support).
  Vec3d box_lo() const;
  Vec3d box_hi() const;
  const std::vector<Light>& lights() const;
  Rgb background(Vec3d direction) const;
  // Bytes per cell of the grid [lo, hi] split in dims; 0 marks an empty cell.
  std::vector<std::uint64_t> Footprints(Vec3d lo, Vec3d hi, std::array<std::uint32_t, 3> dims,
                                        const std::string& mode) const;
  // The leaves (allocated leaf nodes and active tiles of every grid) that overlap each cell
  // of the same grid, as the sparse footprints count them, so that the footprints are their
  // bytes: a regroupable capture's TraceHeader::leaves. Leaves overlapping no cell are left
  // out; the others are numbered in the order of the grids, leaves before tiles.
  CellLeaves Leaves(Vec3d lo, Vec3d hi, std::array<std::uint32_t, 3> dims) const;
  const Impl& impl() const { return *impl_; }

 private:
  explicit Scene(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace raycell
