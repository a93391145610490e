#include "traces/trace_header.h"

#include <algorithm>

#include "base/check.h"
#include "base/format.h"

namespace raycell {

std::string FormatVec3(const Vec3d& v) {
  return FormatReal(v.x) + "," + FormatReal(v.y) + "," + FormatReal(v.z);
}

std::vector<CellId> SubdivisionInfo::CellOfFine(std::size_t frame, std::uint32_t cells) const {
  const std::size_t per_frame = dynamic() ? cells : 0;
  const std::size_t first = frame * per_frame;
  RAYCELL_CHECK_LE(first + cells, boxes.size());
  return raycell::CellOfFine(std::vector<FineBox>(boxes.begin() + std::ptrdiff_t(first),
                                                  boxes.begin() + std::ptrdiff_t(first + cells)),
                             fine);
}

bool SubdivisionInfo::SameCells(std::size_t a, std::size_t b, std::uint32_t cells) const {
  if (!dynamic() || a == b) return true;
  const std::size_t fa = a * cells, fb = b * cells;
  RAYCELL_CHECK_LE(std::max(fa, fb) + cells, boxes.size());
  return std::equal(boxes.begin() + std::ptrdiff_t(fa), boxes.begin() + std::ptrdiff_t(fa + cells),
                    boxes.begin() + std::ptrdiff_t(fb));
}

std::uint64_t CellLeaves::UnionBytes(const std::vector<std::uint32_t>& cells) const {
  std::vector<std::uint32_t> all;
  for (std::uint32_t c : cells) {
    all.insert(all.end(), leaves.begin() + std::ptrdiff_t(begin[c]),
               leaves.begin() + std::ptrdiff_t(begin[c + 1]));
  }
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  std::uint64_t sum = 0;
  for (std::uint32_t l : all) sum += bytes[l];
  return sum;
}

std::string CameraPathInfo::ToString() const {
  const std::string view = "eye " + FormatVec3(eye) + " target " + FormatVec3(target) + " up " +
                           FormatVec3(up) + " fov " + FormatReal(fov_deg);
  if (kind == "orbit") {
    return "orbit of " + FormatReal(orbit_degrees) + " degrees over frames " +
           std::to_string(first_frame) + ".." +
           std::to_string(std::int64_t{first_frame} + frame_count - 1) + " (" + view + ")";
  }
  if (kind == "still") return "still camera (" + view + ")";
  if (kind == "keyframes") {
    std::string s = "keyframes";
    for (const CameraKey& k : keys) {
      s += " [" + std::to_string(k.frame) + ": eye " + FormatVec3(k.eye) + " target " +
           FormatVec3(k.target) + " fov " + FormatReal(k.fov_deg) + "]";
    }
    return s + " (up " + FormatVec3(up) + ")";
  }
  if (kind.empty()) return "not recorded";
  return "'" + kind + "'";
}

}  // namespace raycell
