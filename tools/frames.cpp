#include "tools/frames.h"

#include "base/check.h"
#include "base/parse.h"

namespace raycell {

std::vector<std::size_t> SelectFrameRange(const TraceReader& r, const std::string& range) {
  std::vector<std::size_t> out;
  const std::vector<int> wanted = range.empty() ? std::vector<int>{} : ParseFrameRange(range);
  for (std::size_t i = 0; i < r.frames().size(); ++i) {
    const int f = r.frames()[i].frame;
    if (range.empty() || (f >= wanted.front() && f <= wanted.back())) out.push_back(i);
  }
  if (out.empty()) throw InputError(r.path() + ": no frame in --frames " + range);
  return out;
}

}  // namespace raycell
