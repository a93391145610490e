// Trace files written and read back: round trips, the index, the .tmp/rename protocol,
// determinism, `capnp decode` compatibility, JSONL and info output. (The size of a realistic
// trace is a benchmark: tools/bench/trace_size.cpp.)
#include <capnp/serialize.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "base/check.h"
#include "tests/test_util.h"
#include "tests/traces/trace_format.h"
#include "tests/traces/trace_test_util.h"
#include "traces/jsonl.h"
#include "traces/trace.capnp.h"
#include "traces/trace_inspect.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

std::string TempPath(const std::string& name) { return testing::TempPath("io", name); }

bool Exists(const std::string& path) { return std::ifstream(path).good(); }

using testing::Head;
using testing::RandomFrame;
using testing::ReadBytes;
using testing::TestHeader;

struct Frame {
  std::int32_t number;
  RayBatch rays;
};

// Appends `rays` in random-size chunks whose ids continue across calls.
void AppendInChunks(TraceWriter& w, const RayBatch& rays, std::mt19937_64& rng) {
  std::size_t i = 0;
  while (i < rays.size()) {
    const std::size_t n = std::min<std::size_t>(rays.size() - i, 1 + rng() % 3000);
    RayBatch chunk(rays.store_t());
    chunk.set_first_id(i);
    for (std::size_t k = i; k < i + n; ++k) {
      const RayView r = rays.ray(k);
      chunk.BeginRay(r.kind, r.parent, r.spawn, r.pixel_x, r.pixel_y);
      for (std::size_t v = 0; v < r.visit_count; ++v) {
        const Visit x = r.visit(v);
        chunk.AddVisit(x.cell, x.samples, x.t_enter, x.t_exit);
      }
    }
    w.Append(chunk);
    i += n;
  }
}

std::vector<FrameSummary> WriteFrames(TraceWriter& w, const std::vector<Frame>& frames,
                                      std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<FrameSummary> summaries;
  for (const Frame& f : frames) {
    w.BeginFrame(f.number);
    AppendInChunks(w, f.rays, rng);
    summaries.push_back(w.EndFrame());
  }
  return summaries;
}

std::vector<FrameSummary> WriteTrace(const std::string& path, const TraceHeader& header,
                                     const std::vector<Frame>& frames,
                                     const TraceWriterOptions& options = {}) {
  TraceWriter w = TraceWriter::Create(path, header, options);
  std::vector<FrameSummary> summaries = WriteFrames(w, frames, 99);
  w.Finish();
  return summaries;
}

std::vector<Frame> RandomFrames(bool store_t, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Frame> frames;
  frames.push_back({10, RandomFrame(rng, 300, store_t, 27)});
  frames.push_back({11, RandomFrame(rng, 9000, store_t, 27)});  // several batches
  frames.push_back({12, RayBatch(store_t)});                    // empty
  frames.push_back({13, RandomFrame(rng, 2500, store_t, 27)});
  return frames;
}

void ExpectSummaryOf(const FrameSummary& s, const Frame& f) {
  EXPECT_EQ(s.frame, f.number);
  EXPECT_EQ(s.rays, f.rays.size());
  EXPECT_EQ(s.visits, f.rays.visit_count());
  std::uint64_t samples = 0;
  for (std::uint32_t x : f.rays.samples()) samples += x;
  EXPECT_EQ(s.samples, samples);
}

// With and without t; in the current format (8) and in formats 7, 6 and 5, which the writer
// still writes when asked (options.format_version), so that files of the previous writers
// are known to read.
class RoundTripTest : public ::testing::TestWithParam<std::tuple<bool, std::uint32_t>> {};

TEST_P(RoundTripTest, WhatIsReadEqualsWhatWasWritten) {
  const auto [store_t, version] = GetParam();
  const std::string path = TempPath(store_t ? "rt_t.rct" : "rt.rct");
  TraceHeader header = TestHeader({3, 3, 3}, store_t);
  const std::vector<Frame> frames = RandomFrames(store_t, 1);
  TraceWriterOptions options;
  options.max_batch_rays = 1000;
  options.format_version = version;
  const std::vector<FrameSummary> written = WriteTrace(path, header, frames, options);

  const TraceReader reader = TraceReader::Open(path);
  EXPECT_EQ(reader.warning(), "");
  header.format_version = version;
  EXPECT_EQ(reader.header(), header);
  ASSERT_EQ(reader.frames().size(), frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    SCOPED_TRACE(k);
    const FrameSummary& s = reader.frames()[k];
    EXPECT_EQ(s, written[k]);
    EXPECT_EQ(s.offset, written[k].offset);
    EXPECT_EQ(s.length, written[k].length);
    ExpectSummaryOf(s, frames[k]);
    const RayBatch loaded = reader.LoadFrame(k);
    EXPECT_TRUE(loaded == frames[k].rays);
    EXPECT_EQ(loaded.cells(), frames[k].rays.cells());
    EXPECT_EQ(loaded.parents(), frames[k].rays.parents());
    EXPECT_EQ(loaded.t_exits(), frames[k].rays.t_exits());
  }
  std::remove(path.c_str());
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutT, RoundTripTest,
                         ::testing::Combine(::testing::Bool(), ::testing::Values(8u, 7u, 6u, 5u)));

TEST(TraceIoTest, ForEachBatchStreamsBatchesOfBoundedSize) {
  const std::string path = TempPath("batches.rct");
  const std::vector<Frame> frames = RandomFrames(false, 2);
  TraceWriterOptions options;
  options.max_batch_rays = 700;
  options.max_batch_visits = 1500;
  WriteTrace(path, TestHeader({3, 3, 3}, false), frames, options);
  const TraceReader reader = TraceReader::Open(path);
  RayBatch joined(false);
  std::size_t batches = 0;
  reader.ForEachBatch(1, [&](const RayBatch& b) {
    EXPECT_EQ(b.first_id(), joined.size());
    EXPECT_LE(b.size(), 700u);
    EXPECT_LE(b.visit_count(), 1500u + 5);  // a batch ends once it reaches the limit
    joined.AppendRebased(b);
    ++batches;
  });
  EXPECT_GE(batches, 13u);
  EXPECT_EQ(joined, frames[1].rays);
  std::size_t empty_batches = 0;
  reader.ForEachBatch(2, [&](const RayBatch&) { ++empty_batches; });
  EXPECT_EQ(empty_batches, 0u);
  std::remove(path.c_str());
}

// By default a batch holds 65536 rays in format 5 and 2^18 in the range-coded formats, whose
// models start anew in every batch (traces/format.h); the 2^20 visits end a batch in both.
TEST(TraceIoTest, RangeCodedFormatsWriteLargerBatchesByDefault) {
  RayBatch frame(false);
  const std::uint32_t rays = 300000;
  for (std::uint32_t i = 0; i < rays; ++i) {
    frame.BeginRay(RayKind::kPrimary, kNoParent, 0, i % 640, i / 640);
    frame.AddVisit(CellId(i % 27), 1 + i % 5, 0, 0);
  }
  for (const std::uint32_t version : {5u, 6u, 8u}) {
    SCOPED_TRACE(version);
    const std::string path = TempPath("default_batches.rct");
    TraceWriterOptions options;
    options.format_version = version;
    WriteTrace(path, TestHeader({3, 3, 3}, false), {{0, frame}}, options);
    const TraceReader reader = TraceReader::Open(path);
    std::vector<std::size_t> sizes;
    reader.ForEachBatch(0, [&](const RayBatch& b) { sizes.push_back(b.size()); });
    const std::vector<std::size_t> expected =
        version == 5 ? std::vector<std::size_t>{65536, 65536, 65536, 65536, 37856}
                     : std::vector<std::size_t>{262144, 37856};
    EXPECT_EQ(sizes, expected);
    EXPECT_TRUE(reader.LoadFrame(0) == frame);
    std::remove(path.c_str());
  }
  // Ended by visits first: 2^20 visits of rays of 8 visits each, in format 8 too.
  RayBatch long_rays(false);
  for (std::uint32_t i = 0; i < 200000; ++i) {
    long_rays.BeginRay(RayKind::kPrimary, kNoParent, 0, i % 640, i / 640);
    for (std::uint32_t v = 0; v < 8; ++v) long_rays.AddVisit(CellId((i + v) % 27), 1, 0, 0);
  }
  const std::string path = TempPath("visit_batches.rct");
  TraceWriterOptions options;
  options.format_version = 8;
  WriteTrace(path, TestHeader({3, 3, 3}, false), {{0, long_rays}}, options);
  std::vector<std::size_t> sizes;
  TraceReader::Open(path).ForEachBatch(0, [&](const RayBatch& b) { sizes.push_back(b.size()); });
  EXPECT_EQ(sizes, (std::vector<std::size_t>{131072, 68928}));
  std::remove(path.c_str());
}

TEST(TraceIoTest, OpensAFrameThroughTheIndexWithoutDecodingOthers) {
  const std::string path = TempPath("direct.rct");
  const std::vector<Frame> frames = RandomFrames(false, 3);
  const std::vector<FrameSummary> written = WriteTrace(path, TestHeader({3, 3, 3}, false), frames);
  // Wreck frame 11's bytes: frame 13 must still open through the index.
  std::string bytes = ReadBytes(path);
  for (std::uint64_t i = written[1].offset + 8; i < written[1].offset + written[1].length; ++i) {
    bytes[i] = static_cast<char>(bytes[i] ^ 0x5A);
  }
  testing::WriteBytes(path, bytes);
  const TraceReader reader = TraceReader::Open(path);
  EXPECT_EQ(reader.warning(), "");
  EXPECT_EQ(reader.LoadFrame(3), frames[3].rays);
  EXPECT_EQ(reader.LoadFrame(0), frames[0].rays);
  try {
    reader.LoadFrame(1);
    ADD_FAILURE() << "damaged frame read without error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": frame 11 (#1, offset "), std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
}

TEST(TraceIoTest, BytesInMemoryReadAsTheFile) {
  const std::string path = TempPath("memory.rct");
  const std::vector<Frame> frames = RandomFrames(true, 14);
  WriteTrace(path, TestHeader({3, 3, 3}, true), frames);
  const std::string bytes = ReadBytes(path);
  const TraceReader file = TraceReader::Open(path);
  const TraceReader memory = TraceReader::OpenBytes(bytes, path);
  EXPECT_EQ(memory.warning(), "");
  EXPECT_EQ(memory.path(), path);
  EXPECT_TRUE(memory.header() == file.header());
  ASSERT_EQ(memory.frames().size(), frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) EXPECT_EQ(memory.LoadFrame(k), frames[k].rays);
  // Damage reads the same way too: a truncated copy warns as the truncated file does.
  const std::string cut = bytes.substr(0, file.frames()[3].offset + 5);
  testing::WriteBytes(path, cut);
  EXPECT_EQ(TraceReader::OpenBytes(cut, path).warning(), TraceReader::Open(path).warning());
  EXPECT_NE(TraceReader::OpenBytes(cut, path).warning(), "");
  EXPECT_EQ(TraceReader::OpenBytes(cut, path).frames().size(), 3u);
  std::remove(path.c_str());
}

// trace_reader.h: several threads may read frames of one TraceReader at once (run under
// ThreadSanitizer in CI).
TEST(TraceIoTest, ThreadsReadFramesOfOneReaderAtOnce) {
  const std::string path = TempPath("threads.rct");
  const std::vector<Frame> frames = RandomFrames(false, 15);
  TraceWriterOptions options;
  options.max_batch_rays = 500;
  WriteTrace(path, TestHeader({3, 3, 3}, false), frames, options);
  const TraceReader reader = TraceReader::Open(path);
  std::vector<int> wrong(4, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int round = 0; round < 3; ++round) {
        for (std::size_t k = 0; k < frames.size(); ++k) {
          wrong[t] +=
              !(reader.LoadFrame((k + t) % frames.size()) == frames[(k + t) % frames.size()].rays);
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(wrong, std::vector<int>(4, 0));
  std::remove(path.c_str());
}

TEST(TraceIoTest, WritesToTmpAndRenamesOnFinish) {
  const std::string path = TempPath("tmp.rct");
  const std::vector<Frame> frames = RandomFrames(true, 4);
  std::remove(path.c_str());
  {
    TraceWriter w = TraceWriter::Create(path, TestHeader({3, 3, 3}, true));
    EXPECT_TRUE(Exists(path + ".tmp"));
    WriteFrames(w, {frames[0], frames[1]}, 5);
    EXPECT_FALSE(Exists(path));
    w.Finish();
    EXPECT_TRUE(Exists(path));
    EXPECT_FALSE(Exists(path + ".tmp"));
  }
  EXPECT_EQ(TraceReader::Open(path).frames().size(), 2u);
  std::remove(path.c_str());
}

TEST(TraceIoTest, TmpAppearsWithItsCompleteHeader) {
  const std::string path = TempPath("tmp_header.rct");
  testing::WriteBytes(path + ".tmp", "a stale .tmp of an earlier capture");
  // A header the writer refuses: nothing is written, the stale file is left alone.
  TraceHeader bad = TestHeader();
  bad.cells = {1000, 1000, 1000};
  EXPECT_THROW(TraceWriter::Create(path, bad), InputError);
  EXPECT_EQ(ReadBytes(path + ".tmp"), "a stale .tmp of an earlier capture");
  // The .tmp is replaced, at once, by one that holds the complete header (and no frame).
  TraceWriter w = TraceWriter::Create(path, TestHeader());
  const TraceReader tmp = TraceReader::Open(path + ".tmp");
  EXPECT_TRUE(tmp.header() == TestHeader());
  EXPECT_EQ(tmp.frames().size(), 0u);
  EXPECT_EQ(tmp.readable_end(), tmp.file_size());
  w.Finish();
  std::remove(path.c_str());
}

// Limits the size of files this process writes, for one scope (SIGXFSZ ignored: a write
// beyond the limit then fails with EFBIG).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit r = old_;
    r.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &r);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  void (*old_handler_)(int) = nullptr;
};

TEST(TraceIoTest, AFailureWhileWritingTheHeaderLeavesNoUnreadableTmp) {
  const std::string path = TempPath("header_fails.rct");
  std::remove((path + ".tmp").c_str());
  TraceHeader h = TestHeader({64, 64, 64});
  std::mt19937_64 rng(3);
  for (std::uint64_t& f : h.footprints) f = rng();  // incompressible: the header is 2 MB
  {
    const FileSizeLimit limit(4096);
    EXPECT_THROW(TraceWriter::Create(path, h), InputError);
  }
  // Either no .tmp, or one that opens: here none, since the header never completed.
  EXPECT_FALSE(Exists(path + ".tmp"));
}

TEST(TraceIoTest, InterruptedCaptureLeavesReadableTmp) {
  const std::string path = TempPath("interrupted.rct");
  const std::vector<Frame> frames = RandomFrames(false, 5);
  std::mt19937_64 rng(6);
  const RayBatch big = RandomFrame(rng, 200000, false, 27);
  {
    TraceWriter w = TraceWriter::Create(path, TestHeader({3, 3, 3}, false));
    WriteFrames(w, {frames[0], frames[1]}, 5);
    w.BeginFrame(99);
    w.Append(big);  // the unfinished frame leaves a partial zstd frame behind
  }                 // destroyed without Finish
  EXPECT_FALSE(Exists(path));
  const TraceReader reader = TraceReader::Open(path + ".tmp");
  EXPECT_NE(reader.warning().find("index: missing"), std::string::npos) << reader.warning();
  EXPECT_NE(reader.warning().find("kept 2 complete frame(s)"), std::string::npos)
      << reader.warning();
  EXPECT_NE(reader.warning().find("truncated"), std::string::npos) << reader.warning();
  ASSERT_EQ(reader.frames().size(), 2u);
  EXPECT_EQ(reader.LoadFrame(0), frames[0].rays);
  EXPECT_EQ(reader.LoadFrame(1), frames[1].rays);
  std::remove((path + ".tmp").c_str());
}

TEST(TraceIoTest, TmpWithOnlyFinishedFramesReadsWithWarning) {
  const std::string path = TempPath("finished_only.rct");
  const std::vector<Frame> frames = RandomFrames(false, 7);
  {
    TraceWriter w = TraceWriter::Create(path, TestHeader({3, 3, 3}, false));
    WriteFrames(w, frames, 5);
  }
  const TraceReader reader = TraceReader::Open(path + ".tmp");
  EXPECT_NE(reader.warning(), "");
  ASSERT_EQ(reader.frames().size(), frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) EXPECT_EQ(reader.LoadFrame(k), frames[k].rays);
  std::remove((path + ".tmp").c_str());
}

TEST(TraceIoTest, SameDataGivesByteIdenticalFiles) {
  const std::vector<Frame> frames = RandomFrames(true, 8);
  const std::string a = TempPath("same_a.rct"), b = TempPath("same_b.rct");
  WriteTrace(a, TestHeader({3, 3, 3}, true), frames);
  WriteTrace(b, TestHeader({3, 3, 3}, true), frames);
  const std::string bytes = ReadBytes(a);
  EXPECT_GT(bytes.size(), 1000u);
  EXPECT_TRUE(bytes == ReadBytes(b));
  std::remove(a.c_str());
  std::remove(b.c_str());
}

std::size_t CountOccurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto i = text.find(what); i != std::string::npos; i = text.find(what, i + 1)) ++n;
  return n;
}

TEST(TraceIoTest, ZstdAndCapnpDecodeTheWholeFile) {
  if (std::system("command -v zstd >/dev/null 2>&1 && command -v capnp >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "zstd or capnp not installed";
  }
  const std::string path = TempPath("decode.rct");
  const std::vector<Frame> frames = RandomFrames(false, 9);
  TraceWriterOptions options;
  options.max_batch_rays = 1000;
  WriteTrace(path, TestHeader({3, 3, 3}, false), frames, options);
  std::size_t batches = 0;
  const TraceReader reader = TraceReader::Open(path);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    reader.ForEachBatch(k, [&](const RayBatch&) { ++batches; });
  }
  const std::string out = path + ".txt";
  const std::string cmd = "zstd -qdc '" + path + "' > '" + path +
                          ".bin' && capnp decode --short '" + RAYCELL_SOURCE_DIR +
                          "/traces/trace.capnp' Record < '" + path + ".bin' > '" + out + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const std::string text = ReadBytes(out);
  // --short prints one message per line.
  EXPECT_EQ(CountOccurrences(text, "\n"), 2 + batches + frames.size()) << text.substr(0, 300);
  EXPECT_EQ(text.rfind("(header = (formatVersion = 5, producer = \"raycell test\"", 0), 0u);
  // The 27 footprints 7, 1007, 2007, ... in one record of 27 runs of one cell.
  EXPECT_EQ(CountOccurrences(text, "\n(footprints = (firstCell = 0, values = (narrow = [7, 255, "),
            1u);
  EXPECT_EQ(CountOccurrences(text, "\n(batch = (frame = "), batches);
  EXPECT_EQ(CountOccurrences(text, "\n(frameEnd = (frame = "), frames.size());
  EXPECT_EQ(batches, 1u + 9u + 0u + 3u);
  for (const std::string& f : {path, path + ".bin", out}) std::remove(f.c_str());
}

// A primary ray (id 0) with a reflection (1) and a shadow ray (2), and a second primary (3).
RayBatch HandMadeFrame() {
  RayBatch b(false);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 5, 7);
  b.AddVisit(CellId(5), 12, 0, 0);
  b.AddVisit(CellId(4), 30, 0, 0);
  b.AddVisit(CellId(1), 2, 0, 0);
  b.BeginRay(RayKind::kReflection, 0, 2, 5, 7);
  b.AddVisit(CellId(1), 3, 0, 0);
  b.BeginRay(RayKind::kShadow, 0, 1, 5, 7);
  b.AddVisit(CellId(4), 300, 0, 0);
  b.AddVisit(CellId(26), 0, 0, 0);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 70000, 8);
  return b;
}

const char kHandMadeJsonl[] =
    R"({"id":0,"parent":null,"spawn":null,"kind":"primary","pixel":[5,7],"cells":[5,4,1],"samples":[12,30,2]}
{"id":1,"parent":0,"spawn":2,"kind":"reflection","pixel":[5,7],"cells":[1],"samples":[3]}
{"id":2,"parent":0,"spawn":1,"kind":"shadow","pixel":[5,7],"cells":[4,26],"samples":[300,0]}
{"id":3,"parent":null,"spawn":null,"kind":"primary","pixel":[70000,8],"cells":[],"samples":[]}
)";

TEST(TraceIoTest, JsonlOfAHandMadeFrameIsExact) {
  const std::string path = TempPath("jsonl.rct");
  WriteTrace(path, TestHeader({3, 3, 3}, false), {{150, HandMadeFrame()}});
  const TraceReader reader = TraceReader::Open(path);
  std::ostringstream all, one;
  WriteJsonl(reader, std::nullopt, all);
  WriteJsonl(reader, 0, one);
  EXPECT_EQ(all.str(), kHandMadeJsonl);
  EXPECT_EQ(one.str(), kHandMadeJsonl);
  std::remove(path.c_str());
}

TEST(TraceIoTest, JsonlOfSeveralFramesStartsWithTheFrameNumber) {
  const std::string path = TempPath("jsonl2.rct");
  WriteTrace(path, TestHeader({3, 3, 3}, false), {{150, HandMadeFrame()}, {151, HandMadeFrame()}});
  const TraceReader reader = TraceReader::Open(path);
  std::ostringstream all, second;
  WriteJsonl(reader, std::nullopt, all);
  WriteJsonl(reader, 1, second);
  EXPECT_EQ(second.str(), kHandMadeJsonl);
  const std::string text = all.str();
  EXPECT_EQ(CountOccurrences(text, "\n"), 8u);
  EXPECT_EQ(text.rfind("{\"frame\":150,\"id\":0,\"parent\":null,", 0), 0u);
  EXPECT_NE(
      text.find("\n{\"frame\":151,\"id\":3,\"parent\":null,\"spawn\":null,\"kind\":\"primary\""),
      std::string::npos);
  std::remove(path.c_str());
}

TEST(TraceIoTest, PrintInfoShowsHeaderFramesAndTotals) {
  const std::string path = TempPath("info.rct");
  WriteTrace(path, TestHeader({3, 3, 3}, false), RandomFrames(false, 10));
  const TraceReader reader = TraceReader::Open(path);
  std::ostringstream out;
  PrintInfo(reader, "info.rct", out);
  const std::string text = out.str();
  for (const char* want : {"format version: 5", "producer:       raycell test", "builtin:smoke",
                           "density (fog, builtin", "3x3x3 = 27 cells", "sparse", "320x200",
                           "shadow", "refraction", "total", "naive uncompressed", "ratio:"}) {
    EXPECT_NE(text.find(want), std::string::npos) << want << "\n" << text;
  }
  for (const char* row :
       {"\n      10 ", "\n      11 ", "\n      12 ", "\n      13 ", "\n   total "}) {
    EXPECT_EQ(CountOccurrences(text, row), 1u) << row << "\n" << text;
  }
  std::remove(path.c_str());
}

TEST(TraceIoTest, FileWithoutFrames) {
  const std::string path = TempPath("no_frames.rct");
  WriteTrace(path, TestHeader({3, 3, 3}, true), {});
  const TraceReader reader = TraceReader::Open(path);
  EXPECT_EQ(reader.warning(), "");
  EXPECT_EQ(reader.header(), TestHeader({3, 3, 3}, true));
  EXPECT_TRUE(reader.frames().empty());
  std::ostringstream out;
  WriteJsonl(reader, std::nullopt, out);
  EXPECT_EQ(out.str(), "");
  std::remove(path.c_str());
}

TEST(TraceIoTest, ErrorsNameTheFile) {
  const std::string path = TempPath("does_not_exist.rct");
  try {
    TraceReader::Open(path);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ": cannot open", 0), 0u) << e.what();
  }
  EXPECT_THROW(TraceWriter::Create(TempPath("no_such_dir/x.rct"), TestHeader({3, 3, 3}, false)),
               InputError);
  const std::string ok = TempPath("errors.rct");
  WriteTrace(ok, TestHeader({3, 3, 3}, false), RandomFrames(false, 11));
  const TraceReader reader = TraceReader::Open(ok);
  EXPECT_THROW(reader.LoadFrame(4), InputError);
  std::remove(ok.c_str());
}

// ---- The encoding of sibling rays --------------------------------------------------------

// A primary ray (pixel (5, 7), cells 4, 5, 13) and the 50 shadow rays it casts, as a
// renderer emits them: spawned at visits 0 (20 rays), 1 (20) and 2 (10), one path per spawn
// visit, samples equal within a spawn group except for ray 30.
RayBatch SiblingFrame() {
  RayBatch b(false);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 5, 7);
  b.AddVisit(CellId(4), 30, 0, 0);
  b.AddVisit(CellId(5), 31, 0, 0);
  b.AddVisit(CellId(13), 29, 0, 0);
  for (int i = 1; i <= 50; ++i) {
    const std::uint32_t spawn = i <= 20 ? 0 : i <= 40 ? 1 : 2;
    b.BeginRay(RayKind::kShadow, 0, spawn, 5, 7);
    if (spawn == 0) {
      b.AddVisit(CellId(4), 6, 0, 0);
      b.AddVisit(CellId(1), 3, 0, 0);
    } else if (spawn == 1) {
      b.AddVisit(CellId(5), i == 30 ? 10 : 9, 0, 0);
    } else {
      b.AddVisit(CellId(13), 2, 0, 0);
      b.AddVisit(CellId(12), 2, 0, 0);
    }
  }
  return b;
}

// The uncompressed messages of the frame at `offset`..`offset + length` of `path`.
kj::Array<capnp::word> FrameMessages(const std::string& path, const FrameSummary& s) {
  const std::string bytes = ReadBytes(path).substr(s.offset, s.length);
  ZSTD_DCtx* dctx = ZSTD_createDCtx();
  std::string out;
  ZSTD_inBuffer in{bytes.data(), bytes.size(), 0};
  std::vector<char> buffer(ZSTD_DStreamOutSize());
  std::size_t left = 1;
  while (left != 0 && in.pos < in.size) {
    ZSTD_outBuffer o{buffer.data(), buffer.size(), 0};
    left = ZSTD_decompressStream(dctx, &o, &in);
    RAYCELL_CHECK(!ZSTD_isError(left));
    out.append(buffer.data(), o.pos);
  }
  ZSTD_freeDCtx(dctx);
  auto words = kj::heapArray<capnp::word>(out.size() / sizeof(capnp::word));
  std::memcpy(words.begin(), out.data(), words.size() * sizeof(capnp::word));
  return words;
}

std::vector<std::uint64_t> Values(schema::Column::Reader c) {
  std::vector<std::uint64_t> v;
  unsigned wide = 0;
  for (std::uint8_t b : c.getNarrow()) v.push_back(b < 255 ? b : c.getWide()[wide++]);
  return v;
}

TEST(TraceIoTest, SiblingRaysEncodeToRunsOfEqualHeads) {
  const std::string path = TempPath("siblings.rct");
  const RayBatch frame = SiblingFrame();
  TraceWriterOptions options;
  options.format_version = 5;  // whose sample columns are checked below
  const std::vector<FrameSummary> written =
      WriteTrace(path, TestHeader({3, 3, 2}, false), {{0, frame}}, options);
  EXPECT_EQ(TraceReader::Open(path).LoadFrame(0), frame);

  const kj::Array<capnp::word> words = FrameMessages(path, written[0]);
  capnp::FlatArrayMessageReader message(words);
  const auto record = message.getRoot<schema::Record>();
  ASSERT_EQ(record.which(), schema::Record::BATCH);
  const auto batch = record.getBatch();
  // One parent: both reference rules code the batch alike, and the writer keeps the sibling
  // rule on a tie.
  EXPECT_EQ(batch.getReferenceRule(), kReferenceSibling);
  // Every shadow ray's parent is the last non-shadow ray (parent code 0), so no parent is
  // stored; a spawn is the previous sibling's (code 0) or one more (code 1); a sibling with
  // the previous sibling's cells stores no path; only the primary ray stores a pixel.
  const std::uint8_t same = Head(RayKind::kShadow, 0, 0, false, false);
  const std::uint8_t next_spawn = Head(RayKind::kShadow, 0, 1, true, false);
  std::vector<std::uint8_t> heads;
  for (std::uint8_t h : batch.getHeads()) heads.push_back(h);
  EXPECT_EQ(heads, (std::vector<std::uint8_t>{Head(RayKind::kPrimary, 0, 0, true, true),
                                              Head(RayKind::kShadow, 0, 0, true, false), same,
                                              next_spawn, same, next_spawn, same}));
  EXPECT_EQ(Values(batch.getHeadRuns()), (std::vector<std::uint64_t>{0, 0, 18, 0, 18, 0, 8}));
  EXPECT_TRUE(Values(batch.getParents()).empty());
  EXPECT_TRUE(Values(batch.getSpawns()).empty());
  EXPECT_EQ(Values(batch.getPixels()), (std::vector<std::uint64_t>{10, 14}));
  // Count, then per visit the step code (dx + 2) + 5 (dy + 2) + 25 (dz + 2) from the
  // previous cell, the first from the predicted cell: 0 for the primary ray, the parent's cell
  // at the spawn for the others. In the 3x3x2 grid cell 4 is (1,1,0), 5 (2,1,0), 13 (1,1,1),
  // 1 (1,0,0) and 12 (0,1,1).
  EXPECT_EQ(Values(batch.getPrimaryPaths()), (std::vector<std::uint64_t>{3, 68, 63, 86}));
  EXPECT_EQ(Values(batch.getSecondaryPaths()),
            (std::vector<std::uint64_t>{2, 62, 57, 1, 62, 2, 62, 61}));
  // Samples: residuals against the reference ray's (here the previous sibling's) visit of
  // the same cell (the samples themselves without one), r > 0 stored as r + 1, runs of n
  // zero residuals as n's digits in bijective base 2 (digit 1 -> 0, digit 2 -> 1), least
  // significant first. Shadow rays' samples are in their own column.
  EXPECT_EQ(Values(batch.getPrimarySamples()), (std::vector<std::uint64_t>{31, 32, 30}));
  EXPECT_TRUE(Values(batch.getSecondarySamples()).empty());
  EXPECT_EQ(Values(batch.getShadowSamples()),
            (std::vector<std::uint64_t>{
                7,  4,           // ray 1: 6, 3
                1,  1, 1, 0, 0,  // rays 2..20: 38 zeros = 2 + 2*2 + 2*4 + 1*8 + 1*16
                10,              // ray 21: 9 (ray 20 has no visit of cell 5)
                1,  0, 0,        // rays 22..29: 8 zeros = 2 + 1*2 + 1*4
                3,  2,           // rays 30 and 31: 10 (zigzag(1) = 2), 9 (zigzag(-1) = 1)
                0,  1, 0,        // rays 32..40: 9 zeros = 1 + 2*2 + 1*4
                3,  3,           // ray 41: 2, 2 (ray 40 visits neither 13 nor 12)
                1,  1, 0, 0,     // rays 42..50: 18 zeros = 2 + 2*2 + 1*4 + 1*8
            }));
  std::remove(path.c_str());
}

// Version 5 codes paths as steps in the grid, escaping those of more than 2 cells along an
// axis: random rays (whose consecutive visits jump anywhere) round trip on grids where most
// steps escape, on a flat grid (a regrouped trace's cells are numbered so) and on 2 cells.
TEST(TraceIoTest, RoundTripsOnAnyGridShape) {
  for (const std::array<std::uint32_t, 3> cells :
       {std::array<std::uint32_t, 3>{64, 64, 64}, {300, 1, 1}, {1, 7, 1}, {2, 1, 1}}) {
    SCOPED_TRACE(cells[0] * cells[1] * cells[2]);
    const std::string path = TempPath("grid.rct");
    std::mt19937_64 rng(cells[0] + cells[1]);
    const std::vector<Frame> frames = {
        {0, RandomFrame(rng, 3000, false, cells[0] * cells[1] * cells[2], 8)}};
    const std::vector<FrameSummary> written = WriteTrace(path, TestHeader(cells, false), frames);
    const TraceReader reader = TraceReader::Open(path);
    ASSERT_EQ(reader.frames().size(), 1u) << reader.warning();
    EXPECT_EQ(reader.frames()[0], written[0]);
    EXPECT_TRUE(reader.LoadFrame(0) == frames[0].rays);
    std::remove(path.c_str());
  }
}

// Two pixels, each a primary ray and shadow rays spawned along it; the second pixel's are
// the first's. Version 5 predicts a shadow ray from the corresponding ray of the previous
// pixel (same kind, parent kind and place among its siblings), so the second pixel stores
// no path and only zero residuals, though its rays differ from their previous siblings.
RayBatch TwoPixelsWithShadowRays() {
  RayBatch frame(false);
  for (std::uint32_t x = 0; x < 2; ++x) {
    const RayId primary = frame.size();
    frame.BeginRay(RayKind::kPrimary, kNoParent, 0, x, 0);
    frame.AddVisit(CellId(0), 10, 0, 0);
    frame.AddVisit(CellId(1), 10, 0, 0);
    frame.BeginRay(RayKind::kShadow, primary, 0, x, 0);
    frame.AddVisit(CellId(0), 5, 0, 0);
    frame.AddVisit(CellId(2), 7, 0, 0);
    frame.BeginRay(RayKind::kShadow, primary, 1, x, 0);
    frame.AddVisit(CellId(1), 4, 0, 0);
    frame.AddVisit(CellId(3), 9, 0, 0);
  }
  return frame;
}

// `frame` written in format `version` on a grid of `cells` (file NAME + version): checks that
// the file says that version and reads back the same rays, removes it, and returns the frame's
// messages as stored.
kj::Array<capnp::word> WrittenIn(const RayBatch& frame, std::array<std::uint32_t, 3> cells,
                                 std::uint32_t version, const std::string& name) {
  const std::string path = TempPath(name + std::to_string(version) + ".rct");
  TraceWriterOptions options;
  options.format_version = version;
  const std::vector<FrameSummary> written =
      WriteTrace(path, TestHeader(cells, false), {{0, frame}}, options);
  const TraceReader reader = TraceReader::Open(path);
  EXPECT_EQ(reader.header().format_version, version);
  EXPECT_TRUE(reader.LoadFrame(0) == frame);
  kj::Array<capnp::word> words = FrameMessages(path, written[0]);
  std::remove(path.c_str());
  return words;
}

kj::Array<capnp::word> TwoPixelsWrittenIn(std::uint32_t version) {
  return WrittenIn(TwoPixelsWithShadowRays(), {2, 2, 1}, version, "corresponding");
}

// Format 5, as the previous writer wrote it (options.format_version = 5): every column as
// trace.capnp describes it for version 5.
TEST(TraceIoTest, RaysArePredictedFromTheCorrespondingRayOfThePreviousPixel) {
  const kj::Array<capnp::word> words = TwoPixelsWrittenIn(5);
  capnp::FlatArrayMessageReader message(words);
  const auto batch = message.getRoot<schema::Record>().getBatch();
  // The corresponding rule, which codes the batch in fewer bytes than the sibling rule.
  EXPECT_EQ(batch.getReferenceRule(), kReferenceCorresponding);
  // Rays 1 and 2 only (ray 4's and 5's paths are those of rays 1 and 2): 2 visits, from the
  // parent's cell at the spawn (0, then 1) step (0,0,0) = 62, then (0,+1,0) = 67.
  EXPECT_EQ(Values(batch.getSecondaryPaths()), (std::vector<std::uint64_t>{2, 62, 67, 2, 62, 67}));
  // Ray 1: 5, 7 (no reference); ray 2: 4, 9 (its reference, ray 1, visits neither cell 1
  // nor 3); rays 4 and 5: 4 zeros (= 2 + 1*2: digits 2, 1 -> 1, 0).
  EXPECT_EQ(Values(batch.getShadowSamples()), (std::vector<std::uint64_t>{6, 8, 5, 10, 1, 0}));
  // The second primary ray repeats the first's path, with zero residuals.
  EXPECT_EQ(Values(batch.getPrimaryPaths()), (std::vector<std::uint64_t>{2, 62, 63}));
  EXPECT_EQ(Values(batch.getPrimarySamples()), (std::vector<std::uint64_t>{11, 11, 1}));
  EXPECT_EQ(batch.getSampleCode().size(), 0u);
}

// Format 6 codes the same rays with the same references and paths, but every visit's sample
// value in Batch.sampleCode (range coded), the three sample columns empty.
TEST(TraceIoTest, Format6RangeCodesTheSamples) {
  const kj::Array<capnp::word> words = TwoPixelsWrittenIn(6);
  capnp::FlatArrayMessageReader message(words);
  const auto batch = message.getRoot<schema::Record>().getBatch();
  EXPECT_EQ(batch.getReferenceRule(), kReferenceCorresponding);
  EXPECT_EQ(Values(batch.getSecondaryPaths()), (std::vector<std::uint64_t>{2, 62, 67, 2, 62, 67}));
  EXPECT_EQ(Values(batch.getPrimaryPaths()), (std::vector<std::uint64_t>{2, 62, 63}));
  EXPECT_EQ(batch.getPrimarySamples().getNarrow().size(), 0u);
  EXPECT_EQ(batch.getSecondarySamples().getNarrow().size(), 0u);
  EXPECT_EQ(batch.getShadowSamples().getNarrow().size(), 0u);
  // 12 values: a range code of at least 5 bytes (its flush), far fewer than 12 values' bytes.
  EXPECT_GE(batch.getSampleCode().size(), 5u);
  EXPECT_LE(batch.getSampleCode().size(), 12u);
}

// Primary rays alternating between two paths that share no cell, each cell's samples always
// the same (and large): a ray's reference (the previous primary ray) never visits its cells,
// so format 6 codes every visit's samples whole; format 7 finds them in its visit table (the
// same cell entered and left by the same steps) and codes zero residuals.
TEST(TraceIoTest, Format7PredictsSamplesFromTheVisitTable) {
  RayBatch frame(false);
  const std::vector<std::vector<std::uint32_t>> paths = {{0, 1, 2}, {48, 52}};
  for (std::uint32_t x = 0; x < 400; ++x) {
    frame.BeginRay(RayKind::kPrimary, kNoParent, 0, x, 0);
    for (const std::uint32_t cell : paths[x % 2])
      frame.AddVisit(CellId(cell), 1000 + 37 * cell, 0, 0);
  }
  std::size_t code_bytes[2] = {0, 0};
  for (const std::uint32_t version : {6u, 7u}) {
    SCOPED_TRACE(version);
    const kj::Array<capnp::word> words = WrittenIn(frame, {4, 4, 4}, version, "table");
    capnp::FlatArrayMessageReader message(words);
    const auto batch = message.getRoot<schema::Record>().getBatch();
    EXPECT_EQ(batch.getVisitTable(), version == 7);  // the smaller code
    code_bytes[version - 6] = batch.getSampleCode().size();
  }
  // 1000 values of 10 bits or more: format 6 stores their low bits as they are (over 600
  // bytes); format 7 only the first ray of each path's (about 10 bytes) and 998 zeros.
  EXPECT_GT(code_bytes[0], 600u);
  EXPECT_LT(code_bytes[1], 60u);
}

// Primary rays alternating between two paths that share no cell: each ray's reference (the
// previous primary ray) took the other path, so every ray has a new path. Format 7 writes each
// in primaryPaths (its visit count and a step code per visit); format 8 predicts each step and
// each end from the path table (the last ray that left the same cell entered the same way)
// and codes nearly every prediction's "held" in a small fraction of a bit.
TEST(TraceIoTest, Format8PredictsPathsFromThePathTable) {
  RayBatch frame(false);
  const std::vector<std::vector<std::uint32_t>> paths = {{0, 1, 2, 6}, {16, 20, 21}};
  for (std::uint32_t x = 0; x < 400; ++x) {
    frame.BeginRay(RayKind::kPrimary, kNoParent, 0, x, 0);
    for (const std::uint32_t cell : paths[x % 2]) frame.AddVisit(CellId(cell), 5, 0, 0);
  }
  std::size_t path_bytes[2] = {0, 0};
  for (const std::uint32_t version : {7u, 8u}) {
    SCOPED_TRACE(version);
    const kj::Array<capnp::word> words = WrittenIn(frame, {4, 4, 4}, version, "paths");
    capnp::FlatArrayMessageReader message(words);
    const auto batch = message.getRoot<schema::Record>().getBatch();
    EXPECT_EQ(batch.getSecondaryPaths().getNarrow().size(), 0u);
    if (version == 7) {
      path_bytes[0] = batch.getPrimaryPaths().getNarrow().size();
      EXPECT_EQ(batch.getPathCode().size(), 0u);
    } else {
      EXPECT_EQ(batch.getPrimaryPaths().getNarrow().size(), 0u);
      path_bytes[1] = batch.getPathCode().size();
    }
  }
  // 400 new paths: format 7 (1 + 3.5) x 400 = 1800 bytes before zstd; format 8 about 2,000
  // predictions that hold and a few dozen symbols while its table fills.
  EXPECT_EQ(path_bytes[0], 1800u);
  EXPECT_LT(path_bytes[1], 60u);
}

// Random rays in a grid large enough that steps escape (more than 2 cells along an axis),
// secondary rays spawned anywhere along their parents, and paths of every length: what format 8
// reads is what was written, in batches small and large (a new table and models per batch).
TEST(TraceIoTest, Format8ReadsBackRandomPathsWithEscapes) {
  std::mt19937_64 rng(42);
  RayBatch frame(false);
  const std::uint32_t cells = 16 * 4 * 8;
  std::vector<std::uint32_t> counts;
  for (std::uint32_t i = 0; i < 3000; ++i) {
    // A secondary ray's parent is one of the 40 rays before it with a visit to spawn it from.
    const RayId back = i == 0 ? 0 : i - 1 - rng() % std::min<std::uint32_t>(i, 40);
    const bool primary = i == 0 || rng() % 3 == 0 || counts[back] == 0;
    const RayId parent = primary ? kNoParent : back;
    const std::uint32_t spawn = primary ? 0 : static_cast<std::uint32_t>(rng() % counts[back]);
    const auto kind = primary ? RayKind::kPrimary : static_cast<RayKind>(1 + rng() % 3);
    frame.BeginRay(kind, parent, spawn, i % 64, i / 64);
    const std::uint32_t n = static_cast<std::uint32_t>(rng() % 7);
    std::uint32_t cell = static_cast<std::uint32_t>(rng() % cells);
    for (std::uint32_t v = 0; v < n; ++v) {
      // Mostly neighbours, sometimes a jump anywhere (an escaped step).
      cell = rng() % 4 == 0 ? static_cast<std::uint32_t>(rng() % cells)
                            : (cell + (rng() % 2 ? 1 : 16)) % cells;
      frame.AddVisit(CellId(cell), static_cast<std::uint32_t>(rng() % 50), 0, 0);
    }
    counts.push_back(n);
  }
  for (const std::size_t batch_rays : {std::size_t{1}, std::size_t{7}, std::size_t{5000}}) {
    SCOPED_TRACE(batch_rays);
    const std::string path = TempPath("escapes8.rct");
    TraceWriterOptions options;
    options.format_version = 8;
    options.max_batch_rays = batch_rays;
    WriteTrace(path, TestHeader({16, 4, 8}, false), {{0, frame}}, options);
    const TraceReader reader = TraceReader::Open(path);
    EXPECT_EQ(reader.header().format_version, 8u);
    const RayBatch loaded = reader.LoadFrame(0);
    EXPECT_TRUE(loaded == frame);
    EXPECT_EQ(loaded.cells(), frame.cells());
    std::remove(path.c_str());
  }
}

}  // namespace
}  // namespace raycell
