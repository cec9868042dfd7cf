#pragma once
// Motor mixer: body wrench (collective thrust + torques) -> per-rotor thrusts -> rotor speeds,
// with saturation handling, and the inverse allocation (rotor thrusts/speeds -> wrench).

#include <array>

#include <Eigen/Core>

#include "navstack/control/vehicle.h"
#include "navstack/control/wrench.h"

namespace enavi::navstack {

/// What the mixer had to give up to stay inside the rotors' thrust range [0, MaxThrustPerRotor].
struct MixResult {
  RotorCommand command;              ///< rotor speeds, rad/s, order of RotorPositions()
  std::array<double, 4> thrust{};    ///< per-rotor thrust, N, after saturation handling
  Wrench achieved;                   ///< wrench the commanded thrusts produce (inverse allocation)
  bool roll_pitch_scaled = false;    ///< roll/pitch torque scaled down (direction kept)
  bool thrust_clipped = false;       ///< collective thrust moved to make room for roll/pitch
  bool yaw_clipped = false;          ///< yaw torque reduced to what was left
};

/// Control allocation for the quadrotor of VehicleParams. Rotor i produces thrust f_i along
/// body +z at RotorPositions()[i] and a reaction torque -kSpin[i] * moment_coeff * f_i about
/// body z; f_i = thrust_coeff * omega_i^2.
///
/// Saturation priority (highest first), so that attitude stays controllable when a demand is
/// infeasible:
///   1. roll/pitch torque: if the differential thrust it needs exceeds the rotors' range, the
///      roll/pitch torque vector is scaled down uniformly (its direction is kept);
///   2. collective thrust: clamped to the range that leaves room for that roll/pitch torque and
///      for some yaw torque between zero and the demand (so a thrust demand above the maximum,
///      or below zero, is moved, never the roll/pitch torque);
///   3. yaw torque: clamped to what the remaining per-rotor headroom allows; it may shrink to
///      zero but never reverses sign.
/// A feasible wrench is reproduced exactly (no flag set).
class Mixer {
 public:
  explicit Mixer(const VehicleParams& vehicle = {});

  /// Wrench -> rotor speeds with the saturation priority above.
  MixResult Mix(const Wrench& wrench) const;

  /// Unsaturated allocation: per-rotor thrusts exactly producing the wrench (may be negative or
  /// above the maximum).
  std::array<double, 4> AllocateUnconstrained(const Wrench& wrench) const;

  /// Inverse allocation: wrench produced by the given per-rotor thrusts, N.
  Wrench WrenchFromThrusts(const std::array<double, 4>& thrust) const;
  /// Inverse allocation: wrench produced by the given rotor speeds, rad/s.
  Wrench WrenchFromSpeeds(const RotorCommand& command) const;

  /// Rotor speed that produces thrust f (f clamped to [0, MaxThrustPerRotor]).
  double SpeedForThrust(double f) const;

  const VehicleParams& vehicle() const { return vehicle_; }
  /// Allocation matrix: [thrust, tau_x, tau_y, tau_z]^T = A * f.
  const Eigen::Matrix4d& allocation() const { return A_; }

 private:
  VehicleParams vehicle_;
  Eigen::Matrix4d A_;
  Eigen::Matrix4d A_inv_;
  double f_max_;
};

}  // namespace enavi::navstack
