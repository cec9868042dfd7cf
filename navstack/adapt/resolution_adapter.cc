#include "navstack/adapt/resolution_adapter.h"

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
  RequireRange(options_.low_eci, 0.0, 1.0, "low_eci");
  RequireRange(options_.coarsen_after, 0.0, 1e6, "coarsen_after", /*lo_open=*/true);
  RequireRange(options_.quiet_period, 0.0, 1e6, "quiet_period", /*lo_open=*/true);
  RequireRange(options_.refine_hold, 0.0, 1e6, "refine_hold");
  RequireRange(options_.min_refine_interval, 0.0, 1e6, "min_refine_interval");
  RequireRange(options_.high_eci, options_.low_eci, 1.0, "high_eci");
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

void ResolutionAdapter::Refine(double t) {
  // Every trigger restarts the quiet period, also one held back below.
  quiet_since_ = t;
  // Several triggers in a row usually report the same obstacle coming into view: one step each
  // min_refine_interval, so a burst does not jump straight to the finest (costliest) map.
  if (has_refined_ && t - last_refine_t_ + kTimeSlack < options_.min_refine_interval) return;
  floor_ = std::min(std::max(floor_, level_ + 1), num_levels() - 1);
  has_refined_ = true;
  last_refine_t_ = t;
  // A refinement restarts the low-eci period: coarsening needs fresh evidence.
  eci_low_ = false;
}

void ResolutionAdapter::OnCollisionTrigger(double t) { Refine(t); }

double ResolutionAdapter::OnPathPlanned(double t, const PathScoreInputs& path) {
  const double s = PathScore(path, options_.gamma);
  if (s < options_.score_threshold) Refine(t);
  return s;
}

void ResolutionAdapter::ObserveEci(double t, double eci) {
  if (std::isnan(eci) || std::isnan(t)) {
    throw std::domain_error("ResolutionAdapter::ObserveEci: eci and t must be numbers");
  }
  if (eci > options_.low_eci) {
    eci_low_ = false;
    // Cluttered view ahead: plan on a finer map before the triggers ask for it (paper Sec. VI:
    // higher eci, finer resolution).
    if (eci >= options_.high_eci) Refine(t);
  } else if (!eci_low_) {
    eci_low_ = true;
    eci_low_since_ = t;
  }
  const bool low_sustained = eci_low_ && t - eci_low_since_ + kTimeSlack >= options_.coarsen_after;
  const bool quiet = t - quiet_since_ + kTimeSlack >= options_.quiet_period;
  const bool held = !has_refined_ || t - last_refine_t_ + kTimeSlack >= options_.refine_hold;
  if (!(low_sustained || quiet) || !held || level_ == 0) return;
  // One step coarser than where we plan now, and give that level another try.
  const int target = level_ - 1;
  floor_ = std::min(floor_, target);
  outcome_[static_cast<std::size_t>(target)] = Outcome::kUnknown;
  // The next step needs another full period of either kind (and a Select() at the new level).
  eci_low_since_ = t;
  quiet_since_ = t;
}

}  // namespace enavi::navstack
