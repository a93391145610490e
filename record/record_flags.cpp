#include "record/record_flags.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string_view>

#include "base/check.h"
#include "base/parse.h"
#include "record/cell_grid.h"
#include "record/scene.h"
#include "record/scene_file.h"
#include "traces/cell_dims.h"

namespace raycell {
namespace {

Vec3d ParseVec(const std::string& text, const std::string& option) {
  double v[3];
  char tail;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &tail) != 3 ||
      !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
    throw InputError(option + " '" + text + "': expected three finite numbers X,Y,Z");
  }
  return {v[0], v[1], v[2]};
}

// "--orbit D" turns by D degrees over the frames recorded; "--orbit N:D" over frames 0..N-1,
// and records them all unless --frames A..B picks a range of them (docs/design.md §3).
void ApplyOrbit(const RecordFlags& a, RecordOptions& o) {
  if (a.orbit.empty()) return;
  const auto colon = a.orbit.find(':');
  const std::string deg = colon == std::string::npos ? a.orbit : a.orbit.substr(colon + 1);
  char* end = nullptr;
  o.camera.orbit_degrees = std::strtod(deg.c_str(), &end);
  if (deg.empty() || *end || !std::isfinite(o.camera.orbit_degrees)) {
    throw InputError("--orbit '" + a.orbit + "': expected DEGREES or FRAMES:DEGREES");
  }
  if (colon != std::string::npos) {
    const auto n = ParseInt(std::string_view(a.orbit).substr(0, colon),
                            "--orbit '" + a.orbit + "' frames", 1, 1000000);
    o.camera.orbit_first = 0;
    o.camera.orbit_frames = static_cast<int>(n);
    if (a.frames.empty()) o.frames = ParseFrameRange("0.." + std::to_string(n - 1));
  }
}

// --grid / --all-grids on a scene file: the chosen grids, in the file's order.
void ChooseSceneGrids(const RecordFlags& a, SceneDescription& d) {
  const SceneSpec& spec = a.opt.scene;
  if (spec.all_grids && !spec.grids.empty()) {
    throw InputError("--grid and --all-grids: give one or the other");
  }
  if (spec.grids.empty()) return;
  std::vector<std::string> names;
  for (const GridDesc& g : d.grids) names.push_back(g.name);
  for (const std::string& g : spec.grids) {
    if (std::find(names.begin(), names.end(), g) == names.end()) {
      throw InputError("--grid '" + g + "': " + spec.source + " has no float grid '" + g +
                       "' (float grids: " + Join(names, ", ") + ")");
    }
  }
  d.grids.erase(std::remove_if(d.grids.begin(), d.grids.end(),
                               [&](const GridDesc& g) {
                                 return std::find(spec.grids.begin(), spec.grids.end(), g.name) ==
                                        spec.grids.end();
                               }),
                d.grids.end());
}

// A scene file read, the flags applied over it; sets o's scene, camera and frames.
void ApplySceneFile(const RecordFlags& a, RecordOptions& o) {
  SceneDescription d = LoadSceneDescription(o.scene.source);
  ChooseSceneGrids(a, d);
  for (const std::string& m : a.opt.scene.materials) ApplyMaterialText(d, m);
  if (!a.lights.empty()) {
    d.lights.clear();
    for (const auto& l : a.lights) d.lights.push_back(ParseLight(l));
  }
  CameraPathSpec& c = d.camera;
  if (!a.eye.empty()) c.eye = ParseVec(a.eye, "--eye");
  if (!a.target.empty()) c.target = ParseVec(a.target, "--target");
  if (!a.up.empty()) c.up = ParseVec(a.up, "--up");
  if (a.fov_given) c.fov_deg = a.opt.camera.fov_deg;
  if (!a.opt.camera.keyframes_file.empty()) {
    ValidateCameraSpec(c);  // --up before the keys take it
    c.keys = ReadKeyframeFile(a.opt.camera.keyframes_file, c.up);
    c.orbit_degrees = 0, c.orbit_frames = 0, c.orbit_first = 0;
  }
  RecordOptions orbit;
  orbit.camera = c;
  orbit.camera.orbit_frames = 0, orbit.camera.orbit_first = 0;  // --orbit DEGREES: no frames
  ApplyOrbit(a, orbit);  // --orbit replaces the file's orbit and key frames
  if (!a.orbit.empty()) {
    c = orbit.camera;
    c.keys.clear();
  }
  if (!a.frames.empty()) {
    const auto f = ParseFrameRange(a.frames);
    d.frames = FormatFrameRange(f.front(), f.back());
  } else if (!a.orbit.empty() && c.orbit_frames > 0) {
    d.frames = FormatFrameRange(0, c.orbit_frames - 1);
  } else if (d.frames.empty()) {
    d.frames = c.orbit_frames > 0
                   ? FormatFrameRange(c.orbit_first, c.orbit_frames - 1 + c.orbit_first)
                   : "0..0";
  }
  ValidateSceneDescription(d, o.scene.source);
  o.frames = ParseFrameRange(d.frames);
  o.camera = c;
  o.scene.materials.clear();
  o.scene.lights.clear();
  o.scene.grids.clear();
  o.scene.all_grids = false;
  o.scene.description = std::make_shared<const SceneDescription>(std::move(d));
}

}  // namespace

RecordOptions ToRecordOptions(const RecordFlags& a) {
  RecordOptions o = a.opt;
  if (IsSceneFile(o.scene.source)) {
    ApplySceneFile(a, o);
  } else {
    if (!a.frames.empty()) o.frames = ParseFrameRange(a.frames);
    ApplyOrbit(a, o);
  }
  if (IsSequencePattern(o.scene.source) && a.frames.empty()) {
    throw InputError("--scene '" + o.scene.source + "' is a sequence pattern: give --frames A..B");
  }
  o.cells = ParseCellDims(a.cells);
  const auto wh = ParseResolution(a.res);
  o.settings.width = wh[0], o.settings.height = wh[1];
  if (!o.scene.description) {
    for (const auto& l : a.lights) o.scene.lights.push_back(ParseLight(l));
    if (!a.eye.empty()) o.camera.eye = ParseVec(a.eye, "--eye");
    if (!a.target.empty()) o.camera.target = ParseVec(a.target, "--target");
    if (!a.up.empty()) o.camera.up = ParseVec(a.up, "--up");
  }
  o.settings.single_precision = a.precision == "single";
  o.image_encoding = ParsePngEncoding(a.image_encoding, "--image-encoding");
  if (a.no_images) o.images_dir.clear();
  o.progress = !a.quiet;
  return o;
}

}  // namespace raycell
