#include "record/record_flags.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "base/check.h"
#include "base/parse.h"
#include "record/cell_grid.h"
#include "record/scene.h"
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

}  // namespace

RecordOptions ToRecordOptions(const RecordFlags& a) {
  RecordOptions o = a.opt;
  if (!a.frames.empty()) o.frames = ParseFrameRange(a.frames);
  ApplyOrbit(a, o);
  if (IsSequencePattern(o.scene.source) && a.frames.empty()) {
    throw InputError("--scene '" + o.scene.source + "' is a sequence pattern: give --frames A..B");
  }
  o.cells = ParseCellDims(a.cells);
  const auto wh = ParseResolution(a.res);
  o.settings.width = wh[0], o.settings.height = wh[1];
  for (const auto& l : a.lights) o.scene.lights.push_back(ParseLight(l));
  if (!a.eye.empty()) o.camera.eye = ParseVec(a.eye, "--eye");
  if (!a.target.empty()) o.camera.target = ParseVec(a.target, "--target");
  o.camera.up = ParseVec(a.up, "--up");
  o.settings.single_precision = a.precision == "single";
  o.image_encoding = ParsePngEncoding(a.image_encoding, "--image-encoding");
  if (a.no_images) o.images_dir.clear();
  o.progress = !a.quiet;
  return o;
}

}  // namespace raycell
