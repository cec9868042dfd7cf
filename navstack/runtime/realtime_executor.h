#pragma once
// The emulated clock's TaskExecutor (docs/design.md, "Time: two clocks"): the navigation stack's jobs run in
// real time on `threads` worker threads. Periodic and sporadic releases follow sim time, read
// from a TimeSource (time_source.h): wall time / dilation in the emulated clock's navstack
// process, ROS time in our ROS node (ros/node/); ready jobs are dispatched without preemption,
// earliest deadline first (global EDF over the workers) or first released first served (a ROS
// node's spinner). A job's code runs under the shared side of a JobLock, its commit (and everything
// else that writes the stack's state: frames, odometry) under the exclusive side, so a stack
// that is not thread-safe (NavStack) runs unchanged: jobs only read shared state, each writes
// only its own task's fields, and commits serialise.
//
// What a job costs is measured, not modelled (JobTiming): where the board's speed is known (the
// emulated clock's navstack process), its thread CPU time (CLOCK_THREAD_CPUTIME_ID, code +
// commit) times `host_to_board` (1 / the board's per-core speed relative to the host); where it
// is not (a ROS node, which sees only ROS time, as on a real board), the sim time its code and
// commit took. How fast a worker runs is not this class's business: the owner makes each worker
// thread one board core (a SCHED_DEADLINE speed server or a per-thread cgroup quota) in
// `on_worker_start`, or the board's cgroups do (the ROS bridge).

#include <sys/types.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "navstack/runtime/executor.h"
#include "navstack/runtime/time_source.h"
#include "navstack/runtime/virtual_executor.h"

namespace enavi::navstack {

/// Readers-writer lock with writer priority: once a writer waits, new readers wait too, so a
/// stream of overlapping jobs (readers) cannot starve a commit (writer). Meets the standard
/// Lockable and SharedLockable requirements (std::unique_lock / std::shared_lock).
class JobLock {
 public:
  void lock_shared();
  void unlock_shared();
  void lock();
  /// Takes the exclusive side only if nobody holds or waits for it and no reader is inside.
  bool try_lock();
  void unlock();

 private:
  std::mutex m_;
  std::condition_variable readers_cv_, writers_cv_;
  int readers_ = 0;
  int writers_waiting_ = 0;
  bool writer_ = false;
};

/// How a job's board time is measured.
enum class JobTiming {
  kThreadCpu,  ///< its thread CPU time x host_to_board (the board's speed is known)
  kElapsed,    ///< the sim time its code and commit took on the TimeSource (a node's own clock)
};

struct RealtimeExecutorOptions {
  /// Worker threads (= board cores the jobs may use), >= 1.
  int threads = 1;
  /// kGlobalEdf: earliest absolute deadline first; kFifoNonPreemptive: earliest release first.
  /// Both without preemption: a started job keeps its worker until it finishes.
  SchedulingPolicy policy = SchedulingPolicy::kGlobalEdf;
  /// Sim time (shared: its owner sets it: the epoch of a DilatedSteadyClock, the steps of a
  /// SteppedClock). Null: a DilatedSteadyClock of dilation 1 whose epoch is Start()'s instant.
  std::shared_ptr<TimeSource> clock;
  JobTiming timing = JobTiming::kThreadCpu;
  /// kThreadCpu: board seconds per host CPU second of a job: 1 / (board per-core speed / host speed).
  double host_to_board = 1.0;
  /// Runs first on each worker thread (e.g. enter a SCHED_DEADLINE speed server).
  std::function<void(int worker)> on_worker_start;
  /// Runs after each commit, still under the exclusive JobLock (e.g. publish the stack's outputs).
  std::function<void(TaskId task)> after_commit;
  /// Sees every finished job: its work counts and the host CPU time of its code and commit
  /// (on the worker thread, no lock held).
  JobObserver observer;
};

/// Time commits and the stack's other writers spent waiting for running jobs.
struct JobLockStats {
  std::int64_t commits = 0;
  double commit_wait_s = 0.0;      ///< wall seconds, summed
  double commit_wait_max_s = 0.0;  ///< wall seconds, longest single wait
};

class RealtimeExecutor final : public TaskExecutor {
 public:
  /// Throws std::invalid_argument for threads < 1 or a non-positive host_to_board.
  explicit RealtimeExecutor(RealtimeExecutorOptions options);
  ~RealtimeExecutor() override;  ///< Stop()s and joins
  RealtimeExecutor(const RealtimeExecutor&) = delete;
  RealtimeExecutor& operator=(const RealtimeExecutor&) = delete;

  void Register(TaskId task, JobFn fn) override;
  void SetRate(TaskId task, double hz) override;
  double rate(TaskId task) const override;
  void Trigger(TaskId task, double relative_deadline) override;
  /// The clock runs by itself: blocks until now() >= t (returns at once before Start() or after Stop()).
  void AdvanceTo(double t) override;
  /// Sim time: 0 before Start(), then the clock's, never negative.
  double now() const override;
  int cores() const override { return options_.threads; }
  /// A copy of the task's counters taken now, owned by the calling thread: valid until that
  /// thread asks for the same task again.
  const TaskStats& stats(TaskId task) const override;
  bool active(TaskId task) const override;
  double JobElapsed(TaskId, const WorkCounts&, double job_start) const override { return now() - job_start; }

  /// Creates the workers (each runs on_worker_start first) and the release thread; returns once
  /// every worker has run its start hook. No job starts before Start().
  void Launch();
  /// Releases and dispatch begin, at the clock's time now (a DilatedSteadyClock's epoch must be
  /// set; the default clock's is set to this instant). Launch()es first if needed.
  void Start();
  /// Stops releasing, lets running jobs finish (their commits are applied), joins all threads.
  /// Idempotent.
  void Stop();

  /// The lock the stack's writers outside the executor (frames, odometry) must take exclusively.
  JobLock& job_lock() { return job_lock_; }
  /// Kernel thread ids: workers (after Launch()) and the release thread.
  std::vector<pid_t> WorkerTids() const;
  pid_t ReleaseThreadTid() const;
  std::array<TaskStats, kTaskCount> AllStats() const;
  /// Per task: release instants the release thread reached only after the next one was due (a
  /// loaded host) while no job of the task was active. Neither released nor missed: the task did
  /// not overrun, this clock was late; only the latest due instant is released.
  std::array<std::int64_t, kTaskCount> ReleaseLags() const;
  /// Wall seconds each task's jobs spent executing (code and commit, not waiting for a worker
  /// or the lock): against host_cpu_s x dilation / speed it shows whether a job ran at the
  /// board's speed (1.0) or was held back further by a busy host (> 1).
  std::array<double, kTaskCount> ExecutionWallSeconds() const;
  JobLockStats lock_stats() const;
  /// What the first job or commit that threw said; empty while none did. After a throw no
  /// further jobs start: the stack's state is not trustworthy any more.
  std::string error() const;

 private:
  struct Job {
    double release = 0, deadline = 0;
    bool started = false;
  };
  struct Slot {
    JobFn fn;
    double rate_hz = 0;
    double next_release = 0;
    double last_release = -1;
    double last_finish = -1;  ///< sim time the last job finished
    std::optional<Job> job;
    std::optional<double> pending_trigger;
    TaskStats stats;
    double wall_s = 0;
    std::int64_t release_lags = 0;
  };

  double NowLocked() const;
  /// Releases a job of `task` at sim time `at` (caller holds mutex_).
  void ReleaseLocked(int task, double at, double relative_deadline);
  /// The most urgent ready job not yet started, -1 if none (caller holds mutex_).
  int PickLocked() const;
  void WorkerLoop(int worker);
  void ReleaseLoop();
  void Fail(const std::string& what);

  RealtimeExecutorOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable work_cv_;     // workers: a job became ready, or stop
  std::condition_variable release_cv_;  // release thread: rates changed, started, or stop
  std::array<Slot, kTaskCount> slots_;
  std::shared_ptr<TimeSource> clock_;
  bool default_clock_ = false;
  bool launched_ = false, started_ = false, stopping_ = false;
  std::vector<std::thread> threads_;
  std::vector<pid_t> worker_tids_;
  pid_t release_tid_ = 0;
  std::string error_;
  JobLock job_lock_;
  JobLockStats lock_stats_;
};

}  // namespace enavi::navstack
