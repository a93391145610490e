// Numerical stability of the renderer: no NaN or infinity reaches an image or a trace for
// zero, negative and extreme densities, a camera inside the volume and rays tangent to a
// level set (the renderer CHECKs every pixel is finite, so a NaN aborts the test); grids
// holding NaN are refused with a message; transmittance stays in [0, 1] and never increases
// along any ray; the single- and double-precision marchers agree within stated tolerances.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

#include "base/check.h"
#include "record/cell_grid.h"
#include "record/image.h"
#include "record/renderer.h"
#include "tests/record/record_test_util.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

using namespace testing;

// A fog ball of radius 1 whose active voxels all hold `value`; with more values, one such
// grid per value (overlapping fog volumes), named density, density1, ...
std::string FogBall(const std::filesystem::path& dir, const std::string& name,
                    std::vector<float> values) {
  openvdb::initialize();
  openvdb::GridPtrVec grids;
  for (std::size_t i = 0; i < values.size(); ++i) {
    auto g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, {0, 0, 0}, 0.1f);
    openvdb::tools::sdfToFogVolume(*g);
    for (auto it = g->beginValueOn(); it; ++it) it.setValue(values[i]);
    g->setName(i == 0 ? "density" : "density" + std::to_string(i));
    grids.push_back(g);
  }
  const std::string path = (dir / (name + ".vdb")).string();
  openvdb::io::File(path).write(grids);
  return path;
}

std::string FogBall(const std::filesystem::path& dir, const std::string& name, float value) {
  return FogBall(dir, name, std::vector<float>{value});
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
  return {ReadPng((dir / "img" / "frame_0000.png").string(), PngEncoding::kSrgb), r.frames().at(0)};
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
  // An opaque ball: each primary ray ends at its first sample in it, after one shadow ray,
  // so there are at most as many shadow rays as primary rays. That sample scatters all the
  // light its shadow ray brings: at most albedo x light = 1.5 / 1.6 x 0.7 = 0.65625 (plus
  // half an 8-bit sRGB step, 0.0043 there), and that much where the shadow ray, which starts
  // a shadow step further on, leaves the ball at once (the lit side).
  const Capture dense = RecordOne(dir, FogBall(dir, "dense", std::numeric_limits<float>::max()));
  const auto& kinds = dense.frame.rays_by_kind;
  EXPECT_GT(kinds[int(RayKind::kShadow)], 0u);
  EXPECT_LE(kinds[int(RayKind::kShadow)], kinds[int(RayKind::kPrimary)]);
  EXPECT_LE(MaxChannel(dense.image), 0.65625 + 0.0043);
  EXPECT_GT(MaxChannel(dense.image), 0.65625 - 0.0043);
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

// One frame rendered in memory: the linear image, the stats, the visits per cell and the
// visits whose recorded t_enter/t_exit are not finite or out of order (always 0 expected).
struct InMemory {
  Image image{1, 1};
  FrameStats stats;
  std::vector<std::uint64_t> visits_per_cell;
  std::uint64_t bad_t = 0;
};

InMemory RenderInMemory(const SceneSpec& spec, const CameraPathSpec& camera,
                        const RenderSettings& settings, std::array<std::uint32_t, 3> dims,
                        std::function<void(const MarchSample&)> probe = {}) {
  const auto scene = Scene::Load(spec, 0);
  const CellGrid cells = CellGrid::Create(scene->box_lo(), scene->box_hi(), dims);
  RenderJob job;
  job.scene = scene.get();
  job.cells = &cells;
  const auto footprints = scene->Footprints(scene->box_lo(), scene->box_hi(), dims, "sparse");
  job.footprints = &footprints;
  job.camera = MakeCameraPath(camera, {0}, scene->box_lo(), scene->box_hi()).at(0);
  job.settings = settings;
  job.settings.store_t = true;  // the trace's parameters are checked too
  job.threads = probe ? 1 : 0;
  job.sample_probe = std::move(probe);
  InMemory out;
  out.visits_per_cell.assign(cells.cell_count(), 0);
  job.sink = [&](const RayBatch& b) {
    for (CellId c : b.cells()) ++out.visits_per_cell.at(c.value());
    for (std::size_t v = 0; v < b.visit_count(); ++v) {
      const float t0 = b.t_enters()[v], t1 = b.t_exits()[v];
      if (!(std::isfinite(t0) && std::isfinite(t1) && t0 >= 0 && t0 <= t1)) ++out.bad_t;
    }
  };
  out.image = Image(settings.width, settings.height);
  EXPECT_TRUE(RenderFrame(job, &out.image, &out.stats));
  return out;
}

// Every fog sample of every ray, checked as it is taken: optical depth >= 0, transmittance in
// [0, 1], both never NaN, t never decreasing (it repeats only where Real cannot tell step
// positions apart) and transmittance never increasing along each ray.
class TransmittanceChecker {
 public:
  std::function<void(const MarchSample&)> Probe() {
    return [this](const MarchSample& s) { Check(s); };
  }
  std::uint64_t samples() const { return samples_; }
  std::uint64_t rays() const { return last_.size(); }
  int failures() const { return failures_; }

 private:
  void Check(const MarchSample& s) {
    ++samples_;
    const auto key = std::make_tuple(s.px, s.py, s.ray);
    auto [it, first] = last_.try_emplace(key, s);
    for (int ch = 0; ch < 3; ++ch) {
      const double tau = s.tau[ch], tr = s.transmittance[ch];
      bool ok = tau >= 0 && tr >= 0 && tr <= 1;  // false for NaN
      if (!first) ok = ok && s.t >= it->second.t && tr <= it->second.transmittance[ch];
      if (!ok && failures_++ < 10) {
        ADD_FAILURE() << "pixel (" << s.px << "," << s.py << ") ray " << s.ray << " (kind "
                      << int(s.kind) << ", depth " << s.depth << ") at t=" << s.t << " channel "
                      << ch << ": tau " << tau << ", transmittance " << tr
                      << (first
                              ? ""
                              : ", before: t=" + std::to_string(it->second.t) + " transmittance " +
                                    std::to_string(it->second.transmittance[ch]));
      }
    }
    it->second = s;
  }
  std::map<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>, MarchSample> last_;
  std::uint64_t samples_ = 0;
  int failures_ = 0;
};

TEST(Stability, TransmittanceStaysInTheUnitIntervalAndNeverIncreasesAlongARay) {
  const auto dir = TempDir("transmittance");
  struct Case {
    std::string name;
    SceneSpec scene;
    CameraPathSpec camera;
    double cutoff;
  };
  std::vector<Case> cases;
  cases.push_back({"built-in", {}, {}, 0.005});
  cases.push_back({"built-in, no cutoff", {}, {}, 0.0});
  Case inside{"camera inside the cloud", {}, {}, 0.005};
  inside.camera.eye = {0, 0, 0};
  inside.camera.target = {1, 0, 0};
  cases.push_back(inside);
  // Far enough that single precision cannot tell consecutive step positions apart (t / step
  // is about 4e7 > 2^24): the march must still end, with transmittance still monotone.
  Case far{"camera 10^6 away", {}, {}, 0.005};
  far.camera.eye = {0, 0, 1e6};
  far.camera.target = {0, 0, 0};
  far.camera.fov_deg = 3e-4;
  cases.push_back(far);
  for (auto [name, v] : {std::pair<const char*, float>{"dense", 1e30f},
                         {"max", std::numeric_limits<float>::max()},
                         {"thin", std::numeric_limits<float>::min()},
                         {"negative", -3.0f}}) {
    Case c{std::string(name) + " ball", {}, {}, 0.0};
    c.scene.source = FogBall(dir, name, v);
    cases.push_back(c);
  }
  // A negative grid overlapping a positive one: unclamped, their sum would lower the
  // optical depth below zero where the positive one is thin.
  Case mixed{"positive and negative balls", {}, {}, 0.0};
  mixed.scene.source = FogBall(dir, "mixed", {0.5f, -3.0f});
  mixed.scene.all_grids = true;
  cases.push_back(mixed);
  for (const bool single : {false, true}) {
    for (const Case& c : cases) {
      SCOPED_TRACE(c.name + (single ? ", single precision" : ", double precision"));
      RenderSettings set;
      set.width = set.height = 32;
      set.cutoff = c.cutoff;
      set.single_precision = single;
      TransmittanceChecker checker;
      const InMemory r = RenderInMemory(c.scene, c.camera, set, {3, 3, 3}, checker.Probe());
      EXPECT_EQ(checker.failures(), 0);
      EXPECT_EQ(r.bad_t, 0u);
      if (c.name != "negative ball") {
        EXPECT_GT(checker.rays(), 0u);
      }
    }
  }
}

// Materials and lights at the ends of their ranges (the parser's limits): transparent and
// overflowing fog, huge gain, full mirrors, glass that does not bend and glass of index 10,
// black surfaces, point lights inside the fog and inside the mirror sphere. The renderer
// CHECKs every pixel finite; the probe checks every sample.
TEST(Stability, MaterialsAndLightsAtTheEndsOfTheirRangesStayFinite) {
  const std::vector<std::vector<std::string>> materials = {
      {"cloud:absorb=0,0,0:scatter=0,0,0"},
      {"cloud:absorb=1e38,1e38,1e38:scatter=1e38,1e38,1e38"},        // the sum overflows a float
      {"cloud:absorb=1e300,1e300,1e300:scatter=1e300,1e300,1e300"},  // and a double
      {"cloud:absorb=0,0,0:scatter=1e-30,1e-30,1e-30:gain=1e30"},
      {"mirror:reflect=1", "glass:reflect=0:transparency=1:ior=1"},
      {"mirror:color=0,0,0", "glass:reflect=0:transparency=1:ior=10:color=1,0,1"},
  };
  std::vector<std::vector<Light>> lights = {{}};
  lights.push_back({{Light::Type::kPoint, {0, 0, 0}, {1, 1, 1}}});            // in the cloud
  lights.push_back({{Light::Type::kPoint, {1.35, -0.35, 0.45}, {1, 1, 1}}});  // in the sphere
  lights.push_back({{Light::Type::kDirectional, {0, 1, 0}, {1e30, 1e30, 1e30}}});
  for (const bool single : {false, true}) {
    for (const auto& m : materials) {
      for (const auto& l : lights) {
        SceneSpec scene;
        scene.materials = m;
        scene.lights = l;
        SCOPED_TRACE(m.front() + (m.size() > 1 ? " " + m.back() : "") + ", " +
                     std::to_string(l.size()) + " light(s) given, " +
                     (single ? "single" : "double"));
        RenderSettings set;
        set.width = set.height = 24;
        set.single_precision = single;
        TransmittanceChecker checker;
        const InMemory r = RenderInMemory(scene, {}, set, {3, 3, 3}, checker.Probe());
        EXPECT_EQ(checker.failures(), 0);
        EXPECT_EQ(r.bad_t, 0u);
        EXPECT_GT(r.stats.visits, 0u);
      }
    }
  }
}

// Beyond those ends: a clear message naming the value, nothing rendered.
TEST(Stability, MaterialsAndLightsBeyondTheirRangesAreRefused) {
  const auto message = [](const SceneSpec& spec) {
    return testing::ErrorOf([&] { Scene::Load(spec, 0); });  // "" when accepted
  };
  SceneSpec s;
  s.materials = {"mirror:color=1.5,0,0"};
  EXPECT_NE(message(s).find("'mirror:color=1.5,0,0' key 'color': must be at most 1"),
            std::string::npos)
      << message(s);
  s = {};
  s.lights = {{Light::Type::kPoint, {0, 0, 0}, {1e31, 0, 0}}};
  EXPECT_NE(message(s).find("must be at most 1e+30"), std::string::npos) << message(s);
  s.lights = {{Light::Type::kPoint, {0, NAN, 0}, {1, 1, 1}}};
  EXPECT_NE(message(s).find("must be finite"), std::string::npos) << message(s);
  s.lights = {{Light::Type::kDirectional, {0, 0, 0}, {1, 1, 1}}};
  EXPECT_NE(message(s).find("must not be zero"), std::string::npos) << message(s);
  try {
    ParseLight("dir:0,1,0:1,-1,1");
    ADD_FAILURE() << "a negative light was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("must not be negative"), std::string::npos) << e.what();
  }
}

// The sink runs on a thread of its own: its exception (a full disk, say) stops the frame
// and reaches the caller; a cancel leaves the rays of the finished rows, in id order.
TEST(Stability, SinkErrorsAndCancelsStopTheFrameCleanly) {
  const auto scene = Scene::Load({}, 0);
  const CellGrid cells = CellGrid::Create(scene->box_lo(), scene->box_hi(), {2, 2, 2});
  RenderJob job;
  job.scene = scene.get();
  job.cells = &cells;
  const auto footprints = scene->Footprints(scene->box_lo(), scene->box_hi(), {2, 2, 2}, "sparse");
  job.footprints = &footprints;
  job.camera = MakeCameraPath({}, {0}, scene->box_lo(), scene->box_hi()).at(0);
  job.settings.width = job.settings.height = 64;
  Image image(64, 64);
  FrameStats stats;
  int batches = 0;
  job.sink = [&](const RayBatch&) {
    if (++batches == 5) throw InputError("disk full (test)");
  };
  try {
    RenderFrame(job, &image, &stats);
    ADD_FAILURE() << "the sink's error was lost";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "disk full (test)");
  }
  EXPECT_EQ(batches, 5);  // nothing more reached the sink after its error

  std::atomic<bool> cancel{false};
  job.cancel = &cancel;
  RayId next = 0;
  std::uint32_t rows = 0;
  job.sink = [&](const RayBatch& b) {
    EXPECT_EQ(b.first_id(), next);
    next += b.size();
    if (++rows == 10) cancel = true;
  };
  EXPECT_FALSE(RenderFrame(job, &image, &stats));
  EXPECT_GE(rows, 10u);
  EXPECT_LT(rows, 64u);
  EXPECT_EQ(next, stats.rays);
}

double RelativeDiff(double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); }

// The stated tolerance (also in BENCHMARKS.md): on the built-in scene the single-precision
// marcher's linear image is within RMSE 1e-4 of the double one's (mean radiance about 0.2)
// and no pixel channel differs by more than 5e-3; rays and visits differ by under 0.1%,
// samples by under 0.3%, and the visits per cell by under 0.1% in total. Measured: RMSE
// 3.1e-6, largest difference 2.2e-4, 1 ray in 38371, 4 visits in 93919, 159 samples in
// 457806.
TEST(Stability, SingleAndDoublePrecisionMarchersAgreeOnTheBuiltInScene) {
  RenderSettings set;
  set.width = set.height = 96;
  const InMemory dbl = RenderInMemory({}, {}, set, {3, 3, 3});
  set.single_precision = true;
  const InMemory sgl = RenderInMemory({}, {}, set, {3, 3, 3});
  const ImageDiff d = Compare(sgl.image, dbl.image);
  std::uint64_t cell_l1 = 0, cell_total = 0;
  for (std::size_t c = 0; c < dbl.visits_per_cell.size(); ++c) {
    cell_l1 += std::uint64_t(
        std::llabs(std::int64_t(sgl.visits_per_cell[c]) - std::int64_t(dbl.visits_per_cell[c])));
    cell_total += dbl.visits_per_cell[c];
  }
  std::cout << "single vs double: image RMSE " << d.rmse << " (mean " << d.mean << "), max "
            << d.max_abs << "; rays " << sgl.stats.rays << " vs " << dbl.stats.rays << ", visits "
            << sgl.stats.visits << " vs " << dbl.stats.visits << ", samples " << sgl.stats.samples
            << " vs " << dbl.stats.samples << ", per-cell visits L1 " << cell_l1 << " of "
            << cell_total << "\n";
  EXPECT_GT(d.mean, 0.01);  // the scene is lit: the comparison means something
  EXPECT_LT(d.rmse, 1e-4);
  EXPECT_LT(d.max_abs, 5e-3);
  EXPECT_LT(RelativeDiff(sgl.stats.rays, dbl.stats.rays), 1e-3);
  EXPECT_LT(RelativeDiff(sgl.stats.visits, dbl.stats.visits), 1e-3);
  EXPECT_LT(RelativeDiff(sgl.stats.samples, dbl.stats.samples), 3e-3);
  EXPECT_LT(double(cell_l1), 1e-3 * double(cell_total));
}

}  // namespace
}  // namespace raycell
