#pragma once
// The virtual clock: a discrete-event, preemptive global-EDF schedule of the board's N cores in
// sim time. A job's code runs on the host when the simulated scheduler first gives it a core; its
// board time comes from the cost model; its commit is applied at its simulated finish. In measured
// mode a job's host CPU is its code's plus the task's mean commit CPU so far (the commit itself
// runs only at the finish, after the job's board time had to be known).

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "navstack/runtime/cost_model.h"
#include "navstack/runtime/executor.h"

namespace enavi::navstack {

/// How jobs share the board's cores.
enum class SchedulingPolicy {
  /// Preemptive global EDF over all cores: E-Navi's tasks under SCHED_DEADLINE (paper Sec. III.A).
  kGlobalEdf,
  /// Non-preemptive, first released first served: the callbacks of a ROS node's single-threaded
  /// spinner, as in the fixed-configuration baseline (Ego-Planner's node), on `cores` threads.
  kFifoNonPreemptive,
};

class VirtualExecutor final : public TaskExecutor {
 public:
  /// @pre cores >= 1; `cost` outlives the executor.
  VirtualExecutor(int cores, const CostModel& cost, SchedulingPolicy policy = SchedulingPolicy::kGlobalEdf,
                  double t0 = 0.0);

  void Register(TaskId task, JobFn fn) override;
  void SetRate(TaskId task, double hz) override;
  double rate(TaskId task) const override { return slot(task).rate_hz; }
  void Trigger(TaskId task, double relative_deadline) override;
  /// Runs the schedule up to `t`, or stops at the instant a started job awaits a decision from
  /// outside (JobOutput::awaits_decision), after the round of jobs dispatched with it has run its
  /// code: paused() is then true, and the next AdvanceTo (with the same t) goes on from there.
  void AdvanceTo(double t) override;
  bool paused() const { return paused_round_.has_value(); }
  double now() const override { return now_; }
  int cores() const override { return cores_; }
  const TaskStats& stats(TaskId task) const override { return slot(task).stats; }
  double JobElapsed(TaskId task, const WorkCounts& work_so_far, double job_start) const override;
  bool active(TaskId task) const override { return slot(task).job.has_value(); }
  void SetJobObserver(JobObserver observer) { observer_ = std::move(observer); }

 private:
  struct Job {
    double release = 0, deadline = 0;
    double remaining = 0;  ///< board seconds still to execute
    bool started = false;
    std::function<void()> commit{};
    WorkCounts work{};
    double host_cpu_s = 0;  ///< of the job's code at its start
  };
  struct Slot {
    JobFn fn;
    double rate_hz = 0;
    double next_release = 0;
    double last_release = -1;
    std::optional<Job> job;
    std::optional<double> pending_trigger;  ///< relative deadline of a coalesced trigger
    double commit_cpu_mean_s = 0;  ///< running mean host CPU of the task's commits
    TaskStats stats;
  };

  Slot& slot(TaskId t) { return slots_[static_cast<int>(t)]; }
  const Slot& slot(TaskId t) const { return slots_[static_cast<int>(t)]; }
  void Release(TaskId task, double relative_deadline);
  /// The (at most N) active jobs with the earliest deadlines, in a deterministic order.
  std::vector<TaskId> Running() const;
  void Start(TaskId task);
  void Finish(TaskId task);

  int cores_;
  SchedulingPolicy policy_;
  const CostModel& cost_;
  double now_;
  std::array<Slot, kTaskCount> slots_;
  JobObserver observer_;
  double job_cpu0_ = 0;  ///< host thread CPU when the job whose code runs now started
  bool awaiting_ = false;  ///< a job started in this dispatch round awaits a decision
  std::optional<std::vector<TaskId>> paused_round_;  ///< the round AdvanceTo stopped in
};

}  // namespace enavi::navstack
