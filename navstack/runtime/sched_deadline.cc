#include "navstack/runtime/sched_deadline.h"

#include <sched.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace enavi::navstack {
namespace {

// struct sched_attr of sched_setattr(2), defined here because glibc < 2.41 does not declare it.
// Layout of SCHED_ATTR_SIZE_VER1 (56 bytes), the version with utilisation clamps.
struct KernelSchedAttr {
  std::uint32_t size;
  std::uint32_t sched_policy;
  std::uint64_t sched_flags;
  std::int32_t sched_nice;
  std::uint32_t sched_priority;
  std::uint64_t sched_runtime;
  std::uint64_t sched_deadline;
  std::uint64_t sched_period;
  std::uint32_t sched_util_min;
  std::uint32_t sched_util_max;
};
static_assert(sizeof(KernelSchedAttr) == 56, "sched_attr layout VER1");

constexpr std::uint32_t kSchedOther = 0;
constexpr std::uint32_t kSchedDeadline = 6;

int SysSchedSetattr(pid_t tid, const KernelSchedAttr& attr) {
  return static_cast<int>(syscall(SYS_sched_setattr, tid, &attr, 0u));
}

int SysSchedGetattr(pid_t tid, KernelSchedAttr* attr) {
  return static_cast<int>(syscall(SYS_sched_getattr, tid, attr, sizeof(*attr), 0u));
}

std::string DescribeRefusal(int err, const DeadlineParams& p) {
  std::string params = "runtime " + std::to_string(p.runtime_ns) + " ns, deadline " +
                       std::to_string(p.deadline_ns) + " ns, period " +
                       std::to_string(p.period_ns) + " ns";
  switch (err) {
    case EPERM:
      return "SCHED_DEADLINE refused (EPERM): the thread lacks CAP_SYS_NICE (run as root), or "
             "its CPU affinity / cpuset does not span the whole root domain, or the root "
             "domain has no DL bandwidth (sched_rt_runtime_us = 0); running SCHED_OTHER";
    case EBUSY:
      return "SCHED_DEADLINE refused (EBUSY): admission control, the root domain's DL "
             "bandwidth (sched_rt_runtime_us / sched_rt_period_us x CPUs, minus the fair "
             "server's reservation) cannot fit " + params + "; running SCHED_OTHER";
    case EINVAL:
      return "SCHED_DEADLINE refused (EINVAL): the kernel needs 1024 ns <= runtime <= "
             "deadline <= period and a period within sched_deadline_period_{min,max}_us, got " +
             params + "; running SCHED_OTHER";
    case ENOSYS:
      return "SCHED_DEADLINE unavailable (ENOSYS): kernel without sched_setattr; running "
             "SCHED_OTHER";
    default:
      return "SCHED_DEADLINE refused (" + std::string(std::strerror(err)) + "), " + params +
             "; running SCHED_OTHER";
  }
}

}  // namespace

DeadlineParams SpeedServerParams(double rate, std::int64_t server_period_ns) {
  if (!(rate > 0.0 && rate <= 1.0)) {
    throw std::invalid_argument("SpeedServerParams: rate must be in (0, 1], got " +
                                std::to_string(rate));
  }
  if (server_period_ns < 100'000) {
    throw std::invalid_argument("SpeedServerParams: server_period_ns must be >= 100000 (the "
                                "kernel's sched_deadline_period_min_us), got " +
                                std::to_string(server_period_ns));
  }
  DeadlineParams p;
  p.period_ns = server_period_ns;
  p.deadline_ns = server_period_ns;
  p.runtime_ns = static_cast<std::int64_t>(std::llround(rate * static_cast<double>(server_period_ns)));
  return p;
}

std::optional<SchedAttr> GetSchedAttr(pid_t tid) {
  KernelSchedAttr raw{};
  if (SysSchedGetattr(tid, &raw) != 0) return std::nullopt;
  SchedAttr a;
  a.policy = static_cast<int>(raw.sched_policy);
  a.nice = raw.sched_nice;
  a.priority = static_cast<int>(raw.sched_priority);
  a.flags = raw.sched_flags;
  a.runtime_ns = static_cast<std::int64_t>(raw.sched_runtime);
  a.deadline_ns = static_cast<std::int64_t>(raw.sched_deadline);
  a.period_ns = static_cast<std::int64_t>(raw.sched_period);
  return a;
}

bool EnterOther() {
  KernelSchedAttr attr{};
  attr.size = sizeof(attr);
  attr.sched_policy = kSchedOther;
  return SysSchedSetattr(0, attr) == 0;
}

DeadlineResult EnterDeadline(const DeadlineParams& params, const DeadlineOptions& options) {
  DeadlineResult result;
  result.params = params;
  KernelSchedAttr attr{};
  attr.size = sizeof(attr);
  attr.sched_policy = kSchedDeadline;
  attr.sched_flags = params.flags;
  // Negative values would wrap to huge unsigned ones; let the kernel see them as 0 (EINVAL).
  attr.sched_runtime = static_cast<std::uint64_t>(std::max<std::int64_t>(params.runtime_ns, 0));
  attr.sched_deadline = static_cast<std::uint64_t>(std::max<std::int64_t>(params.deadline_ns, 0));
  attr.sched_period = static_cast<std::uint64_t>(std::max<std::int64_t>(params.period_ns, 0));

  for (int attempt = 0;; ++attempt) {
    if (SysSchedSetattr(0, attr) == 0) {
      result.deadline = true;
      return result;
    }
    result.error = errno;
    if (result.error != EBUSY || attempt >= options.ebusy_retries) break;
    std::this_thread::sleep_for(options.retry_delay);
  }
  result.reason = DescribeRefusal(result.error, params);
  // A refused change leaves the old policy in place; make sure the fallback really is
  // SCHED_OTHER (the thread may have been SCHED_DEADLINE with other parameters before).
  if (auto current = GetSchedAttr(0); current && current->policy != 0) {
    if (!EnterOther()) result.reason += " (and returning to SCHED_OTHER failed too)";
  }
  return result;
}

}  // namespace enavi::navstack
