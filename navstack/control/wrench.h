#pragma once
// Body wrench exchanged between the tracking controller and the motor mixer.

#include <Eigen/Core>

namespace enavi::navstack {

/// Collective thrust along body +z and torques about the body axes (FLU), at the centre of mass.
struct Wrench {
  double thrust = 0.0;                                 ///< N
  Eigen::Vector3d torque_B = Eigen::Vector3d::Zero();  ///< N m
};

}  // namespace enavi::navstack
