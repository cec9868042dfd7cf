#include "navstack/adapt/resolution_adapter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "navstack/common/argument_check.h"

namespace enavi::navstack {
namespace {

// Tolerance on sim-time comparisons, so a period that ends exactly on a sample counts as elapsed.
constexpr double kTimeSlack = 1e-9;

constexpr ArgumentCheck kCheck("path score");

void RequireRange(double v, double lo, double hi, const char* name, bool lo_open = false) {
  const bool ok = (lo_open ? v > lo : v >= lo) && v <= hi;
  if (!ok) {
    throw std::invalid_argument(std::string("resolution adapter: ") + name + " = " +
                                std::to_string(v) + " must be in " + (lo_open ? "(" : "[") +
                                std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
}

}  // namespace

double PathScore(const PathScoreInputs& in, double gamma) {
  kCheck.NonNegative(in.path_length, "path_length");
  kCheck.NonNegative(in.straight_length, "straight_length");
  kCheck.NonNegative(in.occupied_cells, "occupied_cells");
  kCheck.NonNegative(in.total_cells, "total_cells");
  kCheck.NonNegative(gamma, "gamma");
  if (in.straight_length <= 0.0) return 1.0;
  const double density = in.total_cells > 0.0 ? in.occupied_cells / in.total_cells : 0.0;
  const double l_ref = (1.0 + gamma * density) * in.straight_length;
  // The paper defines s only for |L| >= |L*|: a path shorter than the reference is ideal.
  if (in.path_length <= l_ref) return 1.0;
  return std::exp(-(in.path_length - l_ref) / in.straight_length);
}

std::int64_t ManhattanCellDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   double resolution, const Eigen::Vector3d& origin) {
  if (!(resolution > 0.0)) throw std::domain_error("ManhattanCellDistance: resolution must be > 0");
  std::int64_t d = 0;
  for (int k = 0; k < 3; ++k) {
    const auto ca = static_cast<std::int64_t>(std::floor((a[k] - origin[k]) / resolution));
    const auto cb = static_cast<std::int64_t>(std::floor((b[k] - origin[k]) / resolution));
    d += ca > cb ? ca - cb : cb - ca;
  }
  return d;
}

ResolutionAdapter::ResolutionAdapter(const ResolutionAdapterOptions& options) : options_(options) {
  const auto& ladder = options_.ladder;
  if (ladder.empty()) throw std::invalid_argument("resolution adapter: ladder is empty");
  for (std::size_t i = 0; i < ladder.size(); ++i) {
    if (!(ladder[i] > 0.0) || std::isinf(ladder[i])) {
      throw std::invalid_argument("resolution adapter: ladder[" + std::to_string(i) +
                                  "] must be finite and > 0");
    }
    if (i > 0 && !(ladder[i] < ladder[i - 1])) {
      throw std::invalid_argument("resolution adapter: ladder must be strictly decreasing "
                                  "(coarsest first); ladder[" + std::to_string(i) + "] is not");
    }
  }
  RequireRange(options_.gamma, 0.0, 100.0, "gamma");
  RequireRange(options_.score_threshold, 0.0, 1.0, "score_threshold");
  RequireRange(options_.high_eci, 0.0, 1.0, "high_eci");
  RequireRange(options_.step_lifetime, 0.0, 1e6, "step_lifetime", /*lo_open=*/true);
  RequireRange(options_.min_refine_interval, 0.0, 1e6, "min_refine_interval");
  if (!options_.grid_origin.allFinite()) {
    throw std::invalid_argument("resolution adapter: grid_origin must be finite");
  }
  outcome_.assign(ladder.size(), Outcome::kUnknown);
}

ResolutionDecision ResolutionAdapter::Select(const Eigen::Vector3d& p_start_W,
                                             const Eigen::Vector3d& p_goal_W) {
  const int last = num_levels() - 1;
  ResolutionDecision d;
  d.level = -1;
  bool any_separating = false;
  // Greedy: coarsest admissible level first.
  for (int l = floor_; l <= last; ++l) {
    const double res = options_.ladder[static_cast<std::size_t>(l)];
    if (ManhattanCellDistance(p_start_W, p_goal_W, res, options_.grid_origin) == 0) continue;
    any_separating = true;
    if (outcome_[static_cast<std::size_t>(l)] == Outcome::kFailed) continue;
    d.level = l;
    d.reason = ResolutionReason::kGreedy;
    break;
  }
  if (d.level < 0) {
    d.level = last;
    d.reason = any_separating ? ResolutionReason::kAllFailed : ResolutionReason::kSameCell;
  }
  d.resolution = options_.ladder[static_cast<std::size_t>(d.level)];
  d.changed = has_decision_ && d.level != level_;
  has_decision_ = true;
  level_ = d.level;
  return d;
}

void ResolutionAdapter::ReportPlanningOutcome(int level, bool found_path) {
  if (level < 0 || level >= num_levels()) {
    throw std::out_of_range("ResolutionAdapter::ReportPlanningOutcome: level " +
                            std::to_string(level) + " outside the ladder");
  }
  outcome_[static_cast<std::size_t>(level)] = found_path ? Outcome::kFound : Outcome::kFailed;
}

void ResolutionAdapter::Advance(double t) {
  if (std::isnan(t)) throw std::domain_error("ResolutionAdapter: t must be a number");
  if (!step_ends_.empty()) {
    if (t + kTimeSlack < step_ends_.front()) return;
    step_ends_.pop_front();
  } else if (t - last_change_t_ + kTimeSlack < options_.step_lifetime) {
    return;
  }
  last_change_t_ = t;
  if (level_ == 0) return;
  // One level coarser than where we plan now, and give that level another try.
  const int target = level_ - 1;
  floor_ = std::min(floor_, target);
  outcome_[static_cast<std::size_t>(target)] = Outcome::kUnknown;
}

void ResolutionAdapter::Refine(double t) {
  Advance(t);
  // Several triggers in a row usually report the same obstacle coming into view: one step each
  // min_refine_interval, so a burst does not jump straight to the finest (costliest) map.
  if (has_refined_ && t - last_refine_t_ + kTimeSlack < options_.min_refine_interval) return;
  if (level_ == num_levels() - 1) return;
  has_refined_ = true;
  last_refine_t_ = t;
  last_change_t_ = t;
  floor_ = std::max(floor_, level_ + 1);
  step_ends_.push_back(t + options_.step_lifetime);
}

void ResolutionAdapter::OnCollisionTrigger(double t) { Refine(t); }

double ResolutionAdapter::OnPathPlanned(double t, const PathScoreInputs& path) {
  const double s = PathScore(path, options_.gamma);
  if (s < options_.score_threshold) Refine(t);
  return s;
}

void ResolutionAdapter::ObserveEci(double t, double eci) {
  if (std::isnan(eci)) throw std::domain_error("ResolutionAdapter::ObserveEci: eci must be a number");
  // A cluttered view ahead: plan on a finer map before the triggers ask for it.
  if (eci >= options_.high_eci) {
    Refine(t);
  } else {
    Advance(t);
  }
}

}  // namespace enavi::navstack
