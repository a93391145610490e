#include "traces/trace_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <utility>

#include "traces/format.h"

namespace raycell {
namespace trace_io {

// ---- Input file --------------------------------------------------------------------------

FileIn::FileIn(const std::string& path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw InputError(path + ": cannot open: " + std::strerror(errno));
  struct stat st;
  if (::fstat(fd_, &st) != 0) {
    const int error = errno;
    ::close(fd_);
    throw InputError(path + ": cannot stat: " + std::strerror(error));
  }
  size_ = static_cast<std::uint64_t>(st.st_size);
}

FileIn::FileIn(std::string&& bytes) : memory_(std::move(bytes)), size_(memory_.size()) {}

FileIn::~FileIn() {
  if (fd_ >= 0) ::close(fd_);
}

void FileIn::ReadAt(std::uint64_t offset, void* dst, std::size_t n) const {
  if (offset > size_ || n > size_ - offset) {
    throw BadData("truncated: needs bytes " + Str(offset) + ".." + Str(offset + n) +
                  " but the file has " + Str(size_));
  }
  if (fd_ < 0) {
    if (n > 0) std::memcpy(dst, memory_.data() + offset, n);
    return;
  }
  auto* p = static_cast<char*>(dst);
  while (n > 0) {
    const ssize_t got = ::pread(fd_, p, n, static_cast<off_t>(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) throw BadData(std::string("read failed: ") + std::strerror(errno));
    p += got;
    offset += static_cast<std::uint64_t>(got);
    n -= static_cast<std::size_t>(got);
  }
}

std::uint64_t LoadU64(const unsigned char* b) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = v << 8 | b[i];
  return v;
}

// ---- One zstd frame, decompressed on demand ----------------------------------------------

namespace {

// Decompression contexts kept per thread for reuse: creating one per frame costs a
// 100 KB allocation and, for each new frame, its window buffer again. A reader takes one
// (Acquire) and gives it back (Release), so nested readings on a thread each have their own.
class DCtxPool {
 public:
  static ZSTD_DCtx* Acquire() {
    std::vector<ZSTD_DCtx*>& free = Free().contexts;
    ZSTD_DCtx* dctx = nullptr;
    if (free.empty()) {
      dctx = ZSTD_createDCtx();
      RAYCELL_CHECK(dctx != nullptr);
    } else {
      dctx = free.back();
      free.pop_back();
      ZSTD_DCtx_reset(dctx, ZSTD_reset_session_and_parameters);
    }
    ZSTD_DCtx_setParameter(dctx, ZSTD_d_windowLogMax, kTraceMaxWindowLog);
    return dctx;
  }
  static void Release(ZSTD_DCtx* dctx) {
    std::vector<ZSTD_DCtx*>& free = Free().contexts;
    if (free.size() < kKept) {
      free.push_back(dctx);
    } else {
      ZSTD_freeDCtx(dctx);
    }
  }

 private:
  static constexpr std::size_t kKept = 4;
  struct List {
    std::vector<ZSTD_DCtx*> contexts;
    ~List() {
      for (ZSTD_DCtx* d : contexts) ZSTD_freeDCtx(d);
    }
  };
  static List& Free() {
    thread_local List list;
    return list;
  }
};

}  // namespace

ZstdFrameReader::ZstdFrameReader(const FileIn& file, std::uint64_t offset, std::uint64_t end)
    : file_(file), start_(offset), next_(offset), end_(std::min(end, file.size())) {
  if (file.U32At(offset) != ZSTD_MAGICNUMBER) {
    throw BadData("no zstd frame starts at offset " + Str(offset));
  }
  // No larger than the bytes there are to read (small frames are common).
  buffer_.resize(
      static_cast<std::size_t>(std::min<std::uint64_t>(ZSTD_DStreamInSize(), end_ - offset)));
  dctx_ = DCtxPool::Acquire();
}

ZstdFrameReader::~ZstdFrameReader() { DCtxPool::Release(dctx_); }

void ZstdFrameReader::Refill() {
  const std::size_t n =
      static_cast<std::size_t>(std::min<std::uint64_t>(buffer_.size(), end_ - next_));
  if (n == 0 && end_ == file_.size()) {
    throw BadData("truncated: the file ends at byte " + Str(end_) + " inside the zstd frame");
  }
  if (n == 0) throw BadData("the zstd frame runs past its end at byte " + Str(end_));
  file_.ReadAt(next_, buffer_.data(), n);
  next_ += n;
  in_ = ZSTD_inBuffer{buffer_.data(), n, 0};
}

// ---- Messages ----------------------------------------------------------------------------

namespace {

constexpr std::size_t kMaxSegments = 512;

void ReadExactly(ZstdFrameReader& in, void* dst, std::size_t n, const char* what) {
  if (in.Read(dst, n) != n) throw BadData(std::string("zstd frame ends inside ") + what);
}

}  // namespace

capnp::ReaderOptions MessageOptions() {
  capnp::ReaderOptions options;
  options.traversalLimitInWords = kTraceMaxMessageBytes / sizeof(capnp::word);
  options.nestingLimit = 16;
  return options;
}

bool ReadMessage(ZstdFrameReader& in, kj::Array<capnp::word>& words) {
  std::uint32_t first[2];
  const std::size_t got = in.Read(first, 4);
  if (got == 0) return false;
  if (got != 4) throw BadData("zstd frame ends inside a message's segment table");
  const std::size_t segments = std::size_t{first[0]} + 1;
  if (segments > kMaxSegments) throw BadData("message has " + Str(segments) + " segments");
  const std::size_t table_words = segments / 2 + 1;
  std::vector<std::uint32_t> table(table_words * 2);
  table[0] = first[0];
  ReadExactly(in, table.data() + 1, table.size() * 4 - 4, "a segment table");
  std::uint64_t body_words = 0;
  for (std::size_t s = 0; s < segments; ++s) body_words += table[1 + s];
  if (body_words * 8 > kTraceMaxMessageBytes) {
    throw BadData("message of " + Str(body_words * 8) + " bytes exceeds the limit");
  }
  words = kj::heapArray<capnp::word>(table_words + body_words);
  kj::byte* bytes = words.asBytes().begin();
  std::memcpy(bytes, table.data(), table_words * 8);
  ReadExactly(in, bytes + table_words * 8, body_words * 8, "a message");
  return true;
}

}  // namespace trace_io
}  // namespace raycell
