#include "base/file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <utility>

#include "base/check.h"

namespace raycell {
namespace {

std::string Name(const std::string& path, const std::string& what) {
  return what.empty() ? path : what;
}

// Removes the temporary when the write did not finish.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::string path) : path_(std::move(path)) {}
  ~TemporaryFile() {
    if (!path_.empty()) std::remove(path_.c_str());
  }
  const std::string& path() const { return path_; }
  void Release() { path_.clear(); }

 private:
  std::string path_;
};

}  // namespace

void WriteFileAtomically(const std::string& path, std::string_view bytes, const std::string& what) {
  WriteFileAtomically(
      path, [&](std::ostream& out) { out.write(bytes.data(), std::streamsize(bytes.size())); },
      what);
}

void WriteFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                         const std::string& what) {
  TemporaryFile tmp(path + ".tmp");
  {
    std::ofstream out(tmp.path(), std::ios::binary | std::ios::trunc);
    if (!out) {
      throw InputError(Name(path, what) + ": cannot open " + tmp.path() +
                       " for writing: " + std::strerror(errno));
    }
    write(out);
    if (!out.flush())
      throw InputError(Name(path, what) + ": write failed: " + std::strerror(errno));
  }
  RenameFile(tmp.path(), path, what);
  tmp.Release();
}

bool ReadFile(const std::string& path, std::string* bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return false;  // opens, but reads nothing
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::string read(std::istreambuf_iterator<char>(in), {});
  if (in.bad()) return false;
  *bytes = std::move(read);
  return true;
}

void RenameFile(const std::string& from, const std::string& to, const std::string& what) {
  if (std::rename(from.c_str(), to.c_str()) != 0) {
    throw InputError(Name(to, what) + ": cannot rename " + from + " to " + to + ": " +
                     std::strerror(errno));
  }
}

}  // namespace raycell
