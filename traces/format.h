// The trace format's constants, shared by the writer and the reader (DESIGN.md §3; the format
// itself is documented field by field in traces/trace.capnp): the format version, magic
// numbers, the layout of a ray's head byte, and every limit of the format. A limit here is
// what the reader accepts; the writer refuses, up front and with a message naming the limit,
// whatever the reader could not read.
#pragma once

#include <cstddef>
#include <cstdint>

namespace raycell {

// ---- Version and magic numbers -----------------------------------------------------------

// The format version this code writes (Header.formatVersion); it reads 1..this.
inline constexpr std::uint32_t kTraceFormatVersion = 1;
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

}  // namespace raycell
