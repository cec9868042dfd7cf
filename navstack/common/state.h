#pragma once
// Vehicle state and trajectory references exchanged between planner, controller and simulator.

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace enavi::navstack {

/// Vehicle state estimate (the simulator provides ground truth: perfect odometry).
/// Body frame B: x forward, y left, z up (FLU). World frame W: z up.
struct VehicleState {
  double t = 0.0;
  Eigen::Vector3d p_WB = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_WB = Eigen::Vector3d::Zero();       ///< expressed in W
  Eigen::Vector3d a_WB = Eigen::Vector3d::Zero();       ///< expressed in W (finite difference)
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  Eigen::Vector3d w_WB_B = Eigen::Vector3d::Zero();     ///< angular velocity in B
};

/// a in (-pi, pi].
inline double WrapAngle(double a) {
  constexpr double kPi = 3.14159265358979323846;
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a <= 0.0) a += 2.0 * kPi;
  return a - kPi;
}

/// Reference for the tracking controller at one instant.
struct TrajectorySample {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d j = Eigen::Vector3d::Zero();
  double yaw = 0.0;
  double yaw_rate = 0.0;
};

}  // namespace enavi::navstack
