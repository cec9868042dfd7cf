#pragma once
// Throttle benchmark core (`enavi bench throttle --board B --json`): does the cgroup emulation
// of board B slow a fixed CPU-bound workload down by what the board's numbers say?
//
// Workload: W units of a register-only integer + floating-point loop per thread, W sized so
// one unthrottled host thread needs `work_seconds` of CPU. Reference: that CPU time, measured
// on one thread of an unthrottled child process (median of `reference_repeats`; CPU time, not
// wall time, so other load on the host does not shrink the expected figure). Emulated run:
// T threads, each doing the same W units, in a child process placed in the board's groups,
// each thread in its own per-core group. Per thread:
//   measured_slowdown = wall time of the thread / reference
//   expected_slowdown = 1 / min(speed / k, cores x speed / (k T), host_cpus / T)
// The primary phase runs one thread per board core (T = cores): every thread is held to one
// board core's speed and together they use the board's whole capacity, so both caps are
// exercised; expected = k / speed. The extra phases run T = 1 (per-core speed alone) and
// T = 2 x cores (the board cap binds: expected = 2 k / speed).

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "workers/emulation/board_quota.h"
#include "workers/emulation/cgroup_manager.h"

namespace enavi::bench {

struct ThrottleBenchOptions {
  /// k; 0 = the smallest that fits the board into the host's free CPUs (MinimumDilation).
  double dilation = 0.0;
  std::int64_t period_us = 20'000;
  /// Host CPU seconds of work per thread. The emulated run takes work_seconds x slowdown.
  double work_seconds = 1.0;
  int reference_repeats = 3;
  /// Also run the single-thread and the oversubscribed (2 x cores threads) phases.
  bool extra_phases = true;
  /// Hold each thread to one board core with a SCHED_DEADLINE speed server (runtime =
  /// speed / k x period) instead of a per-thread cgroup quota; see workers/board/EMULATION.md.
  bool deadline_servers = false;
  emulation::CgroupOptions cgroup;
};

struct ThrottlePhase {
  std::string name;
  int threads = 0;
  double expected_slowdown = 0.0;
  double measured_slowdown = 0.0;  ///< mean over threads
  double relative_error = 0.0;     ///< measured / expected - 1
  double max_thread_error = 0.0;   ///< worst single thread, signed
  double mean_wall_s = 0.0;
  double makespan_s = 0.0;
  double mean_cpu_s = 0.0;         ///< CPU each thread used (vs the reference: cost inflation)
  std::int64_t nr_throttled = 0;   ///< periods in which the board group was throttled
  std::vector<double> thread_wall_s;
  std::string note;                ///< e.g. why SCHED_DEADLINE was refused
};

struct ThrottleBenchResult {
  bool ok = false;
  std::string message;  ///< why it could not run (no cgroups, admission refused, ...)
  std::string board;
  emulation::BoardQuota quota;
  double host_cpus = 0.0;
  std::int64_t work_units = 0;
  double reference_cpu_s = 0.0;
  double reference_wall_s = 0.0;
  // The primary phase (one thread per board core).
  double expected_slowdown = 0.0;
  double measured_slowdown = 0.0;
  double relative_error = 0.0;
  std::vector<ThrottlePhase> phases;
  std::string mode;  ///< "cgroup" or "deadline"
};

/// Runs the benchmark for `board` (id for the report, cores and per-core speed relative to this
/// host). Throws std::invalid_argument for out-of-range numbers (see ComputeBoardQuota);
/// returns ok = false with a message when the host cannot emulate (no writable cgroup
/// hierarchy, admission refused).
ThrottleBenchResult RunThrottleBench(const std::string& board_id, const emulation::BoardCpu& board,
                                     const ThrottleBenchOptions& options = {});

nlohmann::json ToJson(const ThrottleBenchResult& result);

/// The fixed workload: `units` iterations of the reference loop; returns a value that depends
/// on every iteration (so it cannot be optimised away).
std::uint64_t ThrottleWorkload(std::int64_t units);

}  // namespace enavi::bench
