// raycell against OpenVDB's own renderer, vdb_render: the grid a file renders by default,
// and the linear image of the same volume, camera, steps, cutoff, light, absorption,
// scattering and gain. The comparisons skip with a message when vdb_render
// (libopenvdb-tools) or the shared data is absent.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>

#include "base/check.h"
#include "record/image.h"
#include "record/recorder.h"
#include "record/scene.h"
#include "tests/record/record_test_util.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

using namespace testing;

// A fog ball of radius 1 around `centre`, named `name`.
openvdb::FloatGrid::Ptr Ball(const std::string& name, openvdb::Vec3f centre) {
  auto g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, centre, 0.1f);
  openvdb::tools::sdfToFogVolume(*g);
  g->setName(name);
  return g;
}

// A fluid-cache-like file: four float grids (written in the order given) and a vec3 grid.
std::string FourGrids(const std::filesystem::path& dir) {
  openvdb::initialize();
  auto velocity = openvdb::Vec3SGrid::create();
  velocity->setName("velocity");
  velocity->tree().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
  const std::string path = (dir / "four.vdb").string();
  openvdb::io::File(path).write({Ball("temperature", {0, 0, 0}), Ball("density", {3, 0, 0}),
                                 Ball("flame", {0, 3, 0}), velocity, Ball("shadow", {0, 0, 3})});
  return path;
}

std::vector<std::string> Names(const Scene& s) {
  std::vector<std::string> out;
  for (const GridInfo& g : s.grids()) out.push_back(g.name);
  return out;
}

TEST(GridChoice, OneGridByDefaultAsVdbRenderChoosesElseTheNamedOnesOrAll) {
  const auto dir = TempDir("grids");
  SceneSpec spec;
  spec.source = FourGrids(dir);
  // vdb_render takes the first float grid OpenVDB lists, which lists grids by name.
  EXPECT_EQ(Names(*Scene::Load(spec, 0)), std::vector<std::string>{"density"});
  spec.grids = {"shadow"};
  EXPECT_EQ(Names(*Scene::Load(spec, 0)), std::vector<std::string>{"shadow"});
  spec.grids = {"shadow", "flame", "shadow"};
  EXPECT_EQ(Names(*Scene::Load(spec, 0)), (std::vector<std::string>{"shadow", "flame"}));
  spec.grids.clear();
  spec.all_grids = true;
  EXPECT_EQ(Names(*Scene::Load(spec, 0)).size(), 4u);
  spec.all_grids = false;
  spec.grids = {"velocity"};
  try {
    Scene::Load(spec, 0);
    ADD_FAILURE() << "a vec3 grid was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--grid 'velocity': " + spec.source +
                                         " has no float grid 'velocity' (float grids: density, "
                                         "flame, shadow, temperature)"),
              std::string::npos)
        << e.what();
  }
  // The built-in scene renders all its grids unless told otherwise.
  EXPECT_EQ(Names(*Scene::Load({}, 0)).size(), 3u);
  SceneSpec builtin;
  builtin.grids = {"glass"};
  EXPECT_EQ(Names(*Scene::Load(builtin, 0)), std::vector<std::string>{"glass"});
}

// ---------------------------------------------------------------- against vdb_render

constexpr char kVdbRender[] = "/usr/bin/vdb_render";

std::string Triple(const Vec3d& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g", v.x, v.y, v.z);
  return buf;
}

// Renders `vdb` with both at 64x64 (raycell's default framing, given to vdb_render), both
// with vdb_render's default material and light spelled out, and compares their linear
// images.
ImageDiff AgainstVdbRender(const std::string& vdb, const std::string& name) {
  const auto dir = TempDir("vdb_render_" + name);
  RecordOptions o = SmallBuiltin(dir, 64);
  o.scene.source = vdb;
  o.scene.lights = {ParseLight("dir:0.3,0.3,0:0.7,0.7,0.7")};
  o.settings.primary_step = 1;
  o.settings.shadow_step = 3;
  o.settings.cutoff = 0.005;
  o.images_dir = (dir / "img").string();
  o.image_encoding = PngEncoding::kLinear;
  std::ostringstream log;
  Record(o, log);
  // The material is given to vdb_render only: raycell's default must be the same.
  const CameraKey cam = TraceReader::Open(o.out).header().cameras.at(0);
  const std::string vr_png = (dir / "vdb_render.png").string();
  const std::string cmd =
      std::string(kVdbRender) + " " + vdb + " " + vr_png +
      " -res 64x64 -step 1 -shadowstep 3 -cutoff 0.005 -light 0.3,0.3,0,0.7,0.7,0.7"
      " -absorb 0.1,0.1,0.1 -scatter 1.5,1.5,1.5 -gain 0.2 -cpus 1 -fov " +
      std::to_string(cam.fov_deg) + " -translate " + Triple(cam.eye) + " -lookat " +
      Triple(cam.target) + " -up " + Triple(cam.up) + " > /dev/null 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const ImageDiff d =
      Compare(ReadPng((dir / "img" / "frame_0000.png").string(), PngEncoding::kLinear),
              ReadPng(vr_png, PngEncoding::kLinear));
  std::cout << name << ": raycell vs vdb_render, linear 64x64: RMSE " << d.rmse
            << ", largest channel difference " << d.max_abs << ", mean " << d.mean << " vs "
            << d.mean_other << " (ratio " << d.mean / d.mean_other << ")\n";
  return d;
}

bool HaveVdbRender() { return std::filesystem::exists(kVdbRender); }

// The stated tolerance: RMSE at most 0.004 and no channel off by more than 0.03 (on values
// in 0..1; both PNGs are 8-bit, vdb_render's truncated, raycell's rounded, so a value can
// differ by 1.5/255 = 0.006 from quantisation alone), and the mean radiance within 2%.
void ExpectMatch(const ImageDiff& d) {
  EXPECT_GT(d.mean_other, 0.01);  // lit: the comparison means something
  EXPECT_LT(d.rmse, 0.004);
  EXPECT_LT(d.max_abs, 0.03);
  EXPECT_NEAR(d.mean / d.mean_other, 1.0, 0.02);
}

TEST(VdbRender, SameRadianceOnTheSmokePlume) {
  const std::string smoke = testing::SharedData() + "/mj_smoke.vdb";
  if (!HaveVdbRender()) GTEST_SKIP() << "no " << kVdbRender << " (Debian libopenvdb-tools)";
  if (!std::filesystem::exists(smoke)) GTEST_SKIP() << "no " << smoke << " (../shared/data)";
  ExpectMatch(AgainstVdbRender(smoke, "mj_smoke"));
}

// The fluid cache holds density, flame, shadow, temperature (float) and velocity: both
// render the density grid alone by default.
TEST(VdbRender, SameGridAndRadianceOnTheFluidCache) {
  const std::string fluid = testing::SharedData() + "/fluid_seq/fluid_data_0150.vdb";
  if (!HaveVdbRender()) GTEST_SKIP() << "no " << kVdbRender << " (Debian libopenvdb-tools)";
  if (!std::filesystem::exists(fluid)) GTEST_SKIP() << "no " << fluid << " (../shared/data)";
  ExpectMatch(AgainstVdbRender(fluid, "fluid_data_0150"));
}

// Four balls apart, in grids written out of name order: the same picture only if both
// choose the same grid.
TEST(VdbRender, SameDefaultGridOnAFileOfSeveralFloatGrids) {
  if (!HaveVdbRender()) GTEST_SKIP() << "no " << kVdbRender << " (Debian libopenvdb-tools)";
  const auto dir = TempDir("four_for_vdb_render");
  ExpectMatch(AgainstVdbRender(FourGrids(dir), "four_grids"));
}

}  // namespace
}  // namespace raycell
