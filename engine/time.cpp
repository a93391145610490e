#include "engine/time.h"

#include <cmath>
#include <sstream>

namespace raycell {

std::optional<SimTime> SimTime::TryFromSeconds(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return std::nullopt;
  const double ps = std::nearbyint(seconds * double(kPsPerS));
  // 2^64 is exactly representable; every double below it converts to uint64 exactly.
  if (!(ps < 18446744073709551616.0)) return std::nullopt;
  return SimTime(std::uint64_t(ps));
}

SimTime SimTime::FromSeconds(double seconds) {
  const std::optional<SimTime> t = TryFromSeconds(seconds);
  if (!t) {
    std::ostringstream v;
    v << "(seconds = " << seconds << ")";
    detail::CheckFailed("SimTime::FromSeconds: finite, >= 0 and < 2^64 ps", __FILE__, __LINE__,
                        v.str());
  }
  return *t;
}

}  // namespace raycell
