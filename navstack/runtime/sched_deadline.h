#pragma once
// Linux real-time scheduling for the navstack's periodic tasks (docs/design.md, "Time: two clocks", emulated
// clock): SCHED_DEADLINE through sched_setattr(2) with a fallback to SCHED_OTHER. The emulated
// clock's RealtimeExecutor puts each of its worker threads (one board core) under a speed server.
//
// Findings on how SCHED_DEADLINE meets CFS bandwidth control and cpusets, with the experiment
// that shows each one, are in workers/board/EMULATION.md.

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace enavi::navstack {

/// SCHED_DEADLINE reservation of a thread (CBS server): at most `runtime` of CPU time in every
/// `period`, to be delivered within `deadline` of each activation. All in nanoseconds.
struct DeadlineParams {
  std::int64_t runtime_ns = 0;
  std::int64_t deadline_ns = 0;
  std::int64_t period_ns = 0;
  std::uint64_t flags = 0;  ///< SCHED_FLAG_* (e.g. SCHED_FLAG_RECLAIM); 0 = hard reservation
};

/// A hard CPU-rate reservation: runtime = rate x period, deadline = period. With the default
/// (non-reclaiming) flags the kernel throttles the thread as soon as its budget is spent, even
/// on an idle CPU, so a thread under it runs at `rate` of a host core: the emulated clock uses
/// it as one board core of relative speed s under dilation k (rate = s / k).
/// Throws std::invalid_argument unless 0 < rate <= 1 and server_period_ns >= 100 us.
DeadlineParams SpeedServerParams(double rate, std::int64_t server_period_ns = 10'000'000);

/// Scheduling attributes of a thread as the kernel reports them (sched_getattr).
struct SchedAttr {
  int policy = 0;  ///< SCHED_OTHER = 0, SCHED_FIFO = 1, SCHED_RR = 2, SCHED_DEADLINE = 6 ...
  int nice = 0;
  int priority = 0;
  std::uint64_t flags = 0;
  std::int64_t runtime_ns = 0;
  std::int64_t deadline_ns = 0;
  std::int64_t period_ns = 0;
};

/// Reads the attributes of thread `tid` (0 = the calling thread); nullopt with errno set if the
/// kernel refuses (e.g. the thread does not exist).
std::optional<SchedAttr> GetSchedAttr(pid_t tid = 0);

struct DeadlineOptions {
  /// EBUSY from admission control can be transient: the bandwidth of a DL task that exited or
  /// left SCHED_DEADLINE is returned only at its 0-lag time. Retry this many times.
  int ebusy_retries = 5;
  std::chrono::milliseconds retry_delay{100};
};

/// Outcome of asking for SCHED_DEADLINE. `deadline` false means the thread runs SCHED_OTHER
/// (nice unchanged) and `reason` says why the kernel refused, in words a result can carry.
struct DeadlineResult {
  bool deadline = false;
  int error = 0;            ///< errno of the last refusal, 0 on success
  std::string reason;       ///< empty on success
  DeadlineParams params;    ///< what was asked for
};

/// Puts the calling thread under SCHED_DEADLINE with `params`. On refusal (EPERM: no
/// CAP_SYS_NICE or an affinity/cpuset narrower than the root domain; EBUSY: admission control;
/// EINVAL: parameters the kernel does not accept) the thread is left in (or returned to)
/// SCHED_OTHER and the result says why. Never throws for a refusal.
DeadlineResult EnterDeadline(const DeadlineParams& params, const DeadlineOptions& options = {});

/// Returns the calling thread to SCHED_OTHER, nice 0. False (errno set) if the kernel refuses.
bool EnterOther();

}  // namespace enavi::navstack
