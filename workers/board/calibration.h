#pragma once
// Host calibration of the board cost model (docs/design.md, "Time: two clocks", `enavi calibrate`): the host
// CPU time of many real navstack jobs against their work counts, fitted to nanoseconds per work
// unit and per job of each task by non-negative least squares.

#include <string>
#include <vector>

#include "navstack/common/work.h"
#include "navstack/runtime/task.h"
#include "workers/board/board_profile.h"

namespace enavi::board {

struct JobSample {
  navstack::TaskId task = navstack::TaskId::kPerception;
  navstack::WorkCounts work;
  double host_cpu_s = 0;
};

/// One coefficient of the fit: a work unit's ns per unit or a task's ns per job.
struct CoefficientFit {
  std::string name;   ///< work unit or task name
  double ns = 0;      ///< the fitted value
  int jobs = 0;       ///< jobs that carry it (a non-zero count of the unit; jobs of the task)
  double share = 0;   ///< fraction of all measured job time it explains
  /// Why the fit left it at 0 (no job used it, collinear with what, or too small to see);
  /// empty when it is not 0.
  std::string zero_reason;
};

struct TaskFitQuality {
  std::string task;
  int jobs = 0;
  double measured_s = 0;   ///< total host CPU time of the task's jobs
  double predicted_s = 0;  ///< what the fitted model says for the same jobs
  double r2 = 0;           ///< over the task's jobs alone (0 when they do not vary)
  /// (predicted - measured) / measured: the model's bias for this task.
  double relative_residual() const { return measured_s > 0 ? (predicted_s - measured_s) / measured_s : 0.0; }
};

struct CostFit {
  ReferenceCosts costs;  ///< the fitted coefficients (ns per job of each task, ns per unit)
  int samples = 0;
  double r2 = 0;         ///< coefficient of determination over all jobs
  std::vector<CoefficientFit> units;     ///< one per work unit, in WorkUnit order
  std::vector<CoefficientFit> overheads; ///< one per task (ns per job), in TaskId order
  std::vector<TaskFitQuality> per_task;  ///< tasks with jobs, in TaskId order
};

/// Fits each task's ns per job and each unit's ns per unit to the samples. Throws
/// std::invalid_argument when there are fewer samples than twice the coefficients.
CostFit FitCosts(const std::vector<JobSample>& samples);

/// This host's single-core speed relative to the reference core: the reference model's time for
/// the samples' work divided by the time this host took (> 1: faster than the reference).
double RelativeSpeed(const std::vector<JobSample>& samples, const ReferenceCosts& reference);

/// reference_costs.yaml text for `costs` (the format LoadReferenceCosts reads); `comment` goes
/// into the header, one "# " line per line.
std::string ReferenceCostsYaml(const ReferenceCosts& costs, const std::string& comment);

}  // namespace enavi::board
