// Damaged trace files: truncated at many offsets, bytes flipped at many positions, and
// well-formed frames with invalid content. Reading must either give the right data for the
// frames it reports or throw an InputError naming the file and the frame (or the header or
// index); frames before the damage stay readable; nothing crashes or hangs.
#include <capnp/message.h>
#include <capnp/serialize.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <zstd.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "base/check.h"
#include "tests/cell_list.h"
#include "tests/test_util.h"
#include "tests/traces/trace_format.h"
#include "tests/traces/trace_test_util.h"
#include "traces/path_coder.h"
#include "traces/sample_coder.h"
#include "traces/trace.capnp.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

// Ends the process if a test runs longer than its bound (a hang is a failure too).
class Watchdog {
 public:
  explicit Watchdog(std::chrono::seconds bound)
      : thread_([this, bound] {
          std::unique_lock<std::mutex> lock(mutex_);
          if (!done_.wait_for(lock, bound, [this] { return finished_; })) {
            std::fprintf(stderr, "watchdog: test exceeded its time bound\n");
            std::_Exit(2);
          }
        }) {}
  ~Watchdog() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      finished_ = true;
    }
    done_.notify_all();
    thread_.join();
  }

 private:
  std::mutex mutex_;
  std::condition_variable done_;
  bool finished_ = false;
  std::thread thread_;
};

std::string TempPath(const std::string& name) { return testing::TempPath("corrupt", name); }

using testing::ErrorOf;
using testing::Head;
using testing::RandomFrame;
using testing::ReadBytes;
using testing::TestHeader;
using testing::WriteBytes;

bool Contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

struct Reference {
  std::string path;
  std::string bytes;
  std::vector<RayBatch> frames;
  std::vector<FrameSummary> summaries;
  std::uint64_t header_length = 0;
};

// Writes a 4-frame trace of `rays` rays per frame (one frame empty).
Reference MakeReference(const std::string& name, std::size_t rays, std::size_t batch_rays) {
  Reference ref;
  ref.path = TempPath(name);
  std::mt19937_64 rng(rays);
  TraceWriterOptions options;
  options.max_batch_rays = batch_rays;
  TraceWriter w = TraceWriter::Create(ref.path, TestHeader({2, 2, 2}, true), options);
  for (int f = 0; f < 4; ++f) {
    ref.frames.push_back(f == 2 ? RayBatch(true) : RandomFrame(rng, rays, true, 8, 3));
    w.BeginFrame(20 + f);
    w.Append(ref.frames.back());
    ref.summaries.push_back(w.EndFrame());
  }
  w.Finish();
  ref.bytes = ReadBytes(ref.path);
  ref.header_length = ref.summaries[0].offset;
  return ref;
}

bool NamesFileAndPart(const std::string& message, const std::string& path) {
  return Contains(message, path + ": ") &&
         (Contains(message, ": header: ") || Contains(message, ": frame ") ||
          Contains(message, ": index: "));
}

// Opens a damaged copy whose damage starts at byte `damage`, checks the contract and
// returns how many frames read correctly.
// What the damaged files led to, to check that the tests reach every outcome.
struct Outcomes {
  std::size_t open_failed = 0, fallback = 0, frame_failed = 0, frame_ok = 0;
};
Outcomes outcomes;

void ExpectOutcomes(bool frames_fail) {
  std::printf("open failed %zu, index fallback %zu, frames failed %zu, frames read %zu\n",
              outcomes.open_failed, outcomes.fallback, outcomes.frame_failed, outcomes.frame_ok);
  EXPECT_GT(outcomes.open_failed, 0u);
  EXPECT_GT(outcomes.fallback, 0u);
  EXPECT_GT(outcomes.frame_ok, 0u);
  EXPECT_EQ(outcomes.frame_failed > 0, frames_fail);
  outcomes = {};
}

std::size_t CheckDamaged(const Reference& ref, const std::string& path, std::uint64_t damage) {
  std::optional<TraceReader> reader;
  try {
    reader.emplace(TraceReader::Open(path));
  } catch (const InputError& e) {
    ++outcomes.open_failed;
    EXPECT_TRUE(NamesFileAndPart(e.what(), path)) << e.what();
    EXPECT_LT(damage, ref.header_length) << "open failed after the header: " << e.what();
    return 0;
  }
  std::size_t good = 0;
  outcomes.fallback += !reader->warning().empty();
  for (std::size_t k = 0; k < reader->frames().size(); ++k) {
    const bool before_damage = ref.summaries[k].offset + ref.summaries[k].length <= damage;
    try {
      const RayBatch frame = reader->LoadFrame(k);
      EXPECT_EQ(reader->frames()[k].frame, ref.summaries[k].frame);
      EXPECT_TRUE(frame == ref.frames[k]) << "frame " << k << " read wrong data";
      ++good;
      ++outcomes.frame_ok;
    } catch (const InputError& e) {
      ++outcomes.frame_failed;
      EXPECT_TRUE(Contains(e.what(), path + ": frame ")) << e.what();
      EXPECT_FALSE(before_damage) << "frame " << k << " before the damage: " << e.what();
    }
  }
  for (std::size_t k = 0; k < ref.summaries.size(); ++k) {
    const bool before_damage = ref.summaries[k].offset + ref.summaries[k].length <= damage;
    if (before_damage && damage >= ref.header_length) {
      EXPECT_LT(k, reader->frames().size()) << "frame " << k << " lost; " << reader->warning();
    }
  }
  return good;
}

void TruncateAt(const Reference& ref, const std::string& path, std::uint64_t n) {
  SCOPED_TRACE("truncated to " + std::to_string(n) + " of " + std::to_string(ref.bytes.size()));
  WriteBytes(path, ref.bytes.substr(0, n));
  const std::size_t good = CheckDamaged(ref, path, n);
  if (n < ref.header_length) return;
  std::size_t complete = 0;
  for (const FrameSummary& s : ref.summaries) complete += s.offset + s.length <= n;
  EXPECT_EQ(good, complete);
}

void FlipAt(const Reference& ref, const std::string& path, std::uint64_t pos, unsigned mask) {
  SCOPED_TRACE("byte " + std::to_string(pos) + " xor " + std::to_string(mask));
  std::string bytes = ref.bytes;
  bytes[pos] = static_cast<char>(bytes[pos] ^ mask);
  WriteBytes(path, bytes);
  CheckDamaged(ref, path, pos);
}

TEST(TraceCorruptionTest, TruncatedAtEveryOffsetOfASmallFile) {
  const Watchdog watchdog(std::chrono::seconds(300));
  const Reference ref = MakeReference("small.rct", 40, 16);
  ASSERT_LT(ref.bytes.size(), 20000u);
  const std::string path = TempPath("small_cut.rct");
  for (std::uint64_t n = 0; n <= ref.bytes.size(); ++n) TruncateAt(ref, path, n);
  ExpectOutcomes(false);
  WriteBytes(path, ref.bytes.substr(0, ref.summaries[3].offset + 10));
  EXPECT_TRUE(Contains(TraceReader::Open(path).warning(),
                       ": frame #3 (offset " + std::to_string(ref.summaries[3].offset) +
                           "): truncated: the file ends"));
  for (std::uint64_t n : {std::uint64_t{2}, ref.header_length - 1}) {
    WriteBytes(path, ref.bytes.substr(0, n));
    try {
      TraceReader::Open(path);
      ADD_FAILURE() << "opened a file cut inside its header";
    } catch (const InputError& e) {
      EXPECT_TRUE(Contains(e.what(), path + ": header: truncated")) << e.what();
    }
  }
  std::remove(path.c_str());
  std::remove(ref.path.c_str());
}

TEST(TraceCorruptionTest, FlippedAtEveryPositionOfASmallFile) {
  const Watchdog watchdog(std::chrono::seconds(300));
  const Reference ref = MakeReference("small_flip.rct", 40, 16);
  const std::string path = TempPath("small_flipped.rct");
  std::mt19937 rng(3);
  for (std::uint64_t pos = 0; pos < ref.bytes.size(); ++pos) {
    FlipAt(ref, path, pos, 1u << (pos % 8));
    FlipAt(ref, path, pos, 1 + rng() % 255);
  }
  ExpectOutcomes(true);
  std::remove(path.c_str());
  std::remove(ref.path.c_str());
}

TEST(TraceCorruptionTest, DamageSpreadOverALargerFile) {
  const Watchdog watchdog(std::chrono::seconds(300));
  const Reference ref = MakeReference("large.rct", 6000, 1000);
  const std::string path = TempPath("large_damaged.rct");
  std::mt19937_64 rng(4);
  for (int i = 0; i < 300; ++i) {
    TruncateAt(ref, path, rng() % (ref.bytes.size() + 1));
    FlipAt(ref, path, rng() % ref.bytes.size(), 1 + rng() % 255);
  }
  // The header is a small part of the file, which random positions may all miss.
  TruncateAt(ref, path, rng() % ref.header_length);
  FlipAt(ref, path, rng() % ref.header_length, 1 + rng() % 255);
  ExpectOutcomes(true);
  std::remove(path.c_str());
  std::remove(ref.path.c_str());
}

TEST(TraceCorruptionTest, DamagedIndexFallsBackToScanning) {
  const Reference ref = MakeReference("index.rct", 100, 64);
  const std::string path = TempPath("index_damaged.rct");
  std::string bytes = ref.bytes;
  bytes[bytes.size() - 40] ^= 0x10;  // inside the index message
  WriteBytes(path, bytes);
  const TraceReader reader = TraceReader::Open(path);
  EXPECT_TRUE(Contains(reader.warning(), path + ": index: damaged: checksum mismatch"))
      << reader.warning();
  ASSERT_EQ(reader.frames().size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(reader.LoadFrame(k), ref.frames[k]);
  std::remove(path.c_str());
  std::remove(ref.path.c_str());
}

// ---- Well-formed frames with invalid content ----------------------------------------------

// Batch columns as stored (already coded as trace.capnp's "Column encoding" says).
struct RawBatch {
  std::int32_t frame = 5;
  std::uint64_t first_id = 0;
  std::vector<std::uint8_t> heads;
  std::vector<std::uint64_t> runs, parents, spawns, pixels, primary_paths, secondary_paths,
      primary_samples, secondary_samples, shadow_samples;
  std::uint8_t reference_rule = 0;
  std::vector<std::uint8_t> sample_code;  // format 6
  bool visit_table = false;               // format 7
  std::vector<std::uint8_t> path_code;    // format 8
  std::size_t t_values = 3;               // entries of tEnter and tExit
  bool drop_wide_pixels = false;          // leave the pixels' escaped values out
};

void FillColumn(schema::Column::Builder out, const std::vector<std::uint64_t>& values,
                bool bad_escape = false) {
  std::vector<std::uint64_t> wide;
  auto narrow = out.initNarrow(static_cast<unsigned>(values.size()));
  for (unsigned i = 0; i < values.size(); ++i) {
    narrow.set(i, values[i] < 255 ? static_cast<std::uint8_t>(values[i]) : 255);
    if (values[i] >= 255 && !bad_escape) wide.push_back(values[i]);
  }
  auto w = out.initWide(static_cast<unsigned>(wide.size()));
  for (unsigned i = 0; i < wide.size(); ++i) w.set(i, wide[i]);
}

std::string Flat(capnp::MallocMessageBuilder& message) {
  const auto words = capnp::messageToFlatArray(message);
  return std::string(words.asChars().begin(), words.asChars().size());
}

std::string BatchMessage(const RawBatch& b) {
  capnp::MallocMessageBuilder message;
  auto out = message.initRoot<schema::Record>().initBatch();
  out.setFrame(b.frame);
  out.setFirstId(b.first_id);
  auto heads = out.initHeads(static_cast<unsigned>(b.heads.size()));
  for (unsigned i = 0; i < b.heads.size(); ++i) heads.set(i, b.heads[i]);
  FillColumn(out.initHeadRuns(), b.runs);
  FillColumn(out.initParents(), b.parents);
  FillColumn(out.initSpawns(), b.spawns);
  FillColumn(out.initPixels(), b.pixels, b.drop_wide_pixels);
  FillColumn(out.initPrimaryPaths(), b.primary_paths);
  FillColumn(out.initSecondaryPaths(), b.secondary_paths);
  FillColumn(out.initPrimarySamples(), b.primary_samples);
  FillColumn(out.initSecondarySamples(), b.secondary_samples);
  FillColumn(out.initShadowSamples(), b.shadow_samples);
  out.setReferenceRule(b.reference_rule);
  out.setSampleCode(capnp::Data::Reader(b.sample_code.data(), b.sample_code.size()));
  out.setVisitTable(b.visit_table);
  out.setPathCode(capnp::Data::Reader(b.path_code.data(), b.path_code.size()));
  out.initTEnter(static_cast<unsigned>(b.t_values));
  out.initTExit(static_cast<unsigned>(b.t_values));
  return Flat(message);
}

std::string FrameEndMessage(const FrameSummary& s) {
  capnp::MallocMessageBuilder message;
  auto out = message.initRoot<schema::Record>().initFrameEnd();
  out.setFrame(s.frame);
  out.setRays(s.rays);
  out.setVisits(s.visits);
  out.setSamples(s.samples);
  auto kinds = out.initRaysByKind(4);
  for (unsigned k = 0; k < 4; ++k) kinds.set(k, s.rays_by_kind[k]);
  out.setChecksum(s.checksum);
  return Flat(message);
}

std::string ZstdFrame(const std::string& content) {
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
  std::string out(ZSTD_compressBound(content.size()), '\0');
  const std::size_t n =
      ZSTD_compress2(cctx, out.data(), out.size(), content.data(), content.size());
  ZSTD_freeCCtx(cctx);
  RAYCELL_CHECK(!ZSTD_isError(n));
  out.resize(n);
  return out;
}

constexpr std::uint8_t kPrimaryHead = Head(RayKind::kPrimary, 0, 0, true, true);
// Parent: the last non-shadow ray; spawn: 0 (no sibling) + 1; its own path; same pixel.
constexpr std::uint8_t kShadowHead = Head(RayKind::kShadow, 0, 1, true, false);

// A primary ray (cells 3 then 2, samples 5 and 6) and a shadow ray spawned at its second
// visit (cell 2, samples 7), all at pixel (1, 1), in a 2x2x2 grid; coded as format version 4.
RawBatch GoodBatch() {
  RawBatch b;
  b.heads = {kPrimaryHead, kShadowHead};
  b.runs = {0, 0};              // one ray each
  b.pixels = {2, 2};            // zigzag(+1), zigzag(+1)
  b.primary_paths = {2, 3, 1};  // 2 visits: cell 3, then 3 + unzigzag(1) = 2
  b.secondary_paths = {1, 2};   // 1 visit: cell 2
  b.primary_samples = {6, 7};   // 5 + 1, 6 + 1 (no reference ray: samples as they are)
  b.secondary_samples = {8};    // 7 + 1
  return b;
}

// The same rays coded as format version 5: paths as cell steps (see "Paths" in trace.capnp),
// the shadow ray's samples in shadowSamples.
RawBatch GoodBatchV5() {
  RawBatch b = GoodBatch();
  // 2 visits: from the predicted cell 0 = (0,0,0) step (+1,+1,0) to cell 3 = (1,1,0), code
  // 3 + 5*3 + 25*2; then step (-1,0,0) to cell 2 = (0,1,0), code 1 + 5*2 + 25*2.
  b.primary_paths = {2, 68, 61};
  // 1 visit: from the parent's cell at the spawn (2), step (0,0,0), code 2 + 5*2 + 25*2.
  b.secondary_paths = {1, 62};
  b.secondary_samples = {};
  b.shadow_samples = {8};  // 7 + 1 (no reference ray)
  return b;
}

// The same rays coded as format version 6: version 5's columns but the samples, which are
// range coded in sampleCode (see "Samples" in trace.capnp): ray 0 (primary, a path of its own,
// no reference) 5 and 6, ray 1 (shadow, the same) 7, none a residual.
RawBatch GoodBatchV6() {
  RawBatch b = GoodBatchV5();
  b.primary_samples = {};
  b.shadow_samples = {};
  SampleEncoder code;
  SampleContext primary(0, true), shadow(3, true);
  code.Add(primary.Of(false, 0, false), 5);
  primary.Next(false, 5, 5);
  code.Add(primary.Of(false, 0, true), 6);
  code.Add(shadow.Of(false, 0, true), 7);
  code.Finish();
  b.sample_code = code.code();
  return b;
}

// The header frame of a 2x2x2 capture written as format `version` (its file at `path` is
// removed).
std::string HeaderFrame(const std::string& path, std::uint32_t version) {
  TraceWriterOptions options;
  options.format_version = version;
  TraceWriter w = TraceWriter::Create(path, TestHeader({2, 2, 2}, true), options);
  w.Finish();
  const std::string bytes = ReadBytes(path);
  std::remove(path.c_str());
  const std::size_t n = ZSTD_findFrameCompressedSize(bytes.data(), bytes.size());
  RAYCELL_CHECK(!ZSTD_isError(n));
  return bytes.substr(0, n);
}

FrameSummary GoodSummary() {
  RayBatch rays(true);
  rays.BeginRay(RayKind::kPrimary, kNoParent, 0, 1, 1);
  rays.AddVisit(CellId(3), 5, 0, 0);
  rays.AddVisit(CellId(2), 6, 0, 0);
  rays.BeginRay(RayKind::kShadow, 0, 1, 1, 1);
  rays.AddVisit(CellId(2), 7, 0, 0);
  FrameAccumulator acc(5, true);
  for (std::size_t i = 0; i < rays.size(); ++i) acc.AddRay(rays.ray(i));
  return acc.Summary();
}

// Crafted frames after the header of a format version 4 capture (a version 5 one in
// InvalidContentV5Test).
class InvalidContentTest : public ::testing::Test {
 protected:
  explicit InvalidContentTest(std::uint32_t version = 4) : version_(version) {}
  void SetUp() override { header_ = HeaderFrame(TempPath("content.rct"), version_); }
  void TearDown() override { std::remove(path_.c_str()); }

  // Header of the reference file, then one crafted frame, no index.
  TraceReader Read(const std::vector<RawBatch>& batches, const std::optional<FrameSummary>& end) {
    std::string content;
    for (const RawBatch& b : batches) content += BatchMessage(b);
    if (end) content += FrameEndMessage(*end);
    WriteBytes(path_, header_ + ZstdFrame(content));
    return TraceReader::Open(path_);
  }

  void ExpectRejected(const std::vector<RawBatch>& batches, const std::string& reason,
                      const std::optional<FrameSummary>& end = GoodSummary()) {
    const TraceReader reader = Read(batches, end);
    EXPECT_EQ(reader.frames().size(), 0u);
    EXPECT_TRUE(Contains(reader.warning(), path_ + ": frame ")) << reader.warning();
    EXPECT_TRUE(Contains(reader.warning(), reason)) << reader.warning();
  }

  std::uint32_t version_;
  std::string header_;
  std::string path_ = TempPath("crafted.rct");
};

TEST_F(InvalidContentTest, CraftedGoodFrameReads) {
  const TraceReader reader = Read({GoodBatch()}, GoodSummary());
  ASSERT_EQ(reader.frames().size(), 1u) << reader.warning();
  const RayBatch frame = reader.LoadFrame(0);
  EXPECT_EQ(frame.cells(), (testing::CellList{3, 2, 2}));
  EXPECT_EQ(frame.ray(1).parent, 0u);
  EXPECT_EQ(frame.ray(1).spawn, 1u);
}

TEST_F(InvalidContentTest, ParentMustBeAnEarlierRay) {
  RawBatch b = GoodBatch();
  b.heads[1] = Head(RayKind::kShadow, 2, 1, true, false);  // parent given in `parents`
  b.parents = {2};                                         // id - 2 < 0
  ExpectRejected({b},
                 "frame 5 (#0, offset " + std::to_string(header_.size()) + "): ray 1: bad parent");
  b.parents = {0};
  ExpectRejected({b}, "ray 1: bad parent");
  b.parents = {};
  ExpectRejected({b}, "column parents: too few values");
  b.parents = {1, 1};
  ExpectRejected({b}, "column parents: extra values");
  b = GoodBatch();
  b.heads[1] = Head(RayKind::kShadow, 1, 1, true, false);  // the previous ray's parent: none
  ExpectRejected({b}, "ray 1: bad parent");
  b.heads[1] = Head(RayKind::kShadow, 3, 1, true, false);  // invalid code
  ExpectRejected({b}, "ray 1: bad parent");
  b = GoodBatch();
  b.heads = {kShadowHead, kPrimaryHead};  // no non-shadow ray before ray 0
  ExpectRejected({b}, "ray 0: bad parent");
}

TEST_F(InvalidContentTest, PrimaryRaysHaveNoParentAndNoSpawn) {
  RawBatch b = GoodBatch();
  b.heads[0] = Head(RayKind::kPrimary, 2, 0, true, true);
  b.parents = {1};
  ExpectRejected({b}, "ray 0: primary ray with a parent");
  b = GoodBatch();
  b.heads[1] = Head(RayKind::kPrimary, 0, 1, true, false);
  ExpectRejected({b}, "ray 1: primary ray with a spawn index");
}

TEST_F(InvalidContentTest, SpawnMustBeAVisitOfTheParent) {
  RawBatch b = GoodBatch();
  b.heads[1] = Head(RayKind::kShadow, 0, 2, true, false);  // spawn 2 of a 2-visit parent
  ExpectRejected({b}, "ray 1: spawn 2 >= visit count of parent 0");
  b.heads[1] = Head(RayKind::kShadow, 0, 3, true, false);  // spawn given in `spawns`
  b.spawns = {7};
  ExpectRejected({b}, "ray 1: spawn 7 >= visit count of parent 0");
  b.spawns = {std::uint64_t{1} << 32};
  ExpectRejected({b}, "ray 1: bad spawn");
  b.spawns = {};
  ExpectRejected({b}, "column spawns: too few values");
}

TEST_F(InvalidContentTest, CellsMustBeInTheGrid) {
  RawBatch b = GoodBatch();
  b.secondary_paths = {1, 8};
  ExpectRejected({b}, "ray 1: bad cell");
  b = GoodBatch();
  b.primary_paths = {2, 3, 300};  // a delta leaving the grid, through the escape list
  ExpectRejected({b}, "ray 0: bad cell");
  b.primary_paths = {2, 3, 7};  // 3 - 4 < 0
  ExpectRejected({b}, "bad cell delta");
}

TEST_F(InvalidContentTest, PathsAndSamplesMustMatchTheRays) {
  RawBatch b = GoodBatch();
  b.secondary_paths = {2, 2, 0};  // two visits, but one sample and one pair of t
  ExpectRejected({b}, "column secondarySamples: too few values");
  b.secondary_samples = {8, 8};
  ExpectRejected({b}, "t columns have bad length");
  b = GoodBatch();
  b.secondary_paths = {0};  // no visits, leaving values unused
  ExpectRejected({b}, "column secondarySamples: extra values");
  b = GoodBatch();
  b.primary_paths = {2, 3, 1, 5};
  ExpectRejected({b}, "column primaryPaths: extra values");
  b = GoodBatch();
  b.t_values = 4;
  ExpectRejected({b}, "t columns have 4 values for 3 visits");
  b = GoodBatch();
  b.secondary_paths = {kTraceMaxRayVisits + 1};
  ExpectRejected({b}, "ray 1: too many visits");
  b = GoodBatch();
  b.heads[1] = Head(RayKind::kShadow, 0, 1, false, false);  // the path of a ray it lacks
  b.secondary_paths = {};
  ExpectRejected({b}, "ray 1: repeats the path of a reference ray it does not have");
}

TEST_F(InvalidContentTest, ZeroRunsMustFitTheVisits) {
  RawBatch b = GoodBatch();
  b.secondary_samples = {0, 0};  // 3 zeros for 1 visit
  ExpectRejected({b}, "column secondarySamples: extra values");
  b.secondary_samples.assign(41, 1);  // a run of more than 2^40 zeros
  ExpectRejected({b}, "column secondarySamples: bad zero run");
  b = GoodBatch();
  b.primary_samples = {1, 7};  // a run of 2 zeros, then one value too many
  ExpectRejected({b}, "column primarySamples: extra values");
  b.primary_samples = {1};  // two zeros: the samples 0 and 0, then the checksum disagrees
  ExpectRejected({b},
                 "decoded frame 5: 2 rays (1 primary, 0 reflection, 0 refraction, 1 shadow), "
                 "3 visits, 7 samples");
}

TEST_F(InvalidContentTest, HeadsAndEscapesMustBeValid) {
  RawBatch b = GoodBatch();
  b.runs = {0};
  ExpectRejected({b}, "column headRuns has 1 values, expected 2");
  b.runs = {0, kTraceMaxBatchRays};
  ExpectRejected({b}, "batch has more than 4194304 rays");
  b = GoodBatch();
  b.pixels = {300, 2};
  b.drop_wide_pixels = true;
  ExpectRejected({b}, "column pixels: bad escape");
  b.pixels = {std::uint64_t{1} << 40, 2};
  b.drop_wide_pixels = false;
  ExpectRejected({b}, "bad pixel x delta");
}

TEST_F(InvalidContentTest, BatchesMustContinueTheFrame) {
  RawBatch b = GoodBatch();
  b.first_id = 1;
  ExpectRejected({b}, "batch starts at ray 1, expected 0");
  RawBatch second = GoodBatch();
  second.first_id = 2;
  ExpectRejected(
      {GoodBatch(), second},
      "frameEnd says frame 5: 2 rays (1 primary, 0 reflection, 0 refraction, 1 shadow), 3 visits, "
      "18 samples; decoded frame 5: 4 rays");
  second.frame = 6;
  ExpectRejected({GoodBatch(), second}, "batch of frame 6");
}

TEST_F(InvalidContentTest, Version4HasNoShadowSamplesColumnOrReferenceRule) {
  RawBatch b = GoodBatch();
  b.shadow_samples = {1};
  ExpectRejected({b}, "column shadowSamples: extra values");
  b = GoodBatch();
  b.reference_rule = 1;
  ExpectRejected({b}, "bad reference rule 1");
}

class InvalidContentV5Test : public InvalidContentTest {
 protected:
  InvalidContentV5Test() : InvalidContentTest(5) {}
};

TEST_F(InvalidContentV5Test, CraftedGoodFrameReads) {
  const TraceReader reader = Read({GoodBatchV5()}, GoodSummary());
  EXPECT_EQ(reader.header().format_version, 5u);
  ASSERT_EQ(reader.frames().size(), 1u) << reader.warning();
  const RayBatch frame = reader.LoadFrame(0);
  EXPECT_EQ(frame.cells(), (testing::CellList{3, 2, 2}));
  EXPECT_EQ(frame.samples(), (std::vector<std::uint32_t>{5, 6, 7}));
  EXPECT_EQ(frame.ray(1).parent, 0u);
  EXPECT_EQ(frame.ray(1).spawn, 1u);
}

TEST_F(InvalidContentV5Test, StepsMustStayInTheGrid) {
  RawBatch b = GoodBatchV5();
  b.primary_paths = {2, 68, 126};  // not a step code
  ExpectRejected({b}, "ray 0: bad cell");
  b.primary_paths = {2, 68, 63};  // (+1,0,0) from x = 1 leaves the 2x2x2 grid
  ExpectRejected({b}, "ray 0: bad cell");
  b.primary_paths = {2, 68, 125, 0, 0, 2};  // escaped (0,0,+1): cell 7, then the checksum
  ExpectRejected({b}, "checksum mismatch");
  b.primary_paths = {2, 68, 125, 0, 0, 4};  // escaped (0,0,+2) leaves the grid
  ExpectRejected({b}, "ray 0: bad cell");
  b.primary_paths = {2, 68, 125, 0, std::uint64_t{1} << 40, 0};  // a huge escaped step
  ExpectRejected({b}, "ray 0: bad cell");
  b.primary_paths = {2, 68, 125, 0};  // an escape without its three values
  ExpectRejected({b}, "column primaryPaths: too few values");
  b = GoodBatchV5();
  b.secondary_paths = {1, 0};  // (-2,-2,-2) from the parent's cell 2 leaves the grid
  ExpectRejected({b}, "ray 1: bad cell");
}

TEST_F(InvalidContentV5Test, ReferenceRuleIsZeroOrOne) {
  RawBatch b = GoodBatchV5();
  b.reference_rule = 1;  // the shadow ray has no corresponding ray nor sibling either way
  EXPECT_EQ(Read({b}, GoodSummary()).frames().size(), 1u);
  b.reference_rule = 2;
  ExpectRejected({b}, "bad reference rule 2");
}

TEST_F(InvalidContentV5Test, ShadowSamplesMustFitTheShadowVisits) {
  RawBatch b = GoodBatchV5();
  b.shadow_samples = {8, 8};
  ExpectRejected({b}, "column shadowSamples: extra values");
  b.shadow_samples = {};
  ExpectRejected({b}, "column shadowSamples: too few values");
  b = GoodBatchV5();
  b.secondary_samples = {8};  // version 5 keeps shadow rays' samples out of secondarySamples
  ExpectRejected({b}, "column secondarySamples: extra values");
}

class InvalidContentV6Test : public InvalidContentTest {
 protected:
  InvalidContentV6Test() : InvalidContentTest(6) {}
};

TEST_F(InvalidContentV6Test, CraftedGoodFrameReads) {
  const TraceReader reader = Read({GoodBatchV6()}, GoodSummary());
  EXPECT_EQ(reader.header().format_version, 6u);
  ASSERT_EQ(reader.frames().size(), 1u) << reader.warning();
  const RayBatch frame = reader.LoadFrame(0);
  EXPECT_EQ(frame.cells(), (testing::CellList{3, 2, 2}));
  EXPECT_EQ(frame.samples(), (std::vector<std::uint32_t>{5, 6, 7}));
}

TEST_F(InvalidContentV6Test, SamplesAreInTheSampleCodeOnly) {
  RawBatch b = GoodBatchV6();
  b.primary_samples = {6, 7};
  ExpectRejected({b}, "column primarySamples: extra values");
  b = GoodBatchV6();
  b.sample_code.pop_back();
  ExpectRejected({b}, "sampleCode of 6 bytes ends at byte 7");
  b = GoodBatchV6();
  b.sample_code.push_back(0);
  ExpectRejected({b}, "sampleCode of 8 bytes ends at byte 7");
  b = GoodBatchV6();
  b.sample_code = {};
  ExpectRejected({b}, "sampleCode of 0 bytes ends at byte");
  b = GoodBatchV6();
  b.sample_code = std::vector<std::uint8_t>(6, 0xFF);  // huge values: bad samples
  ExpectRejected({b}, "ray 0: bad samples");
}

class InvalidContentV7Test : public InvalidContentTest {
 protected:
  InvalidContentV7Test() : InvalidContentTest(7) {}
};

// A version 7 batch without visitTable is coded as version 6's. With it, no visit of
// GoodBatchV6 finds its key in the visit table (the shadow ray's visit of cell 2 is another
// group's), so the same code reads too: the contexts of predictor 0 are version 6's.
TEST_F(InvalidContentV7Test, CraftedGoodFrameReads) {
  for (const bool table : {false, true}) {
    SCOPED_TRACE(table);
    RawBatch b = GoodBatchV6();
    b.visit_table = table;
    const TraceReader reader = Read({b}, GoodSummary());
    EXPECT_EQ(reader.header().format_version, 7u);
    ASSERT_EQ(reader.frames().size(), 1u) << reader.warning();
    const RayBatch frame = reader.LoadFrame(0);
    EXPECT_EQ(frame.cells(), (testing::CellList{3, 2, 2}));
    EXPECT_EQ(frame.samples(), (std::vector<std::uint32_t>{5, 6, 7}));
    b.sample_code.push_back(0);
    ExpectRejected({b}, "sampleCode of 8 bytes ends at byte 7");
  }
}

class InvalidContentV8Test : public InvalidContentTest {
 protected:
  InvalidContentV8Test() : InvalidContentTest(8) {}
};

// The same rays coded as format version 8: version 6's batch (no visit table) with the paths
// range coded in pathCode (see "Paths" in trace.capnp): ray 0 (primary, no reference, its
// parent's step unknown) from cell 0 through cells 3 and 2; ray 1 (shadow) from its parent's
// cell at the spawn, 2, through cell 2, its parent having entered cell 2 from cell 3 by the step
// (-1, 0, 0), class 0 + 3 * 1 + 9 * 1 = 12.
RawBatch GoodBatchV8() {
  RawBatch b = GoodBatchV6();
  b.primary_paths = {};
  b.secondary_paths = {};
  PathEncoder paths({2, 2, 2});
  const CellId primary[] = {CellId(3), CellId(2)}, shadow[] = {CellId(2)};
  paths.Add(0, 0, primary, 2, PathTable::kFromSpawn + 1, nullptr, 0);
  paths.Add(2, 2, shadow, 1, 12, nullptr, 0);
  paths.Finish();
  b.path_code = paths.code();
  return b;
}

// Either way: the paths range coded, or (pathCode empty) in the columns as version 7's.
TEST_F(InvalidContentV8Test, CraftedGoodFrameReads) {
  for (const bool coded : {true, false}) {
    SCOPED_TRACE(coded);
    const TraceReader reader = Read({coded ? GoodBatchV8() : GoodBatchV6()}, GoodSummary());
    EXPECT_EQ(reader.header().format_version, 8u);
    ASSERT_EQ(reader.frames().size(), 1u) << reader.warning();
    const RayBatch frame = reader.LoadFrame(0);
    EXPECT_EQ(frame.cells(), (testing::CellList{3, 2, 2}));
    EXPECT_EQ(frame.samples(), (std::vector<std::uint32_t>{5, 6, 7}));
  }
}

TEST_F(InvalidContentV8Test, PathsAreInThePathCodeOnly) {
  RawBatch b = GoodBatchV8();
  b.primary_paths = {2, 68, 61};
  ExpectRejected({b}, "column primaryPaths: extra values");
  b = GoodBatchV8();
  b.path_code.push_back(0);
  ExpectRejected({b}, "pathCode of " + std::to_string(b.path_code.size()) + " bytes ends at byte");
  b = GoodBatchV8();
  b.path_code = {};  // no path code: the paths are in the columns, which are empty
  ExpectRejected({b}, "column primaryPaths: too few values");
  b.path_code = {0};  // read as zeros: symbol 0, the step (-2,-2,-2), leaves the grid
  ExpectRejected({b}, "ray 0: bad path");
  // Ray 0's steps coded from cell 1 = (1,0,0): (0,+1,0) to cell 3, then (-1,0,0) to cell 2.
  // The reader starts from cell 0: (0,+1,0) to cell 2 = (0,1,0), then (-1,0,0) leaves the grid.
  b = GoodBatchV8();
  PathEncoder out_of_grid({2, 2, 2});
  const CellId cells[] = {CellId(3), CellId(2)};
  out_of_grid.Add(0, 1, cells, 2, PathTable::kFromSpawn + 1, nullptr, 0);
  out_of_grid.Finish();
  b.path_code = out_of_grid.code();
  ExpectRejected({b}, "ray 0: bad path");
  b.path_code = std::vector<std::uint8_t>(8, 0xFF);  // no symbol of a path
  ExpectRejected({b}, "ray 0: bad path");
}

TEST_F(InvalidContentV7Test, PathCodeIsRefused) {
  RawBatch b = GoodBatchV6();
  b.path_code = GoodBatchV8().path_code;
  ExpectRejected({b}, "pathCode in a batch of format version 7 or earlier");
}

TEST_F(InvalidContentV6Test, VisitTableIsRefused) {
  RawBatch b = GoodBatchV6();
  b.visit_table = true;
  ExpectRejected({b}, "visitTable in a batch of format version 6 or earlier");
}

TEST_F(InvalidContentV5Test, SampleCodeIsRefused) {
  RawBatch b = GoodBatchV5();
  b.sample_code = GoodBatchV6().sample_code;
  ExpectRejected({b}, "sampleCode in a batch of format version 5 or earlier");
}

TEST_F(InvalidContentTest, FrameEndMustMatchTheRays) {
  FrameSummary s = GoodSummary();
  s.checksum ^= 1;
  ExpectRejected({GoodBatch()}, "checksum mismatch: frameEnd says", s);
  s = GoodSummary();
  s.samples += 1;
  ExpectRejected(
      {GoodBatch()},
      "3 visits, 19 samples; decoded frame 5: 2 rays (1 primary, 0 reflection, 0 refraction, "
      "1 shadow), 3 visits, 18 samples",
      s);
  ExpectRejected({GoodBatch()}, "without a frameEnd record", std::nullopt);
}

// ---- Well-formed header frames with invalid content --------------------------------------

std::string HeaderMessage(std::uint32_t version, std::array<std::uint32_t, 3> cells,
                          const std::vector<std::uint64_t>& footprints_in_header = {}) {
  capnp::MallocMessageBuilder message;
  auto out = message.initRoot<schema::Record>().initHeader();
  out.setFormatVersion(version);
  out.setCellsX(cells[0]);
  out.setCellsY(cells[1]);
  out.setCellsZ(cells[2]);
  auto f = out.initFootprints(static_cast<unsigned>(footprints_in_header.size()));
  for (unsigned i = 0; i < footprints_in_header.size(); ++i) f.set(i, footprints_in_header[i]);
  out.initSettings().setZstdLevel(3);
  return Flat(message);
}

std::string FootprintsMessage(std::uint64_t first, const std::vector<std::uint64_t>& values,
                              const std::vector<std::uint64_t>& runs) {
  capnp::MallocMessageBuilder message;
  auto out = message.initRoot<schema::Record>().initFootprints();
  out.setFirstCell(first);
  FillColumn(out.initValues(), values);
  FillColumn(out.initRuns(), runs);
  return Flat(message);
}

class InvalidHeaderTest : public ::testing::Test {
 protected:
  void TearDown() override { std::remove(path_.c_str()); }

  // A file of one header frame holding `messages`, and no frames.
  std::string Open(const std::string& messages) {
    WriteBytes(path_, ZstdFrame(messages));
    return ErrorOf([&] { TraceReader::Open(path_); });
  }
  void ExpectRejected(const std::string& messages, const std::string& reason) {
    EXPECT_EQ(Open(messages), path_ + ": header: " + reason);
  }

  std::string path_ = TempPath("crafted_header.rct");
};

TEST_F(InvalidHeaderTest, CraftedGoodHeadersRead) {
  EXPECT_EQ(Open(HeaderMessage(2, {2, 2, 2}) + FootprintsMessage(0, {300, 0}, {2, 4})), "");
  EXPECT_EQ(TraceReader::Open(path_).header().footprints,
            (std::vector<std::uint64_t>{300, 300, 300, 0, 0, 0, 0, 0}));
  EXPECT_EQ(Open(HeaderMessage(2, {2, 2, 2}) + FootprintsMessage(0, {1}, {2}) +
                 FootprintsMessage(3, {2}, {4})),
            "");
  EXPECT_EQ(TraceReader::Open(path_).header().footprints,
            (std::vector<std::uint64_t>{1, 1, 1, 2, 2, 2, 2, 2}));
  EXPECT_EQ(Open(HeaderMessage(1, {2, 1, 1}, {5, 6})), "");
  EXPECT_EQ(TraceReader::Open(path_).header().footprints, (std::vector<std::uint64_t>{5, 6}));
  // Versions 1 and 2 have no camera path: it reads as not recorded. Version 3 reads it.
  EXPECT_EQ(TraceReader::Open(path_).header().path.kind, "");
  EXPECT_EQ(Open(HeaderMessage(3, {2, 1, 1}) + FootprintsMessage(0, {5}, {1})), "");
  EXPECT_EQ(TraceReader::Open(path_).header().path.kind, "");  // a version 3 header without one
}

TEST_F(InvalidHeaderTest, FootprintRecordsMustCoverTheCellsOnce) {
  const std::string header = HeaderMessage(2, {2, 2, 2});
  ExpectRejected(header, "0 footprints for 8 cells");
  ExpectRejected(header + FootprintsMessage(0, {5}, {3}), "4 footprints for 8 cells");
  ExpectRejected(header + FootprintsMessage(0, {5}, {8}), "footprints for more than 8 cells");
  ExpectRejected(header + FootprintsMessage(0, {5, 6}, {3, 3}) + FootprintsMessage(8, {1}, {0}),
                 "footprints for more than 8 cells");
  ExpectRejected(header + FootprintsMessage(0, {5}, {3}) + FootprintsMessage(5, {6}, {2}),
                 "footprints record starts at cell 5, expected 4");
  ExpectRejected(header + FootprintsMessage(0, {5, 6}, {7}),
                 "column footprint runs has 1 values, expected 2");
  ExpectRejected(header + FootprintsMessage(0, {}, {}), "footprints record without runs");
  ExpectRejected(header + FootprintsMessage(0, {5}, {std::uint64_t{1} << 63}),
                 "footprints for more than 8 cells");
  ExpectRejected(HeaderMessage(2, {2, 2, 2}, {1, 1, 1, 1, 1, 1, 1, 1}),
                 "version 2 header with footprints in it");
  ExpectRejected(header + FootprintsMessage(0, {5}, {7}) + BatchMessage(GoodBatch()),
                 "a record other than footprints after the header");
}

// A list of empty structs costs a message nothing, so the traversal limit lets it claim
// millions of elements: 520 bytes declaring 3910656 grids took the reader 11 s and 800 MB
// (found by fuzz/trace_reader.cpp; kept in its corpus).
TEST(TraceCorruptionTest, ListsOfEmptyStructsAreRefusedBeforeTheyAreRead) {
  const std::string path = std::string(RAYCELL_SOURCE_DIR) +
                           "/fuzz/corpus/trace_reader/regress_timeout_3910656_empty_grids.rct";
  EXPECT_EQ(ErrorOf([&] { TraceReader::Open(path); }),
            path + ": header: 3910656 grids exceed the trace format's limit of 1024 " +
                "(kTraceMaxGrids)");
}

TEST_F(InvalidHeaderTest, VersionsAndLimitsAreChecked) {
  ExpectRejected(HeaderMessage(1, {2, 1, 1}, {5, 6}) + FootprintsMessage(0, {5}, {1}),
                 "more than one message in the header frame");
  ExpectRejected(HeaderMessage(1, {2, 1, 1}, {5}), "1 footprints for 2 cells");
  ExpectRejected(HeaderMessage(9, {2, 1, 1}),
                 "format version 9 is not supported (this reader "
                 "reads 1..8)");
  ExpectRejected(HeaderMessage(0, {2, 1, 1}),
                 "format version 0 is not supported (this reader "
                 "reads 1..8)");
  // A grid beyond the limit is refused before anything is allocated for its cells.
  ExpectRejected(HeaderMessage(2, {4096, 4096, 4096}) + FootprintsMessage(0, {5}, {0}),
                 "cell grid 4096x4096x4096 = 68719476736 cells exceeds the trace format's limit "
                 "of 16777216 cells (kTraceMaxCells, e.g. 256x256x256)");
  ExpectRejected(HeaderMessage(2, {2, 0, 2}),
                 "cell grid 2x0x2: every dimension must be at least 1");
}

}  // namespace
}  // namespace raycell
