#include "workers/board/calibration.h"

#include <cstdio>
#include <stdexcept>

#include "workers/board/nnls.h"

namespace enavi::board {

namespace {
constexpr int kUnits = static_cast<int>(navstack::WorkUnit::kCount);
}

CostFit FitCosts(const std::vector<JobSample>& samples) {
  // One coefficient per unit and no per-job intercept: the eci's pixel count never varies, so an
  // intercept would absorb its whole cost and charge it to every other task's jobs.
  const int n_coef = kUnits;
  if (static_cast<int>(samples.size()) < 2 * n_coef)
    throw std::invalid_argument("calibration: " + std::to_string(samples.size()) + " job samples, need at least " +
                                std::to_string(2 * n_coef));
  Eigen::MatrixXd A(samples.size(), n_coef);
  Eigen::VectorXd b(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    for (int u = 0; u < kUnits; ++u) A(i, u) = static_cast<double>(samples[i].work.n[u]);
    b[i] = samples[i].host_cpu_s * 1e9;
  }
  // Unit-norm columns: counts span 1 to 1e6, which would otherwise swamp the solver's tolerance.
  Eigen::VectorXd scale(n_coef);
  for (int j = 0; j < n_coef; ++j) {
    const double norm = A.col(j).norm();
    scale[j] = norm > 0 ? norm : 1.0;
    A.col(j) /= scale[j];
  }
  const NnlsResult nnls = SolveNnls(A, b);
  if (!nnls.converged) throw std::runtime_error("calibration: the cost fit did not converge");
  const Eigen::VectorXd coef = nnls.x.cwiseQuotient(scale);

  CostFit fit;
  fit.samples = static_cast<int>(samples.size());
  fit.costs.ns.ns_per_job = 0.0;
  for (int u = 0; u < kUnits; ++u) {
    fit.costs.ns.ns_per_unit[u] = coef[u];
    if (A.col(u).isZero()) fit.unobserved_units.emplace_back(navstack::kWorkUnitNames[u]);
  }
  const Eigen::VectorXd predicted = A * nnls.x;
  const double mean = b.mean();
  const double ss_tot = (b.array() - mean).square().sum();
  fit.r2 = ss_tot > 0 ? 1.0 - (b - predicted).squaredNorm() / ss_tot : 0.0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    TaskFitQuality& q = fit.per_task[std::string(navstack::TaskName(samples[i].task))];
    ++q.jobs;
    q.measured_s += samples[i].host_cpu_s;
    q.predicted_s += predicted[i] * 1e-9;
  }
  return fit;
}

double RelativeSpeed(const std::vector<JobSample>& samples, const ReferenceCosts& reference) {
  const navstack::WorkCountCostModel model(reference.ns);
  double reference_s = 0, host_s = 0;
  for (const JobSample& s : samples) {
    reference_s += model.JobSeconds(s.task, s.work, 0.0);
    host_s += s.host_cpu_s;
  }
  if (host_s <= 0) throw std::invalid_argument("calibration: no measured job time");
  return reference_s / host_s;
}

std::string ReferenceCostsYaml(const ReferenceCosts& costs, const std::string& comment) {
  std::string out = "# " + comment + "\n";
  out += "reference_cpu: \"" + costs.reference_cpu + "\"\n";
  out += "calibration_id: \"" + costs.calibration_id + "\"\n";
  char line[160];
  std::snprintf(line, sizeof line, "ns_per_job: %.1f\n", costs.ns.ns_per_job);
  out += line;
  out += "ns_per_unit:\n";
  for (int u = 0; u < kUnits; ++u) {
    std::snprintf(line, sizeof line, "  %s: %.4f\n", std::string(navstack::kWorkUnitNames[u]).c_str(),
                  costs.ns.ns_per_unit[u]);
    out += line;
  }
  return out;
}

}  // namespace enavi::board
