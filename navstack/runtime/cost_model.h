#pragma once
// How long a job takes on the emulated board (docs/design.md, "Time: two clocks").

#include <array>
#include <string>

#include "navstack/common/work.h"
#include "navstack/runtime/task.h"

namespace enavi::navstack {

class CostModel {
 public:
  virtual ~CostModel() = default;
  /// Board execution time of one job in seconds, from its work counts (model mode) or from the
  /// host CPU time its code took (measured mode).
  virtual double JobSeconds(TaskId task, const WorkCounts& work, double host_cpu_seconds) const = 0;
  /// "model" or "measured".
  virtual std::string mode() const = 0;
  /// Whether JobSeconds reads host_cpu_seconds: reading the thread's CPU clock is a system call,
  /// too slow to make at every search step when the answer is ignored.
  virtual bool uses_host_cpu() const = 0;
};

/// How the model turns prices into time; in the provenance digest with the prices, so that two
/// results priced alike by different rules never look comparable. 2: idle jobs cost nothing.
inline constexpr int kCostModelRevision = 2;

/// model: time = the task's fixed per-job overhead + sum(count x ns_per_unit). Bit-reproducible.
/// A job that counted no work costs nothing: it found nothing to do and returned (Ego-Planner's
/// 100 Hz FSM tick between plans, a check with no trajectory) in ~2 us on the reference core,
/// while the overheads are the fixed part of jobs that work (workers/board/EMULATION.md, "The
/// baseline's idle planning jobs": priced at the overhead, idle ticks came out 31x their time).
class WorkCountCostModel final : public CostModel {
 public:
  struct Coefficients {
    std::array<double, static_cast<int>(WorkUnit::kCount)> ns_per_unit{};
    /// What one job of each task costs whatever its work counts: the code that runs on every
    /// job (frame hand-over, map and trajectory look-ups, result packing) and the commit. One
    /// per task because each task's fixed part is different code.
    std::array<double, kTaskCount> ns_per_job{};
  };
  explicit WorkCountCostModel(const Coefficients& board) : c_(board) {}
  double JobSeconds(TaskId task, const WorkCounts& work, double) const override {
    if (work.Idle()) return 0.0;
    double ns = c_.ns_per_job[static_cast<int>(task)];
    for (std::size_t i = 0; i < work.n.size(); ++i) ns += static_cast<double>(work.n[i]) * c_.ns_per_unit[i];
    return ns * 1e-9;
  }
  std::string mode() const override { return "model"; }
  bool uses_host_cpu() const override { return false; }
  const Coefficients& coefficients() const { return c_; }

 private:
  Coefficients c_;
};

/// measured: the host thread CPU time of the job's code, scaled by host speed / board speed.
class MeasuredCostModel final : public CostModel {
 public:
  explicit MeasuredCostModel(double host_to_board) : scale_(host_to_board) {}
  double JobSeconds(TaskId, const WorkCounts&, double host_cpu_seconds) const override {
    return host_cpu_seconds * scale_;
  }
  std::string mode() const override { return "measured"; }
  bool uses_host_cpu() const override { return true; }

 private:
  double scale_;
};

}  // namespace enavi::navstack
