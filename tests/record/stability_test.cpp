// Numerical stability of the renderer: no NaN or infinity reaches an image or a trace for
// zero, negative and extreme densities, a camera inside the volume and rays tangent to a
// level set (the renderer CHECKs every pixel is finite, so a NaN aborts the test); grids
// holding NaN are refused with a message.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <cmath>
#include <limits>
#include <sstream>

#include "tests/record/record_test_util.h"
#include "traces/check.h"
#include "traces/record/image.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

using testing::SmallBuiltin;
using testing::TempDir;

// A fog ball of radius 1 whose active voxels all hold `value`.
std::string FogBall(const std::filesystem::path& dir, const std::string& name, float value) {
  openvdb::initialize();
  auto g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, {0, 0, 0}, 0.1f);
  openvdb::tools::sdfToFogVolume(*g);
  for (auto it = g->beginValueOn(); it; ++it) it.setValue(value);
  g->setName("density");
  const std::string path = (dir / (name + ".vdb")).string();
  openvdb::io::File(path).write({g});
  return path;
}

struct Capture {
  Image image{1, 1};
  FrameSummary frame;
};

Capture RecordOne(const std::filesystem::path& dir, const std::string& scene,
                  double cutoff = 0.005) {
  RecordOptions o = SmallBuiltin(dir, 32);
  o.scene.source = scene;
  o.settings.cutoff = cutoff;
  o.images_dir = (dir / "img").string();
  std::ostringstream log;
  Record(o, log);
  const TraceReader r = TraceReader::Open(o.out);
  r.LoadFrame(0);  // every ray and visit reads back and validates
  return {ReadPng((dir / "img" / "frame_0000.png").string()), r.frames().at(0)};
}

double MaxChannel(const Image& img) {
  double m = 0;
  for (const Rgb& p : img.pixels()) m = std::max({m, p.r, p.g, p.b});
  return m;
}

TEST(Stability, ZeroAndNegativeDensitiesRenderBlackAndStillRecordVisits) {
  const auto dir = TempDir("zero");
  for (float v : {0.0f, -5.0f}) {
    for (double cutoff : {0.005, 0.0}) {  // a zero cutoff lets zero density through
      const Capture c = RecordOne(dir, FogBall(dir, "ball", v), cutoff);
      EXPECT_EQ(MaxChannel(c.image), 0.0) << "density " << v << " cutoff " << cutoff;
      EXPECT_GT(c.frame.visits, 0u);
      EXPECT_EQ(c.frame.rays_by_kind[int(RayKind::kShadow)], 0u);
    }
  }
}

TEST(Stability, ExtremeDensitiesStayFinite) {
  const auto dir = TempDir("extreme");
  // An opaque ball: each primary ray ends at its first sample in it, after one shadow ray
  // (which ends at its own first sample), so there are at most as many shadow rays as
  // primary rays, and the in-scattered light is that of a zero-thickness layer: black.
  const Capture dense = RecordOne(dir, FogBall(dir, "dense", std::numeric_limits<float>::max()));
  const auto& kinds = dense.frame.rays_by_kind;
  EXPECT_GT(kinds[int(RayKind::kShadow)], 0u);
  EXPECT_LE(kinds[int(RayKind::kShadow)], kinds[int(RayKind::kPrimary)]);
  EXPECT_EQ(MaxChannel(dense.image), 0.0);
  const Capture thin = RecordOne(dir, FogBall(dir, "thin", std::numeric_limits<float>::min()));
  EXPECT_LE(MaxChannel(thin.image), 1.0);
}

TEST(Stability, GridsHoldingNanAreRefused) {
  const auto dir = TempDir("nan");
  const std::string path = FogBall(dir, "nan", std::numeric_limits<float>::quiet_NaN());
  try {
    RecordOne(dir, path);
    FAIL() << "a grid of NaN was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite value"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("density"), std::string::npos) << e.what();
  }
}

TEST(Stability, CameraInsideTheVolumeAndRaysTangentToTheMirror) {
  const auto dir = TempDir("inside");
  RecordOptions o = SmallBuiltin(dir, 32);
  std::ostringstream log;
  o.camera.eye = {0, 0, 0};  // inside the cloud
  o.camera.target = {1, 0, 0};
  EXPECT_EQ(Record(o, log).frames, 1u);
  // The mirror sphere: centre (1.35, -0.35, 0.45), radius 0.5. Rays through the image centre
  // graze its top.
  o.camera.eye = {1.35, 0.15, 6};
  o.camera.target = {1.35, 0.15, 0.45};
  o.settings.width = o.settings.height = 64;
  EXPECT_EQ(Record(o, log).frames, 1u);
  const TraceReader r = TraceReader::Open(o.out);
  EXPECT_GT(r.frames().at(0).rays_by_kind[int(RayKind::kReflection)], 0u);
}

}  // namespace
}  // namespace raycell
