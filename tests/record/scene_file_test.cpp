// Scene files (record/scene_file.h, docs/scenes.md): every file of scenes/ parses; bad files
// are InputErrors naming FILE:LINE and the key, and leave nothing behind through the command;
// --print-scene's output records the same trace byte for byte; the built-in scene is
// scenes/builtin.toml; noise matches a floating-point reference; transforms and animation
// move the grids as they say.
#include "record/scene_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "base/check.h"
#include "record/record_flags.h"
#include "record/scene.h"
#include "tests/test_util.h"
#include "tests/tools/cli_util.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;
using testing::ErrorOf;
using testing::Raycell;

fs::path Dir() {
  static const fs::path dir = testing::TempDir("scene_file");
  return dir;
}

fs::path Write(const std::string& name, const std::string& text) {
  const fs::path p = Dir() / name;
  std::ofstream(p) << text;
  return p;
}

// The message of loading `text` as a scene file ("" when accepted).
std::string ParseError(const std::string& text) {
  return ErrorOf([&] { ParseSceneDescription(text, "s.toml", "."); });
}

void ExpectHas(const std::string& message, const std::string& part) {
  EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

// A sphere grid with `extra` lines among its keys (line 5 on), before its shape.
std::string Sphere(const std::string& extra = "") {
  return "\n[[grid]]\nname = \"ball\"\nvoxel = 0.1\n" + extra +
         "[[grid.shape]]\ntype = \"sphere\"\nradius = 1\n";
}
const std::string kSphere = Sphere();

// Every scene of the suite parses and passes the checks (no grid is built): a broken suite
// file fails here.
TEST(SceneFile, EverySuiteFileParsesAndValidates) {
  int files = 0;
  for (const auto& e : fs::directory_iterator(fs::path(RAYCELL_SOURCE_DIR) / "scenes")) {
    if (e.path().extension() != ".toml") continue;
    ++files;
    SCOPED_TRACE(e.path().string());
    const SceneDescription d = LoadSceneDescription(e.path().string());
    EXPECT_FALSE(d.grids.empty());
    // Its first lines say which character of a workload it stands for.
    std::ifstream in(e.path());
    std::string first;
    std::getline(in, first);
    EXPECT_EQ(first.rfind("# ", 0), 0u) << "no comment at the top";
    // Its printed form reads back to the same print.
    const std::string printed = PrintSceneDescription(d);
    EXPECT_EQ(PrintSceneDescription(ParseSceneDescription(printed, "printed", ".")), printed);
  }
  EXPECT_GE(files, 10);
}

// The embedded built-in scene is the file's text.
TEST(SceneFile, BuiltinIsTheFile) {
  EXPECT_EQ(std::string(BuiltinSceneText()),
            testing::ReadBytes((fs::path(RAYCELL_SOURCE_DIR) / "scenes/builtin.toml").string()));
  const SceneDescription d = LoadSceneDescription("builtin");
  EXPECT_EQ(d.name, "builtin");
  ASSERT_EQ(d.grids.size(), 3u);
  EXPECT_TRUE(d.grids[0].fog);
  EXPECT_EQ(d.grids[0].shapes.size(), 3u);
  EXPECT_EQ(d.grids[2].shapes[0].type, "icosahedron");
}

TEST(SceneFile, UnknownKeysAndBadValuesNameTheLineAndKey) {
  ExpectHas(ParseError(Sphere("colour = 1\n")), "s.toml:5:1: unknown key 'colour' in grid 'ball'");
  ExpectHas(ParseError("nmae = \"x\"\n" + std::string(kSphere)), "s.toml:1:1: unknown key 'nmae'");
  std::string bad = kSphere;
  bad.replace(bad.find("radius = 1"), 10, "radius = -1");
  ExpectHas(ParseError(bad), "s.toml:7:10: grid 'ball' shape 1 radius: must be in (0, 1e+06]");
  bad = kSphere;
  bad.replace(bad.find("radius = 1"), 10, "radius = nan");
  ExpectHas(ParseError(bad), "s.toml:7:10: grid 'ball' shape 1 radius: must be a finite number");
  bad = kSphere;
  bad.replace(bad.find("voxel = 0.1"), 11, "voxel = 0");
  ExpectHas(ParseError(bad), "s.toml:4:9: grid 'ball' voxel: must be in (0, 1000]");
  bad = kSphere;
  bad.replace(bad.find("voxel = 0.1"), 11, "voxel = 0.0001");
  ExpectHas(ParseError(bad), "grid 'ball': about ");
  ExpectHas(ParseError(bad), "exceeds the limit of");
  bad = kSphere;
  bad.replace(bad.find("sphere"), 6, "blob");
  ExpectHas(ParseError(bad), "s.toml:6:8: grid 'ball' shape 1 type: unknown shape 'blob'");
  ExpectHas(ParseError("name = \"empty\"\n"), "s.toml: the scene has no grid");
  ExpectHas(ParseError(Sphere("material = { reflect = 2 }\n")),
            "s.toml:5:24: grid 'ball' material.reflect: must be in [0, 1]");
  ExpectHas(ParseError(Sphere("material = { absorb = 1 }\n")),
            "unknown key 'absorb' in grid 'ball' material");
  ExpectHas(ParseError(Sphere("noise = { seed = 1 }\n")), "noise modulates a fog");
  ExpectHas(ParseError("[camera]\nfov = 200\n" + kSphere),
            "s.toml:2:7: camera.fov: must be in (0, 180]");
  ExpectHas(ParseError("[[light]]\ntype = \"dir\"\ndirection = [0, 0, 0]\n" + kSphere),
            "light 1: direction must not be zero");
  ExpectHas(ParseError("x = [1,\n"),
            "s.toml:1:9: Error while parsing array");  // toml++'s own parse errors
  ExpectHas(ErrorOf([] { LoadSceneDescription((Dir() / "missing.toml").string()); }),
            "missing.toml: cannot read the scene file");
}

// Each error through the command: exit 2, a message naming it, and neither the trace nor the
// images folder left behind.
TEST(SceneFile, CommandRefusesBadScenesBeforeAnyOutput) {
  std::string negative = kSphere;
  negative.replace(negative.find("radius = 1"), 10, "radius = -1");
  std::string nan = kSphere;
  nan.replace(nan.find("radius = 1"), 10, "radius = nan");
  std::string zero = kSphere;
  zero.replace(zero.find("voxel = 0.1"), 11, "voxel = 0");
  std::string huge = kSphere;
  huge.replace(huge.find("voxel = 0.1"), 11, "voxel = 0.0001");
  // Grown to a negative radius at frame 2: found when frame 2's grid is built.
  const std::string shrinks = Sphere("animate = { grow = -0.75 }\n");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {Write("unknown.toml", Sphere("colour = 1\n")).string(),
       "unknown.toml:5:1: unknown key 'colour' in grid 'ball'"},
      {(Dir() / "absent.toml").string(), "absent.toml: cannot read the scene file"},
      {Write("negative.toml", negative).string(), "radius: must be in (0, 1e+06], got -1"},
      {Write("nan.toml", nan).string(), "radius: must be a finite number, got nan"},
      {Write("zero.toml", zero).string(), "zero.toml:4:9: grid 'ball' voxel: must be in (0, 1000]"},
      {Write("huge.toml", huge).string(), "exceeds the limit of"},
      {Write("empty.toml", "name = \"nothing\"\n").string(), "the scene has no grid"},
      {Write("shrinks.toml", shrinks).string(), "at frame 2 shape sphere"},
  };
  for (const auto& [file, expected] : cases) {
    const fs::path out = Dir() / "out.rct", images = Dir() / "images";
    const auto r = Raycell("record --scene " + file + " --res 16x16 --frames 0..2 --quiet --out " +
                           out.string() + " --images " + images.string());
    EXPECT_EQ(r.code, 2) << r.out;
    ExpectHas(r.out, expected);
    EXPECT_FALSE(fs::exists(out)) << file;
    EXPECT_FALSE(fs::exists(out.string() + ".tmp")) << file;
    EXPECT_FALSE(fs::exists(images)) << file;
  }
}

// --print-scene writes the resolved scene; recording it gives the trace of the original
// byte for byte (flags applied: orbit, material, light, fov), for the built-in scene and for
// an animated scene with noise, a CSG and a transform.
TEST(SceneFile, PrintedSceneRecordsTheSameTrace) {
  const std::string animated = Write("anim.toml", R"(# an animated test scene
[[grid]]
name = "puff"
role = "fog"
voxel = 0.1
noise = { seed = 3, period = 4, octaves = 2, amount = 0.7, threshold = 0.2 }
animate = { translate = [0.1, 0, 0], grow = 0.05 }
material = { absorb = 0.1, scatter = 0.5 }
[[grid.shape]]
type = "sphere"
radius = 0.6
[[grid]]
name = "holed"
voxel = 0.1
scale = 0.8
translate = [1.5, 0.0123456789012, 0]  # more digits than %g keeps
rotate = { axis = [1, 1, 0], degrees = 30 }
[[grid.shape]]
type = "cube"
scale = 0.8
[[grid.shape]]
op = "difference"
type = "box"
min = [-0.2, -0.2, -1]
max = [0.2, 0.2, 1]
)")
                                   .string();
  for (const std::string& scene : {std::string("builtin"), animated}) {
    SCOPED_TRACE(scene);
    const std::string flags = "--scene " + scene +
                              " --orbit 2:30 --fov 35 --light dir:1,1,0:0.5,0.5,0.5 --material " +
                              (scene == "builtin" ? "cloud:absorb=0.01" : "puff:gain=0.5");
    const std::string common = " --res 16x16 --cells 3x3x3 --no-images --quiet --out ";
    const fs::path printed = Dir() / "printed.toml";
    const auto p = Raycell("record " + flags + " --print-scene > " + printed.string(), false);
    ASSERT_EQ(p.code, 0);
    const fs::path a = Dir() / "a.rct", b = Dir() / "b.rct";
    ASSERT_EQ(Raycell("record " + flags + common + a.string()).code, 0);
    ASSERT_EQ(Raycell("record --scene " + printed.string() + common + b.string()).code, 0);
    EXPECT_EQ(testing::ReadBytes(a.string()), testing::ReadBytes(b.string()));
    EXPECT_GT(testing::ReadBytes(a.string()).size(), 1000u);
    // An animated scene is recorded as a sequence is: its volume changes every frame.
    const TraceHeader h = TraceReader::Open(a.string()).header();
    EXPECT_EQ(h.volume_changes(), scene != "builtin") << h.scene;
    EXPECT_EQ(h.scene, scene == "builtin" ? "builtin" : animated + "@%d");
  }
}

// A grid read from a VDB file (path relative to the scene file) renders the rays the file
// renders as --scene: the same `trace cat` output; role = "surface" on a fog grid is refused.
TEST(SceneFile, FileGridRendersAsTheFileDoes) {
  const fs::path vdb = fs::path(RAYCELL_SHARED_DATA) / "mj_smoke.vdb";
  if (!fs::exists(vdb)) GTEST_SKIP() << vdb << " absent";
  const std::string rel = fs::relative(fs::absolute(vdb), Dir()).string();
  const fs::path scene =
      Write("smoke.toml", "[[grid]]\nname = \"smoke\"\nrole = \"fog\"\nfile = \"" + rel + "\"\n");
  const std::string common = " --res 16x16 --orbit 2:30 --cells 3x3x3 --no-images --quiet --out ";
  const fs::path a = Dir() / "vdb.rct", b = Dir() / "toml.rct";
  ASSERT_EQ(Raycell("record --scene " + vdb.string() + common + a.string()).code, 0);
  ASSERT_EQ(Raycell("record --scene " + scene.string() + common + b.string()).code, 0);
  const auto ca = Raycell("trace cat " + a.string()), cb = Raycell("trace cat " + b.string());
  EXPECT_GT(ca.out.size(), 1000u);
  EXPECT_EQ(ca.out, cb.out);
  const fs::path bad =
      Write("surface.toml", "[[grid]]\nname = \"s\"\nrole = \"surface\"\nfile = \"" + rel + "\"\n");
  const auto r = Raycell("record --scene " + bad.string() + common + (Dir() / "bad.rct").string());
  EXPECT_EQ(r.code, 2);
  ExpectHas(r.out, "role = \"surface\" needs a level set");
}

// Inline key frames make the camera path a --keyframes file with the same keys makes.
TEST(SceneFile, InlineKeyFramesAreTheKeyframesFilesPath) {
  const SceneDescription d = ParseSceneDescription(
      "[camera]\nup = [0, 0, 1]\nfov = 30\n"
      "[[camera.key]]\nframe = 0\neye = [0, -5, 1]\ntarget = [0, 0, 0]\n"
      "[[camera.key]]\nframe = 10\neye = [5, 0, 1]\ntarget = [0, 0, 0.5]\nfov = 45\n" +
          kSphere,
      "k.toml", ".");
  CameraPathSpec file;
  file.up = {0, 0, 1};
  file.keyframes_file = Write("keys.txt", "0 0 -5 1 0 0 0 30\n10 5 0 1 0 0 0.5 45\n").string();
  const std::vector<int> frames = {0, 5, 10};
  const CameraPathInfo a = MakeCameraPathInfo(d.camera, frames, {-1, -1, -1}, {1, 1, 1});
  const CameraPathInfo b = MakeCameraPathInfo(file, frames, {-1, -1, -1}, {1, 1, 1});
  EXPECT_EQ(a.kind, "keyframes");
  EXPECT_TRUE(a == b);
  EXPECT_TRUE(CameraOf(a, 5) == CameraOf(b, 5));
  EXPECT_EQ(CameraOf(a, 5).fov_deg, 37.5);  // halfway between 30 and 45
}

// The flags override the file, and the printed scene shows it.
TEST(SceneFile, FlagsOverrideTheFile) {
  RecordFlags f;
  f.opt.scene.source = "builtin";
  f.opt.scene.materials = {"mirror:reflect=0.25"};
  f.lights = {"point:0,3,0"};
  f.eye = "0,0,5";
  f.orbit = "4:90";
  f.opt.scene.grids = {"mirror", "cloud"};
  const RecordOptions o = ToRecordOptions(f);
  ASSERT_TRUE(o.scene.description);
  const SceneDescription& d = *o.scene.description;
  ASSERT_EQ(d.grids.size(), 2u);  // in the file's order
  EXPECT_EQ(d.grids[0].name, "cloud");
  EXPECT_EQ(d.grids[1].surface_material.reflectivity, 0.25);
  EXPECT_EQ(d.grids[1].surface_material.ior, 1.5);  // the file's other keys kept
  ASSERT_EQ(d.lights.size(), 1u);
  EXPECT_EQ(d.lights[0].type, Light::Type::kPoint);
  EXPECT_EQ(o.camera.eye.z, 5);
  EXPECT_EQ(o.camera.orbit_frames, 4);
  EXPECT_EQ(o.frames, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(d.frames, "0..3");
  ExpectHas(ErrorOf([&] {
              RecordFlags g;
              g.opt.scene.materials = {"nosuch:absorb=1"};
              ToRecordOptions(g);
            }),
            "--material 'nosuch:absorb=1': builtin has no grid 'nosuch'");
}

// Noise is value noise: at lattice points the hash itself, between them the trilinear blend,
// as a floating-point reference computes it from the lattice values.
TEST(SceneFile, NoiseIsTrilinearValueNoiseInRange) {
  NoiseDesc n;
  n.on = true;
  n.seed = 42;
  n.period = 8;
  n.octaves = 1;
  const double den = double(NoiseDenominator(n));
  EXPECT_EQ(NoiseDenominator(n), 65535ull * 512);
  auto at = [&](int x, int y, int z) { return double(NoiseNumerator(n, x, y, z)) / den; };
  // Reference: blend the eight lattice values of the cell by hand.
  for (const auto& p : {std::array<int, 3>{3, 5, 1}, {-3, 12, -9}, {100, -77, 5}}) {
    const int c[3] = {int(std::floor(p[0] / 8.0)), int(std::floor(p[1] / 8.0)),
                      int(std::floor(p[2] / 8.0))};
    double ref = 0;
    for (int k = 0; k < 8; ++k) {
      double w = 1;
      int q[3];
      for (int a = 0; a < 3; ++a) {
        const double f = (p[a] - c[a] * 8) / 8.0;
        w *= (k >> a) & 1 ? f : 1 - f;
        q[a] = (c[a] + ((k >> a) & 1)) * 8;
      }
      ref += w * at(q[0], q[1], q[2]);
    }
    EXPECT_NEAR(at(p[0], p[1], p[2]), ref, 1e-12);
  }
  // In [0, 1], not constant, and 0 exactly where below the threshold.
  n.octaves = 3;
  n.amount = 0.5;
  n.threshold = 0.5;
  double lo = 1, hi = 0;
  for (int x = -20; x < 20; ++x) {
    for (int y = -3; y < 3; ++y) {
      const double v = double(NoiseNumerator(n, x, y, 7)) / double(NoiseDenominator(n));
      lo = std::min(lo, v), hi = std::max(hi, v);
      const double f = NoiseFactor(n, x, y, 7);
      if (v < 0.5) {
        EXPECT_EQ(f, 0);
      } else {
        EXPECT_NEAR(f, 0.5 + 0.5 * v, 1e-12);
      }
    }
  }
  EXPECT_GE(lo, 0);
  EXPECT_LE(hi, 1);
  EXPECT_LT(lo, hi - 0.1);
}

SceneSpec SpecOf(const std::string& text) {
  SceneSpec s;
  s.source = "t.toml";
  s.description =
      std::make_shared<const SceneDescription>(ParseSceneDescription(text, "t.toml", "."));
  return s;
}

// translate moves the box; a 45 degree turn about y widens a cube's box by sqrt 2; animate
// moves it by its rate times the frame.
TEST(SceneFile, TransformsAndAnimationMoveTheGrid) {
  const auto cube = [](const std::string& extra) {
    return "[[grid]]\nname = \"c\"\nvoxel = 0.05\n" + extra +
           "[[grid.shape]]\ntype = \"box\"\nmin = [-1, -1, -1]\nmax = [1, 1, 1]\n";
  };
  const auto plain = Scene::Load(SpecOf(cube("")), 0);
  const auto moved = Scene::Load(SpecOf(cube("translate = [5, 0, 0]\n")), 0);
  EXPECT_NEAR(moved->box_lo().x - plain->box_lo().x, 5, 1e-6);
  EXPECT_NEAR(moved->box_hi().y, plain->box_hi().y, 1e-6);
  const auto turned = Scene::Load(SpecOf(cube("rotate = { axis = [0, 1, 0], degrees = 45 }\n")), 0);
  const double w0 = plain->box_hi().x - plain->box_lo().x;
  const double w1 = turned->box_hi().x - turned->box_lo().x;
  EXPECT_NEAR(w1 / w0, std::sqrt(2.0), 0.05);
  EXPECT_NEAR(turned->box_hi().y - turned->box_lo().y, plain->box_hi().y - plain->box_lo().y, 1e-6);
  const SceneSpec anim = SpecOf(cube("animate = { translate = [0, 0.5, 0] }\n"));
  EXPECT_TRUE(VolumeChanges(anim));
  EXPECT_EQ(SceneLabel(anim), "t.toml@%d");
  EXPECT_NEAR(Scene::Load(anim, 3)->box_lo().y - Scene::Load(anim, 0)->box_lo().y, 1.5, 1e-6);
  EXPECT_FALSE(VolumeChanges(SpecOf(cube(""))));
  EXPECT_EQ(SceneLabel(SpecOf(cube(""))), "t.toml");
}

}  // namespace
}  // namespace raycell
