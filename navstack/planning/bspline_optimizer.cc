#include "navstack/planning/bspline_optimizer.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include <lbfgs.h>

#include "navstack/planning/lbfgs_array.h"

namespace enavi::navstack {
namespace {

using Vec3 = Eigen::Vector3d;

// The optimiser aims slightly below the limits so that time re-allocation is rarely needed.
constexpr double kLimitTarget = 0.97;
// Curve parameters u of the clearance points of each segment.
constexpr double kClearanceU[] = {0.0, 0.5};
// Time re-allocation overshoots the measured excess a little so one round usually suffices.
constexpr double kStretchMargin = 1.03;
// Bounds of the stretch factor per round and over all rounds.
constexpr double kMaxStretchPerRound = 2.0;
constexpr double kMaxTotalStretch = 3.0;

// Cost of the control points; the free ones (columns [3, n-3)) are L-BFGS's variables.
class Cost {
 public:
  Cost(const UniformBspline& spline, const DistanceField& field, const PlannerOptions& options,
       double clearance_weight)
      : q_(spline.control_points()),
        dt_(spline.dt()),
        field_(field),
        w_smooth_(options.weight_smoothness),
        w_clear_(clearance_weight),
        w_feas_(options.weight_feasibility),
        d_safe_(options.robot_radius + options.safe_distance_margin),
        v_lim_(kLimitTarget * options.v_max),
        a_lim_(kLimitTarget * options.a_max) {
    const int m = spline.num_segments();
    for (int i = 0; i < m; ++i) {
      for (double u : kClearanceU) {
        if (i == 0 && u == 0.0) continue;  // the start point is fixed
        samples_.push_back({i, UniformBspline::Basis(u, 0)});
      }
    }
  }

  int num_free() const { return static_cast<int>(q_.cols()) - 6; }
  int work_per_evaluation() const { return static_cast<int>(q_.cols() + samples_.size()); }
  const Eigen::Matrix3Xd& control_points() const { return q_; }

  void SetFree(const double* x) {
    q_.middleCols(3, num_free()) = Eigen::Map<const Eigen::Matrix3Xd>(x, 3, num_free());
  }

  // Cost at the current control points; gradient with respect to the free ones into g.
  double Evaluate(double* g) {
    const int n = static_cast<int>(q_.cols());
    Eigen::Matrix3Xd grad = Eigen::Matrix3Xd::Zero(3, n);
    double cost = 0.0;

    // Smoothness: squared jerk of the control polygon.
    for (int i = 0; i + 3 < n; ++i) {
      const Vec3 j = q_.col(i + 3) - 3.0 * q_.col(i + 2) + 3.0 * q_.col(i + 1) - q_.col(i);
      cost += w_smooth_ * j.squaredNorm();
      const Vec3 dj = 2.0 * w_smooth_ * j;
      grad.col(i + 3) += dj;
      grad.col(i + 2) -= 3.0 * dj;
      grad.col(i + 1) += 3.0 * dj;
      grad.col(i) -= dj;
    }

    // Clearance: quadratic penalty below the safe distance, pushed along the field's gradient.
    for (const Sample& s : samples_) {
      const Vec3 p = q_.middleCols<4>(s.segment) * s.basis;
      Vec3 grad_d;
      const double d = field_.Distance(p, &grad_d);
      if (d >= d_safe_) continue;
      const double e = d_safe_ - d;
      cost += w_clear_ * e * e;
      const Vec3 dp = -2.0 * w_clear_ * e * grad_d;
      for (int k = 0; k < 4; ++k) grad.col(s.segment + k) += s.basis[k] * dp;
    }

    // Feasibility: control velocities and accelerations beyond the limits.
    const double inv_v2 = 1.0 / (v_lim_ * v_lim_), inv_a2 = 1.0 / (a_lim_ * a_lim_);
    for (int i = 0; i + 1 < n; ++i) {
      const Vec3 v = (q_.col(i + 1) - q_.col(i)) / dt_;
      const double s = v.squaredNorm() * inv_v2 - 1.0;
      if (s <= 0.0) continue;
      cost += w_feas_ * s * s;
      const Vec3 dv = w_feas_ * 2.0 * s * 2.0 * inv_v2 * v / dt_;
      grad.col(i + 1) += dv;
      grad.col(i) -= dv;
    }
    for (int i = 0; i + 2 < n; ++i) {
      const Vec3 a = (q_.col(i + 2) - 2.0 * q_.col(i + 1) + q_.col(i)) / (dt_ * dt_);
      const double s = a.squaredNorm() * inv_a2 - 1.0;
      if (s <= 0.0) continue;
      cost += w_feas_ * s * s;
      const Vec3 da = w_feas_ * 2.0 * s * 2.0 * inv_a2 * a / (dt_ * dt_);
      grad.col(i + 2) += da;
      grad.col(i + 1) -= 2.0 * da;
      grad.col(i) += da;
    }

    Eigen::Map<Eigen::Matrix3Xd>(g, 3, num_free()) = grad.middleCols(3, num_free());
    ++evaluations_;
    return cost;
  }

  int evaluations() const { return evaluations_; }

 private:
  struct Sample {
    int segment;
    Eigen::Vector4d basis;
  };
  Eigen::Matrix3Xd q_;
  double dt_;
  const DistanceField& field_;
  double w_smooth_, w_clear_, w_feas_, d_safe_, v_lim_, a_lim_;
  std::vector<Sample> samples_;
  int evaluations_ = 0;
};

// What liblbfgs' C callbacks see through their void* instance.
struct LbfgsContext {
  Cost* cost;
  int iterations = 0;
};

lbfgsfloatval_t EvaluateCallback(void* instance, const lbfgsfloatval_t* x, lbfgsfloatval_t* g,
                                 const int /*n*/, const lbfgsfloatval_t /*step*/) {
  Cost* cost = static_cast<LbfgsContext*>(instance)->cost;
  cost->SetFree(x);
  return cost->Evaluate(g);
}

int ProgressCallback(void* instance, const lbfgsfloatval_t*, const lbfgsfloatval_t*,
                     const lbfgsfloatval_t, const lbfgsfloatval_t, const lbfgsfloatval_t,
                     const lbfgsfloatval_t, int, int k, int) {
  static_cast<LbfgsContext*>(instance)->iterations = k;
  return 0;  // never cancel: the iteration bound is param.max_iterations
}

}  // namespace

double LimitExcessRatio(const UniformBspline& s, const PlannerOptions& options) {
  const double r_v = s.MaxControlSpeed(2) / options.v_max;
  const double r_a = std::sqrt(s.MaxControlAcceleration(1) / options.a_max);
  return std::max({r_v, r_a, 1.0});
}

UniformBspline OptimizeControlPoints(const UniformBspline& spline, const DistanceField& field,
                                     const PlannerOptions& options, double clearance_weight,
                                     WorkCounts* work, OptimizationSummary* summary) {
  Cost cost(spline, field, options, clearance_weight);
  const int n = 3 * cost.num_free();
  if (n <= 0) return spline;
  LbfgsArray x(n);
  Eigen::Map<Eigen::Matrix3Xd>(x.data, 3, cost.num_free()) =
      spline.control_points().middleCols(3, cost.num_free());

  lbfgs_parameter_t param;
  lbfgs_parameter_init(&param);
  param.max_iterations = options.max_optimizer_iterations;
  param.epsilon = 1e-5;
  param.past = 3;
  param.delta = 1e-5;
  param.max_linesearch = 20;

  LbfgsContext ctx{&cost};
  lbfgsfloatval_t fx = 0.0;
  lbfgs(n, x.data, &fx, EvaluateCallback, ProgressCallback, &ctx, &param);
  // On a line-search failure liblbfgs restores the last accepted point into x; take x as final.
  cost.SetFree(x.data);

  if (work != nullptr) {
    work->Add(WorkUnit::kOptimizerEval,
              static_cast<std::int64_t>(cost.evaluations()) * cost.work_per_evaluation());
  }
  if (summary != nullptr) {
    ++summary->lbfgs_runs;
    summary->iterations += ctx.iterations;
    summary->evaluations += cost.evaluations();
    summary->final_cost = fx;
  }
  return UniformBspline(cost.control_points(), spline.dt());
}

UniformBspline StretchTime(const UniformBspline& spline, const TrajectorySample& start,
                           double factor) {
  const double duration = spline.duration() * factor;
  const int m = std::max(4, static_cast<int>(std::ceil(spline.num_segments() * factor - 1e-9)));
  const double dt = duration / m;
  std::vector<Vec3> targets;
  targets.reserve(m - 1);
  for (int k = 1; k < m; ++k) targets.push_back(spline.Position(k * dt / factor));
  const Vec3 end = spline.control_points().col(spline.num_control_points() - 1);
  return FitBspline(start.p, start.v, start.a, targets, end, dt);
}

double MinClearance(const UniformBspline& spline, const DistanceField& field,
                    const ClearanceRule& rule, WorkCounts* work) {
  const double speed = std::max(spline.MaxControlSpeed(0), 1e-3);
  const double h = std::min(spline.dt() / 4.0, 0.5 * field.resolution() / speed);
  const int n = std::max(1, static_cast<int>(std::ceil(spline.duration() / h)));
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= n; ++i) {
    const Vec3 p = spline.Position(spline.duration() * i / n);
    if (rule.InEscapeBall(p)) continue;
    best = std::min(best, field.Distance(p));
  }
  if (work != nullptr) work->Add(WorkUnit::kTrajectorySample, n + 1);
  return best;
}

UniformBspline OptimizeTrajectory(const UniformBspline& initial, const TrajectorySample& start,
                                  const DistanceField& field, const ClearanceRule& rule,
                                  const PlannerOptions& options, WorkCounts* work,
                                  OptimizationSummary* summary) {
  OptimizationSummary local;
  OptimizationSummary& sum = summary != nullptr ? *summary : local;
  UniformBspline spline = initial;
  double clearance_weight = options.weight_clearance;
  // Re-allocation rounds are shared by all clearance retries, and the total stretch is capped:
  // excess caused by the start state itself (e.g. fast towards a close wall) does not shrink
  // with more time, and must not make the trajectory crawl.
  int reallocations_left = options.max_time_reallocations;
  double total_stretch = 1.0;
  for (int retry = 0;; ++retry) {
    // Optimise, then stretch time while the limits are exceeded.
    while (true) {
      spline = OptimizeControlPoints(spline, field, options, clearance_weight, work, &sum);
      const double ratio = LimitExcessRatio(spline, options);
      if (ratio <= 1.0 || reallocations_left == 0 || total_stretch >= kMaxTotalStretch) break;
      const double factor = std::min({ratio * kStretchMargin, kMaxStretchPerRound,
                                      kMaxTotalStretch / total_stretch});
      spline = StretchTime(spline, start, factor);
      total_stretch *= factor;
      --reallocations_left;
      ++sum.time_reallocations;
    }
    sum.min_clearance = MinClearance(spline, field, rule, work);
    sum.clearance_ok = sum.min_clearance >= options.robot_radius;
    if (sum.clearance_ok || retry >= options.max_clearance_retries) break;
    clearance_weight *= 4.0;
    ++sum.clearance_retries;
  }
  sum.max_speed = spline.MaxControlSpeed(2);
  sum.max_acceleration = spline.MaxControlAcceleration(1);
  sum.within_limits = sum.max_speed <= options.v_max && sum.max_acceleration <= options.a_max;
  std::ostringstream msg;
  msg << sum.lbfgs_runs << " L-BFGS runs (" << sum.iterations << " iterations, " << sum.evaluations
      << " evaluations), " << sum.time_reallocations << " time re-allocations, "
      << sum.clearance_retries << " clearance retries; max control speed " << sum.max_speed
      << " m/s, acceleration " << sum.max_acceleration << " m/s^2, min clearance "
      << sum.min_clearance << " m";
  sum.message = msg.str();
  return spline;
}

}  // namespace enavi::navstack
