#include "engine/event.h"

namespace raycell {

std::string Event::ToString() const {
  return "t=" + time.ToString() + " prio=" + std::to_string(priority) +
         " seq=" + std::to_string(seq) + " target=" + std::to_string(target) +
         " kind=" + std::to_string(kind) + " payload=" + std::to_string(payload);
}

}  // namespace raycell
