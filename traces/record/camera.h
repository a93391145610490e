// Pinhole cameras and camera paths (an orbit of N frames by D degrees, or key frames).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "traces/record/vec3.h"
#include "traces/trace_header.h"

namespace raycell {

// A pinhole camera for one frame: rays through pixel (px + jx, py + jy), jx, jy in [0, 1).
class PinholeCamera {
 public:
  static PinholeCamera Create(const CameraKey& key, std::uint32_t width, std::uint32_t height);
  // Unit direction of the ray through film position (x, y) in pixels, y down.
  Vec3d Direction(double x, double y) const;
  Vec3d eye() const { return eye_; }

 private:
  Vec3d eye_, forward_, right_, up_;
  double half_w_ = 0, half_h_ = 0, width_ = 0, height_ = 0;
};

// How the camera moves over the frames of a capture.
struct CameraPathSpec {
  // Where the first frame looks from and at; unset (NaN) eye/target frame the scene box.
  Vec3d eye{NAN, NAN, NAN}, target{NAN, NAN, NAN}, up{0, 1, 0};
  double fov_deg = 40;
  double orbit_degrees = 0;    // total orbit about the up axis through target over the frames
  std::string keyframes_file;  // if set: lines "frame ex ey ez tx ty tz fov", interpolated
};

// Checks the camera options before the scene is known: --fov in (0, 180) degrees, --up
// finite and not zero, --eye and --target finite (where given) and distinct. InputError
// naming the option, its value and the valid range.
void ValidateCameraSpec(const CameraPathSpec& spec);
// Checks the camera of one frame made from `spec` (an --up parallel to the view direction,
// a key frame whose eye is its target): InputError naming the options or the key-frame file,
// and the frame.
void CheckCamera(const CameraPathSpec& spec, const CameraKey& key);

// One CameraKey per frame number in `frames`, for a scene box [lo, hi]. InputError when the
// default framing would put the eye at infinity (a field of view too small for the box).
std::vector<CameraKey> MakeCameraPath(const CameraPathSpec& spec, const std::vector<int>& frames,
                                      Vec3d box_lo, Vec3d box_hi);

}  // namespace raycell
