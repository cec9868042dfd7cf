#pragma once
// Knobs of the emulated clock (`--clock emulated`, DESIGN.md section 4) that are not part of an
// episode spec: where the host calibration is, and what tests need to provoke fallbacks.

#include <sys/types.h>

#include <cstdint>
#include <functional>
#include <string>

namespace enavi::sim {

struct EmulationOptions {
  /// Host calibration file; empty: board::CalibrationPath() ($ENAVI_CALIBRATION, XDG state dir).
  std::string calibration_file;
  /// Make each worker thread a SCHED_DEADLINE speed server (runtime = speed / k x period). When
  /// false, or when the kernel refuses, the per-thread cgroup quota does the speed emulation.
  bool sched_deadline = true;
  std::int64_t server_period_us = 10'000;  ///< SCHED_DEADLINE speed server period
  std::int64_t cfs_period_us = 20'000;     ///< CFS bandwidth period of the cgroup quotas
  /// Episode cpuset ("0-1"); empty: all of the worker's CPUs. A cpuset narrower than the root
  /// domain makes the kernel refuse SCHED_DEADLINE (EPERM): the fallback path.
  std::string cpus;
  /// Called with the navstack process id once it runs inside its cgroup.
  std::function<void(pid_t)> on_navstack_started;
};

}  // namespace enavi::sim
