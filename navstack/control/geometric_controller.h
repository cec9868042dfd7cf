#pragma once
// Geometric tracking controller on SE(3) (Lee, Leok, McClamroch, "Geometric tracking control of
// a quadrotor UAV on SE(3)", CDC 2010), written for a z-up world frame and an FLU body frame.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/state.h"
#include "navstack/control/vehicle.h"
#include "navstack/control/wrench.h"

namespace enavi::navstack {

/// Gains and limits. Defaults are tuned for the X500-class VehicleParams (1.5 kg,
/// J = diag(0.0217, 0.0217, 0.040)) with its motor lag, at 200 Hz: position loop about
/// 2.6 rad/s (xy) / 2.9 rad/s (z) natural frequency, attitude loop about 15 rad/s
/// (roll/pitch, damping 0.75) and 5 rad/s (yaw, 0.9). 1 m steps overshoot about 2 %, also
/// with the motor time constants tripled (tests/unit/control/closed_loop_test.cc).
struct GeometricControllerOptions {
  double rate_hz = 200.0;  ///< Update() call rate; the integrator steps 1/rate_hz per call
  Eigen::Vector3d k_position{10.0, 10.0, 13.0};  ///< N/m, world axes
  Eigen::Vector3d k_velocity{7.0, 7.0, 8.0};     ///< N/(m/s), world axes
  Eigen::Vector3d k_integral{3.0, 3.0, 8.0};     ///< N/(m s), world axes; 0 disables
  double integral_limit = 3.0;                   ///< N, bound on each axis of the integral force
  /// m/s: an axis integrates only while its velocity error is below this (near steady state),
  /// so steps and manoeuvres do not wind the integral up.
  double integral_max_speed_error = 0.2;
  /// m: the position error fed to the integrator is clipped to +-this, so a large error
  /// integrates at a bounded rate (a steady offset of any size is still removed, as long as
  /// the force it needs is within integral_limit).
  double integral_error_limit = 0.1;
  Eigen::Vector3d k_attitude{4.9, 4.9, 1.0};     ///< N m/rad, body axes (k_R of the paper)
  Eigen::Vector3d k_rate{0.49, 0.49, 0.36};      ///< N m s/rad, body axes (k_Omega)
  double max_tilt_deg = 35.0;  ///< bound on the angle between desired body z and world z
  double min_thrust = 1.5;     ///< N, collective thrust floor (keeps rotors spinning)
  double max_thrust = 30.0;    ///< N, collective thrust ceiling (<= 4 x MaxThrustPerRotor)
  bool drag_feedforward = true;  ///< compensate VehicleParams::linear_drag (body axes) at v_ref
  bool jerk_feedforward = true;  ///< desired angular velocity from the reference jerk / yaw rate
};

/// Everything the controller computed in one step (for logs and tests).
struct ControlOutput {
  Wrench wrench;                                          ///< desired thrust (N) and torques
  Eigen::Matrix3d R_WD = Eigen::Matrix3d::Identity();     ///< desired attitude
  Eigen::Vector3d w_WD_D = Eigen::Vector3d::Zero();       ///< desired angular velocity in D
  Eigen::Vector3d F_W = Eigen::Vector3d::Zero();          ///< desired force after limits, W
  Eigen::Vector3d e_p_W = Eigen::Vector3d::Zero();        ///< position error p - p_ref
  Eigen::Vector3d e_v_W = Eigen::Vector3d::Zero();        ///< velocity error v - v_ref
  Eigen::Vector3d e_R = Eigen::Vector3d::Zero();          ///< attitude error: tilt (x, y) then yaw (z), each 2 sin(angle / 2) x axis
  Eigen::Vector3d e_w_B = Eigen::Vector3d::Zero();        ///< angular velocity error
  bool tilt_limited = false;    ///< horizontal force cut to respect max_tilt_deg
  bool thrust_limited = false;  ///< desired force or collective thrust hit a thrust limit
};

/// Position/attitude tracking: from the vehicle state and a trajectory sample (position,
/// velocity, acceleration and jerk feed-forward, yaw and yaw rate) to collective thrust and body
/// torques. Force: F = -k_p e_p - k_v e_v + I + m (a_ref + g e_z) [+ drag at v_ref]; the
/// desired body z is F / |F| after the tilt and thrust limits (vertical force has priority over
/// horizontal); desired heading from the yaw angle; thrust f = F . R e_z; torque
/// M = -k_R e_R - k_W e_W + W x J W - J (W^ R^T R_D W_D) (the angular-acceleration feed-forward
/// is taken as zero: the reference carries no snap), with e_R the quaternion error from the
/// desired attitude to the body's split into tilt and then yaw (the paper's eq. 10 fails near a
/// half turn and couples a large yaw error into the tilt; see Compute).
class GeometricController {
 public:
  /// @throws std::invalid_argument naming the option and its allowed range on a bad value.
  explicit GeometricController(const VehicleParams& vehicle = {},
                               const GeometricControllerOptions& options = {});

  /// One control step. Call at options().rate_hz.
  /// @throws std::domain_error on a non-finite state or reference.
  ControlOutput Compute(const VehicleState& state, const TrajectorySample& reference);

  /// Clears the integral term (e.g. on take-off or after a reference jump).
  void Reset();

  const GeometricControllerOptions& options() const { return options_; }
  const VehicleParams& vehicle() const { return vehicle_; }
  const Eigen::Vector3d& integral_W() const { return integral_W_; }

 private:
  VehicleParams vehicle_;
  GeometricControllerOptions options_;
  Eigen::Vector3d integral_W_ = Eigen::Vector3d::Zero();
};

}  // namespace enavi::navstack
