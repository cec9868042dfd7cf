#pragma once
// Check of the current trajectory against a newer map snapshot: the replan trigger of the
// collision task (docs/design.md, "One episode", f_col).

#include <Eigen/Core>

#include "navstack/common/work.h"
#include "navstack/map/voxel_grid.h"
#include "navstack/planning/observed_space.h"
#include "navstack/planning/trajectory.h"

namespace enavi::navstack {

struct CollisionCheckResult {
  bool collides = false;
  double t_hit = 0.0;                            ///< absolute time of the first colliding sample
  Eigen::Vector3d p_hit = Eigen::Vector3d::Zero();  ///< trajectory position there
  bool unobserved = false;  ///< the hit is unobserved space near the vehicle, not an occupied cell
};

/// First time in [t_from, t_to] (clamped to the trajectory) at which a sphere of `radius` around
/// the trajectory touches an occupied cell of grid (unknown and outside the grid count as free,
/// as in planning), or, given `observed`, at which the trajectory itself enters an unknown cell
/// that the rule blocks (ObservedSpaceRule::Blocks). Samples every resolution / 2 of travel at the trajectory's largest control
/// speed over the interval, t_to included. Adds one kTrajectorySample per sample and one
/// kCellProbe per cell inspected (cells whose box lies within radius of the sample).
/// @throws std::invalid_argument if radius < 0 or the grid is malformed.
CollisionCheckResult CheckTrajectory(const Trajectory& trajectory, double t_from, double t_to,
                                     const VoxelGrid& grid, double radius, WorkCounts* work,
                                     const ObservedSpaceRule* observed = nullptr);

}  // namespace enavi::navstack
