#include "traces/trace_header.h"

#include "base/format.h"

namespace raycell {
namespace {

std::string Csv(const Vec3d& v) {
  return FormatReal(v.x) + "," + FormatReal(v.y) + "," + FormatReal(v.z);
}

}  // namespace

std::string CameraPathInfo::ToString() const {
  const std::string view = "eye " + Csv(eye) + " target " + Csv(target) + " up " + Csv(up) +
                           " fov " + FormatReal(fov_deg);
  if (kind == "orbit") {
    return "orbit of " + FormatReal(orbit_degrees) + " degrees over frames " +
           std::to_string(first_frame) + ".." +
           std::to_string(std::int64_t{first_frame} + frame_count - 1) + " (" + view + ")";
  }
  if (kind == "still") return "still camera (" + view + ")";
  if (kind == "keyframes") {
    std::string s = "keyframes";
    for (const CameraKey& k : keys) {
      s += " [" + std::to_string(k.frame) + ": eye " + Csv(k.eye) + " target " + Csv(k.target) +
           " fov " + FormatReal(k.fov_deg) + "]";
    }
    return s + " (up " + Csv(up) + ")";
  }
  if (kind.empty()) return "not recorded";
  return "'" + kind + "'";
}

}  // namespace raycell
