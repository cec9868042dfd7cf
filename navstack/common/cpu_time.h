#pragma once
// CPU time of the calling thread: what measured cost mode, calibration and benchmarks time with
// (immune to other processes' load, unlike wall time).

#include <time.h>

namespace enavi::navstack {

inline double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace enavi::navstack
