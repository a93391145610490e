// The recorder's options at and beyond their limits: every size-like option is checked before
// the scene is read (a missing scene file would otherwise be the error), with a message
// naming the option and its limit; camera options name themselves and their range; PNGs
// are written and read back in both encodings.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "base/check.h"
#include "base/parse.h"
#include "record/image.h"
#include "record/recorder.h"
#include "tests/record/record_test_util.h"

namespace raycell {
namespace {

using testing::SmallBuiltin;
using testing::TempDir;

// Record's error message for `o`, or "accepted" when it ran.
std::string Message(const RecordOptions& o) {
  std::ostringstream log;
  try {
    Record(o, log);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

class RecordLimits : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TempDir("limits");
    base_ = SmallBuiltin(dir_, 8);
    // Read right after the options are checked: an error naming this file means that the
    // options passed and the scene was about to be read.
    base_.scene.source = (dir_ / "missing.vdb").string();
  }
  // Expects the options changed by `change` to be refused up front with a message holding
  // every one of `parts`, and no file written.
  template <typename Change>
  void ExpectRefused(Change change, std::initializer_list<std::string> parts) {
    RecordOptions o = base_;
    change(o);
    const std::string m = Message(o);
    EXPECT_EQ(m.find("missing.vdb"), std::string::npos) << "not checked up front: " << m;
    for (const std::string& p : parts) EXPECT_NE(m.find(p), std::string::npos) << m;
    EXPECT_FALSE(std::filesystem::exists(o.out));
    EXPECT_FALSE(std::filesystem::exists(o.out + ".tmp"));
  }
  // Expects the options to pass the checks (the error is then the missing scene file).
  template <typename Change>
  void ExpectAccepted(Change change) {
    RecordOptions o = base_;
    change(o);
    const std::string m = Message(o);
    EXPECT_NE(m.find("missing.vdb"), std::string::npos) << m;
  }
  std::filesystem::path dir_;
  RecordOptions base_;
};

TEST_F(RecordLimits, CellsBeyondTheTraceFormatsLimitAreRefusedBeforeTheSceneIsRead) {
  ExpectRefused(
      [](RecordOptions& o) {
        o.cells = {1000, 1000, 1000};
      },
      {"--cells 1000x1000x1000", "1000000000 cells",
       "limit of " + std::to_string(kMaxCaptureCells)});
  ExpectRefused(
      [](RecordOptions& o) {
        o.cells = {4096, 4096, 2};
      },
      {"--cells 4096x4096x2", std::to_string(kMaxCaptureCells)});
  ExpectAccepted([](RecordOptions& o) { o.cells = {4096, 4096, 1}; });  // exactly the limit
  ExpectAccepted([](RecordOptions& o) { o.cells = {256, 256, 256}; });
  ExpectRefused([](RecordOptions& o) { o.cells = {0, 2, 2}; }, {"--cells"});
}

TEST_F(RecordLimits, PixelsAndPrimaryRaysBeyondTheirLimitsAreRefused) {
  ExpectRefused(
      [](RecordOptions& o) { o.settings.width = o.settings.height = 65536; },
      {"--res 65536x65536", "4294967296 pixels", "limit of " + std::to_string(kMaxPixels)});
  ExpectAccepted([](RecordOptions& o) { o.settings.width = o.settings.height = 8192; });
  ExpectRefused(
      [](RecordOptions& o) {
        o.settings.width = o.settings.height = 8192;
        o.settings.spp = 2;
      },
      {"--res x --spp", "= 134217728 primary rays", std::to_string(kMaxPrimaryRays)});
  ExpectAccepted([](RecordOptions& o) {
    o.settings.width = o.settings.height = 2048;
    o.settings.spp = 16;  // 2^26: exactly the limit
  });
  ExpectRefused([](RecordOptions& o) { o.settings.spp = 4097; }, {"--spp", "1..4096"});
  ExpectRefused([](RecordOptions& o) { o.settings.max_depth = 17; }, {"--max-depth", "16"});
}

TEST_F(RecordLimits, FramesThreadsAndModesBeyondTheirLimitsAreRefused) {
  ExpectRefused([](RecordOptions& o) { o.frames = ParseFrameRange("0..100000"); },
                {"--frames", "100001 frames", "limit of " + std::to_string(kMaxCaptureFrames)});
  ExpectAccepted([](RecordOptions& o) { o.frames = ParseFrameRange("0..99999"); });
  ExpectRefused([](RecordOptions& o) { o.frames.clear(); }, {"--frames"});
  ExpectRefused([](RecordOptions& o) { o.threads = -1; }, {"--threads -1", "0..1024"});
  ExpectRefused([](RecordOptions& o) { o.threads = 1025; }, {"--threads 1025", "0..1024"});
  ExpectRefused([](RecordOptions& o) { o.scene.footprint_mode = "huge"; }, {"--footprint 'huge'"});
  ExpectRefused(
      [](RecordOptions& o) {
        o.scene.all_grids = true;
        o.scene.grids = {"density"};
      },
      {"--grid and --all-grids"});
}

TEST_F(RecordLimits, CameraOptionsNameThemselvesAndTheirRange) {
  for (double fov : {0.0, -5.0, 180.0, double(NAN), double(INFINITY)}) {
    ExpectRefused([&](RecordOptions& o) { o.camera.fov_deg = fov; },
                  {"--fov", "must be in (0, 180) degrees"});
  }
  ExpectRefused([](RecordOptions& o) { o.camera.up = {0, 0, 0}; }, {"--up 0,0,0", "not be zero"});
  ExpectRefused([](RecordOptions& o) { o.camera.up = {0, NAN, 0}; }, {"--up", "finite"});
  ExpectRefused([](RecordOptions& o) { o.camera.eye = {INFINITY, 0, 0}; }, {"--eye", "finite"});
  ExpectRefused(
      [](RecordOptions& o) {
        o.camera.eye = {1, 2, 3};
        o.camera.target = {1, 2, 3};
      },
      {"--eye and --target are the same point 1,2,3"});
  ExpectRefused([](RecordOptions& o) { o.camera.orbit_degrees = NAN; }, {"--orbit", "finite"});
}

// Camera problems that show only once the scene box is known, on the built-in scene.
TEST(RecordCamera, FramingAndUpProblemsNameTheOptionsAndTheFrame) {
  const auto dir = TempDir("camera");
  RecordOptions o = SmallBuiltin(dir, 8);
  o.camera.fov_deg = 1e-300;  // the default framing would put the eye at infinity
  std::string m = Message(o);
  EXPECT_NE(m.find("--fov 1e-300: too small to frame the scene box"), std::string::npos) << m;
  EXPECT_NE(m.find("give --eye"), std::string::npos) << m;
  o = SmallBuiltin(dir, 8);
  o.camera.eye = {0, 5, 0};
  o.camera.target = {0, 0, 0};
  m = Message(o);
  EXPECT_NE(m.find("--eye/--target/--up/--fov/--orbit, frame 0"), std::string::npos) << m;
  EXPECT_NE(m.find("up 0,1,0 is parallel to the view direction"), std::string::npos) << m;
  EXPECT_FALSE(std::filesystem::exists(o.out + ".tmp"));
}

// Material and light texts name the option, the key and the valid range.
TEST(RecordMaterials, BadMaterialsAndLightsNameTheOptionKeyAndRange) {
  const auto message = [](const SceneSpec& spec) {
    return testing::ErrorOf([&] { Scene::Load(spec, 0); });  // "" when accepted
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"cloud:absorb=-1", "--material 'cloud:absorb=-1' key 'absorb': must not be negative"},
      {"cloud:scatter=x", "--material 'cloud:scatter=x' key 'scatter': 'x' is not a finite"},
      {"cloud:gain=-2", "key 'gain': must not be negative"},
      {"cloud:shine=1", "unknown fog material key (known: absorb, scatter, gain)"},
      {"mirror:reflect=2", "key 'reflect': must be in [0, 1]"},
      {"mirror:ior=0.5", "key 'ior': must be in [1, 10]"},
      {"mirror:reflect=0.6:transparency=0.6", "reflect + transparency must not exceed 1"},
      {"nosuch:absorb=1", "builtin has no float grid 'nosuch' (float grids: cloud, mirror, glass)"},
      {"cloud", "expected GRID:key=value"},
  };
  for (const auto& [text, expected] : cases) {
    SceneSpec s;
    s.materials = {text};
    EXPECT_NE(message(s).find(expected), std::string::npos) << text << ": " << message(s);
  }
  // Scene::WithMaterials (the fuzz target's way, one file read for many inputs) applies a
  // material exactly as Load does: the same messages, and a good material accepted by both.
  const std::unique_ptr<Scene> builtin = Scene::Load(SceneSpec{}, 0);
  for (const auto& c : cases) {
    SceneSpec s;
    s.materials = {c.first};
    EXPECT_EQ(testing::ErrorOf([&] { builtin->WithMaterials({c.first}, "builtin"); }), message(s))
        << c.first;
  }
  SceneSpec good;
  good.materials = {"cloud:absorb=0.5:scatter=2", "mirror:reflect=0.5"};
  EXPECT_EQ(message(good), "");
  EXPECT_EQ(testing::ErrorOf([&] {
              EXPECT_EQ(builtin->WithMaterials(good.materials, "builtin")->grids().size(),
                        builtin->grids().size());
            }),
            "");
  SceneSpec s;
  s.grids = {"mirror"};
  s.materials = {"cloud:absorb=1"};
  EXPECT_NE(message(s).find("grid 'cloud' is not rendered (choose it with --grid cloud"),
            std::string::npos)
      << message(s);
  for (const auto& [text, expected] : std::vector<std::pair<std::string, std::string>>{
           {"dir:0,0,0", "--light 'dir:0,0,0': direction must not be zero"},
           {"spot:1,1,1", "expected dir:X,Y,Z[:R,G,B] or point:X,Y,Z[:R,G,B]"},
           {"dir:0,1,0:2e30", "must be at most 1e+30"},
           {"point:0,nan,0", "is not a finite number"}}) {
    try {
      ParseLight(text);
      ADD_FAILURE() << text << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

// ---------------------------------------------------------------------------- PNG images

Image Ramp() {
  Image img(256, 3);
  for (std::uint32_t x = 0; x < 256; ++x) {
    const double v = x / 255.0;
    img.at(x, 0) = {v, v * v, 1 - v};
    img.at(x, 1) = {v * 0.01, v * 0.5 + 0.25, v};
    img.at(x, 2) = {-1, 2, double(NAN)};  // clamped to 0 and 1; NaN to 0
  }
  return img;
}

std::string Chunks(const std::string& path) { return testing::ReadBytes(path).substr(0, 120); }

TEST(Png, BothEncodingsRoundTripWithinHalfAStepOfTheirCurve) {
  const auto dir = TempDir("png");
  const Image img = Ramp();
  for (const PngEncoding e : {PngEncoding::kSrgb, PngEncoding::kLinear}) {
    SCOPED_TRACE(ToString(e));
    const std::string path = (dir / (std::string(ToString(e)) + ".png")).string();
    WritePng(img, path, e);
    const Image back = ReadPng(path, e);
    ASSERT_EQ(back.width(), 256u);
    ASSERT_EQ(back.height(), 3u);
    for (std::uint32_t y = 0; y < 2; ++y) {
      for (std::uint32_t x = 0; x < 256; ++x) {
        const Rgb &p = img.at(x, y), &q = back.at(x, y);
        for (auto [a, b] : {std::pair{p.r, q.r}, {p.g, q.g}, {p.b, q.b}}) {
          // Half a step of 1/255 in the encoded value, times the decoding curve's largest
          // slope: 1 for linear, 2.4 / 1.055 < 2.3 for sRGB (at 1).
          const double tol = e == PngEncoding::kLinear ? 0.5 / 255 + 1e-12 : 0.5 / 255 * 2.3;
          EXPECT_NEAR(a, b, tol) << "pixel " << x << "," << y;
        }
      }
    }
    EXPECT_EQ(back.at(0, 2).r, 0.0);
    EXPECT_EQ(back.at(0, 2).g, 1.0);
    EXPECT_EQ(back.at(0, 2).b, 0.0);
  }
  // Each file says how it is encoded, and the encodings differ: a mid grey written linear
  // and read as sRGB comes back much darker.
  EXPECT_NE(Chunks((dir / "srgb.png").string()).find("sRGB"), std::string::npos);
  EXPECT_NE(Chunks((dir / "linear.png").string()).find("gAMA"), std::string::npos);
  EXPECT_EQ(Chunks((dir / "linear.png").string()).find("sRGB"), std::string::npos);
  const Image misread = ReadPng((dir / "linear.png").string(), PngEncoding::kSrgb);
  EXPECT_LT(misread.at(128, 0).r, 0.25);
  EXPECT_THROW(ParsePngEncoding("gamma22", "--image-encoding"), InputError);
  EXPECT_THROW(ReadPng((dir / "none.png").string(), PngEncoding::kSrgb), InputError);
}

}  // namespace
}  // namespace raycell
