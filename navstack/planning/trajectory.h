#pragma once
// The planner's output: a B-spline in absolute time, with the yaw the forward camera should take.

#include <vector>

#include <Eigen/Core>

#include "navstack/common/state.h"
#include "navstack/planning/bspline.h"
#include "navstack/planning/planner_options.h"

namespace enavi::navstack {

/// A uniform cubic B-spline that starts at absolute time t0, plus a yaw profile.
///
/// Yaw rule (the depth camera looks along body x): when moving at least
/// options.yaw_speed_threshold, face the point the curve reaches options.yaw_lookahead seconds
/// later (in a bend the camera sees round the corner first), or the horizontal velocity when that
/// point is too close; when slower, face the horizontal direction the curve will have moved in
/// the next 0.5 s if that is at least threshold x 0.5 s (start from hover); otherwise keep the
/// previous heading. The heading starts at yaw0 turning at yaw_rate0 (continuity with the
/// previous reference) and turns at most options.yaw_rate_max, changing its rate by at most
/// options.yaw_accel_max, braking in time to stop at the desired heading. Immutable after
/// construction: Sample() is safe to call from several threads.
class Trajectory {
 public:
  Trajectory(UniformBspline spline, double t0, double yaw0, const PlannerOptions& options = {},
             double yaw_rate0 = 0.0);

  /// Reference at absolute time t, clamped to [start_time(), end_time()]; after the end: the end
  /// point at rest (v = a = j = 0, yaw rate 0), yaw held. Yaw in (-pi, pi].
  TrajectorySample Sample(double t) const;

  double start_time() const { return t0_; }
  double end_time() const { return t0_ + spline_.duration(); }
  double duration() const { return spline_.duration(); }
  /// Arc length of the curve [m].
  double length() const { return length_; }
  Eigen::Vector3d end_point() const { return spline_.Position(spline_.duration()); }
  const UniformBspline& spline() const { return spline_; }
  /// The yaw rate the heading started with (the constructor's yaw_rate0, within the rate limit).
  double start_yaw_rate() const { return yaw_rate0_; }

 private:
  UniformBspline spline_;
  double t0_;
  double length_ = 0.0;
  double yaw_step_ = 0.0;
  double yaw_rate0_ = 0.0;
  std::vector<double> yaw_;  ///< unwrapped yaw every yaw_step_ from t0 to the end
};

}  // namespace enavi::navstack
