#include "traces/trace_regroup.h"

#include <filesystem>
#include <system_error>

#include "base/check.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {

RegroupSummary RegroupTrace(const std::string& in, const std::string& spec,
                            const std::string& out) {
  std::error_code ec;
  if (std::filesystem::equivalent(in, out, ec)) {
    throw InputError("--out " + out + ": is the input; write the regrouped trace elsewhere");
  }
  const TraceReader stored = TraceReader::OpenStored(in);
  if (!stored.header().regroupable) {
    throw InputError(in + ": not a regroupable capture (record it with `raycell record " +
                     "--regroupable` on a fine grid, e.g. --cells 12x12x12 --regroupable)");
  }
  if (!stored.warning().empty()) {
    throw InputError(in + ": incomplete or damaged (" + stored.warning() + "); regroup a " +
                     "complete capture (`raycell trace verify` says what is wrong)");
  }
  const TraceReader reader = TraceReader::Open(in, spec.empty() ? std::string() : spec);
  TraceWriterOptions options;
  options.name_at_finish = true;
  // The input's format where it can be written (5 and later), else the default.
  if (reader.header().format_version >= 5) options.format_version = reader.header().format_version;
  TraceWriter writer = TraceWriter::Create(out, reader.header(), options);
  RegroupSummary sum;
  sum.cells = reader.header().cell_count();
  for (std::size_t i = 0; i < reader.frames().size(); ++i) {
    writer.BeginFrame(reader.frames()[i].frame);
    reader.ForEachBatch(i, [&](const RayBatch& b) { writer.Append(b); });
    const FrameSummary s = writer.EndFrame();
    RAYCELL_CHECK(s == reader.frames()[i]);
    ++sum.frames;
    sum.fine_visits += stored.frames()[i].visits;
    sum.visits += s.visits;
    sum.rays += s.rays;
  }
  writer.Finish();
  sum.bytes = std::filesystem::file_size(out);
  return sum;
}

}  // namespace raycell
