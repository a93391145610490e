// Fuzz target: `raycell trace concat` of damaged inputs. The fuzzer's bytes are one or two
// trace files joined with a valid capture (fuzz/data/concat_frame0.rct: frame 0 of the
// built-in scene's orbit 3:90 at 8x8, 2x2x2 cells). Input layout: byte 0 even, the rest is
// one file (joined with the valid one); byte 0 odd, bytes 1-2 (little-endian, modulo the
// rest's length + 1) split the rest into two files (joined with the valid one between them).
// Properties: a refusal is an InputError and leaves neither OUT nor any other file beside
// the inputs; a join gives a complete trace (opened without warning) holding every input's
// frames, each of which passes ReadEncodedFrame, and consecutive cameras.
#include "traces/trace_concat.h"

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "base/check.h"
#include "traces/trace_reader.h"

namespace {

namespace fs = std::filesystem;

const fs::path& WorkDir() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() /
                       ("raycell_fuzz_concat_" + std::to_string(static_cast<long>(::getpid())));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

std::string Write(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::string path = (WorkDir() / name).string();
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

std::size_t FilesIn(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
  return n;
}

std::size_t FramesOf(const std::string& path) {
  return raycell::TraceReader::Open(path).frames().size();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace raycell;
  if (size < 1) return 0;
  const std::string valid = RAYCELL_FUZZ_DATA "/concat_frame0.rct";
  std::vector<std::string> inputs;
  if (data[0] % 2 == 0) {
    inputs = {valid, Write("a.rct", data + 1, size - 1)};
  } else {
    if (size < 3) return 0;
    const std::size_t rest = size - 3;
    const std::size_t split = (std::size_t{data[1]} | std::size_t{data[2]} << 8) % (rest + 1);
    inputs = {Write("a.rct", data + 3, split), valid,
              Write("b.rct", data + 3 + split, rest - split)};
  }
  const std::string out = (WorkDir() / "out.rct").string();
  const std::size_t files_before = FilesIn(WorkDir());
  RAYCELL_CHECK(!fs::exists(out));
  try {
    const ConcatSummary s = ConcatTraces(inputs, out);
    const TraceReader joined = TraceReader::Open(out);
    RAYCELL_CHECK(joined.warning().empty());
    std::size_t frames = 0;
    for (const std::string& in : inputs) frames += FramesOf(in);
    RAYCELL_CHECK_EQ(joined.frames().size(), frames);
    RAYCELL_CHECK_EQ(s.frames, frames);
    const auto& cameras = joined.header().cameras;
    RAYCELL_CHECK_EQ(cameras.size(), frames);
    for (std::size_t i = 0; i < frames; ++i) {
      RAYCELL_CHECK_EQ(std::int64_t{cameras[i].frame},
                       std::int64_t{cameras[0].frame} + static_cast<std::int64_t>(i));
      joined.ReadEncodedFrame(i);
    }
    fs::remove(out);
  } catch (const InputError&) {
    RAYCELL_CHECK(!fs::exists(out));
  }
  RAYCELL_CHECK_EQ(FilesIn(WorkDir()), files_before);
  return 0;
}
