// CPU time, for benchmarks on a shared machine: it counts only the time the code ran, where
// wall time also counts the other processes' turns.
#pragma once

#include <ctime>

#include "base/check.h"

namespace raycell {

// Seconds of CPU time of `clock` (CLOCK_THREAD_CPUTIME_ID, CLOCK_PROCESS_CPUTIME_ID).
inline double CpuSeconds(clockid_t clock) {
  timespec t{};
  RAYCELL_CHECK(clock_gettime(clock, &t) == 0);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
// Of the calling thread.
inline double ThreadCpuSeconds() { return CpuSeconds(CLOCK_THREAD_CPUTIME_ID); }
// Of the whole process, every thread.
inline double ProcessCpuSeconds() { return CpuSeconds(CLOCK_PROCESS_CPUTIME_ID); }

}  // namespace raycell
