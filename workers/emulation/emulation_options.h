#pragma once
// Knobs of the emulated clock (`--clock emulated`, docs/design.md, "Time: two clocks") that are not part of an
// episode spec: where the host calibration is, and what tests need to provoke fallbacks.

#include <sys/types.h>

#include <cstdint>
#include <functional>
#include <string>

#include "workers/board/host_calibration.h"

namespace enavi::emulation {

struct EmulationOptions {
  /// Host calibration file; empty: board::CalibrationPath() ($ENAVI_CALIBRATION, XDG state dir).
  std::string calibration_file;
  /// Make each worker thread a SCHED_DEADLINE speed server (runtime = speed / k x period). When
  /// false, or when the kernel refuses, the per-thread cgroup quota does the speed emulation.
  bool sched_deadline = true;
  /// SCHED_DEADLINE speed server period. A server hands out its budget up front, so a job of C
  /// CPU seconds ends up to (1 - rate) x period before C / rate: 2 ms keeps that under ~1 ms
  /// (10 ms made 25 ms planning jobs finish ~6 % early); the kernel enforces DL budgets with
  /// hrtimers, accurate to < 1 % at 3 ms (bench throttle --deadline).
  std::int64_t server_period_us = 2'000;
  std::int64_t cfs_period_us = 20'000;     ///< CFS bandwidth period of the cgroup quotas
  /// How far (wall time) the simulator may run ahead of the navstack, so that a frame is
  /// rendered before its capture time and handed over exactly at it (rendering a 640 x 480
  /// frame takes ~7 ms here). Plans that land later than their start time reach the
  /// controller up to this late; those landing earlier (the usual case) are unaffected.
  std::int64_t lead_us = 20'000;
  /// A frame is handed over this much (wall time) before its capture time x k: the navstack
  /// copies it (~0.3 ms) and takes its lock before applying it, and a job released at the
  /// capture instant (perception at f_sen) must find it there, as on the virtual clock.
  std::int64_t frame_early_us = 2'000;
  /// Run the simulator's paced threads SCHED_FIFO (priority 1) during the episode, so other
  /// load on the host cannot make it miss its schedule (falls back to SCHED_OTHER if refused).
  bool simulator_fifo = true;
  /// How long an episode waits for host CPUs that other emulated episodes hold before admission
  /// is refused, wall seconds (0: refused at once). A farm worker's episodes wait (several
  /// emulated episodes on one host take turns); `enavi fly` does not.
  double admission_wait_s = 0;
  /// Episode cpuset ("0-1"); empty: all of the worker's CPUs. A cpuset narrower than the root
  /// domain makes the kernel refuse SCHED_DEADLINE (EPERM): the fallback path.
  std::string cpus;
  /// Called with the navstack process id once it runs inside its cgroup.
  std::function<void(pid_t)> on_navstack_started;
  /// Measures this host's speed against the reference core now, per CPU (board::ProbeHostSpeed),
  /// before the episode starts; empty: no probe, the calibration's speed stands. Supplied by the command
  /// that runs the episode: the probe flies episodes, and this library sits below them.
  std::function<board::SpeedProbe()> probe_host_speed;
  /// Divide the board by the probed speed (the calibration's, moved by the probe's drift) rather
  /// than the calibration's: the board then is as fast as its profile says on the host as it is
  /// now, give or take the probe's own scatter (a few per cent here, and now and then a probe 35 %
  /// low: workers/board/EMULATION.md). false: the probe only reports the drift (and warns beyond
  /// board::kSpeedDriftWarning). Set by the runner from the episode spec's `speed_probe`.
  bool use_probed_speed = false;
};

}  // namespace enavi::emulation
