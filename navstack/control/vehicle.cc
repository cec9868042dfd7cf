#include "navstack/control/vehicle.h"

#include <cmath>

namespace enavi::navstack {

std::array<Eigen::Vector3d, 4> VehicleParams::RotorPositions() const {
  const double a = arm_length / std::sqrt(2.0);
  return {Eigen::Vector3d(a, -a, 0), Eigen::Vector3d(-a, a, 0), Eigen::Vector3d(a, a, 0),
          Eigen::Vector3d(-a, -a, 0)};
}

}  // namespace enavi::navstack
