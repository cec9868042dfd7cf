#pragma once
// Quadrotor parameters shared by the controller's mixer and the simulator's rotor model, so the
// two agree by construction. Defaults: an X500-class frame (PX4 SITL x500 model values).

#include <array>

#include <Eigen/Core>

namespace enavi::navstack {

struct VehicleParams {
  double mass = 1.5;                                         ///< kg
  Eigen::Vector3d inertia_diag{0.0217, 0.0217, 0.040};       ///< kg m^2 about body x, y, z
  double arm_length = 0.25;                                  ///< m, centre to rotor axis
  double thrust_coeff = 8.54858e-06;                        ///< N / (rad/s)^2
  double moment_coeff = 0.016;                               ///< m: rotor drag torque = k_m * thrust
  double motor_time_constant_up = 0.0125;                    ///< s, first-order lag spinning up
  double motor_time_constant_down = 0.025;                   ///< s, spinning down
  double omega_max = 1000.0;                                 ///< rad/s
  Eigen::Vector3d linear_drag{0.25, 0.25, 0.35};             ///< N/(m/s), body axes
  double collision_radius = 0.30;                            ///< m, frame + propellers
  Eigen::Vector3d p_BC{0.15, 0.0, 0.05};                     ///< camera position in body frame

  /// Rotor positions in B (X configuration: front-right, rear-left, front-left, rear-right) and
  /// spin directions (+1 counter-clockwise seen from above, producing -z reaction torque).
  std::array<Eigen::Vector3d, 4> RotorPositions() const;
  static constexpr std::array<int, 4> kSpin{+1, +1, -1, -1};
  double MaxThrustPerRotor() const { return thrust_coeff * omega_max * omega_max; }
  double Gravity() const { return 9.81; }
};

/// Commanded rotor speeds, rad/s, in the order of VehicleParams::RotorPositions().
struct RotorCommand {
  std::array<double, 4> omega{};
};

}  // namespace enavi::navstack
