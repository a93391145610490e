// A progress bar on stderr when it is a terminal; silent otherwise (pipes, CI, tests).
#pragma once

#include <chrono>
#include <string>

namespace raycell {

class Progress {
 public:
  // enabled: draw at all; the bar also stays quiet when stderr is not a terminal.
  explicit Progress(bool enabled = true);
  ~Progress();
  // fraction in [0, 1] of the whole job; label says what is being done.
  void Update(double fraction, const std::string& label);
  void Done();

 private:
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace raycell
