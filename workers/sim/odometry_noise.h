#pragma once
// Imperfect odometry as a visual-inertial odometry (VIO) gives it: white noise on position and
// yaw plus a random-walk drift of both, seeded per episode. The stack (and the flight controller,
// which flies on the same estimate) is handed the corrupted state; the metrics keep the truth.

#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "navstack/common/state.h"
#include "navstack/rl/random.h"

namespace enavi::sim {

struct OdometryNoiseOptions {
  double position_white_m = 0.0;            ///< std of the white position noise, per axis
  double position_walk_m_per_sqrt_s = 0.0;  ///< random-walk drift density of position, per axis
  double yaw_white_rad = 0.0;
  double yaw_walk_rad_per_sqrt_s = 0.0;
  bool Active() const {
    return position_white_m > 0.0 || position_walk_m_per_sqrt_s > 0.0 || yaw_white_rad > 0.0 ||
           yaw_walk_rad_per_sqrt_s > 0.0;
  }
};

/// The presets of api::kOdometryNoisePresets: none (the default: the truth), good, typical, poor.
///
/// Drift: monocular VIO pipelines on the EuRoC flights (40-130 m each) end a few decimetres off
/// (Delmerico and Scaramuzza, "A Benchmark Comparison of Monocular Visual-Inertial Odometry
/// Algorithms for Flying Robots", ICRA 2018): about 0.5 % of the distance flown for the best
/// pipelines, 1-2 % typical, several % for those that struggle. These percentages are our reading
/// of the benchmark's plots, rounded. A random walk grows with sqrt(t), not with distance; the
/// densities give 0.5 / 1.5 / 5 % after a 20 m flight at 2 m/s (10 s): sigma = fraction * 20 m /
/// sqrt(10 s). The white noise (1-10 cm) and the yaw values (tenths of a degree, a yaw drift of
/// 0.05-0.5 deg/sqrt(s)) are our estimates of a VIO pose's jitter and heading drift, not numbers
/// from the benchmark.
/// @throws std::invalid_argument "odometry_noise: ..." naming the presets for anything else.
OdometryNoiseOptions OdometryNoisePreset(const std::string& name);

/// Corrupts the true state as a VIO would. Update() draws a new error when the VIO delivers a
/// pose (the episode calls it at every depth frame: the camera rate); Apply() adds the current
/// error to a true state (between frames the IMU propagation keeps the error as it was).
class OdometryNoise {
 public:
  /// @throws std::invalid_argument naming the field when a value is negative or not finite.
  OdometryNoise(const OdometryNoiseOptions& options, std::uint64_t seed);

  /// The error at time t (s, non-decreasing): the drift walks over the time since the last
  /// update, the white noise is drawn afresh.
  /// @throws std::invalid_argument when t goes backwards.
  void Update(double t);
  /// The estimate of `truth`: position plus the position error; orientation, velocity and
  /// acceleration rotated about world z by the yaw error (a VIO's world frame turned by its
  /// heading error); body rates true (the gyro's).
  navstack::VehicleState Apply(const navstack::VehicleState& truth) const;

  bool active() const { return options_.Active(); }
  /// Current error: position (m) and yaw (rad), estimate minus truth.
  const Eigen::Vector3d& position_error() const { return error_p_; }
  double yaw_error() const { return error_yaw_; }

 private:
  OdometryNoiseOptions options_;
  navstack::rl::Rng rng_;
  double t_last_ = 0.0;
  Eigen::Vector3d drift_p_ = Eigen::Vector3d::Zero();
  double drift_yaw_ = 0.0;
  Eigen::Vector3d error_p_ = Eigen::Vector3d::Zero();
  double error_yaw_ = 0.0;
};

}  // namespace enavi::sim
