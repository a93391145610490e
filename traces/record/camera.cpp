#include "traces/record/camera.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "base/check.h"

namespace raycell {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string Str(Vec3d v) { return Num(v.x) + "," + Num(v.y) + "," + Num(v.z); }

Vec3d RotateAbout(Vec3d v, Vec3d axis, double radians) {
  // Rodrigues' rotation of v about the unit axis.
  const double c = std::cos(radians), s = std::sin(radians);
  return v * c + Cross(axis, v) * s + axis * (Dot(axis, v) * (1 - c));
}

struct Keyframe {
  int frame;
  Vec3d eye, target;
  double fov;
};

std::vector<Keyframe> ReadKeyframes(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open key-frame file");
  std::vector<Keyframe> keys;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    std::istringstream s(line);
    Keyframe k{};
    if (!(s >> k.frame >> k.eye.x >> k.eye.y >> k.eye.z >> k.target.x >> k.target.y >> k.target.z >>
          k.fov) ||
        !IsFinite(k.eye) || !IsFinite(k.target) || !(k.fov > 0 && k.fov < 180)) {
      throw InputError(path + ":" + std::to_string(n) +
                       ": expected 'frame ex ey ez tx ty tz fov' with finite numbers and "
                       "0 < fov < 180");
    }
    if (!keys.empty() && k.frame <= keys.back().frame) {
      throw InputError(path + ":" + std::to_string(n) + ": key frames must increase");
    }
    keys.push_back(k);
  }
  if (keys.empty()) throw InputError(path + ": no key frames");
  return keys;
}

CameraKey Interpolate(const std::vector<Keyframe>& keys, int frame, Vec3d up) {
  auto hi = std::lower_bound(keys.begin(), keys.end(), frame,
                             [](const Keyframe& k, int f) { return k.frame < f; });
  if (hi == keys.begin())
    return {frame, keys.front().eye, keys.front().target, up, keys.front().fov};
  if (hi == keys.end()) return {frame, keys.back().eye, keys.back().target, up, keys.back().fov};
  const Keyframe& a = *(hi - 1);
  const Keyframe& b = *hi;
  const double w = double(frame - a.frame) / double(b.frame - a.frame);
  return {frame, a.eye * (1 - w) + b.eye * w, a.target * (1 - w) + b.target * w, up,
          a.fov * (1 - w) + b.fov * w};
}

}  // namespace

PinholeCamera PinholeCamera::Create(const CameraKey& key, std::uint32_t width,
                                    std::uint32_t height) {
  if (!IsFinite(key.eye) || !IsFinite(key.target) || !IsFinite(key.up)) {
    throw InputError("camera: eye " + Str(key.eye) + ", target " + Str(key.target) + " and up " +
                     Str(key.up) + " must be finite");
  }
  if (!(key.fov_deg > 0 && key.fov_deg < 180)) {
    throw InputError("camera: field of view " + Num(key.fov_deg) + " must be in (0, 180) degrees");
  }
  const Vec3d f = key.target - key.eye;
  if (!(Length(f) > 0)) {
    throw InputError("camera: eye and target are the same point " + Str(key.eye));
  }
  if (!std::isfinite(Length(f))) {
    throw InputError("camera: eye " + Str(key.eye) + " and target " + Str(key.target) +
                     " are too far apart (their distance overflows a double)");
  }
  PinholeCamera c;
  c.eye_ = key.eye;
  c.forward_ = Normalize(f);
  const Vec3d r = Cross(c.forward_, key.up);
  if (!(Length(r) > 1e-12)) {
    throw InputError("camera: up " + Str(key.up) + " is parallel to the view direction " +
                     Str(c.forward_) + " (from eye to target)");
  }
  c.right_ = Normalize(r);
  c.up_ = Cross(c.right_, c.forward_);
  c.width_ = width;
  c.height_ = height;
  c.half_h_ = std::tan(key.fov_deg * kPi / 360.0);
  c.half_w_ = c.half_h_ * double(width) / double(height);
  return c;
}

Vec3d PinholeCamera::Direction(double x, double y) const {
  const double u = (2.0 * x / width_ - 1.0) * half_w_;
  const double v = (1.0 - 2.0 * y / height_) * half_h_;
  return Normalize(forward_ + right_ * u + up_ * v);
}

void ValidateCameraSpec(const CameraPathSpec& spec) {
  if (!(spec.fov_deg > 0 && spec.fov_deg < 180)) {
    throw InputError("--fov " + Num(spec.fov_deg) +
                     ": the vertical field of view must be in (0, 180) degrees");
  }
  if (!IsFinite(spec.up)) throw InputError("--up " + Str(spec.up) + ": must be finite");
  if (!(Length(spec.up) > 0)) throw InputError("--up " + Str(spec.up) + ": must not be zero");
  // NaN means "not given" (frame the scene box); infinities are refused.
  for (const auto& [v, name] : {std::pair{spec.eye, "--eye"}, std::pair{spec.target, "--target"}}) {
    for (double c : {v.x, v.y, v.z}) {
      if (std::isinf(c)) throw InputError(std::string(name) + " " + Str(v) + ": must be finite");
    }
  }
  if (!std::isfinite(spec.orbit_degrees)) {
    throw InputError("--orbit " + Num(spec.orbit_degrees) + ": degrees must be finite");
  }
  if (IsFinite(spec.eye) && IsFinite(spec.target) && spec.eye == spec.target) {
    throw InputError("--eye and --target are the same point " + Str(spec.eye) +
                     ": the camera must look somewhere");
  }
}

void CheckCamera(const CameraPathSpec& spec, const CameraKey& key) {
  try {
    PinholeCamera::Create(key, 1, 1);
  } catch (const InputError& e) {
    const std::string where =
        spec.keyframes_file.empty()
            ? "--eye/--target/--up/--fov/--orbit, frame " + std::to_string(key.frame)
            : "--keyframes " + spec.keyframes_file + ", frame " + std::to_string(key.frame);
    throw InputError(where + ": " + e.what());
  }
}

std::vector<CameraKey> MakeCameraPath(const CameraPathSpec& spec, const std::vector<int>& frames,
                                      Vec3d lo, Vec3d hi) {
  if (!spec.keyframes_file.empty()) {
    const auto keys = ReadKeyframes(spec.keyframes_file);
    std::vector<CameraKey> path;
    for (int f : frames) path.push_back(Interpolate(keys, f, spec.up));
    return path;
  }
  const Vec3d center = (lo + hi) * 0.5;
  const Vec3d target = IsFinite(spec.target) ? spec.target : center;
  Vec3d eye = spec.eye;
  if (!IsFinite(eye)) {
    const double radius = 0.5 * Length(hi - lo);
    const double dist = 1.05 * radius / std::sin(spec.fov_deg * kPi / 360.0);
    eye = target + Normalize(Vec3d{0.0, 0.3, 1.0}) * dist;
    if (!std::isfinite(Length(eye - target))) {
      throw InputError("--fov " + Num(spec.fov_deg) +
                       ": too small to frame the scene box from a finite distance; give --eye");
    }
  }
  const Vec3d up = Normalize(spec.up);
  std::vector<CameraKey> path;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const double angle = spec.orbit_degrees * kPi / 180.0 * double(i) / double(frames.size());
    const Vec3d e = target + RotateAbout(eye - target, up, angle);
    path.push_back(CameraKey{frames[i], e, target, up, spec.fov_deg});
  }
  return path;
}

}  // namespace raycell
