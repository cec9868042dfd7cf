#pragma once
// Uniform cubic B-spline: the trajectory representation of the planner (as Ego-Planner).

#include <vector>

#include <Eigen/Core>

namespace enavi::navstack {

/// Uniform cubic B-spline in R^3 over t in [0, duration()], duration = (N - 3) * dt for N control
/// points Q_0..Q_{N-1}. Segment i (t in [i dt, (i+1) dt)) is shaped by Q_i..Q_{i+3}; at its start
/// p = (Q_i + 4 Q_{i+1} + Q_{i+2}) / 6, v = (Q_{i+2} - Q_i) / (2 dt),
/// a = (Q_i - 2 Q_{i+1} + Q_{i+2}) / dt^2. The curve lies in the convex hull of its control
/// points, its velocity in that of V_i = (Q_{i+1} - Q_i) / dt and its acceleration in that of
/// A_i = (V_{i+1} - V_i) / dt: bounding those bounds the whole curve.
class UniformBspline {
 public:
  /// @throws std::invalid_argument if fewer than 4 control points, dt <= 0 or values not finite.
  UniformBspline(Eigen::Matrix3Xd control_points, double dt);

  /// Evaluation; t is clamped to [0, duration()].
  Eigen::Vector3d Position(double t) const { return Evaluate(t, 0); }
  Eigen::Vector3d Velocity(double t) const { return Evaluate(t, 1); }
  Eigen::Vector3d Acceleration(double t) const { return Evaluate(t, 2); }
  Eigen::Vector3d Jerk(double t) const { return Evaluate(t, 3); }
  /// derivative: 0 position, 1 velocity, 2 acceleration, 3 jerk.
  Eigen::Vector3d Evaluate(double t, int derivative) const;

  int num_control_points() const { return static_cast<int>(q_.cols()); }
  int num_segments() const { return static_cast<int>(q_.cols()) - 3; }
  double dt() const { return dt_; }
  double duration() const { return num_segments() * dt_; }
  const Eigen::Matrix3Xd& control_points() const { return q_; }

  /// Largest |V_i| and |A_i| over the control-point differences from index `first_v` / `first_a`
  /// on (upper bounds of the curve's speed and acceleration after those points).
  double MaxControlSpeed(int first_v = 0) const;
  double MaxControlAcceleration(int first_a = 0) const;

  /// Basis weights of segment-local parameter u in [0, 1] for the given derivative (not scaled by
  /// dt): p = sum_j w_j Q_{i+j}, derivative k is sum_j w_j Q_{i+j} / dt^k.
  static Eigen::Vector4d Basis(double u, int derivative);

 private:
  Eigen::Matrix3Xd q_;
  double dt_;
};

/// The three control points that make the curve start at exactly (p0, v0, a0) for knot span dt.
Eigen::Matrix3d StartControlPoints(const Eigen::Vector3d& p0, const Eigen::Vector3d& v0,
                                   const Eigen::Vector3d& a0, double dt);

/// Spline of M = knot_targets.size() + 1 segments (M >= 4) with knot span dt that starts at
/// exactly (p0, v0, a0), ends at rest at p_end (last three control points equal p_end), and whose
/// interior knots k = 1..M-1 are fitted to knot_targets[k-1] by least squares, lightly
/// regularised on control-point acceleration. @throws std::invalid_argument if M < 4 or dt <= 0.
UniformBspline FitBspline(const Eigen::Vector3d& p0, const Eigen::Vector3d& v0,
                          const Eigen::Vector3d& a0,
                          const std::vector<Eigen::Vector3d>& knot_targets,
                          const Eigen::Vector3d& p_end, double dt);

/// Ego-Planner-style initial trajectory along a polyline path from the start state: the path is
/// timed by a trapezoidal speed profile (from the start speed along the path to 0.9 v_max,
/// braking to it first if the start is faster, 0.8 a_max, to rest at the end; slowed down by the
/// time to brake a start velocity pointing away from the path and fly back), sampled every knot
/// span dt ~ control_point_spacing / max(v_max, start speed along the path) and fitted with
/// FitBspline. path.front() is taken as p0 and path.back() as the end point.
/// @throws std::invalid_argument if the path is empty or a parameter is not positive.
UniformBspline BsplineFromPath(const Eigen::Vector3d& v0, const Eigen::Vector3d& a0,
                               const std::vector<Eigen::Vector3d>& path, double v_max,
                               double a_max, double control_point_spacing);

}  // namespace enavi::navstack
