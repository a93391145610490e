// The bytes of a trace file as the reader gets them (internal to traces/: TraceReader's
// parts, not for its users): the file read with pread or held in memory (FileIn), one zstd
// frame decompressed on demand with checks (ZstdFrameReader, on per-thread pooled contexts),
// and one Cap'n Proto message of standard framing read from it, within the format's limits
// (ReadMessage). Bad bytes are BadTraceData, which Guarded turns into an InputError naming
// the file and the part of it.
#pragma once

#include <capnp/message.h>
#include <kj/array.h>
#include <kj/exception.h>
#ifndef ZSTD_STATIC_LINKING_ONLY
#define ZSTD_STATIC_LINKING_ONLY  // ZSTD_getFrameHeader, ZSTD_FRAMEHEADERSIZE_MAX
#endif
#include <zstd.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/check.h"
#include "traces/columns.h"

namespace raycell {
namespace trace_io {

// Bad bytes found while decoding; turned into an InputError naming the file and the part
// of it (header, frame, index) by Guarded() below.
using BadData = BadTraceData;

inline std::string Str(std::uint64_t v) { return std::to_string(v); }

// Runs `body`, turning BadData and Cap'n Proto exceptions into an InputError that starts
// with "<path>: <where()>: ".
template <typename Where, typename Body>
auto Guarded(const std::string& path, Where&& where, Body&& body) {
  try {
    return body();
  } catch (const BadData& e) {
    throw InputError(path + ": " + where() + ": " + e.what());
  } catch (const kj::Exception& e) {
    throw InputError(path + ": " + where() + ": malformed message: " + e.getDescription().cStr());
  }
}

// The file's bytes, read with pread from a file or copied from memory.
class FileIn {
 public:
  // InputError when the file cannot be opened or stat'ed.
  explicit FileIn(const std::string& path);
  // Reads `bytes` instead of a file.
  explicit FileIn(std::string&& bytes);
  FileIn(const FileIn&) = delete;
  FileIn& operator=(const FileIn&) = delete;
  ~FileIn();

  std::uint64_t size() const { return size_; }

  // Reads exactly `n` bytes at `offset`; BadData when the file is shorter.
  void ReadAt(std::uint64_t offset, void* dst, std::size_t n) const;

  // The bytes held in memory, moved out (the object reads nothing after).
  std::string TakeMemory() { return std::move(memory_); }

  std::uint32_t U32At(std::uint64_t offset) const {
    unsigned char b[4];
    ReadAt(offset, b, 4);
    return std::uint32_t{b[0]} | std::uint32_t{b[1]} << 8 | std::uint32_t{b[2]} << 16 |
           std::uint32_t{b[3]} << 24;
  }

 private:
  int fd_ = -1;
  std::string memory_;
  std::uint64_t size_ = 0;
};

// The little-endian uint64 at `b`.
std::uint64_t LoadU64(const unsigned char* b);

// One zstd frame of a file, from `offset` to at most `end`, decompressed as it is read.
class ZstdFrameReader {
 public:
  // BadData when no zstd frame starts at `offset`.
  ZstdFrameReader(const FileIn& file, std::uint64_t offset, std::uint64_t end);
  ZstdFrameReader(const ZstdFrameReader&) = delete;
  ZstdFrameReader& operator=(const ZstdFrameReader&) = delete;
  ~ZstdFrameReader();

  // Reads up to `n` bytes; fewer only when the zstd frame ends (its checksum then verified).
  std::size_t Read(void* dst, std::size_t n) {
    ZSTD_outBuffer out{dst, n, 0};
    while (out.pos < out.size && !done_) Step(out);
    return out.pos;
  }
  bool done() const { return done_; }
  // Compressed bytes of the frame; valid once done().
  std::uint64_t consumed() const { return next_ - (in_.size - in_.pos) - start_; }

 private:
  void Step(ZSTD_outBuffer& out) {
    const std::size_t out_before = out.pos, in_before = in_.pos;
    const std::size_t r = ZSTD_decompressStream(dctx_, &out, &in_);
    if (ZSTD_isError(r)) throw BadData(std::string("zstd: ") + ZSTD_getErrorName(r));
    if (r == 0) {
      done_ = true;
    } else if (in_.pos == in_.size && out.pos == out_before) {
      Refill();
    } else if (in_.pos == in_before && out.pos == out_before) {
      throw BadData("zstd: no progress");
    }
  }

  void Refill();

  const FileIn& file_;
  std::uint64_t start_, next_, end_;
  ZSTD_DCtx* dctx_ = nullptr;
  std::vector<char> buffer_;
  ZSTD_inBuffer in_{nullptr, 0, 0};
  bool done_ = false;
};

// The reader's limits on a message: kTraceMaxMessageBytes in all, nesting 16.
capnp::ReaderOptions MessageOptions();

// Reads one message in standard framing into `words`; returns false at the end of the zstd
// frame. BadData when the frame ends inside it or it exceeds the limits.
bool ReadMessage(ZstdFrameReader& in, kj::Array<capnp::word>& words);

}  // namespace trace_io
}  // namespace raycell
