// Scene files (docs/scenes.md): a scene described in TOML, read into a plain description
// (grids from VDB files or made of OpenVDB primitives, their materials, lights, sky, camera
// path and default frames) and checked, without OpenVDB. record/scene.cpp builds the grids
// of one frame from it (Scene::Load); this file only reads, checks and prints.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "record/camera.h"
#include "record/scene.h"

namespace raycell {

// One primitive of a procedural grid, joined to the shapes before it by `op` (the first
// shape's op is ignored): shapes a, b, c with ops -, d, i make ((a - b) \ c) ∩ ...
struct ShapeDesc {
  enum class Op { kUnion, kDifference, kIntersection };
  Op op = Op::kUnion;
  // "sphere", "box", or a platonic solid: "tetrahedron", "cube", "octahedron",
  // "dodecahedron", "icosahedron".
  std::string type;
  Vec3d center{0, 0, 0};                // sphere and platonic solids, world units
  double radius = 1;                    // sphere, world units
  double scale = 1;                     // platonic solids: OpenVDB's scale, world units
  Vec3d min{-1, -1, -1}, max{1, 1, 1};  // box corners, world units
  int line = 0;                         // where it was written, for messages (0: unknown)
};

// Seeded value noise that multiplies a fog's density (docs/scenes.md "noise"): integer
// arithmetic only, so the same on every machine.
struct NoiseDesc {
  bool on = false;
  std::uint64_t seed = 0;
  int period = 8;        // voxels between lattice points of the first octave: 1, 2, 4, ..., 256
  int octaves = 1;       // 1..8, each at half the period before it and half its weight
  double amount = 1;     // [0, 1]: density x (1 - amount + amount x noise)
  double threshold = 0;  // [0, 1]: voxels whose noise is below it become empty
};

// What changes per frame number f (a grid with any of it makes the scene animated).
struct AnimateDesc {
  Vec3d translate{0, 0, 0};  // world units per frame, added to the transform's
  double rotate = 0;         // degrees per frame about the transform's axis
  double grow = 0;           // world units per frame added to every shape's radius, scale,
                             // and box half-extents
  bool any() const {
    return translate.x != 0 || translate.y != 0 || translate.z != 0 || rotate != 0 || grow != 0;
  }
};

struct GridDesc {
  std::string name;
  bool fog = false;  // rendered as fog (else as a surface)
  // From a VDB file: its path (absolute, or a printf pattern of one file per frame) and the
  // float grid read from it (empty: the first, vdb_render's rule).
  std::string file, vdb_grid;
  // Or made of shapes: a level set with this voxel size (world units) and half band width
  // (voxels); as fog, sdfToFogVolume with this ramp (world units; 0: the whole interior band).
  double voxel = 0.025, band = 3, ramp = 0;
  std::vector<ShapeDesc> shapes;
  // Applied to the grid after it is made: uniform scale, then rotation about an axis through
  // the origin, then translation.
  double scale = 1;
  Vec3d axis{0, 1, 0};
  double degrees = 0;
  Vec3d translate{0, 0, 0};
  NoiseDesc noise;
  AnimateDesc animate;
  FogMaterial fog_material;
  SurfaceMaterial surface_material;
  int line = 0;
  bool from_file() const { return !file.empty(); }
  bool animated() const { return animate.any() || file.find('%') != std::string::npos; }
};

struct SceneDescription {
  // The trace header's scene (an animated scene's followed by "@%d", see SceneLabel);
  // default: the --scene argument as given ("builtin" for the built-in scene).
  std::string name;
  std::vector<GridDesc> grids;
  std::vector<Light> lights;  // empty in a file: vdb_render's default light
  Rgb sky_top{0, 0, 0}, sky_bottom{0, 0, 0};
  CameraPathSpec camera;  // keyframes inline (keys), never a file
  std::string frames;     // "A..B" recorded when --frames is not given; empty: none
  bool animated() const;
};

// Largest voxel count a procedural grid may be estimated to allocate (narrow band, or the
// whole box when noise voxelizes a fog): 2^27 voxels, half a GiB of floats.
inline constexpr double kMaxGridVoxels = double(std::uint64_t{1} << 27);

// Whether --scene names a scene file: "builtin" or a path ending in ".toml".
bool IsSceneFile(const std::string& source);
// Reads and checks a scene: "builtin" is the embedded scenes/builtin.toml, anything else a
// file. `name` defaults to `source`. InputError naming FILE:LINE:COLUMN and the key for an
// unknown key, a wrong type or a bad value, and naming the file when it cannot be read.
SceneDescription LoadSceneDescription(const std::string& source);
// The same from text; `source` names it in messages and is the default name; relative file
// paths are resolved against `dir`.
SceneDescription ParseSceneDescription(std::string_view text, const std::string& source,
                                       const std::string& dir);
// The checks every description passes (ParseSceneDescription calls it): at least one grid,
// unique names, finite values in range, a voxel count within kMaxGridVoxels. InputError
// naming `what` (the file) and the grid.
void ValidateSceneDescription(const SceneDescription& d, const std::string& what);
// The shapes of `g` at frame `frame` (grown by animate.grow), checked: InputError naming the
// grid and frame when a size is no longer positive or the voxel count exceeds the limit.
std::vector<ShapeDesc> ShapesAtFrame(const GridDesc& g, int frame);
// TOML that ParseSceneDescription reads back to an equal description (every value written,
// defaults filled in).
std::string PrintSceneDescription(const SceneDescription& d);
// Seeded value noise (docs/scenes.md "noise"): the noise at voxel (x, y, z) is
// NoiseNumerator / NoiseDenominator in [0, 1], a sum of octaves of trilinear interpolation
// between 16-bit hashes of lattice points (of the seed, the octave and the point), in integer
// arithmetic. NoiseFactor is what the voxel's density is multiplied by: 0 where the noise is
// below the threshold, else 1 - amount + amount x noise (amount and threshold rounded to
// 1/4096); the same on every machine.
std::uint64_t NoiseNumerator(const NoiseDesc& n, std::int32_t x, std::int32_t y, std::int32_t z);
std::uint64_t NoiseDenominator(const NoiseDesc& n);
double NoiseFactor(const NoiseDesc& n, std::int32_t x, std::int32_t y, std::int32_t z);

// The embedded scenes/builtin.toml.
std::string_view BuiltinSceneText();

// A --material value "GRID:key=value:..." applied to the description's grid (the same keys
// and checks as on a loaded scene). InputError naming the value.
void ApplyMaterialText(SceneDescription& d, const std::string& text);

// The key=value fields of a --material text split at ':' (fields[0], the grid, skipped)
// applied to a fog's material or a surface's (exactly one of them given), then the surface
// checked: what --material does to a description and to a loaded scene. InputError naming
// `what` and the key.
void ApplyMaterialFields(const std::vector<std::string>& fields, const std::string& what,
                         FogMaterial* fog, SurfaceMaterial* surface);

// Material keys, shared by --material and scene files: `values` are one number, or three
// (R,G,B) for colours; a grey colour may be one number. InputError naming `what`.
void SetFogKey(FogMaterial& m, const std::string& key, const std::vector<double>& values,
               const std::string& what);
void SetSurfaceKey(SurfaceMaterial& m, const std::string& key, const std::vector<double>& values,
                   const std::string& what);
// reflect + transparency <= 1. InputError naming `what` otherwise.
void CheckSurfaceMaterial(const SurfaceMaterial& m, const std::string& what);
// Parses one material value of --material text: "V" or "R,G,B". InputError naming `what`.
std::vector<double> ParseMaterialValues(const std::string& text, const std::string& what);

}  // namespace raycell
