// Fuzz target: a trace file's bytes opened (header, index or scan) and every frame decoded
// and verified. Bad bytes must give an InputError, never a crash, a leak or a hang; a frame
// that decodes must agree with its summary (the reader checks it).
#include "traces/trace_reader.h"

#include <cstdint>
#include <sstream>
#include <string>

#include "base/check.h"
#include "traces/trace_inspect.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace raycell;
  try {
    const TraceReader reader =
        TraceReader::OpenBytes(std::string(reinterpret_cast<const char*>(data), size), "fuzz.rct");
    RAYCELL_CHECK_LE(reader.readable_end(), reader.file_size());
    for (std::size_t i = 0; i < reader.frames().size(); ++i) {
      const FrameSummary& expected = reader.frames()[i];
      std::uint64_t rays = 0, visits = 0;
      try {
        reader.ForEachBatch(i, [&](const RayBatch& b) {
          RAYCELL_CHECK_EQ(b.first_id(), rays);
          rays += b.size();
          visits += b.visit_count();
        });
      } catch (const InputError&) {
        continue;
      }
      RAYCELL_CHECK_EQ(rays, expected.rays);
      RAYCELL_CHECK_EQ(visits, expected.visits);
    }
    std::ostringstream info;
    PrintInfo(reader, "fuzz.rct", info);
  } catch (const InputError&) {
  }
  return 0;
}
