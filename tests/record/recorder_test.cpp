// The recorder end to end: round trip, determinism across thread counts, secondary rays,
// empty cells, and the real smoke plume.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <sstream>
#include <thread>

#include "base/check.h"
#include "base/parse.h"
#include "tests/record/record_test_util.h"
#include "traces/record/cell_grid.h"
#include "traces/record/image.h"
#include "traces/record/renderer.h"
#include "traces/record/scene.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

using testing::ReadBytes;
using testing::SmallBuiltin;
using testing::TempDir;

TEST(Recorder, RoundTripRayForRayAndVisitForVisit) {
  const auto dir = TempDir("roundtrip");
  SceneSpec spec;
  const auto scene = Scene::Load(spec, 0);
  const CellGrid cells = CellGrid::Create(scene->box_lo(), scene->box_hi(), {3, 3, 3});
  TraceHeader header;
  header.box_min = scene->box_lo();
  header.box_max = scene->box_hi();
  header.cells = {3, 3, 3};
  header.footprints = scene->Footprints(header.box_min, header.box_max, header.cells, "sparse");
  header.settings.width = header.settings.height = 40;
  header.settings.store_t = true;
  header.cameras = MakeCameraPath({}, {0}, header.box_min, header.box_max);
  const std::string path = (dir / "rt.rct").string();
  TraceWriter writer = TraceWriter::Create(path, header);
  RayBatch produced(true);
  RenderJob job;
  job.scene = scene.get();
  job.cells = &cells;
  job.footprints = header.footprints;
  job.camera = header.cameras[0];
  job.settings = header.settings;
  job.sink = [&](const RayBatch& b) {
    produced.AppendRebased(b);
    writer.Append(b);
  };
  Image image(40, 40);
  FrameStats stats;
  writer.BeginFrame(0);
  ASSERT_TRUE(RenderFrame(job, &image, &stats));
  writer.EndFrame();
  writer.Finish();
  ASSERT_GT(produced.size(), 1000u);
  EXPECT_EQ(stats.rays, produced.size());
  const TraceReader reader = TraceReader::Open(path);
  EXPECT_EQ(reader.header(), header);
  const RayBatch read = reader.LoadFrame(0);
  ASSERT_EQ(read.size(), produced.size());
  EXPECT_EQ(read.visit_count(), produced.visit_count());
  EXPECT_TRUE(read == produced);
}

TEST(Recorder, OneAndTwoThreadsGiveByteIdenticalTraces) {
  const auto dir = TempDir("threads");
  RecordOptions one = SmallBuiltin(dir);
  one.frames = {0, 1};
  one.camera.orbit_degrees = 40;
  one.threads = 1;
  one.out = (dir / "t1.rct").string();
  RecordOptions two = one;
  two.threads = 2;
  two.out = (dir / "t2.rct").string();
  std::ostringstream log;
  Record(one, log);
  Record(two, log);
  const std::string a = ReadBytes(one.out), b = ReadBytes(two.out);
  ASSERT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << "traces differ: " << a.size() << " vs " << b.size() << " bytes";
}

TEST(Recorder, BuiltinSceneHasAllKindsAndSpawnedRaysStartInTheirParentsCell) {
  const auto dir = TempDir("kinds");
  RecordOptions o = SmallBuiltin(dir, 64);
  std::ostringstream log;
  Record(o, log);
  const TraceReader reader = TraceReader::Open(o.out);
  const RayBatch b = reader.LoadFrame(0);
  std::array<std::uint64_t, kRayKindCount> kinds{};
  for (std::size_t i = 0; i < b.size(); ++i) {
    const RayView r = b.ray(i);
    ++kinds[int(r.kind)];
    ASSERT_GE(r.visit_count, 1u) << "ray " << r.id << " has no visits";
    for (std::size_t v = 1; v < r.visit_count; ++v) {
      ASSERT_NE(r.cells[v], r.cells[v - 1]) << "ray " << r.id << " repeats a cell";
    }
    if (r.is_primary()) continue;
    ASSERT_LT(r.parent, r.id);
    const RayView p = b.ray(r.parent - b.first_id());
    ASSERT_LT(r.spawn, p.visit_count);
    ASSERT_EQ(r.cells[0], p.cells[r.spawn]) << "ray " << r.id << " of parent " << r.parent;
  }
  for (int k = 0; k < kRayKindCount; ++k) {
    EXPECT_GT(kinds[k], 0u) << "no " << ToString(RayKind(k)) << " rays";
  }
}

// Two fog balls in opposite corners of the scene box: with 2x2x2 cells only cells 0 and 7
// hold data; the six others must have footprint 0 and never be visited.
TEST(Recorder, EmptyCellsHaveFootprintZeroAndAreNeverVisited) {
  openvdb::initialize();
  const auto dir = TempDir("empty");
  auto a = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, {0, 0, 0}, 0.1f);
  auto b = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, {6, 6, 6}, 0.1f);
  openvdb::tools::sdfToFogVolume(*a);
  openvdb::tools::sdfToFogVolume(*b);
  a->setName("near");
  b->setName("far");
  const std::string vdb = (dir / "corners.vdb").string();
  openvdb::io::File(vdb).write({a, b});

  RecordOptions o = SmallBuiltin(dir, 48);
  o.scene.source = vdb;
  o.camera.eye = {14, 3, 0};  // looks across the box so that rays cross empty cells
  o.camera.target = {3, 3, 3};
  std::ostringstream log;
  Record(o, log);
  const TraceReader reader = TraceReader::Open(o.out);
  const auto& fp = reader.header().footprints;
  ASSERT_EQ(fp.size(), 8u);
  EXPECT_GT(fp[0], 0u);
  EXPECT_GT(fp[7], 0u);
  for (int c = 1; c < 7; ++c) EXPECT_EQ(fp[c], 0u) << "cell " << c;
  const RayBatch rays = reader.LoadFrame(0);
  ASSERT_GT(rays.visit_count(), 0u);
  std::array<std::uint64_t, 8> visits{};
  for (CellId c : rays.cells()) ++visits[c];
  for (int c = 1; c < 7; ++c) EXPECT_EQ(visits[c], 0u) << "cell " << c;
  EXPECT_GT(visits[0] + visits[7], 0u);
}

TEST(Recorder, BadScenesAreClearErrorsAndWriteNothing) {
  openvdb::initialize();
  const auto dir = TempDir("bad");
  auto v = openvdb::Vec3SGrid::create();
  v->setName("velocity");
  v->tree().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
  const std::string vec_only = (dir / "vec.vdb").string();
  openvdb::io::File(vec_only).write({v});
  RecordOptions o = SmallBuiltin(dir, 16);
  std::ostringstream log;
  auto message = [&](const std::string& scene) {
    o.scene.source = scene;
    try {
      Record(o, log);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(vec_only).find("no non-empty float grid (found: velocity (vec3s))"),
            std::string::npos)
      << message(vec_only);
  const std::string missing = (dir / "missing.vdb").string();
  EXPECT_NE(message(missing).find(missing), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(o.out));
  EXPECT_FALSE(std::filesystem::exists(o.out + ".tmp"));
}

// Ctrl-C during a capture: the frames finished before it stay readable in OUT.tmp.
TEST(Recorder, InterruptedCaptureLeavesItsFinishedFramesReadable) {
  const auto dir = TempDir("interrupt");
  RecordOptions o = SmallBuiltin(dir, 64);
  o.frames = ParseFrameRange("0..59");
  o.camera.orbit_degrees = 90;
  std::atomic<bool> cancel{false};
  o.cancel = &cancel;
  RecordSummary sum;
  std::ostringstream log;
  std::thread capture([&] { sum = Record(o, log); });
  const std::string tmp = o.out + ".tmp";
  for (int i = 0; i < 3000 && !cancel; ++i) {  // at most 30 s
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    try {
      if (TraceReader::Open(tmp).frames().size() >= 2) cancel = true;
    } catch (const InputError&) {
    }
  }
  capture.join();
  ASSERT_TRUE(sum.interrupted) << "the capture finished before it could be interrupted";
  EXPECT_FALSE(std::filesystem::exists(o.out));
  const TraceReader r = TraceReader::Open(tmp);
  EXPECT_FALSE(r.warning().empty());
  ASSERT_GE(r.frames().size(), 2u);
  EXPECT_EQ(r.frames().size(), sum.frames);
  for (std::size_t i = 0; i < r.frames().size(); ++i) {
    EXPECT_EQ(r.frames()[i].frame, int(i));
    EXPECT_GT(r.LoadFrame(i).size(), 0u);
  }
}

TEST(Recorder, RealSmokePlumeRecordsAndShowsInTheImage) {
  const std::string smoke = testing::SharedData() + "/mj_smoke.vdb";
  if (!std::filesystem::exists(smoke)) {
    GTEST_SKIP() << "no " << smoke << ": ../shared/data is absent, skipping the real-data test";
  }
  const auto dir = TempDir("smoke");
  RecordOptions o = SmallBuiltin(dir, 256);
  o.scene.source = smoke;
  o.images_dir = (dir / "img").string();
  std::ostringstream log;
  const RecordSummary s = Record(o, log);
  EXPECT_EQ(s.frames, 1u);
  const TraceReader reader = TraceReader::Open(o.out);
  const FrameSummary& f = reader.frames().at(0);
  EXPECT_GT(f.rays_by_kind[int(RayKind::kPrimary)], 10000u);
  EXPECT_GT(f.rays_by_kind[int(RayKind::kShadow)], f.rays_by_kind[int(RayKind::kPrimary)]);
  const Image img = ReadPng((dir / "img" / "frame_0000.png").string());
  ASSERT_EQ(img.width(), 256u);
  // The plume: a lit region covering part of the frame around its centre, black corners.
  std::uint64_t lit = 0;
  double cx = 0, cy = 0;
  for (std::uint32_t y = 0; y < img.height(); ++y) {
    for (std::uint32_t x = 0; x < img.width(); ++x) {
      const Rgb& p = img.at(x, y);
      if (p.r + p.g + p.b > 0.03) ++lit, cx += x, cy += y;
    }
  }
  const double frac = double(lit) / (256.0 * 256.0);
  EXPECT_GT(frac, 0.05);
  EXPECT_LT(frac, 0.9);
  EXPECT_NEAR(cx / lit, 128, 40);
  EXPECT_NEAR(cy / lit, 128, 40);
  const Rgb& corner = img.at(0, 0);
  EXPECT_LT(corner.r + corner.g + corner.b, 0.01);
}

}  // namespace
}  // namespace raycell
