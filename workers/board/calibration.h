#pragma once
// Host calibration of the board cost model (docs/design.md, "Time: two clocks", `enavi calibrate`): the host
// CPU time of many real navstack jobs against their work counts, fitted to nanoseconds per work
// unit by non-negative least squares.

#include <map>
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

struct TaskFitQuality {
  int jobs = 0;
  double measured_s = 0;   ///< total host CPU time of the task's jobs
  double predicted_s = 0;  ///< what the fitted model says for the same jobs
};

struct CostFit {
  ReferenceCosts costs;  ///< the fitted coefficients (ns per job, ns per unit)
  int samples = 0;
  double r2 = 0;         ///< coefficient of determination over all jobs
  std::map<std::string, TaskFitQuality> per_task;
  std::vector<std::string> unobserved_units;  ///< units no job used: left at 0
};

/// Fits ns_per_job and ns_per_unit to the samples. Throws std::invalid_argument when there are
/// fewer samples than coefficients.
CostFit FitCosts(const std::vector<JobSample>& samples);

/// This host's single-core speed relative to the reference core: the reference model's time for
/// the samples' work divided by the time this host took (> 1: faster than the reference).
double RelativeSpeed(const std::vector<JobSample>& samples, const ReferenceCosts& reference);

/// reference_costs.yaml text for `costs` (the format LoadReferenceCosts reads).
std::string ReferenceCostsYaml(const ReferenceCosts& costs, const std::string& comment);

}  // namespace enavi::board
