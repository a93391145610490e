// Decoding what a trace file holds, with every check (internal to traces/: TraceReader's
// parts, not for its users; the format is documented in traces/trace.capnp): the header
// frame (the header converted from Cap'n Proto and checked against the format's limits, its
// footprints and a regroupable capture's leaves), and a frame's batches (FrameDecoder: parents,
// spawns, cells, columns, totals against the frame's summary and the index's). Bad bytes are
// BadTraceData inside; ReadFrame names the file and frame in its InputError.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "traces/ray_batch.h"
#include "traces/trace_file.h"
#include "traces/trace_header.h"

namespace raycell {
namespace trace_io {

using BatchFn = std::function<void(const RayBatch&)>;

// Decodes the header frame at offset 0; returns the header and sets `length` (the frame's
// compressed bytes). BadData when it is bad.
TraceHeader ReadHeader(const FileIn& file, std::uint64_t& length);

// Where a frame is and what is known of it before reading it.
struct FrameSlot {
  std::size_t ordinal;           // position among the file's frames (0 = first)
  std::uint64_t offset, end;     // bytes to read: the zstd frame starts at offset, ends <= end
  const FrameSummary* expected;  // from the index or an earlier scan; null when scanning
};

// "frame 150 (#3, offset 12345)", or "frame #3 (offset 12345)" before its number is known.
std::string FrameLabel(const FrameSlot& slot, std::optional<std::int32_t> number);

// Reads and verifies one frame, calling `fn` (if any) with each batch; returns its summary
// as decoded, with its offset and length. InputError "<path>: <FrameLabel>: ..." when bad.
FrameSummary ReadFrame(const FileIn& file, const std::string& path, const TraceHeader& header,
                       const FrameSlot& slot, const BatchFn* fn);

// Checks the stored zstd frame of `slot` (see TraceReader::ReadEncodedFrame) without decoding
// its rays; BadData when bad.
void CheckEncodedFrame(const FileIn& file, const FrameSlot& slot);

}  // namespace trace_io
}  // namespace raycell
