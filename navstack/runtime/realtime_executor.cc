#include "navstack/runtime/realtime_executor.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <shared_mutex>
#include <stdexcept>

#include "navstack/common/cpu_time.h"

namespace enavi::navstack {
namespace {

constexpr double kEps = 1e-9;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// JobLock

void JobLock::lock_shared() {
  std::unique_lock l(m_);
  readers_cv_.wait(l, [this] { return !writer_ && writers_waiting_ == 0; });
  ++readers_;
}

void JobLock::unlock_shared() {
  std::lock_guard l(m_);
  if (--readers_ == 0 && writers_waiting_ > 0) writers_cv_.notify_one();
}

void JobLock::lock() {
  std::unique_lock l(m_);
  ++writers_waiting_;
  writers_cv_.wait(l, [this] { return !writer_ && readers_ == 0; });
  --writers_waiting_;
  writer_ = true;
}

bool JobLock::try_lock() {
  std::lock_guard l(m_);
  if (writer_ || readers_ > 0 || writers_waiting_ > 0) return false;
  writer_ = true;
  return true;
}

void JobLock::unlock() {
  std::lock_guard l(m_);
  writer_ = false;
  if (writers_waiting_ > 0) {
    writers_cv_.notify_one();
  } else {
    readers_cv_.notify_all();
  }
}

// ---------------------------------------------------------------------------------------------
// RealtimeExecutor

RealtimeExecutor::RealtimeExecutor(RealtimeExecutorOptions options)
    : options_(std::move(options)), clock_(options_.clock) {
  if (options_.threads < 1)
    throw std::invalid_argument("RealtimeExecutor: threads must be >= 1, got " + std::to_string(options_.threads));
  if (!(options_.host_to_board > 0) || !std::isfinite(options_.host_to_board))
    throw std::invalid_argument("RealtimeExecutor: host_to_board must be > 0, got " +
                                std::to_string(options_.host_to_board));
  if (!clock_) {
    clock_ = std::make_shared<DilatedSteadyClock>(1.0);
    default_clock_ = true;
  }
  clock_->Listen(mutex_, release_cv_);
}

RealtimeExecutor::~RealtimeExecutor() {
  Stop();
  clock_->Unlisten(release_cv_);
}

double RealtimeExecutor::NowLocked() const {
  if (!started_) return 0.0;
  return std::max(0.0, clock_->Now());
}

double RealtimeExecutor::now() const {
  std::lock_guard l(mutex_);
  return NowLocked();
}

void RealtimeExecutor::Register(TaskId task, JobFn fn) {
  std::lock_guard l(mutex_);
  slots_[static_cast<int>(task)].fn = std::move(fn);
}

void RealtimeExecutor::SetRate(TaskId task, double hz) {
  std::lock_guard l(mutex_);
  Slot& s = slots_[static_cast<int>(task)];
  if (hz < 0) throw std::logic_error("RealtimeExecutor: negative rate for " + std::string(TaskName(task)));
  if (hz > 0 && !s.fn) throw std::logic_error("RealtimeExecutor: task not registered: " + std::string(TaskName(task)));
  if (hz == s.rate_hz) return;
  const bool was_stopped = s.rate_hz == 0;
  s.rate_hz = hz;
  if (hz == 0) return;
  // As the virtual clock: a stopped task starts now, a running one keeps its phase.
  const double now = NowLocked();
  s.next_release = (was_stopped || s.last_release < 0) ? now : std::max(now, s.last_release + 1.0 / hz);
  release_cv_.notify_all();
}

double RealtimeExecutor::rate(TaskId task) const {
  std::lock_guard l(mutex_);
  return slots_[static_cast<int>(task)].rate_hz;
}

void RealtimeExecutor::Trigger(TaskId task, double relative_deadline) {
  std::lock_guard l(mutex_);
  Slot& s = slots_[static_cast<int>(task)];
  if (!s.fn) throw std::logic_error("RealtimeExecutor: task not registered: " + std::string(TaskName(task)));
  if (s.job) {
    s.pending_trigger = s.pending_trigger ? std::min(*s.pending_trigger, relative_deadline) : relative_deadline;
    return;
  }
  ReleaseLocked(static_cast<int>(task), NowLocked(), relative_deadline);
  work_cv_.notify_all();
}

void RealtimeExecutor::ReleaseLocked(int task, double at, double relative_deadline) {
  Slot& s = slots_[task];
  ++s.stats.released;
  s.last_release = at;
  if (s.job) {  // overrun: the running (or still queued) job keeps its place, this release is dropped
    ++s.stats.skipped;
    return;
  }
  s.job = Job{at, at + relative_deadline, false};
}

int RealtimeExecutor::PickLocked() const {
  int best = -1;
  const bool fifo = options_.policy == SchedulingPolicy::kFifoNonPreemptive;
  for (int i = 0; i < kTaskCount; ++i) {
    const auto& job = slots_[i].job;
    if (!job || job->started) continue;
    if (best < 0) {
      best = i;
      continue;
    }
    const Job& b = *slots_[best].job;
    // Ties by release time, then task id (a strict order, as the virtual clock's).
    if (!fifo && job->deadline != b.deadline) {
      if (job->deadline < b.deadline) best = i;
      continue;
    }
    if (job->release < b.release) best = i;
  }
  return best;
}

void RealtimeExecutor::AdvanceTo(double t) {
  std::unique_lock l(mutex_);
  while (started_ && !stopping_ && NowLocked() < t) clock_->WaitUntil(release_cv_, l, t);
}

const TaskStats& RealtimeExecutor::stats(TaskId task) const {
  thread_local std::array<TaskStats, kTaskCount> copy;
  std::lock_guard l(mutex_);
  copy[static_cast<int>(task)] = slots_[static_cast<int>(task)].stats;
  return copy[static_cast<int>(task)];
}

std::array<std::int64_t, kTaskCount> RealtimeExecutor::ReleaseLags() const {
  std::array<std::int64_t, kTaskCount> out{};
  std::lock_guard l(mutex_);
  for (int i = 0; i < kTaskCount; ++i) out[i] = slots_[i].release_lags;
  return out;
}

std::array<double, kTaskCount> RealtimeExecutor::ExecutionWallSeconds() const {
  std::array<double, kTaskCount> out{};
  std::lock_guard l(mutex_);
  for (int i = 0; i < kTaskCount; ++i) out[i] = slots_[i].wall_s;
  return out;
}

std::array<TaskStats, kTaskCount> RealtimeExecutor::AllStats() const {
  std::array<TaskStats, kTaskCount> out;
  std::lock_guard l(mutex_);
  for (int i = 0; i < kTaskCount; ++i) out[i] = slots_[i].stats;
  return out;
}

bool RealtimeExecutor::active(TaskId task) const {
  std::lock_guard l(mutex_);
  return slots_[static_cast<int>(task)].job.has_value();
}

JobLockStats RealtimeExecutor::lock_stats() const {
  std::lock_guard l(mutex_);
  return lock_stats_;
}

std::string RealtimeExecutor::error() const {
  std::lock_guard l(mutex_);
  return error_;
}

std::vector<pid_t> RealtimeExecutor::WorkerTids() const {
  std::lock_guard l(mutex_);
  return worker_tids_;
}

pid_t RealtimeExecutor::ReleaseThreadTid() const {
  std::lock_guard l(mutex_);
  return release_tid_;
}

void RealtimeExecutor::Launch() {
  std::unique_lock l(mutex_);
  if (launched_) return;
  launched_ = true;
  worker_tids_.assign(static_cast<std::size_t>(options_.threads), 0);
  for (int i = 0; i < options_.threads; ++i) threads_.emplace_back([this, i] { WorkerLoop(i); });
  threads_.emplace_back([this] { ReleaseLoop(); });
  work_cv_.wait(l, [this] {
    return release_tid_ != 0 &&
           std::all_of(worker_tids_.begin(), worker_tids_.end(), [](pid_t t) { return t != 0; });
  });
}

void RealtimeExecutor::Start() {
  Launch();
  std::lock_guard l(mutex_);
  if (started_ || stopping_) return;
  if (default_clock_) static_cast<DilatedSteadyClock&>(*clock_).SetEpoch(Clock::now());
  started_ = true;
  release_cv_.notify_all();
  work_cv_.notify_all();
}

void RealtimeExecutor::Stop() {
  {
    std::lock_guard l(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  work_cv_.notify_all();
  release_cv_.notify_all();
  for (std::thread& t : threads_)
    if (t.joinable()) t.join();
  threads_.clear();
}

void RealtimeExecutor::Fail(const std::string& what) {
  std::lock_guard l(mutex_);
  if (error_.empty()) error_ = what;
}

void RealtimeExecutor::ReleaseLoop() {
  std::unique_lock l(mutex_);
  release_tid_ = static_cast<pid_t>(gettid());
  work_cv_.notify_all();
  while (!stopping_) {
    if (!started_) {
      release_cv_.wait(l);
      continue;
    }
    const double now = NowLocked();
    bool released = false;
    double earliest = std::numeric_limits<double>::infinity();
    for (int i = 0; i < kTaskCount; ++i) {
      Slot& s = slots_[i];
      // A late wake-up (a loaded host) finds several instants due. Those at which the task's
      // job was still active are skips, as on the virtual clock; those at which it was not are
      // this thread's lateness, not the task's misses: counted apart, and only the latest due
      // instant is released.
      while (s.rate_hz > 0 && s.next_release <= now + kEps) {
        const double period = 1.0 / s.rate_hz;
        const double at = s.next_release;
        s.next_release += period;
        if (s.next_release <= now + kEps && !s.job) {
          if (at < s.last_finish) {  // the previous job was still running then
            ++s.stats.released;
            ++s.stats.skipped;
            s.last_release = at;
          } else {
            ++s.release_lags;
          }
          continue;
        }
        ReleaseLocked(i, at, period);
        released = true;
      }
      if (s.rate_hz > 0) earliest = std::min(earliest, s.next_release);
    }
    if (released) work_cv_.notify_all();
    clock_->WaitUntil(release_cv_, l, earliest - kEps);  // due as above: within kEps
  }
}

void RealtimeExecutor::WorkerLoop(int worker) {
  if (options_.on_worker_start) {
    try {
      options_.on_worker_start(worker);
    } catch (const std::exception& e) {
      Fail(std::string("worker start hook: ") + e.what());
    }
  }
  std::unique_lock l(mutex_);
  worker_tids_[static_cast<std::size_t>(worker)] = static_cast<pid_t>(gettid());
  work_cv_.notify_all();
  while (true) {
    int task = -1;
    work_cv_.wait(l, [&] {
      if (stopping_) return true;
      if (!started_ || !error_.empty()) return false;
      task = PickLocked();
      return task >= 0;
    });
    if (stopping_) return;
    Slot& s = slots_[task];
    s.job->started = true;
    ++s.stats.started;
    JobFn fn = s.fn;
    l.unlock();

    double cpu = 0.0, wall = 0.0, elapsed = 0.0;
    bool ok = true;
    JobOutput out;
    try {
      std::shared_lock job(job_lock_);
      const auto wall0 = Clock::now();
      const double cpu0 = ThreadCpuSeconds();
      const double sim0 = clock_->Now();
      out = fn();
      if (out.awaits_decision)
        throw std::logic_error("a decision taken outside the stack stops the virtual clock only");
      cpu += ThreadCpuSeconds() - cpu0;
      wall += Seconds(Clock::now() - wall0);
      elapsed += clock_->Now() - sim0;
    } catch (const std::exception& e) {
      Fail(std::string(TaskName(static_cast<TaskId>(task))) + " job: " + e.what());
      ok = false;
    }

    auto finish = [&] {  // caller holds mutex_
      Slot& f = slots_[task];
      const Job job = *f.job;
      f.job.reset();
      ++f.stats.completed;
      f.last_finish = NowLocked();
      if (f.last_finish > job.deadline + kEps) ++f.stats.late;
      const double cost = options_.timing == JobTiming::kThreadCpu ? cpu * options_.host_to_board : elapsed;
      f.stats.busy_s += cost;
      f.stats.cost_sum_s += cost;
      f.stats.cost_max_s = std::max(f.stats.cost_max_s, cost);
      f.stats.cost_recent_s = f.stats.completed == 1 ? cost : 0.75 * f.stats.cost_recent_s + 0.25 * cost;
      f.stats.host_cpu_s += cpu;
      f.wall_s += wall;
      if (f.pending_trigger) {
        const double d = *f.pending_trigger;
        f.pending_trigger.reset();
        ReleaseLocked(task, NowLocked(), d);
      }
    };

    if (ok && out.commit) {
      const auto wait0 = Clock::now();
      std::unique_lock commit(job_lock_);
      const double waited = Seconds(Clock::now() - wait0);
      try {
        const auto wall0 = Clock::now();
        const double cpu0 = ThreadCpuSeconds();
        const double sim0 = clock_->Now();
        out.commit();
        cpu += ThreadCpuSeconds() - cpu0;
        wall += Seconds(Clock::now() - wall0);
        elapsed += clock_->Now() - sim0;
      } catch (const std::exception& e) {
        Fail(std::string(TaskName(static_cast<TaskId>(task))) + " commit: " + e.what());
      }
      {
        std::lock_guard g(mutex_);
        finish();
        ++lock_stats_.commits;
        lock_stats_.commit_wait_s += waited;
        lock_stats_.commit_wait_max_s = std::max(lock_stats_.commit_wait_max_s, waited);
      }
      // Outputs are published with the finish already counted, before any other writer runs.
      if (options_.after_commit) {
        try {
          options_.after_commit(static_cast<TaskId>(task));
        } catch (const std::exception& e) {
          Fail(std::string("after commit of ") + std::string(TaskName(static_cast<TaskId>(task))) + ": " + e.what());
        }
      }
      commit.unlock();
      if (ok && options_.observer) options_.observer(static_cast<TaskId>(task), out.work, cpu);
      l.lock();
    } else {
      if (ok && options_.observer) options_.observer(static_cast<TaskId>(task), out.work, cpu);
      l.lock();
      finish();
    }
    work_cv_.notify_all();
  }
}

}  // namespace enavi::navstack
