// JSON Lines, one ray per line: what `raycell trace cat` writes, and what `raycell analyze
// --paths` and `raycell trace import` read, from raycell or from any other ray tracer. The
// format, its defaults and the renumbering are documented for users in docs/jsonl.md.
//
// Written (exactly, no spaces, keys in this order):
//   {"frame":150,"id":7,"parent":3,"spawn":2,"kind":"reflection","pixel":[x,y],
//    "cells":[5,4,1],"samples":[12,30,2]}
// on one line; "frame" only when asked, "parent" and "spawn" null for primary rays.
//
// Read: keys in any order, lines in any order within a frame. Required: "id", "parent",
// "spawn", "cells"; optional: "frame", "kind", "pixel", "samples" (defaults below). The reader
// hands out one frame at a time as a RayBatch in the order CellTreeBuilder and TraceWriter
// need (one ray tree at a time, parents before children, ids 0..n-1), so that memory holds one
// frame, not the file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <istream>
#include <memory>
#include <optional>
#include <ostream>
#include <string>

#include "traces/format.h"
#include "traces/ray_batch.h"
#include "traces/trace_reader.h"

namespace raycell {

// ---- Writing --------------------------------------------------------------------------------

// Buffers lines (std::to_chars) and writes them to the stream in chunks of about 1 MiB.
class JsonlWriter {
 public:
  explicit JsonlWriter(std::ostream& out);
  JsonlWriter(const JsonlWriter&) = delete;
  JsonlWriter& operator=(const JsonlWriter&) = delete;
  ~JsonlWriter();  // flushes

  // One line; with `frame`, the line starts with "frame":N. t_enter/t_exit are not written.
  void Write(const RayView& ray, std::optional<std::int32_t> frame = std::nullopt);
  void Flush();

 private:
  JsonlWriter& Put(char c);
  JsonlWriter& Text(const char* s);
  template <typename T>
  JsonlWriter& Int(T v);
  JsonlWriter& List(const std::uint32_t* v, std::size_t n);
  JsonlWriter& List(const CellId* v, std::size_t n);

  std::ostream& out_;
  std::string buf_;
};

// `raycell trace cat`: with a frame index, that frame's rays without the "frame" key; without,
// every frame in file order, and when the file has more than one frame each line starts with
// its frame number. Ids are the trace's frame-local ids. Throws InputError for unreadable
// frames.
void WriteJsonl(const TraceReader& reader, std::optional<std::size_t> frame_index,
                std::ostream& out);

// ---- Reading --------------------------------------------------------------------------------

// What the reader does not take from the lines.
struct JsonlReadOptions {
  // When not 0: every cell must be < cell_count (a trace's cell grid); `cells_what` names it
  // in errors, e.g. "--cells 2x2x2". When 0, cells must be < kJsonlMaxCells.
  std::uint64_t cell_count = 0;
  std::string cells_what;
};

// The largest cell count the reader accepts without a grid: the trace format's
// (kTraceMaxCells, 2^24), which is also the most a Cell Tree holds.
inline constexpr std::uint64_t kJsonlMaxCells = kTraceMaxCells;

// One frame as read.
struct JsonlFrame {
  std::int32_t frame = 0;  // its "frame" key; 0 when the file has none
  // The frame's rays, first_id 0, no t. Order: ray trees by the id of their primary ray;
  // within a tree, repeatedly the smallest id among the rays whose parent is already placed
  // (so parents come before children, and a tree already in increasing-id order keeps it).
  // New ids are the positions 0, 1, 2, ... in that order.
  RayBatch rays{false};
  bool renumbered = false;  // some ray's new id differs from its id in the file
  std::size_t first_line = 0, last_line = 0;
};

// Reads frames one at a time. Defaults: "kind" is "primary" for a ray without parent and
// "reflection" for a spawned ray; "pixel" is [0,0] for a primary ray and the parent's pixel
// for a spawned ray; "samples" is 1 per visit. "frame": either every line has it or none
// does (then the file is one frame, numbered 0); the lines of one frame must be together, and
// a frame number may not come back later in the file.
//
// Every error is an InputError "NAME:LINE: what", naming the line of the offending ray:
// malformed JSON, unknown or duplicate keys, wrong types, integers out of range, a kind that
// contradicts "parent", "cells"/"samples" of different lengths, a cell repeated at
// consecutive visits, a cell out of range, duplicate ids, an unknown parent, a cycle of
// parents, a spawn index out of range of the parent's visits, a first cell that is not the
// parent's cell at the spawn visit. Blank lines are skipped.
class JsonlReader {
 public:
  JsonlReader(std::istream& in, std::string name, JsonlReadOptions options = {});
  JsonlReader(JsonlReader&&) noexcept;
  JsonlReader& operator=(JsonlReader&&) noexcept;
  ~JsonlReader();

  // The next frame, or false at the end of the input.
  bool Next(JsonlFrame& frame);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raycell
