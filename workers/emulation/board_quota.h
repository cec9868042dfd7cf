#pragma once
// Quota arithmetic of the emulated clock (docs/design.md, "Time: two clocks"): how much host CPU a board gets,
// as a whole and per thread, so that both the board's capacity AND its per-core speed are
// emulated.
//
//   board group  : quota = cores x speed / k host CPUs   (capacity of the whole board)
//   thread group : quota = speed / k host CPUs           (one thread never outruns a board core)
//
// speed = board per-core speed / host per-core speed, k = dilation (1 sim second = k wall
// seconds). A single-threaded job on a board with many slow cores is slowed by k / speed, not
// by k / (cores x speed): the thread cap, not the board cap, binds it.

#include <cstdint>

namespace enavi::emulation {

/// The CPU of a board as the emulation needs it.
struct BoardCpu {
  int cores = 1;            ///< board cores, >= 1
  /// Board per-core speed / host per-core speed, > 0. A board core faster than the host's
  /// (> 1) is emulated by dilating time: one thread gets speed / dilation of a host core, so
  /// the dilation must be at least the speed.
  double core_speed = 1.0;
};

struct QuotaOptions {
  double dilation = 1.0;  ///< k >= 1: 1 sim second = k wall seconds
  /// CFS bandwidth period, microseconds, [1000, 1000000]. Short periods keep the throttled
  /// thread close to a fluid rate (a 10 ms job is not held back for a whole 100 ms period), but
  /// at 5 ms the kernel (HZ 250 here) loses ~15 % of the quota; 20 ms is within ~5 % on every
  /// board measured (bench_throttle_sweep, workers/board/EMULATION.md).
  std::int64_t period_us = 20'000;
};

/// Quotas of one emulated board, rounded to what the kernel is given.
struct BoardQuota {
  int cores = 1;
  double core_speed = 1.0;
  double dilation = 1.0;
  std::int64_t period_us = 20'000;
  std::int64_t board_quota_us = 0;  ///< per period, for the board group
  std::int64_t core_quota_us = 0;   ///< per period, for each thread group

  /// Host CPUs the board may use: board_quota_us / period_us (~ cores x speed / k).
  double BoardCpus() const { return static_cast<double>(board_quota_us) / period_us; }
  /// Rate of one thread, host CPUs: core_quota_us / period_us (~ speed / k).
  double CoreCpus() const { return static_cast<double>(core_quota_us) / period_us; }
};

/// Smallest quota the kernel accepts (cpu.cfs_quota_us and cpu.max), microseconds.
inline constexpr std::int64_t kMinQuotaUs = 1000;

/// Quotas for `board` under `options`. Throws std::invalid_argument (message names the field,
/// the value and the allowed range) for cores < 1, a speed that is not > 0, dilation < 1 or
/// below the speed, a period outside [1000, 1000000] us, or a per-thread quota below kMinQuotaUs.
BoardQuota ComputeBoardQuota(const BoardCpu& board, const QuotaOptions& options);

/// Smallest dilation k >= 1 at which the whole board fits in `host_cpus_free` host CPUs
/// (cores x speed / k <= host_cpus_free) and one board core in one host core (k >= speed),
/// rounded up to a multiple of 0.25 so it reads well in a job spec. Throws std::invalid_argument for a non-positive host_cpus_free.
double MinimumDilation(const BoardCpu& board, double host_cpus_free);

/// Expected slowdown (emulated wall time / unthrottled wall time of one thread alone on a host
/// core) of each of `threads` identical CPU-bound threads on the emulated board, fluid model:
///   rate = min(core_cpus, board_cpus / threads, host_cpus / threads),  slowdown = 1 / rate.
/// With threads <= cores and the board fitting the host this is k / speed.
double ExpectedSlowdown(const BoardQuota& quota, int threads, double host_cpus);

/// Converts a utilisation measured on the host during emulation (percent of one HOST core over
/// wall time, e.g. from /proc) into the figure the board would report (percent of one BOARD
/// core over board time): x k / speed. A thread busy all the time is held at speed / k of a
/// host core, i.e. 100 % of a board core.
double HostToBoardPercent(double host_percent, const BoardQuota& quota);

}  // namespace enavi::emulation
