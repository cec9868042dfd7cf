#pragma once
// TaskExecutor: runs the navigation stack's jobs under an emulated onboard computer
// (docs/design.md, "Time: two clocks"). Deadlines equal periods (paper Sec. III.A).

#include <array>
#include <cstdint>
#include <functional>

#include "navstack/runtime/task.h"

namespace enavi::navstack {

struct TaskStats {
  std::int64_t released = 0;   ///< release instants, periodic and sporadic
  std::int64_t started = 0;
  std::int64_t completed = 0;
  std::int64_t late = 0;       ///< finished after their deadline
  std::int64_t skipped = 0;    ///< releases dropped because the previous job was still running
  double busy_s = 0.0;         ///< board time spent executing this task
  double cost_sum_s = 0.0;     ///< board time of started jobs
  double cost_max_s = 0.0;
  double cost_recent_s = 0.0;  ///< exponential average (weight 0.25) of recent jobs' board time
  double host_cpu_s = 0.0;     ///< host CPU time spent in the task's code

  /// Deadline misses: late finishes plus skipped releases (an overrun job takes its successors' slots).
  std::int64_t misses() const { return late + skipped; }
  double MeanCost() const { return started > 0 ? cost_sum_s / static_cast<double>(started) : 0.0; }
};

class TaskExecutor {
 public:
  virtual ~TaskExecutor() = default;
  /// The code a job of `task` runs. Must be called before the task is released.
  virtual void Register(TaskId task, JobFn fn) = 0;
  /// Periodic releases at `hz` with deadline = period; 0 stops them. A new rate applies from the
  /// next release. An overrunning task skips releases rather than queueing without bound.
  virtual void SetRate(TaskId task, double hz) = 0;
  virtual double rate(TaskId task) const = 0;
  /// Releases one sporadic job now with the given relative deadline. If a job of the task is
  /// active, the request is kept and one more job is released when it finishes.
  virtual void Trigger(TaskId task, double relative_deadline) = 0;
  /// Runs the schedule up to sim time `t` (s): releases, starts, preemptions and finishes.
  virtual void AdvanceTo(double t) = 0;
  virtual double now() const = 0;
  virtual int cores() const = 0;
  virtual const TaskStats& stats(TaskId task) const = 0;
  /// True while a job of the task is released and not finished.
  virtual bool active(TaskId task) const = 0;
  /// Board time the calling job has used so far, for time limits inside a job (Ego-Planner's
  /// 0.2 s search limit). Virtual clock: the cost model's price of `work_so_far` (measured mode:
  /// of the host CPU the job's code took so far); emulated clock: sim time since `job_start`, the
  /// now() the job read when it started, as ros::Time::now() differences measure it.
  virtual double JobElapsed(TaskId task, const WorkCounts& work_so_far, double job_start) const = 0;
};

/// Sees every job as it finishes: what it did and the host CPU time its code and its commit
/// took. Used by `enavi calibrate` to fit the cost model.
using JobObserver = std::function<void(TaskId task, const WorkCounts& work, double host_cpu_seconds)>;

}  // namespace enavi::navstack
