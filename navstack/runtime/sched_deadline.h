#pragma once
// Linux real-time scheduling for the navstack's periodic tasks (README.md, "The board: time", emulated
// clock): SCHED_DEADLINE through sched_setattr(2) with a fallback to SCHED_OTHER, and a small
// user-space EDF dispatcher that runs periodic jobs on a fixed pool of worker threads.
//
// Findings on how SCHED_DEADLINE meets CFS bandwidth control and cpusets, with the experiment
// that shows each one, are in workers/board/EMULATION.md.

#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace enavi::navstack {

/// SCHED_DEADLINE reservation of a thread (CBS server): at most `runtime` of CPU time in every
/// `period`, to be delivered within `deadline` of each activation. All in nanoseconds.
struct DeadlineParams {
  std::int64_t runtime_ns = 0;
  std::int64_t deadline_ns = 0;
  std::int64_t period_ns = 0;
  std::uint64_t flags = 0;  ///< SCHED_FLAG_* (e.g. SCHED_FLAG_RECLAIM); 0 = hard reservation
};

/// The paper's reservation of a periodic task (Sec. III.A): period = 1/f, deadline = period,
/// runtime = WCET. Throws std::invalid_argument unless f > 0 and 0 < wcet.
DeadlineParams PaperDeadlineParams(double frequency_hz, double wcet_s);

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

/// One released job in the ready queue.
struct ReadyJob {
  int task = 0;
  std::int64_t index = 0;
  std::chrono::steady_clock::time_point release;
  std::chrono::steady_clock::time_point deadline;
};

/// A periodic task for EdfDispatcher. Times are wall-clock (the caller applies any dilation).
struct PeriodicTask {
  std::string name;
  std::chrono::nanoseconds period{0};
  std::chrono::nanoseconds relative_deadline{0};  ///< 0 = the period (implicit deadline)
  std::chrono::nanoseconds phase{0};              ///< first release after Start()
  /// The job; `job.release` and `job.deadline` are absolute steady_clock time points.
  std::function<void(const ReadyJob& job)> body;
};

/// Counters of one task since Start().
struct PeriodicTaskStats {
  std::int64_t released = 0;   ///< jobs put in the ready queue
  std::int64_t completed = 0;
  std::int64_t missed = 0;     ///< completed after their absolute deadline
  std::int64_t skipped = 0;    ///< releases dropped because the previous job was still pending
  std::chrono::nanoseconds max_response{0};  ///< release -> completion
  std::chrono::nanoseconds total_response{0};
  /// CPU time the task's jobs used (CLOCK_THREAD_CPUTIME_ID around each job): the per-task
  /// utilisation numerator, since tasks share the worker threads.
  std::chrono::nanoseconds cpu_time{0};
};

/// Ready queue of an EDF scheduler: earliest absolute deadline first, ties broken by release
/// time and then task id, so the order is a pure function of the pushed jobs.
class EdfReadyQueue {
 public:
  void Push(const ReadyJob& job);
  /// Removes and returns the most urgent job; nullopt when empty.
  std::optional<ReadyJob> Pop();
  bool empty() const { return heap_.empty(); }
  std::size_t size() const { return heap_.size(); }

 private:
  std::vector<ReadyJob> heap_;
};

struct EdfDispatcherOptions {
  /// Worker threads = emulated cores: jobs run on them non-preemptively in EDF order
  /// (global EDF without preemption across the pool).
  int workers = 1;
  /// Called once on each worker thread before it takes jobs, e.g. to enter a SCHED_DEADLINE
  /// speed server or to report the thread id for cgroup placement.
  std::function<void(int worker_index)> on_worker_start;
};

/// User-space EDF dispatcher: a release thread puts periodic jobs into an EdfReadyQueue at
/// their release times; `workers` threads take the most urgent job. A task whose previous job
/// is still queued or running when the next release comes skips that release (counted), so an
/// overrunning task never queues without bound (README.md, "The board: time").
class EdfDispatcher {
 public:
  explicit EdfDispatcher(EdfDispatcherOptions options);
  ~EdfDispatcher();  ///< Stop()s
  EdfDispatcher(const EdfDispatcher&) = delete;
  EdfDispatcher& operator=(const EdfDispatcher&) = delete;

  /// Adds a task (before or after Start()); returns its id. Throws std::invalid_argument for a
  /// non-positive period, a deadline > period or an empty body.
  int AddTask(PeriodicTask task);
  /// Changes the period (and implicit deadline) of a task from its next release on: the
  /// frequency adapter's output. Throws std::invalid_argument for a non-positive period.
  void SetPeriod(int task, std::chrono::nanoseconds period);

  void Start();
  /// Stops releasing, lets running jobs finish, joins all threads. Idempotent.
  void Stop();

  PeriodicTaskStats Stats(int task) const;
  /// Kernel thread ids of the workers (valid after Start() returned).
  std::vector<pid_t> WorkerTids() const;

 private:
  struct TaskState {
    PeriodicTask spec;
    std::chrono::steady_clock::time_point next_release;
    std::int64_t next_index = 0;
    bool pending = false;  ///< a job is queued or running
    PeriodicTaskStats stats;
  };
  void ReleaseLoop();
  void WorkerLoop(int worker_index);

  EdfDispatcherOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable work_cv_;     // workers wait for jobs
  std::condition_variable release_cv_;  // release thread waits for the next release / changes
  std::vector<TaskState> tasks_;
  EdfReadyQueue queue_;
  std::vector<pid_t> worker_tids_;
  std::vector<std::thread> threads_;
  std::chrono::steady_clock::time_point start_;
  bool running_ = false;
  bool stopping_ = false;
};

}  // namespace enavi::navstack
