#include "workers/board/calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>

#include "workers/board/nnls.h"

namespace enavi::board {

namespace {

constexpr int kUnits = static_cast<int>(navstack::WorkUnit::kCount);
constexpr int kTasks = navstack::kTaskCount;
constexpr int kColumns = kUnits + kTasks;  // units first, then one indicator per task

std::string ColumnName(int j) {
  return std::string(j < kUnits ? navstack::kWorkUnitNames[j] : navstack::kTaskNames[j - kUnits]);
}

std::string Number(double v, const char* format) {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

// A task whose jobs all count the same positive amount of a unit no other task counts: its
// per-job column is that unit's column over the count, so the two cannot be told apart. Returns
// the unit, or -1.
int UnitTiedToTask(const Eigen::MatrixXd& A, const std::vector<JobSample>& samples, int task) {
  for (int u = 0; u < kUnits; ++u) {
    double count = -1;
    bool tied = true;
    for (std::size_t i = 0; i < samples.size() && tied; ++i) {
      const bool mine = static_cast<int>(samples[i].task) == task;
      if (!mine) {
        tied = A(i, u) == 0;
      } else if (count < 0) {
        count = A(i, u);
        tied = count > 0;
      } else {
        tied = A(i, u) == count;
      }
    }
    if (tied && count > 0) return u;
  }
  return -1;
}

// Why NNLS left column `j` (of the scaled matrix `As`, active columns `cols`) at 0: collinear with
// the columns that carry cost, or its free least-squares estimate is negative or within noise.
std::string ZeroReason(const Eigen::MatrixXd& As, const Eigen::VectorXd& b, const Eigen::VectorXd& x,
                       const std::vector<int>& cols, const Eigen::VectorXd& scale, int k) {
  std::vector<int> positive;
  for (int m = 0; m < static_cast<int>(cols.size()); ++m)
    if (x[m] > 0) positive.push_back(m);
  Eigen::MatrixXd P(As.rows(), positive.size());
  for (std::size_t m = 0; m < positive.size(); ++m) P.col(m) = As.col(positive[m]);
  // Collinear: the column is (nearly) a combination of the columns that carry cost.
  if (!positive.empty()) {
    const Eigen::VectorXd w = P.colPivHouseholderQr().solve(As.col(k));
    const double rel = (P * w - As.col(k)).norm() / std::max(As.col(k).norm(), 1e-300);
    if (rel < 0.02) {
      std::vector<std::pair<double, int>> parts;
      for (std::size_t m = 0; m < positive.size(); ++m) parts.push_back({-std::abs(w[m]), cols[positive[m]]});
      std::sort(parts.begin(), parts.end());
      std::string with;
      for (std::size_t m = 0; m < std::min<std::size_t>(2, parts.size()); ++m)
        with += (m ? " and " : "") + ColumnName(parts[m].second);
      return "collinear with " + with + " (" + Number(100 * rel, "%.1f") +
             " % of its variation is not explained by them): their coefficients carry its cost";
    }
  }
  // Otherwise free least squares with the column added: its estimate and standard error.
  Eigen::MatrixXd Q(As.rows(), positive.size() + 1);
  Q << P, As.col(k);
  const Eigen::VectorXd z = Q.colPivHouseholderQr().solve(b);
  const double dof = std::max<double>(1, static_cast<double>(As.rows() - Q.cols()));
  const double sigma2 = (Q * z - b).squaredNorm() / dof;
  const Eigen::MatrixXd cov = sigma2 * (Q.transpose() * Q).inverse();
  const int last = static_cast<int>(Q.cols()) - 1;
  const double est = z[last] / scale[k];
  const double se = std::sqrt(std::max(0.0, cov(last, last))) / scale[k];
  const std::string free_fit = "free least squares gives " + Number(est, "%.3g") + " +- " + Number(se, "%.2g") + " ns";
  // Clearly negative: the other coefficients of the same jobs already over-price them, i.e. the
  // linear model does not fit these jobs (e.g. one unit costing differently in two methods).
  if (est + 2 * se < 0) return "the data wants it negative (" + free_fit + "): the same jobs' other units over-price them";
  return "too small to see (" + free_fit + ", not above 0)";
}

// The fit's quality over the jobs `mine` selects (b, predicted: measured and modelled ns).
template <typename Select>
TaskFitQuality FitQuality(const std::vector<JobSample>& samples, const Eigen::VectorXd& b,
                          const Eigen::VectorXd& predicted, std::string task, std::string method, Select mine) {
  TaskFitQuality q;
  q.task = std::move(task);
  q.method = std::move(method);
  double sum = 0, ss_res = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!mine(samples[i])) continue;
    ++q.jobs;
    q.measured_s += b[i] * 1e-9;
    q.predicted_s += predicted[i] * 1e-9;
    sum += b[i];
    ss_res += (b[i] - predicted[i]) * (b[i] - predicted[i]);
  }
  if (q.jobs == 0) return q;
  double ss = 0;
  for (std::size_t i = 0; i < samples.size(); ++i)
    if (mine(samples[i])) ss += (b[i] - sum / q.jobs) * (b[i] - sum / q.jobs);
  q.r2 = ss > 0 ? 1.0 - ss_res / ss : 0.0;
  return q;
}

// Each sample's time under `reference` (its family's prices), seconds.
std::vector<double> ReferenceSeconds(const std::vector<JobSample>& samples, const ReferenceCosts& reference) {
  std::map<std::string, navstack::WorkCountCostModel> models;
  std::vector<double> out;
  out.reserve(samples.size());
  for (const JobSample& s : samples) {
    auto it = models.find(s.family);
    if (it == models.end()) it = models.emplace(s.family, navstack::WorkCountCostModel(reference.For(s.family))).first;
    out.push_back(it->second.JobSeconds(s.task, s.work, 0.0));
  }
  return out;
}


// FitQuality for each method and task with jobs (methods in first-seen order).
std::vector<TaskFitQuality> PerMethodTask(const std::vector<JobSample>& samples, const Eigen::VectorXd& b,
                                          const Eigen::VectorXd& predicted) {
  std::vector<std::string> methods;
  for (const JobSample& s : samples)
    if (!s.method.empty() && std::find(methods.begin(), methods.end(), s.method) == methods.end())
      methods.push_back(s.method);
  std::vector<TaskFitQuality> out;
  for (const std::string& m : methods) {
    for (int t = 0; t < kTasks; ++t) {
      TaskFitQuality q = FitQuality(samples, b, predicted, ColumnName(kUnits + t), m, [t, &m](const JobSample& s) {
        return static_cast<int>(s.task) == t && s.method == m;
      });
      if (q.jobs > 0) out.push_back(q);
    }
  }
  return out;
}

}  // namespace

CostFit FitCosts(const std::vector<JobSample>& samples) {
  const int n = static_cast<int>(samples.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, kColumns);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    for (int u = 0; u < kUnits; ++u) A(i, u) = static_cast<double>(samples[i].work.n[u]);
    A(i, kUnits + static_cast<int>(samples[i].task)) = 1.0;
    b[i] = samples[i].host_cpu_s * 1e9;
  }

  // Columns the data can price: used by some job, and not a task overhead tied to a unit.
  std::vector<std::string> reason(kColumns);
  for (int j = 0; j < kColumns; ++j)
    if (A.col(j).isZero()) reason[j] = j < kUnits ? "no job counted it" : "no job of this task in the sample";
  for (int t = 0; t < kTasks; ++t) {
    if (!reason[kUnits + t].empty()) continue;
    const int u = UnitTiedToTask(A, samples, t);
    if (u >= 0)
      reason[kUnits + t] = "not separable from " + ColumnName(u) + ": every " + ColumnName(kUnits + t) + " job counts " +
                           Number(A.col(u).maxCoeff(), "%.0f") + " of it, whose price carries the per-job cost";
  }
  std::vector<int> cols;
  for (int j = 0; j < kColumns; ++j)
    if (reason[j].empty()) cols.push_back(j);
  const int n_coef = static_cast<int>(cols.size());
  if (n < 2 * std::max(n_coef, 1))
    throw std::invalid_argument("calibration: " + std::to_string(n) + " job samples, need at least " +
                                std::to_string(2 * std::max(n_coef, 1)));

  // Unit-norm columns: counts span 1 to 1e6, which would otherwise swamp the solver's tolerance.
  Eigen::MatrixXd As(n, n_coef);
  Eigen::VectorXd scale(n_coef);
  for (int k = 0; k < n_coef; ++k) {
    As.col(k) = A.col(cols[k]);
    scale[k] = As.col(k).norm();
    As.col(k) /= scale[k];
  }
  const NnlsResult nnls = SolveNnls(As, b);
  if (!nnls.converged) throw std::runtime_error("calibration: the cost fit did not converge");
  Eigen::VectorXd coef = Eigen::VectorXd::Zero(kColumns);
  for (int k = 0; k < n_coef; ++k) coef[cols[k]] = nnls.x[k] / scale[k];
  for (int k = 0; k < n_coef; ++k)
    if (nnls.x[k] <= 0) reason[cols[k]] = ZeroReason(As, b, nnls.x, cols, scale, k);

  CostFit fit;
  fit.samples = n;
  const Eigen::VectorXd predicted = A * coef;
  const double total = b.sum();
  const double ss_tot = (b.array() - b.mean()).square().sum();
  fit.r2 = ss_tot > 0 ? 1.0 - (b - predicted).squaredNorm() / ss_tot : 0.0;
  for (int j = 0; j < kColumns; ++j) {
    CoefficientFit c;
    c.name = ColumnName(j);
    c.ns = coef[j];
    c.jobs = static_cast<int>((A.col(j).array() != 0).count());
    c.share = total > 0 ? coef[j] * A.col(j).sum() / total : 0.0;
    if (coef[j] <= 0) c.zero_reason = reason[j];
    if (j < kUnits) {
      fit.ns.ns_per_unit[j] = coef[j];
      fit.units.push_back(c);
    } else {
      fit.ns.ns_per_job[j - kUnits] = coef[j];
      fit.overheads.push_back(c);
    }
  }
  for (int t = 0; t < kTasks; ++t) {
    TaskFitQuality q = FitQuality(samples, b, predicted, ColumnName(kUnits + t), "",
                                  [t](const JobSample& s) { return static_cast<int>(s.task) == t; });
    if (q.jobs > 0) fit.per_task.push_back(q);
  }
  fit.per_method_task = PerMethodTask(samples, b, predicted);
  return fit;
}

FamilyFits FitCostFamilies(const std::vector<JobSample>& samples) {
  // Idle jobs are priced at 0 by the model (navstack/runtime/cost_model.h), not fitted: thousands
  // of them would pull the per-job overheads of the jobs that work towards their ~2 us.
  std::map<std::string, std::vector<JobSample>> by_family;
  FamilyFits out;
  for (const JobSample& s : samples) {
    if (s.work.Idle())
      ++out.idle;
    else
      by_family[s.family].push_back(s);
  }
  for (const auto& [family, own] : by_family) {
    try {
      out.fits[family] = FitCosts(own);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("cost family '" + family + "': " + e.what());
    }
    out.costs.families[family] = out.fits[family].ns;
  }
  out.samples = static_cast<int>(samples.size());
  const std::vector<double> modelled = ReferenceSeconds(samples, out.costs);
  double mean = 0;
  for (const JobSample& s : samples) mean += s.host_cpu_s / static_cast<double>(samples.size());
  double ss_res = 0, ss_tot = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    ss_res += (samples[i].host_cpu_s - modelled[i]) * (samples[i].host_cpu_s - modelled[i]);
    ss_tot += (samples[i].host_cpu_s - mean) * (samples[i].host_cpu_s - mean);
  }
  out.r2 = ss_tot > 0 ? 1.0 - ss_res / ss_tot : 0.0;
  return out;
}

std::vector<std::string> UnpricedFamilies(const std::vector<JobSample>& samples, const ReferenceCosts& reference) {
  std::set<std::string> out;
  for (const JobSample& s : samples)
    if (reference.families.count(s.family) == 0) out.insert(s.family);
  return {out.begin(), out.end()};
}

namespace {

// The samples whose family `reference` prices.
std::vector<JobSample> PricedSamples(const std::vector<JobSample>& samples, const ReferenceCosts& reference) {
  std::vector<JobSample> out;
  for (const JobSample& s : samples)
    if (reference.families.count(s.family) > 0) out.push_back(s);
  return out;
}

}  // namespace

double RelativeSpeed(const std::vector<JobSample>& all, const ReferenceCosts& reference) {
  const std::vector<JobSample> samples = PricedSamples(all, reference);
  if (samples.empty() && !all.empty()) {
    std::string flown, known;
    for (const std::string& f : UnpricedFamilies(all, reference)) flown += (flown.empty() ? "" : ", ") + f;
    for (const auto& [name, c] : reference.families) known += (known.empty() ? "" : ", ") + name;
    throw std::invalid_argument("calibration: the reference costs " + reference.calibration_id +
                                " price none of the flown cost families (" + flown + "; known: " + known +
                                "): a host's speed is measured on work the reference prices");
  }
  const std::vector<double> modelled = ReferenceSeconds(samples, reference);
  double reference_s = 0, host_s = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    reference_s += modelled[i];
    host_s += samples[i].host_cpu_s;
  }
  if (host_s <= 0) throw std::invalid_argument("calibration: no measured job time");
  return reference_s / host_s;
}

std::vector<TaskFitQuality> ReferenceAgreement(const std::vector<JobSample>& all, const ReferenceCosts& reference,
                                               double relative_speed) {
  if (!(relative_speed > 0)) throw std::invalid_argument("calibration: relative speed must be > 0");
  const std::vector<JobSample> samples = PricedSamples(all, reference);
  const std::vector<double> modelled = ReferenceSeconds(samples, reference);
  const Eigen::Index n = static_cast<Eigen::Index>(samples.size());
  Eigen::VectorXd b(n), predicted(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    b[i] = samples[i].host_cpu_s * 1e9;
    predicted[i] = modelled[i] / relative_speed * 1e9;
  }
  return PerMethodTask(samples, b, predicted);
}

std::string ReferenceCostsYaml(const ReferenceCosts& costs, const std::string& comment) {
  std::string out;
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out += "# " + line + "\n";
  out += "reference_cpu: \"" + costs.reference_cpu + "\"\n";
  out += "calibration_id: \"" + costs.calibration_id + "\"\n";
  out += "families:\n";
  char line[160];
  for (const auto& [family, c] : costs.families) {
    out += "  " + family + ":\n    ns_per_job:\n";
    for (int t = 0; t < kTasks; ++t) {
      std::snprintf(line, sizeof line, "      %s: %.1f\n", std::string(navstack::kTaskNames[t]).c_str(), c.ns_per_job[t]);
      out += line;
    }
    out += "    ns_per_unit:\n";
    for (int u = 0; u < kUnits; ++u) {
      std::snprintf(line, sizeof line, "      %s: %.4f\n", std::string(navstack::kWorkUnitNames[u]).c_str(),
                    c.ns_per_unit[u]);
      out += line;
    }
  }
  return out;
}

}  // namespace enavi::board
