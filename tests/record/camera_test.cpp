// Camera paths: orbits and key frames, and the pinhole camera's rays.
#include "record/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "base/check.h"
#include "tests/test_util.h"

namespace raycell {
namespace {

TEST(CameraPath, OrbitTurnsAboutTheTargetAtConstantDistance) {
  CameraPathSpec spec;
  spec.eye = {0, 0, 10};
  spec.target = {0, 0, 0};
  spec.orbit_degrees = 360;
  const auto path = MakeCameraPath(spec, {0, 1, 2, 3}, {-1, -1, -1}, {1, 1, 1});
  ASSERT_EQ(path.size(), 4u);
  // A quarter turn per frame about +y: (0,0,10) -> (10,0,0) -> (0,0,-10) -> (-10,0,0).
  EXPECT_NEAR(path[1].eye.x, 10, 1e-9);
  EXPECT_NEAR(path[1].eye.z, 0, 1e-9);
  EXPECT_NEAR(path[2].eye.z, -10, 1e-9);
  EXPECT_NEAR(path[3].eye.x, -10, 1e-9);
  for (const auto& k : path) EXPECT_NEAR(Length(k.eye - k.target), 10, 1e-9);
  EXPECT_EQ(path[3].frame, 3);
}

TEST(CameraPath, DefaultFramingSeesTheWholeBox) {
  const auto path = MakeCameraPath({}, {0}, {-1, -2, -3}, {1, 2, 3});
  const Vec3d c{0, 0, 0};
  EXPECT_NEAR(path[0].target.x, c.x, 1e-12);
  const double radius = Length(Vec3d{1, 2, 3});
  const double half_fov = path[0].fov_deg * M_PI / 360;
  EXPECT_GE(Length(path[0].eye - c) * std::sin(half_fov), radius);
}

TEST(CameraPath, KeyFramesInterpolateAndBadLinesNameTheLine) {
  const auto dir = testing::TempDir("camera");
  const auto good = (dir / "raycell_keys_good.txt").string();
  std::ofstream(good) << "# frame eye target fov\n0 0 0 10 0 0 0 40\n10 10 0 10 0 0 0 60\n";
  CameraPathSpec spec;
  spec.keyframes_file = good;
  const auto path = MakeCameraPath(spec, {-5, 0, 5, 10, 20}, {}, {1, 1, 1});
  EXPECT_DOUBLE_EQ(path[0].eye.x, 0);  // before the first key: held
  EXPECT_DOUBLE_EQ(path[2].eye.x, 5);
  EXPECT_DOUBLE_EQ(path[2].fov_deg, 50);
  EXPECT_DOUBLE_EQ(path[4].eye.x, 10);  // after the last: held

  const auto bad = (dir / "raycell_keys_bad.txt").string();
  std::ofstream(bad) << "0 0 0 10 0 0 0 40\n5 0 0 nan 0 0 0 40\n";
  try {
    spec.keyframes_file = bad;
    MakeCameraPath(spec, {0}, {}, {1, 1, 1});
    FAIL() << "a NaN key frame was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(bad + ":2:"), std::string::npos) << e.what();
  }
}

TEST(PinholeCamera, CentreRayLooksAtTheTargetAndCornersSpanTheFieldOfView) {
  const CameraKey key{0, {0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 90};
  const PinholeCamera cam = PinholeCamera::Create(key, 100, 100);
  const Vec3d centre = cam.Direction(50, 50);
  EXPECT_NEAR(centre.z, -1, 1e-12);
  const Vec3d top = cam.Direction(50, 0);  // 45 degrees up
  EXPECT_NEAR(top.y, std::sqrt(0.5), 1e-12);
  EXPECT_THROW(PinholeCamera::Create({0, {1, 1, 1}, {1, 1, 1}, {0, 1, 0}, 40}, 8, 8), InputError);
  EXPECT_THROW(PinholeCamera::Create({0, {0, 0, 5}, {0, 0, 0}, {0, 0, 1}, 40}, 8, 8), InputError);
}

}  // namespace
}  // namespace raycell
