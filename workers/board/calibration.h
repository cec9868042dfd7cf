#pragma once
// Host calibration of the board cost model (docs/design.md, "Time: two clocks", `enavi calibrate`): the host
// CPU time of many real navstack jobs against their work counts, fitted to nanoseconds per work
// unit and per job of each task by non-negative least squares.

#include <map>
#include <string>
#include <vector>

#include "navstack/common/work.h"
#include "navstack/runtime/task.h"
#include "workers/board/board_profile.h"

namespace enavi::board {

struct JobSample {
  navstack::TaskId task = navstack::TaskId::kPerception;
  std::string method;  ///< the navigation method that ran the job (empty: not recorded)
  std::string family = "navstack";  ///< its cost family (navstack::MethodInfo::cost_family)
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
  std::string method;      ///< empty: the jobs of every method
  int jobs = 0;
  double measured_s = 0;   ///< total host CPU time of the task's jobs
  double predicted_s = 0;  ///< what the fitted model says for the same jobs
  double r2 = 0;           ///< over the task's jobs alone (0 when they do not vary)
  /// (predicted - measured) / measured: the model's bias for this task.
  double relative_residual() const { return measured_s > 0 ? (predicted_s - measured_s) / measured_s : 0.0; }
};

struct CostFit {
  ReferenceCosts::Coefficients ns;  ///< the fitted coefficients (ns per job of each task, ns per unit)
  int samples = 0;
  double r2 = 0;         ///< coefficient of determination over all jobs
  std::vector<CoefficientFit> units;     ///< one per work unit, in WorkUnit order
  std::vector<CoefficientFit> overheads; ///< one per task (ns per job), in TaskId order
  std::vector<TaskFitQuality> per_task;  ///< tasks with jobs, in TaskId order
  /// The same per method and task (methods in first-seen order): one price for work that costs
  /// differently in two methods shows as opposite residuals here and cancels in per_task.
  std::vector<TaskFitQuality> per_method_task;
};

/// Fits each task's ns per job and each unit's ns per unit to the samples. Throws
/// std::invalid_argument when there are fewer samples than twice the coefficients.
CostFit FitCosts(const std::vector<JobSample>& samples);

/// One fit per cost family, over that family's samples.
struct FamilyFits {
  ReferenceCosts costs;                   ///< every family's prices (reference_cpu, id left empty)
  std::map<std::string, CostFit> fits;    ///< by family
  int samples = 0;
  int idle = 0;   ///< jobs that counted no work: priced 0 by the model, left out of the fits
  double r2 = 0;  ///< over all jobs, each priced by its family's fit
};
FamilyFits FitCostFamilies(const std::vector<JobSample>& samples);

/// Cost families of the samples that `reference` has no prices for (sorted): a code base
/// calibrated for the first time.
std::vector<std::string> UnpricedFamilies(const std::vector<JobSample>& samples, const ReferenceCosts& reference);

/// This host's single-core speed relative to the reference core: the reference model's time for
/// the samples' work (each priced by its family) divided by the time this host took (> 1: faster).
/// Samples of unpriced families are left out, so a new family can be calibrated against a
/// reference that does not know it yet; throws std::invalid_argument naming the families when the
/// reference prices none of them.
double RelativeSpeed(const std::vector<JobSample>& samples, const ReferenceCosts& reference);

/// How the reference model prices the samples' jobs against what they took here, per method and
/// task (predicted: the reference model's time over `relative_speed`): what the virtual clock
/// charges a method for what the emulated clock would measure. A residual of +30 % on one method
/// and 0 on the others means the reference over-prices that method's work by 30 %. Methods of
/// unpriced families are left out.
std::vector<TaskFitQuality> ReferenceAgreement(const std::vector<JobSample>& samples, const ReferenceCosts& reference,
                                               double relative_speed);

/// reference_costs.yaml text for `costs` (the format LoadReferenceCosts reads); `comment` goes
/// into the header, one "# " line per line.
std::string ReferenceCostsYaml(const ReferenceCosts& costs, const std::string& comment);

}  // namespace enavi::board
