// The trace format's constants, shared by the writer and the reader (docs/design.md §3; the format
// itself is documented field by field in traces/trace.capnp): the format version, magic
// numbers, the layout of a ray's head byte, and every limit of the format. A limit here is
// what the reader accepts; the writer refuses, up front and with a message naming the limit,
// whatever the reader could not read.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace raycell {

struct TraceHeader;

// ---- Version and magic numbers -----------------------------------------------------------

// The format version this code writes (Header.formatVersion); it reads 1..this. Version 2
// moved the footprints out of the header message into `footprints` records (so that grids
// of millions of cells fit); version 3 added the camera path (Header.path) that the cameras
// are a range of; version 4 the regroupable capture (Header.regroupable, its leaves) and the
// subdivision of a regrouped trace (Header.subdivision); version 5 a new batch encoding (rays
// predicted from the corresponding ray of the previous group, paths as cell steps, shadow
// rays' samples in their own column); version 6 the samples range coded under contexts
// (Batch.sampleCode, traces/sample_coder.h); version 7 those samples also predicted from the
// batch's last visit of the cell entered and left by the same steps (VisitTable); version 8 new
// paths range coded too, each step predicted from the reference ray and the batch's earlier rays
// through the cell (Batch.pathCode, traces/path_coder.h); see trace.capnp.
inline constexpr std::uint32_t kTraceFormatVersion = 8;
// The version written unless another is asked for (TraceWriterOptions::format_version, `record
// --trace-format`): 5. Format 6's files are about a sixth smaller, but reading them takes about
// a quarter more CPU (a Max Work replay at 1920x1080, 512 cells: +22-27%; BENCHMARKS.md "Trace
// size"), and a capture is written once and read by every replay.
inline constexpr std::uint32_t kTraceDefaultVersion = 5;
// Magic of the skippable zstd frame that holds the index.
inline constexpr std::uint32_t kTraceIndexMagic = 0x184D2A5B;
// Last 8 bytes of a complete trace file.
inline constexpr char kTraceIndexTag[9] = "RCTINDEX";
// Trailer after the index message: hash, message length, tag.
inline constexpr std::size_t kTraceTrailerBytes = 24;

// ---- Limits ------------------------------------------------------------------------------

// Largest Cap'n Proto message the reader accepts, and the writer ever writes.
inline constexpr std::size_t kTraceMaxMessageBytes = std::size_t{64} << 20;
// Highest zstd level the writer accepts (keeps the window within kTraceMaxWindowLog).
inline constexpr int kTraceMaxZstdLevel = 19;
inline constexpr int kTraceMaxWindowLog = 25;
// Most rays and visits in one batch message, and visits of one ray (see "Limits" in
// trace.capnp). They bound the reader's memory whatever the file says.
inline constexpr std::size_t kTraceMaxBatchRays = std::size_t{1} << 22;
inline constexpr std::size_t kTraceMaxBatchVisits = std::size_t{1} << 25;
inline constexpr std::size_t kTraceMaxRayVisits = std::size_t{1} << 20;
// Rays per batch the writer writes by default (TraceWriterOptions::max_batch_rays): 65536 in
// formats 5 and earlier; 2^18 in the range-coded formats (6 to 8), whose models start anew in
// every batch, so that they learn over more values (docs/design.md §3; at 1920x1080 and 512
// cells perforated's format 8 0.259 -> 0.249 bytes per visit). Either way a batch also ends at
// 2^20 visits, which bounds a batch's memory as before.
inline constexpr std::size_t kTraceBatchRays = 65536;
inline constexpr std::size_t kTraceCodedBatchRays = std::size_t{1} << 18;

// The largest cell grid: nx*ny*nz at most 2^24 cells (256x256x256; any shape, e.g.
// 4096x4096x1). Its footprints take 128 MiB in memory (8 bytes per cell) in every program
// that opens the trace, and up to 16 footprint records in the file.
inline constexpr std::uint64_t kTraceMaxCells = std::uint64_t{1} << 24;
// Runs of equal footprints per `footprints` record (at most 18 MiB per message).
inline constexpr std::size_t kTraceFootprintRunsPerRecord = std::size_t{1} << 20;
// A regroupable capture's leaves: at most 2^26 leaves and 2^27 (cell, leaf) pairs (512 MiB
// in memory), in cellLeaves records of at most 2^20 cells and 2^22 pairs each.
inline constexpr std::uint64_t kTraceMaxLeaves = std::uint64_t{1} << 26;
inline constexpr std::uint64_t kTraceMaxLeafRefs = std::uint64_t{1} << 27;
inline constexpr std::size_t kTraceLeafCellsPerRecord = std::size_t{1} << 20;
inline constexpr std::size_t kTraceLeafRefsPerRecord = std::size_t{1} << 22;
// Most boxes of a regrouped trace's subdivision (cells, times frames for a dynamic one), so
// that the header message stays below 64 MiB.
inline constexpr std::size_t kTraceMaxBoxes = std::size_t{1} << 20;
// Most frames in a file: cameras in the header and entries in the index (each message then
// stays below 30 MiB).
inline constexpr std::size_t kTraceMaxFrames = std::size_t{1} << 18;
// Most grids in the header, and bytes in each text field (producer, scene, footprint mode,
// grid names, roles and sources; the scene is a path, at most PATH_MAX).
inline constexpr std::size_t kTraceMaxGrids = 1024;
inline constexpr std::size_t kTraceMaxTextBytes = 4096;

// nx*ny*nz without overflow.
constexpr std::uint64_t TraceCellCount(const std::array<std::uint32_t, 3>& cells) {
  return std::uint64_t{cells[0]} * cells[1] * cells[2];
}
// Why a cell grid cannot be stored (every dimension at least 1, at most kTraceMaxCells
// cells), e.g. "cell grid 1000x1000x1000 = 1000000000 cells exceeds the trace format's limit
// of 16777216 cells (kTraceMaxCells, e.g. 256x256x256)"; empty when it can.
std::string TraceCellGridProblem(const std::array<std::uint32_t, 3>& cells);
// Why a header cannot be stored: its cell grid, more than kTraceMaxFrames cameras or
// kTraceMaxGrids grids, a text longer than kTraceMaxTextBytes; empty when it can. (The
// writer also requires one footprint per cell, a caller's invariant.)
std::string TraceHeaderProblem(const TraceHeader& header);
// Throws InputError "WHAT: PROBLEM" when TraceCellGridProblem is not empty: the up-front
// check of a --cells option, e.g. CheckTraceCellGrid(cells, "--cells '1000x1000x1000'").
void CheckTraceCellGrid(const std::array<std::uint32_t, 3>& cells, const std::string& what);

// ---- Ray head byte (see "Ray heads" in trace.capnp) --------------------------------------

inline constexpr unsigned kHeadKindMask = 0x03;
inline constexpr unsigned kHeadParentShift = 2;  // 2-bit parent code
inline constexpr unsigned kHeadSpawnShift = 4;   // 2-bit spawn code
inline constexpr unsigned kHeadNewPath = 0x40;
inline constexpr unsigned kHeadNewPixel = 0x80;
inline constexpr unsigned kParentIsLastNonShadow = 0;
inline constexpr unsigned kParentOfPreviousRay = 1;
inline constexpr unsigned kParentExplicit = 2;
inline constexpr unsigned kSpawnExplicit = 3;
// Version 5: a visit's samples are predicted from the reference ray's visit of the same cell,
// searched at most this many visits from the one after the last matched (see "Samples").
inline constexpr std::size_t kSampleMatchWindow = 4;
// Version 5: Batch.referenceRule, how a ray that is not primary finds its reference ray.
inline constexpr unsigned kReferenceSibling = 0;
inline constexpr unsigned kReferenceCorresponding = 1;

}  // namespace raycell
