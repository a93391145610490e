#include "record/camera.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <tuple>
#include <utility>

#include "base/check.h"
#include "base/parse.h"

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

std::vector<CameraKey> ReadKeyframeFile(const std::string& path, Vec3d up) {
  std::vector<CameraKey> keys;
  for (const Keyframe& k : ReadKeyframes(path)) {
    keys.push_back(CameraKey{k.frame, k.eye, k.target, up, k.fov});
  }
  return keys;
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

namespace {

// The eye of the first frame and the target, when the options leave them to the scene box.
std::pair<Vec3d, Vec3d> FrameTheBox(const CameraPathSpec& spec, Vec3d lo, Vec3d hi) {
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
  return {eye, target};
}

}  // namespace

void CheckOrbitFrames(const CameraPathSpec& spec, const std::vector<int>& frames) {
  if (spec.orbit_frames <= 0 || frames.empty()) return;
  const std::int64_t first = spec.orbit_first, last = first + spec.orbit_frames - 1;
  if (frames.front() < first || frames.back() > last) {
    throw InputError("--frames " + FormatFrameRange(frames.front(), frames.back()) +
                     ": not frames of " + "--orbit " + std::to_string(spec.orbit_frames) + ":" +
                     Num(spec.orbit_degrees) + ", whose frames are " +
                     FormatFrameRange(first, last));
  }
}

CameraPathInfo MakeCameraPathInfo(const CameraPathSpec& spec, const std::vector<int>& frames,
                                  Vec3d lo, Vec3d hi) {
  RAYCELL_CHECK(!frames.empty());
  CameraPathInfo path;
  if (!spec.keyframes_file.empty() || !spec.keys.empty()) {
    path.kind = "keyframes";
    path.up = spec.up;
    if (!spec.keyframes_file.empty()) {
      path.keys = ReadKeyframeFile(spec.keyframes_file, spec.up);
    } else {
      for (const CameraKey& k : spec.keys) {
        path.keys.push_back(CameraKey{k.frame, k.eye, k.target, spec.up, k.fov_deg});
      }
    }
    return path;
  }
  std::tie(path.eye, path.target) = FrameTheBox(spec, lo, hi);
  path.up = Normalize(spec.up);
  path.fov_deg = spec.fov_deg;
  if (spec.orbit_degrees == 0 && spec.orbit_frames == 0) {
    path.kind = "still";
    return path;
  }
  path.kind = "orbit";
  path.orbit_degrees = spec.orbit_degrees;
  path.first_frame = spec.orbit_frames > 0 ? spec.orbit_first : frames.front();
  path.frame_count =
      static_cast<std::uint32_t>(spec.orbit_frames > 0 ? spec.orbit_frames : frames.size());
  CheckOrbitFrames(spec, frames);
  return path;
}

CameraKey CameraOf(const CameraPathInfo& path, int frame) {
  if (path.kind == "keyframes") {
    std::vector<Keyframe> keys;
    for (const CameraKey& k : path.keys) keys.push_back({k.frame, k.eye, k.target, k.fov_deg});
    return Interpolate(keys, frame, path.up);
  }
  RAYCELL_CHECK(path.kind == "still" || path.kind == "orbit");
  // A still camera turns by 0 degrees: its eye is computed as an orbit's first frame's.
  const bool orbit = path.kind == "orbit";
  const std::int64_t index = orbit ? std::int64_t{frame} - path.first_frame : 0;
  const double count = orbit ? double(path.frame_count) : 1.0;
  const double angle = path.orbit_degrees * kPi / 180.0 * double(index) / count;
  const Vec3d e = path.target + RotateAbout(path.eye - path.target, path.up, angle);
  return CameraKey{frame, e, path.target, path.up, path.fov_deg};
}

std::vector<CameraKey> MakeCameraPath(const CameraPathSpec& spec, const std::vector<int>& frames,
                                      Vec3d lo, Vec3d hi) {
  const CameraPathInfo path = MakeCameraPathInfo(spec, frames, lo, hi);
  std::vector<CameraKey> cameras;
  for (int f : frames) cameras.push_back(CameraOf(path, f));
  return cameras;
}

}  // namespace raycell
