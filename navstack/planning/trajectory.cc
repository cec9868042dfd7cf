#include "navstack/planning/trajectory.h"

#include <algorithm>
#include <cmath>

namespace enavi::navstack {
namespace {

// Yaw profile resolution and the look-ahead used at low speed.
constexpr double kYawStep = 0.02;
constexpr double kLookAhead = 0.5;
// Curve samples per knot span for the arc length.
constexpr int kLengthSamplesPerSpan = 20;

}  // namespace

Trajectory::Trajectory(UniformBspline spline, double t0, double yaw0, const PlannerOptions& options,
                       double yaw_rate0)
    : spline_(std::move(spline)), t0_(t0) {
  const double duration = spline_.duration();

  // Arc length from dense chords.
  const int n_len = kLengthSamplesPerSpan * spline_.num_segments();
  Eigen::Vector3d prev = spline_.Position(0.0);
  for (int i = 1; i <= n_len; ++i) {
    const Eigen::Vector3d p = spline_.Position(duration * i / n_len);
    length_ += (p - prev).norm();
    prev = p;
  }

  // Yaw profile: desired heading by the rule in the header, rate and acceleration limited,
  // unwrapped.
  const int n = std::max(1, static_cast<int>(std::ceil(duration / kYawStep)));
  yaw_step_ = duration / n;
  yaw_.resize(n + 1);
  yaw_[0] = yaw0;
  yaw_rate0_ = std::clamp(yaw_rate0, -options.yaw_rate_max, options.yaw_rate_max);
  double rate = yaw_rate0_;
  const double threshold = options.yaw_speed_threshold;
  const double max_rate_change = options.yaw_accel_max * yaw_step_;
  for (int k = 1; k <= n; ++k) {
    const double t = k * yaw_step_;
    const Eigen::Vector2d v = spline_.Velocity(t).head<2>();
    // Look where the vehicle will be `yaw_lookahead` from now: in a turn the camera sees the
    // inside of the bend before the vehicle gets there (the velocity would point at the wall).
    const double look = std::max(options.yaw_lookahead, kLookAhead);
    const Eigen::Vector2d ahead = (spline_.Position(std::min(t + look, duration)) - spline_.Position(t)).head<2>();
    const Eigen::Vector2d near = (spline_.Position(t + kLookAhead) - spline_.Position(t)).head<2>();
    double desired = yaw_[k - 1];
    if (v.norm() >= threshold && ahead.norm() >= threshold * look) {
      desired = std::atan2(ahead.y(), ahead.x());
    } else if (v.norm() >= threshold && v.norm() > 0.0) {
      desired = std::atan2(v.y(), v.x());
    } else if (near.norm() >= threshold * kLookAhead && near.norm() > 0.0) {
      desired = std::atan2(near.y(), near.x());
    }
    // The rate that reaches the desired heading in this step, no faster than the rate limit or
    // than the rate w from which the turn, braking a step later, still stops there
    // (w dt + w^2 / 2a = error).
    const double error = WrapAngle(desired - yaw_[k - 1]);
    const double braking = -max_rate_change + std::sqrt(max_rate_change * max_rate_change +
                                                         2.0 * options.yaw_accel_max * std::abs(error));
    const double target =
        std::copysign(std::min({std::abs(error) / yaw_step_, options.yaw_rate_max, braking}), error);
    rate += std::clamp(target - rate, -max_rate_change, max_rate_change);
    yaw_[k] = yaw_[k - 1] + rate * yaw_step_;
  }
}

TrajectorySample Trajectory::Sample(double t) const {
  const double duration = spline_.duration();
  const double tau = std::clamp(t - t0_, 0.0, duration);
  TrajectorySample s;
  s.p = spline_.Position(tau);
  const int n = static_cast<int>(yaw_.size()) - 1;
  if (t - t0_ >= duration) {
    // At rest at the end point.
    s.p = spline_.Position(duration);
    s.yaw = WrapAngle(yaw_.back());
    return s;
  }
  s.v = spline_.Velocity(tau);
  s.a = spline_.Acceleration(tau);
  s.j = spline_.Jerk(tau);
  const int k = std::min(static_cast<int>(std::floor(tau / yaw_step_)), n - 1);
  const double w = tau / yaw_step_ - k;
  s.yaw = WrapAngle(yaw_[k] + w * (yaw_[k + 1] - yaw_[k]));
  s.yaw_rate = (yaw_[k + 1] - yaw_[k]) / yaw_step_;
  return s;
}

}  // namespace enavi::navstack
