// Small double-precision vector maths for the recorder's OpenVDB-free code (cameras, cells).
#pragma once

#include <cmath>

#include "traces/trace_header.h"

namespace raycell {

inline Vec3d operator+(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3d operator*(Vec3d a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3d operator*(double s, Vec3d a) { return a * s; }
inline double Dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d Cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double Length(Vec3d a) { return std::sqrt(Dot(a, a)); }
inline Vec3d Normalize(Vec3d a) { return a * (1.0 / Length(a)); }
inline bool IsFinite(Vec3d a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline double Component(Vec3d a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }

}  // namespace raycell
