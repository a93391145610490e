// The recorder end to end: round trip, determinism across thread counts, secondary rays,
// empty cells, and the real smoke plume.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <sstream>

#include "base/check.h"
#include "base/parse.h"
#include "record/cell_grid.h"
#include "record/image.h"
#include "record/renderer.h"
#include "record/scene.h"
#include "tests/record/record_test_util.h"
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
  job.footprints = &header.footprints;
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
  o.scene.all_grids = true;
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
  for (CellId c : rays.cells()) ++visits[c.value()];
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

// A capture stopped between frames (the stop hook) or cancelled within one (Ctrl-C): the
// frames finished before stay readable in OUT.tmp, and OUT is not written.
TEST(Recorder, StoppedAndCancelledCapturesLeaveTheirFinishedFramesReadable) {
  const auto dir = TempDir("interrupt");
  for (const bool cancel_within_frame : {false, true}) {
    SCOPED_TRACE(cancel_within_frame ? "cancelled within frame 2" : "stopped after frame 1");
    RecordOptions o = SmallBuiltin(dir, 16);
    o.frames = ParseFrameRange("0..5");
    o.camera.orbit_degrees = 90;
    std::atomic<bool> cancel{false};
    o.cancel = &cancel;
    std::vector<std::size_t> asked;
    o.stop = [&](std::size_t done) {
      asked.push_back(done);
      if (done < 2) return false;
      if (!cancel_within_frame) return true;
      cancel = true;  // seen by the next frame's first row
      return false;
    };
    std::ostringstream log;
    const RecordSummary sum = Record(o, log);
    EXPECT_TRUE(sum.interrupted);
    EXPECT_EQ(sum.frames, 2u);
    EXPECT_EQ(asked, (std::vector<std::size_t>{1, 2}));
    EXPECT_NE(log.str().find("interrupted: the 2 finished frames"), std::string::npos) << log.str();
    EXPECT_FALSE(std::filesystem::exists(o.out));
    const TraceReader r = TraceReader::Open(o.out + ".tmp");
    EXPECT_FALSE(r.warning().empty());
    ASSERT_EQ(r.frames().size(), 2u);
    for (std::size_t i = 0; i < r.frames().size(); ++i) {
      EXPECT_EQ(r.frames()[i].frame, int(i));
      EXPECT_GT(r.LoadFrame(i).size(), 0u);
    }
    std::filesystem::remove(o.out + ".tmp");
  }
}

// The stop hook is never asked after the last frame: a capture it does not stop completes.
TEST(Recorder, StopHookThatNeverStopsLetsTheCaptureComplete) {
  const auto dir = TempDir("nostop");
  RecordOptions o = SmallBuiltin(dir, 8);
  o.frames = ParseFrameRange("0..2");
  std::vector<std::size_t> asked;
  o.stop = [&](std::size_t done) {
    asked.push_back(done);
    return false;
  };
  std::ostringstream log;
  const RecordSummary sum = Record(o, log);
  EXPECT_FALSE(sum.interrupted);
  EXPECT_EQ(asked, (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(TraceReader::Open(o.out).frames().size(), 3u);
}

// One frame of a scene rendered in memory in `dims` cells.
struct Rendered {
  Image image{1, 1};
  FrameStats stats;
  std::vector<std::uint64_t> footprints;
  RayBatch rays{false};
};

Rendered RenderIn(const Scene& scene, std::array<std::uint32_t, 3> dims) {
  const CellGrid cells = CellGrid::Create(scene.box_lo(), scene.box_hi(), dims);
  Rendered out;
  out.footprints = scene.Footprints(scene.box_lo(), scene.box_hi(), dims, "sparse");
  RenderJob job;
  job.scene = &scene;
  job.cells = &cells;
  job.footprints = &out.footprints;
  job.camera = MakeCameraPath({}, {0}, scene.box_lo(), scene.box_hi()).at(0);
  job.settings.width = job.settings.height = 32;
  job.sink = [&](const RayBatch& b) { out.rays.AppendRebased(b); };
  out.image = Image(32, 32);
  EXPECT_TRUE(RenderFrame(job, &out.image, &out.stats));
  return out;
}

// `r` (finer cells) shows the same picture bit for bit as `one` (1x1x1) and does the same
// work: finer cells fit the fog closer, so more primary rays miss every non-empty cell (they
// are not recorded), but the same are traced, with the same spawned rays and samples.
void ExpectSamePictureAndWork(const Rendered& r, const Rendered& one) {
  EXPECT_EQ(r.stats.rays + r.stats.primary_missed, one.stats.rays + one.stats.primary_missed);
  EXPECT_GE(r.stats.primary_missed, one.stats.primary_missed);
  for (int k = 1; k < kRayKindCount; ++k) {
    EXPECT_EQ(r.stats.rays_by_kind[k], one.stats.rays_by_kind[k]) << ToString(RayKind(k));
  }
  EXPECT_EQ(r.stats.samples, one.stats.samples);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < one.image.pixels().size(); ++i) {
    const Rgb &p = r.image.pixels()[i], &q = one.image.pixels()[i];
    differing += p.r != q.r || p.g != q.g || p.b != q.b;
  }
  EXPECT_EQ(differing, 0u);
}

// Every visit is to a non-empty cell, consecutive visits differ, and spawned rays start in
// their parent's cell (docs/design.md §1).
void ExpectWellFormedRecord(const Rendered& r) {
  const RayBatch& rays = r.rays;
  ASSERT_EQ(rays.size(), r.stats.rays);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayView ray = rays.ray(i);
    for (std::size_t v = 0; v < ray.visit_count; ++v) {
      ASSERT_GT(r.footprints[ray.cells[v].value()], 0u) << "ray " << i << " visits an empty cell";
      if (v > 0) {
        ASSERT_NE(ray.cells[v], ray.cells[v - 1]) << "ray " << i;
      }
    }
    if (ray.is_primary()) continue;
    const RayView p = rays.ray(ray.parent);
    ASSERT_LT(ray.spawn, p.visit_count);
    ASSERT_EQ(ray.cells[0], p.cells[ray.spawn]) << "ray " << i;
  }
}

// The cell grid changes the record, never the picture: a fog scene rendered in 1x1x1,
// 3x3x3 and 256x256x256 cells gives the same image bit for bit and the same rays and
// samples. At 256^3 (the largest grid a trace holds, kMaxCaptureCells) every visit is
// to a non-empty cell, consecutive visits differ, spawned rays start in their parent's cell,
// and a fine cell is non-empty only inside a non-empty cell of the 2x2x2 grid (256 = 2x128).
TEST(RecorderAtScale, CellGridsUpTo256CubedChangeTheRecordNotThePicture) {
  openvdb::initialize();
  const auto dir = TempDir("scale");
  auto a = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, {0, 0, 0}, 0.1f);
  auto b = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.7f, {1.2f, 0.6f, 0}, 0.1f);
  openvdb::tools::csgUnion(*a, *b);
  openvdb::tools::sdfToFogVolume(*a);
  a->setName("density");
  SceneSpec spec;
  spec.source = (dir / "blobs.vdb").string();
  openvdb::io::File(spec.source).write({a});
  const auto scene = Scene::Load(spec, 0);
  const Rendered one = RenderIn(*scene, {1, 1, 1});
  const Rendered three = RenderIn(*scene, {3, 3, 3});
  const Rendered fine = RenderIn(*scene, {256, 256, 256});
  const Rendered coarse = RenderIn(*scene, {2, 2, 2});
  ASSERT_GT(one.stats.rays_by_kind[int(RayKind::kShadow)], 1000u);
  for (const Rendered* r : {&three, &fine}) ExpectSamePictureAndWork(*r, one);
  EXPECT_LT(one.stats.visits, three.stats.visits);
  EXPECT_LT(three.stats.visits, fine.stats.visits);
  ExpectWellFormedRecord(fine);
  std::uint64_t nonempty = 0;
  for (CellId c : CellRange(fine.footprints.size())) {
    if (fine.footprints[c.value()] == 0) continue;
    ++nonempty;
    const std::uint32_t x = c.value() % 256, y = (c.value() / 256) % 256, z = c.value() / 65536;
    ASSERT_GT(coarse.footprints[x / 128 + 2 * (y / 128 + 2 * (z / 128))], 0u) << "cell " << c;
  }
  EXPECT_GT(nonempty, 1000u);
  EXPECT_LT(nonempty, fine.footprints.size());
}

// Rays spawned at a surface start half a voxel off it (0.0125 in the built-in scene), in
// their parent's cell. In cells smaller than that (y: 2.05 / 256 = 0.008) the start point lies
// cells away from that cell: `raycell record --cells 255x255x255` aborted in the cell DDA.
// Now the spawned ray's first visit is its parent's cell and it goes on from where it
// starts, and the picture is the one of 1x1x1 cells.
TEST(RecorderAtScale, SpawnedRaysInCellsSmallerThanTheirOffset) {
  const auto scene = Scene::Load(SceneSpec{}, 0);  // the built-in scene: fog and surfaces
  const Rendered one = RenderIn(*scene, {1, 1, 1});
  const Rendered fine = RenderIn(*scene, {32, 256, 32});
  ASSERT_GT(one.stats.rays_by_kind[int(RayKind::kReflection)], 50u);
  ASSERT_GT(one.stats.rays_by_kind[int(RayKind::kRefraction)], 50u);
  ExpectSamePictureAndWork(fine, one);
  ExpectWellFormedRecord(fine);
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
  const Image img = ReadPng((dir / "img" / "frame_0000.png").string(), PngEncoding::kSrgb);
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
