#include "navstack/planning/rebound_optimizer.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <vector>

#include <lbfgs.h>

#include "navstack/planning/grid_astar.h"
#include "navstack/planning/lbfgs_array.h"

namespace enavi::navstack {
namespace {

using Vec3 = Eigen::Vector3d;

// Cubic B-spline: the first and last three control points are fixed (start state, rest at the end).
constexpr int kOrder = 3;
// Ego-Planner, bspline_optimizer.cpp calcDistanceCostRebound: the rebound check runs after 3
// evaluations once the mean jerk cost per free control point is below 0.1 ("smooth enough").
constexpr int kReboundCheckAfter = 3;
constexpr double kSmoothEnough = 0.1;
// Ego-Planner, rebound_optimize: lbfgs_params.mem_size = 16, g_epsilon = 0.01.
constexpr int kLbfgsMemory = 16;
constexpr double kLbfgsEpsilon = 0.01;
// As OptimizeTrajectory: stretch bounds per round and in total, and the overshoot of a round.
constexpr double kStretchMargin = 1.03;
constexpr double kMaxStretchPerRound = 2.0;
constexpr double kMaxTotalStretch = 3.0;

// A {p, v} pair: anchor on the obstacle's surface and the direction out of it.
struct Pair {
  Vec3 p;
  Vec3 v;
};

// Ego-Planner's plane cut: where the plane through q with normal `law` crosses the A* path,
// walking from the path's middle towards the crossing.
std::optional<Vec3> PlaneCut(const std::vector<Vec3>& path, const Vec3& q, const Vec3& law) {
  int id = static_cast<int>(path.size()) / 2;
  double val = (path[id] - q).dot(law);
  while (true) {
    const int last = id;
    const double last_val = val;
    id += val >= 0.0 ? -1 : 1;
    if (id < 0 || id >= static_cast<int>(path.size())) return std::nullopt;
    val = (path[id] - q).dot(law);
    if (val * last_val <= 0.0 && (std::abs(val) > 0.0 || std::abs(last_val) > 0.0)) {
      const Vec3 d = path[id] - path[last];
      return Vec3(path[id] + d * (law.dot(q - path[id]) / law.dot(d)));
    }
  }
}

// Dense samples of the curve (as MinClearance: every resolution / 2 of travel, 4 per knot span at
// least) outside the escape ball; exact clearance where the inflated occupancy says it may be
// below robot_radius. The smallest clearance, capped at robot_radius.
double CappedClearance(const UniformBspline& s, const InflatedOccupancy& occ,
                       const ClearanceRule& rule, const PlannerOptions& o, WorkCounts* work) {
  const double r = o.robot_radius;
  const double speed = std::max(s.MaxControlSpeed(0), 1e-3);
  const double h = std::min(s.dt() / 4.0, 0.5 * occ.resolution() / speed);
  const int m = std::max(1, static_cast<int>(std::ceil(s.duration() / h)));
  double best = r;
  for (int i = 0; i <= m; ++i) {
    const Vec3 p = s.Position(s.duration() * i / m);
    if (rule.InEscapeBall(p) || !occ.Occupied(p)) continue;
    best = std::min(best, occ.Clearance(p, r));
  }
  if (work != nullptr) work->Add(WorkUnit::kTrajectorySample, m + 1);
  return best;
}

// One rebound optimisation over a fixed set of control points (Ego-Planner's BsplineOptimizer
// state: control points, their {p, v} pairs, the current collision weight).
class Rebound {
 public:
  Rebound(const UniformBspline& spline, const ReboundMaps& maps,
          const Eigen::AlignedBox3d& bounds, const ClearanceRule& rule,
          const PlannerOptions& options, const OverBudget& over_budget, WorkCounts* work,
          OptimizationSummary* summary)
      : q_(spline.control_points()),
        dt_(spline.dt()),
        occ_(maps.collision),
        guide_(maps.guide),
        bounds_(bounds),
        rule_(rule),
        o_(options),
        over_budget_(over_budget),
        work_(work),
        sum_(summary),
        pairs_(q_.cols()),
        lambda_collision_(options.rebound_lambda_collision) {}

  int n() const { return static_cast<int>(q_.cols()); }
  int num_free() const { return n() - 2 * kOrder; }
  UniformBspline spline() const { return UniformBspline(q_, dt_); }

  // Ego-Planner, bspline_optimizer.cpp initControlPoints: segments of the control polygon that
  // pass through obstacles (sampled every resolution / 2), A* around each, pairs.
  // first: a failed A* is kNoGuide (Ego-Planner "a star error, force return!"); later rounds
  // skip the segment.
  ReboundStatus InitPairs(bool first) {
    const double res = occ_.resolution();
    std::vector<std::pair<int, int>> segments;
    int run_start = -1;
    for (int i = kOrder; i <= n() - kOrder; ++i) {
      const Vec3 a = q_.col(i - 1), b = q_.col(i);
      const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / (0.5 * res))));
      bool hit = false;
      for (int k = 0; k <= steps && !hit; ++k) hit = occ_.Occupied(a + (b - a) * (static_cast<double>(k) / steps));
      if (hit && run_start < 0) run_start = i;
      if (!hit && run_start >= 0) {
        segments.push_back({run_start - 1, i - 1});
        run_start = -1;
      }
    }
    if (run_start >= 0) segments.push_back({run_start - 1, n() - kOrder});
    for (const auto& [in, out] : segments) {
      const ReboundStatus s = Guide(in, out);
      if (s == ReboundStatus::kOverBudget) return s;
      if (s == ReboundStatus::kNoGuide && first) return s;
    }
    return ReboundStatus::kOk;
  }

  // Ego-Planner, bspline_optimizer.cpp check_collision_and_rebound: a control point in an
  // obstacle that all its pairs already see as cleared (d >= resolution) is a new obstacle.
  // True if pairs were added (the running L-BFGS must restart).
  bool CheckAndRebound() {
    const double res = occ_.resolution();
    std::vector<std::pair<int, int>> segments;
    for (int i = kOrder - 1; i <= n() - kOrder; ++i) {
      if (!occ_.Occupied(q_.col(i))) continue;
      bool covered = false;
      for (const Pair& pr : pairs_[i]) covered = covered || (q_.col(i) - pr.p).dot(pr.v) < res;
      if (covered) continue;
      int in = i - 1;
      while (in > 0 && occ_.Occupied(q_.col(in))) --in;
      int out = i + 1;
      while (out < n() - 1 && occ_.Occupied(q_.col(out))) ++out;
      segments.push_back({std::max(in, 0), std::min(out, n() - 1)});
      i = out;
    }
    bool added = false;
    for (const auto& [in, out] : segments) {
      const ReboundStatus s = Guide(in, out);
      if (s == ReboundStatus::kOverBudget) return true;
      added = added || s == ReboundStatus::kOk;
    }
    return added;
  }

  // One L-BFGS run; stopped early when a rebound adds pairs or the budget is spent.
  void RunLbfgs() {
    const int nv = 3 * num_free();
    if (nv <= 0) return;
    LbfgsArray x(nv);
    Eigen::Map<Eigen::Matrix3Xd>(x.data, 3, num_free()) = q_.middleCols(kOrder, num_free());
    lbfgs_parameter_t param;
    lbfgs_parameter_init(&param);
    param.m = kLbfgsMemory;
    param.epsilon = kLbfgsEpsilon;
    param.max_iterations = o_.max_optimizer_iterations;
    param.max_linesearch = 20;
    evaluations_in_run_ = 0;
    stop_for_rebound_ = false;
    lbfgsfloatval_t fx = 0.0;
    lbfgs(nv, x.data, &fx, &Rebound::EvaluateCallback, &Rebound::ProgressCallback, this, &param);
    q_.middleCols(kOrder, num_free()) = Eigen::Map<const Eigen::Matrix3Xd>(x.data, 3, num_free());
    ++sum_->lbfgs_runs;
    sum_->final_cost = fx;
  }

  // Ego-Planner, rebound_optimize: optimise; restart after a rebound (at most max_rebounds);
  // if the converged curve still collides, re-segment with twice the collision weight (at most
  // max_rebound_restarts).
  ReboundStatus Optimize() {
    int rebounds = 0, restarts = 0;
    while (true) {
      RunLbfgs();
      if (budget_spent_) return ReboundStatus::kOverBudget;
      if (stop_for_rebound_) {
        ++sum_->rebounds;
        if (++rebounds <= o_.max_rebounds) continue;
        return ReboundStatus::kOk;
      }
      if (!CurveCollides(spline())) return ReboundStatus::kOk;
      if (++restarts > o_.max_rebound_restarts) return ReboundStatus::kOk;
      ++sum_->clearance_retries;
      const ReboundStatus s = InitPairs(false);
      if (s != ReboundStatus::kOk) return s;
      lambda_collision_ *= 2.0;
    }
  }

  bool CurveCollides(const UniformBspline& s) const {
    return CappedClearance(s, occ_, rule_, o_, work_) < o_.robot_radius;
  }

 private:
  // A* from Q_in to Q_out and the pairs of the segment's control points.
  ReboundStatus Guide(int in, int out) {
    ++sum_->astar_searches;
    const AstarResult a = GridAstar(occ_, bounds_, q_.col(in), q_.col(out), work_, over_budget_);
    sum_->astar_expansions += a.expansions;
    if (a.status == AstarStatus::kOverBudget) {
      budget_spent_ = true;
      return ReboundStatus::kOverBudget;
    }
    if (!a.ok() || a.path.size() < 2) return ReboundStatus::kNoGuide;
    AssignPairs(in, out, a.path);
    return ReboundStatus::kOk;
  }

  // Ego-Planner, initControlPoints steps 1-3: a pair for every interior control point whose plane
  // cuts the A* path (anchor: walking from the cut towards Q_j, the last free point before the
  // obstacle; v: towards the cut); a two-point segment uses its midpoint; the others copy their
  // neighbour's pair.
  void AssignPairs(int in, int out, const std::vector<Vec3>& path) {
    const double res = occ_.resolution();
    std::vector<bool> fresh(n(), false);
    int got = -1;
    for (int j = in + 1; j < out; ++j) {
      const Vec3 q = q_.col(j);
      const std::optional<Vec3> cut = PlaneCut(path, q, q_.col(j + 1) - q_.col(j - 1));
      if (!cut) continue;
      const double length = (*cut - q).norm();
      if (length <= 1e-5) continue;
      for (double a = length; a >= 0.0; a -= res) {
        const bool occupied = guide_.Occupied(q + (*cut - q) * (a / length));
        if (occupied || a < res) {
          const double at = occupied ? a + res : a;
          pairs_[j].push_back({q + (*cut - q) * (at / length), (*cut - q) / length});
          fresh[j] = true;
          got = j;
          break;
        }
      }
    }
    if (out - in == 1) {
      const Vec3 mid = 0.5 * (q_.col(in) + q_.col(out));
      const std::optional<Vec3> cut = PlaneCut(path, mid, q_.col(out) - q_.col(in));
      if (cut && (*cut - mid).norm() > 0.01) {
        pairs_[in].push_back({q_.col(in), (*cut - mid).normalized()});
        fresh[in] = true;
        got = in;
      }
    }
    if (got < 0) return;
    for (int j = got + 1; j <= out; ++j) {
      if (!fresh[j]) pairs_[j].push_back(pairs_[j - 1].back());
    }
    for (int j = got - 1; j >= in; --j) {
      if (!fresh[j]) pairs_[j].push_back(pairs_[j + 1].back());
    }
  }

  // Ego-Planner, combineCostRebound: lambda_smooth f_s + lambda_collision f_c + lambda_feas f_f.
  double Evaluate(double* g) {
    ++evaluations_in_run_;
    ++sum_->evaluations;
    const int nc = n();
    Eigen::Matrix3Xd g_s = Eigen::Matrix3Xd::Zero(3, nc), g_c = g_s, g_f = g_s;

    // Smoothness (calcSmoothnessCost): squared jerk of the control polygon.
    double f_s = 0.0;
    for (int i = 0; i + 3 < nc; ++i) {
      const Vec3 j = q_.col(i + 3) - 3.0 * q_.col(i + 2) + 3.0 * q_.col(i + 1) - q_.col(i);
      f_s += j.squaredNorm();
      const Vec3 dj = 2.0 * j;
      g_s.col(i) -= dj;
      g_s.col(i + 1) += 3.0 * dj;
      g_s.col(i + 2) -= 3.0 * dj;
      g_s.col(i + 3) += dj;
    }

    // Rebound check once the curve is smooth (calcDistanceCostRebound).
    if (evaluations_in_run_ > kReboundCheckAfter && f_s / std::max(num_free(), 1) < kSmoothEnough &&
        !stop_for_rebound_) {
      stop_for_rebound_ = CheckAndRebound();
    }

    // Collision (calcDistanceCostRebound): d = (Q - p) . v, error e = dist0 - d; e^3 below dist0,
    // continued by the quadratic 3 d0 e^2 - 3 d0^2 e + d0^3 beyond.
    const double d0 = o_.rebound_dist0;
    const double qa = 3.0 * d0, qb = -3.0 * d0 * d0, qc = d0 * d0 * d0;
    double f_c = 0.0;
    std::int64_t pairs = 0;
    for (int i = kOrder; i < nc - kOrder; ++i) {
      for (const Pair& pr : pairs_[i]) {
        ++pairs;
        const double e = d0 - (q_.col(i) - pr.p).dot(pr.v);
        if (e < 0.0) continue;
        if (e < d0) {
          f_c += e * e * e;
          g_c.col(i) -= 3.0 * e * e * pr.v;
        } else {
          f_c += qa * e * e + qb * e + qc;
          g_c.col(i) -= (2.0 * qa * e + qb) * pr.v;
        }
      }
    }

    // Feasibility (calcFeasibilityCost): excess of control velocities and accelerations, squared
    // (velocity terms scaled by 1 / dt^2 like Ego-Planner's). Ego-Planner bounds each axis; our
    // limits bound the norm, so the excess is that of |V_i| and |A_i|.
    const double ts_inv2 = 1.0 / (dt_ * dt_);
    double f_f = 0.0;
    for (int i = 0; i + 1 < nc; ++i) {
      const Vec3 v = (q_.col(i + 1) - q_.col(i)) / dt_;
      const double speed = v.norm();
      if (speed <= o_.v_max) continue;
      const double ex = speed - o_.v_max;
      f_f += ex * ex * ts_inv2;
      const Vec3 gr = 2.0 * ex * ts_inv2 * (v / speed) / dt_;
      g_f.col(i) -= gr;
      g_f.col(i + 1) += gr;
    }
    for (int i = 0; i + 2 < nc; ++i) {
      const Vec3 a = (q_.col(i + 2) - 2.0 * q_.col(i + 1) + q_.col(i)) * ts_inv2;
      const double acc = a.norm();
      if (acc <= o_.a_max) continue;
      const double ex = acc - o_.a_max;
      f_f += ex * ex;
      const Vec3 gr = 2.0 * ex * (a / acc) * ts_inv2;
      g_f.col(i) += gr;
      g_f.col(i + 1) -= 2.0 * gr;
      g_f.col(i + 2) += gr;
    }

    if (work_ != nullptr) work_->Add(WorkUnit::kOptimizerEval, nc + pairs);
    const Eigen::Matrix3Xd grad = o_.rebound_lambda_smooth * g_s + lambda_collision_ * g_c +
                                  o_.rebound_lambda_feasibility * g_f;
    Eigen::Map<Eigen::Matrix3Xd>(g, 3, num_free()) = grad.middleCols(kOrder, num_free());
    return o_.rebound_lambda_smooth * f_s + lambda_collision_ * f_c + o_.rebound_lambda_feasibility * f_f;
  }

  static lbfgsfloatval_t EvaluateCallback(void* instance, const lbfgsfloatval_t* x,
                                          lbfgsfloatval_t* g, const int /*n*/,
                                          const lbfgsfloatval_t /*step*/) {
    auto* self = static_cast<Rebound*>(instance);
    self->q_.middleCols(kOrder, self->num_free()) =
        Eigen::Map<const Eigen::Matrix3Xd>(x, 3, self->num_free());
    return self->Evaluate(g);
  }
  // Ego-Planner, earlyExit: a rebound (or the spent budget) cancels the run.
  static int ProgressCallback(void* instance, const lbfgsfloatval_t*, const lbfgsfloatval_t*,
                              const lbfgsfloatval_t, const lbfgsfloatval_t, const lbfgsfloatval_t,
                              const lbfgsfloatval_t, int, int /*k*/, int) {
    auto* self = static_cast<Rebound*>(instance);
    ++self->sum_->iterations;
    return self->stop_for_rebound_ || self->budget_spent_ ? 1 : 0;
  }

  Eigen::Matrix3Xd q_;
  double dt_;
  const InflatedOccupancy& occ_;    // collision: the vehicle's radius (checks, A*)
  const InflatedOccupancy& guide_;  // Ego-Planner's inflation: anchors
  const Eigen::AlignedBox3d& bounds_;
  const ClearanceRule& rule_;
  const PlannerOptions& o_;
  const OverBudget& over_budget_;
  WorkCounts* work_;
  OptimizationSummary* sum_;
  std::vector<std::vector<Pair>> pairs_;
  double lambda_collision_;
  int evaluations_in_run_ = 0;
  bool stop_for_rebound_ = false;
  bool budget_spent_ = false;
};

}  // namespace

UniformBspline OptimizeTrajectoryRebound(const UniformBspline& initial, const TrajectorySample& start,
                                         const ReboundMaps& maps,
                                         const Eigen::AlignedBox3d& bounds, const ClearanceRule& rule,
                                         const PlannerOptions& options, const OverBudget& over_budget,
                                         WorkCounts* work, OptimizationSummary* summary,
                                         ReboundStatus* status) {
  OptimizationSummary local;
  OptimizationSummary& sum = summary != nullptr ? *summary : local;
  UniformBspline spline = initial;
  int reallocations_left = options.max_time_reallocations;
  double total_stretch = 1.0;
  // Optimise; then, while the limits are exceeded, stretch time (Ego-Planner's refineTrajAlgo)
  // and optimise the stretched curve again (its control points change, so its pairs are found
  // afresh; a start state that demands the excess keeps it, as in OptimizeTrajectory).
  Rebound first(spline, maps, bounds, rule, options, over_budget, work, &sum);
  ReboundStatus s = first.InitPairs(true);
  if (s == ReboundStatus::kOk) s = first.Optimize();
  if (s == ReboundStatus::kOk) spline = first.spline();
  while (s == ReboundStatus::kOk) {
    const double ratio = LimitExcessRatio(spline, options);
    if (ratio <= 1.0 || reallocations_left == 0 || total_stretch >= kMaxTotalStretch) break;
    const double factor =
        std::min({ratio * kStretchMargin, kMaxStretchPerRound, kMaxTotalStretch / total_stretch});
    spline = StretchTime(spline, start, factor);
    total_stretch *= factor;
    --reallocations_left;
    ++sum.time_reallocations;
    Rebound again(spline, maps, bounds, rule, options, over_budget, work, &sum);
    s = again.InitPairs(false);
    if (s == ReboundStatus::kOk) s = again.Optimize();
    if (s == ReboundStatus::kOk) spline = again.spline();
  }
  if (status != nullptr) *status = s;
  const double clearance = CappedClearance(spline, maps.collision, rule, options, work);
  sum.min_clearance = clearance;
  sum.clearance_ok = s == ReboundStatus::kOk && clearance >= options.robot_radius;
  sum.max_speed = spline.MaxControlSpeed(2);
  sum.max_acceleration = spline.MaxControlAcceleration(1);
  sum.within_limits = sum.max_speed <= options.v_max && sum.max_acceleration <= options.a_max;
  std::ostringstream msg;
  msg << "rebound: " << sum.lbfgs_runs << " L-BFGS runs (" << sum.iterations << " iterations, "
      << sum.evaluations << " evaluations), " << sum.rebounds << " rebounds, "
      << sum.clearance_retries << " restarts, " << sum.astar_searches << " A* searches ("
      << sum.astar_expansions << " expansions), " << sum.time_reallocations
      << " time re-allocations; max control speed " << sum.max_speed << " m/s, acceleration "
      << sum.max_acceleration << " m/s^2, clearance (capped at robot_radius) " << sum.min_clearance
      << " m";
  if (s == ReboundStatus::kNoGuide) msg << "; no way around an obstacle on the initial path";
  if (s == ReboundStatus::kOverBudget) msg << "; A* stopped by the work budget";
  sum.message = msg.str();
  return spline;
}

}  // namespace enavi::navstack
