#pragma once
// Imperfect odometry as a visual-inertial odometry (VIO) gives it: white noise on position and
// yaw plus a random-walk drift of both, seeded per episode. The stack is handed the corrupted
// estimate; the metrics keep using the truth.

#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "navstack/common/state.h"
#include "navstack/rl/random.h"

namespace enavi::sim {

struct OdometryNoiseOptions {
  double position_white_m = 0.0;          ///< std of the white position noise, per axis
  double position_walk_m_per_sqrt_s = 0.0;  ///< random-walk drift density of position, per axis
  double yaw_white_rad = 0.0;
  double yaw_walk_rad_per_sqrt_s = 0.0;
  bool Active() const {
    return position_white_m > 0.0 || position_walk_m_per_sqrt_s > 0.0 || yaw_white_rad > 0.0 ||
           yaw_walk_rad_per_sqrt_s > 0.0;
  }
};

/// Named presets: none (default), good, typical, poor.
///
/// The drift densities are set from the translation drift that monocular VIO pipelines reach on
/// flying-robot data: roughly 0.5 % (best), 1-2 % (typical) and several % (poor) of the distance
/// flown (Delmerico and Scaramuzza, "A Benchmark Comparison of Monocular Visual-Inertial Odometry
/// Algorithms for Flying Robots", ICRA 2018, EuRoC results). A random walk grows with sqrt(t)
/// rather than with distance; the densities below give those percentages after a 20 m flight at
/// 2 m/s (10 s): sigma_drift = fraction * 20 m / sqrt(10 s). This conversion and the white-noise
/// and yaw values (a few cm, tenths of a degree: the jitter of a VIO pose at camera rate) are our
/// estimates, not numbers read from the benchmark.
/// @throws std::invalid_argument listing the names for anything else.
OdometryNoiseOptions OdometryNoisePreset(const std::string& name);

/// @throws std::invalid_argument naming the field when a value is negative or not finite.
void ValidateOdometryNoise(const OdometryNoiseOptions& options);

class OdometryNoise {
 public:
  /// @throws std::invalid_argument as ValidateOdometryNoise.
  OdometryNoise(const OdometryNoiseOptions& options, std::uint64_t seed);

  /// The estimate the stack receives for the true state at time t (s, non-decreasing): the drift
  /// advances over the time since the last call, white noise is drawn fresh. Velocity,
  /// acceleration and rates stay true (a VIO's velocity is far better than its position).
  /// The orientation is rotated about world z by the yaw error.
  navstack::VehicleState Corrupt(const navstack::VehicleState& truth, double t);

  /// Error of the last Corrupt(): position (m) and yaw (rad), estimate minus truth.
  const Eigen::Vector3d& last_position_error() const { return last_dp_; }
  double last_yaw_error() const { return last_dyaw_; }

 private:
  OdometryNoiseOptions options_;
  navstack::rl::Rng rng_;
  double t_last_ = 0.0;
  Eigen::Vector3d drift_p_ = Eigen::Vector3d::Zero();
  double drift_yaw_ = 0.0;
  Eigen::Vector3d last_dp_ = Eigen::Vector3d::Zero();
  double last_dyaw_ = 0.0;
};

}  // namespace enavi::sim
