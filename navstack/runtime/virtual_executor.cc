#include "navstack/runtime/virtual_executor.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "navstack/common/cpu_time.h"

namespace enavi::navstack {
namespace {

constexpr double kEps = 1e-12;

}  // namespace

VirtualExecutor::VirtualExecutor(int cores, const CostModel& cost, SchedulingPolicy policy, double t0)
    : cores_(cores), policy_(policy), cost_(cost), now_(t0) {
  if (cores < 1) throw std::logic_error("VirtualExecutor: cores must be >= 1");
}

void VirtualExecutor::Register(TaskId task, JobFn fn) { slot(task).fn = std::move(fn); }

void VirtualExecutor::SetRate(TaskId task, double hz) {
  Slot& s = slot(task);
  if (hz < 0) throw std::logic_error("VirtualExecutor: negative rate for " + std::string(TaskName(task)));
  if (hz > 0 && !s.fn) throw std::logic_error("VirtualExecutor: task not registered: " + std::string(TaskName(task)));
  if (hz == s.rate_hz) return;
  const bool was_stopped = s.rate_hz == 0;
  s.rate_hz = hz;
  if (hz == 0) return;
  // A stopped task starts now; a running one keeps its phase and stretches to the new period.
  s.next_release = (was_stopped || s.last_release < 0) ? now_ : std::max(now_, s.last_release + 1.0 / hz);
}

void VirtualExecutor::Trigger(TaskId task, double relative_deadline) {
  Slot& s = slot(task);
  if (!s.fn) throw std::logic_error("VirtualExecutor: task not registered: " + std::string(TaskName(task)));
  if (s.job) {
    s.pending_trigger = s.pending_trigger ? std::min(*s.pending_trigger, relative_deadline) : relative_deadline;
    return;
  }
  Release(task, relative_deadline);
}

void VirtualExecutor::Release(TaskId task, double relative_deadline) {
  Slot& s = slot(task);
  ++s.stats.released;
  s.last_release = now_;
  if (s.job) {  // overrun: the running job keeps the core, this release is dropped
    ++s.stats.skipped;
    return;
  }
  s.job = Job{.release = now_, .deadline = now_ + relative_deadline};
}

std::vector<TaskId> VirtualExecutor::Running() const {
  std::vector<TaskId> ready;
  for (int i = 0; i < kTaskCount; ++i)
    if (slots_[i].job) ready.push_back(static_cast<TaskId>(i));
  const bool fifo = policy_ == SchedulingPolicy::kFifoNonPreemptive;
  // EDF (or FIFO by release); ties by release time, then by task id, so the schedule is
  // deterministic. Without preemption, started jobs keep their cores: they sort first.
  std::sort(ready.begin(), ready.end(), [&](TaskId a, TaskId b) {
    const Job& ja = *slot(a).job;
    const Job& jb = *slot(b).job;
    if (fifo && ja.started != jb.started) return ja.started;
    if (!fifo && ja.deadline != jb.deadline) return ja.deadline < jb.deadline;
    if (ja.release != jb.release) return ja.release < jb.release;
    return a < b;
  });
  if (static_cast<int>(ready.size()) > cores_) ready.resize(cores_);
  return ready;
}

void VirtualExecutor::Start(TaskId task) {
  Slot& s = slot(task);
  Job& job = *s.job;
  const double cpu0 = ThreadCpuSeconds();
  job_cpu0_ = cpu0;
  JobOutput out = s.fn();
  const double host_cpu = ThreadCpuSeconds() - cpu0;
  const double cost = cost_.JobSeconds(task, out.work, host_cpu + s.commit_cpu_mean_s);
  job.started = true;
  job.remaining = cost;
  job.commit = std::move(out.commit);
  job.work = out.work;
  job.host_cpu_s = host_cpu;
  awaiting_ = awaiting_ || out.awaits_decision;
  ++s.stats.started;
  s.stats.cost_sum_s += cost;
  s.stats.cost_max_s = std::max(s.stats.cost_max_s, cost);
  s.stats.cost_recent_s = s.stats.started == 1 ? cost : 0.75 * s.stats.cost_recent_s + 0.25 * cost;
  s.stats.host_cpu_s += host_cpu;
}

double VirtualExecutor::JobElapsed(TaskId task, const WorkCounts& work_so_far, double) const {
  return cost_.JobSeconds(task, work_so_far, cost_.uses_host_cpu() ? ThreadCpuSeconds() - job_cpu0_ : 0.0);
}

void VirtualExecutor::Finish(TaskId task) {
  Slot& s = slot(task);
  Job job = std::move(*s.job);
  s.job.reset();
  ++s.stats.completed;
  if (now_ > job.deadline + kEps) ++s.stats.late;
  double commit_cpu = 0;
  if (job.commit) {
    const double cpu0 = ThreadCpuSeconds();
    job.commit();
    commit_cpu = ThreadCpuSeconds() - cpu0;
  }
  s.stats.host_cpu_s += commit_cpu;
  s.commit_cpu_mean_s += (commit_cpu - s.commit_cpu_mean_s) / static_cast<double>(s.stats.completed);
  if (observer_) observer_(task, job.work, job.host_cpu_s + commit_cpu);
  if (s.pending_trigger) {
    const double d = *s.pending_trigger;
    s.pending_trigger.reset();
    Release(task, d);
  }
}

void VirtualExecutor::AdvanceTo(double t) {
  while (true) {
    std::vector<TaskId> running;
    if (paused_round_) {
      // Resumed: the round that stopped has been released and dispatched already.
      running = std::move(*paused_round_);
      paused_round_.reset();
    } else {
      // Releases due now come first, so a job released at `now_` competes for the cores.
      for (int i = 0; i < kTaskCount; ++i) {
        Slot& s = slots_[i];
        while (s.rate_hz > 0 && s.next_release <= now_ + kEps) {
          const double period = 1.0 / s.rate_hz;
          Release(static_cast<TaskId>(i), period);
          s.next_release += period;
        }
      }
      // Dispatch: jobs that just got a core run their code now, with the data available now.
      running = Running();
      for (TaskId id : running)
        if (!slot(id).job->started) Start(id);
      // A decision is to be taken outside: nothing more happens until it is.
      if (std::exchange(awaiting_, false)) {
        paused_round_ = std::move(running);
        return;
      }
    }
    // Zero-cost jobs finish on the spot; their cores are dispatched again at the same instant.
    bool finished_any = false;
    for (TaskId id : running) {
      if (slot(id).job->remaining <= kEps) {
        Finish(id);
        finished_any = true;
      }
    }
    if (finished_any) continue;
    if (now_ >= t - kEps) break;

    // Run the dispatched jobs until the next release, finish or `t`, whichever comes first.
    double t_next = t;
    for (const Slot& s : slots_)
      if (s.rate_hz > 0) t_next = std::min(t_next, s.next_release);
    for (TaskId id : running) t_next = std::min(t_next, now_ + slot(id).job->remaining);
    const double dt = t_next - now_;
    for (TaskId id : running) {
      Slot& s = slot(id);
      s.job->remaining -= dt;
      s.stats.busy_s += dt;
    }
    now_ = t_next;
    for (TaskId id : running)
      if (slot(id).job->remaining <= kEps) Finish(id);
  }
  now_ = std::max(now_, t);
}

}  // namespace enavi::navstack
