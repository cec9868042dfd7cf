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

DeadlineParams PaperDeadlineParams(double frequency_hz, double wcet_s) {
  if (!(frequency_hz > 0.0) || !std::isfinite(frequency_hz)) {
    throw std::invalid_argument("PaperDeadlineParams: frequency_hz must be > 0, got " +
                                std::to_string(frequency_hz));
  }
  if (!(wcet_s > 0.0) || !std::isfinite(wcet_s)) {
    throw std::invalid_argument("PaperDeadlineParams: wcet_s must be > 0, got " +
                                std::to_string(wcet_s));
  }
  DeadlineParams p;
  p.period_ns = static_cast<std::int64_t>(std::llround(1e9 / frequency_hz));
  p.deadline_ns = p.period_ns;
  p.runtime_ns = static_cast<std::int64_t>(std::llround(wcet_s * 1e9));
  return p;
}

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

// ---------------------------------------------------------------------------------------------
// EdfReadyQueue

namespace {
std::int64_t ThreadCpuNs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// Heap comparator: true when a is less urgent than b (std heaps keep the "largest" on top).
bool LessUrgent(const ReadyJob& a, const ReadyJob& b) {
  if (a.deadline != b.deadline) return a.deadline > b.deadline;
  if (a.release != b.release) return a.release > b.release;
  return a.task > b.task;
}
}  // namespace

void EdfReadyQueue::Push(const ReadyJob& job) {
  heap_.push_back(job);
  std::push_heap(heap_.begin(), heap_.end(), LessUrgent);
}

std::optional<ReadyJob> EdfReadyQueue::Pop() {
  if (heap_.empty()) return std::nullopt;
  std::pop_heap(heap_.begin(), heap_.end(), LessUrgent);
  ReadyJob job = heap_.back();
  heap_.pop_back();
  return job;
}

// ---------------------------------------------------------------------------------------------
// EdfDispatcher

EdfDispatcher::EdfDispatcher(EdfDispatcherOptions options) : options_(std::move(options)) {
  if (options_.workers < 1) {
    throw std::invalid_argument("EdfDispatcher: workers must be >= 1, got " +
                                std::to_string(options_.workers));
  }
}

EdfDispatcher::~EdfDispatcher() { Stop(); }

int EdfDispatcher::AddTask(PeriodicTask task) {
  if (task.period.count() <= 0) {
    throw std::invalid_argument("EdfDispatcher::AddTask: task '" + task.name +
                                "' needs a period > 0");
  }
  if (task.relative_deadline.count() < 0 || task.relative_deadline > task.period) {
    throw std::invalid_argument("EdfDispatcher::AddTask: task '" + task.name +
                                "' needs 0 <= relative_deadline <= period");
  }
  if (!task.body) {
    throw std::invalid_argument("EdfDispatcher::AddTask: task '" + task.name + "' has no body");
  }
  std::lock_guard lock(mutex_);
  TaskState state;
  state.spec = std::move(task);
  if (running_) state.next_release = std::chrono::steady_clock::now() + state.spec.phase;
  tasks_.push_back(std::move(state));
  release_cv_.notify_all();
  return static_cast<int>(tasks_.size()) - 1;
}

void EdfDispatcher::SetPeriod(int task, std::chrono::nanoseconds period) {
  if (period.count() <= 0) {
    throw std::invalid_argument("EdfDispatcher::SetPeriod: period must be > 0");
  }
  std::lock_guard lock(mutex_);
  TaskState& t = tasks_.at(static_cast<std::size_t>(task));
  t.spec.period = period;
  t.spec.relative_deadline = std::chrono::nanoseconds{0};
  release_cv_.notify_all();
}

void EdfDispatcher::Start() {
  std::unique_lock lock(mutex_);
  if (running_ || stopping_) return;
  running_ = true;
  start_ = std::chrono::steady_clock::now();
  for (TaskState& t : tasks_) t.next_release = start_ + t.spec.phase;
  worker_tids_.assign(static_cast<std::size_t>(options_.workers), 0);
  for (int i = 0; i < options_.workers; ++i) {
    threads_.emplace_back([this, i] { WorkerLoop(i); });
  }
  // Start() returns once every worker has run its start hook and published its thread id.
  work_cv_.wait(lock, [this] {
    return std::all_of(worker_tids_.begin(), worker_tids_.end(), [](pid_t t) { return t != 0; });
  });
  threads_.emplace_back([this] { ReleaseLoop(); });
}

void EdfDispatcher::Stop() {
  {
    std::lock_guard lock(mutex_);
    if (!running_ || stopping_) return;
    stopping_ = true;
  }
  work_cv_.notify_all();
  release_cv_.notify_all();
  for (std::thread& t : threads_) t.join();
  threads_.clear();
}

PeriodicTaskStats EdfDispatcher::Stats(int task) const {
  std::lock_guard lock(mutex_);
  return tasks_.at(static_cast<std::size_t>(task)).stats;
}

std::vector<pid_t> EdfDispatcher::WorkerTids() const {
  std::lock_guard lock(mutex_);
  return worker_tids_;
}

void EdfDispatcher::ReleaseLoop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    const auto now = std::chrono::steady_clock::now();
    auto earliest = std::chrono::steady_clock::time_point::max();
    bool released = false;
    for (std::size_t i = 0; i < tasks_.size(); ++i) {
      TaskState& t = tasks_[i];
      while (t.next_release <= now) {
        // One job per task at a time: a release that finds its predecessor pending is skipped.
        if (t.pending) {
          ++t.stats.skipped;
        } else {
          const auto rel_deadline =
              t.spec.relative_deadline.count() > 0 ? t.spec.relative_deadline : t.spec.period;
          queue_.Push(ReadyJob{static_cast<int>(i), t.next_index, t.next_release,
                               t.next_release + rel_deadline});
          t.pending = true;
          ++t.stats.released;
          released = true;
        }
        ++t.next_index;
        t.next_release += t.spec.period;
      }
      earliest = std::min(earliest, t.next_release);
    }
    if (released) work_cv_.notify_all();
    if (earliest == std::chrono::steady_clock::time_point::max()) {
      release_cv_.wait(lock);
    } else {
      release_cv_.wait_until(lock, earliest);
    }
  }
}

void EdfDispatcher::WorkerLoop(int worker_index) {
  if (options_.on_worker_start) options_.on_worker_start(worker_index);
  std::unique_lock lock(mutex_);
  worker_tids_[static_cast<std::size_t>(worker_index)] = static_cast<pid_t>(gettid());
  work_cv_.notify_all();
  while (true) {
    work_cv_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
    if (stopping_) return;
    const ReadyJob job = *queue_.Pop();
    const PeriodicTask& spec = tasks_[static_cast<std::size_t>(job.task)].spec;
    auto body = spec.body;  // copy: AddTask may grow tasks_ while the job runs
    lock.unlock();
    const std::int64_t cpu0 = ThreadCpuNs();
    body(job);
    const std::int64_t cpu_used = ThreadCpuNs() - cpu0;
    const auto done = std::chrono::steady_clock::now();
    lock.lock();
    TaskState& t = tasks_[static_cast<std::size_t>(job.task)];
    t.pending = false;
    ++t.stats.completed;
    if (done > job.deadline) ++t.stats.missed;
    const auto response = std::chrono::duration_cast<std::chrono::nanoseconds>(done - job.release);
    t.stats.max_response = std::max(t.stats.max_response, response);
    t.stats.total_response += response;
    t.stats.cpu_time += std::chrono::nanoseconds(cpu_used);
  }
}

}  // namespace enavi::navstack
