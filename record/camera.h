// Pinhole cameras and camera paths (an orbit of N frames by D degrees, or key frames).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "record/vec3.h"
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
  double orbit_degrees = 0;  // total orbit about the up axis through target over the frames
  // The orbit's frames orbit_first..orbit_first + orbit_frames - 1 (--orbit FRAMES:DEGREES:
  // 0..FRAMES-1), of which a capture records a range; 0 frames: the frames recorded
  // (--orbit DEGREES). No orbit (orbit_degrees 0 and orbit_frames 0): a still camera.
  int orbit_first = 0;
  int orbit_frames = 0;
  std::string keyframes_file;  // if set: lines "frame ex ey ez tx ty tz fov", interpolated
  // Key frames given inline (a scene file's [[camera.key]]), used as the file's would be when
  // no file is set; their `up` is ignored (spec.up is every key's).
  std::vector<CameraKey> keys;
};

// The key frames of a --keyframes file, each with `up`. InputError naming FILE:LINE.
std::vector<CameraKey> ReadKeyframeFile(const std::string& path, Vec3d up);

// Checks the camera options before the scene is known: --fov in (0, 180) degrees, --up
// finite and not zero, --eye and --target finite (where given) and distinct. InputError
// naming the option, its value and the valid range.
void ValidateCameraSpec(const CameraPathSpec& spec);
// Checks the camera of one frame made from `spec` (an --up parallel to the view direction,
// a key frame whose eye is its target): InputError naming the options or the key-frame file,
// and the frame.
void CheckCamera(const CameraPathSpec& spec, const CameraKey& key);

// Checks that consecutive `frames` are frames of spec's orbit, when it has its own frames
// (--orbit FRAMES:DEGREES): InputError naming both ranges if not.
void CheckOrbitFrames(const CameraPathSpec& spec, const std::vector<int>& frames);
// The whole camera path `spec` describes, for a capture of `frames` (consecutive frame
// numbers) of a scene box [lo, hi] (docs/design.md §3 "The trace"): a still camera, an orbit
// over spec's orbit frames (or over `frames` when it has none) or the key frames of the file.
// InputError when the default framing would put the eye at infinity (a field of view too
// small for the box), or when `frames` are not all frames of the orbit.
CameraPathInfo MakeCameraPathInfo(const CameraPathSpec& spec, const std::vector<int>& frames,
                                  Vec3d box_lo, Vec3d box_hi);
// The camera of frame `frame` of `path`: the same for a capture of any range of the path.
CameraKey CameraOf(const CameraPathInfo& path, int frame);
// One CameraKey per frame number in `frames`: CameraOf(MakeCameraPathInfo(...), frame).
std::vector<CameraKey> MakeCameraPath(const CameraPathSpec& spec, const std::vector<int>& frames,
                                      Vec3d box_lo, Vec3d box_hi);

}  // namespace raycell
