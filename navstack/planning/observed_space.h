#pragma once
// Space the vehicle reaches before it can stop must have been seen (ours: methods fixed and enavi;
// Ego-Planner, the baseline, plans through all unknown space as free, as its grid_map does).
//
// Optimistic planning counts unknown cells as free. Far ahead that is what lets a vehicle with a
// 5 m depth range plan at all; next to the vehicle it is how it flew into walls it had never seen.
// Street canyon, seed 5, x86: flying 1 m beside a wall with a level camera, a replan reversed the
// vehicle and dived it 2 m towards the foot of that wall, which the camera's 58 deg vertical field
// of view had never shown from that close; the collision check saw the wall 0.15 s before the hit.
// The same reasoning keeps FASTER's committed trajectory in known-free space (Tordesillas et al.,
// "FASTER: Fast and Safe Trajectory Planner for Flights in Unknown Environments", IROS 2019).
//
// The rule: unknown space within `reach` of the vehicle is an obstacle, where reach is what the
// vehicle flies before it can react and brake,
//
//   reach = v T_react + v^2 / (2 a) + robot radius,
//
// except within `body` of the vehicle: there the camera's view cone (apex at the camera, vertical
// half-angle alpha) is too narrow to hold the vehicle's sphere, so even straight ahead cannot
// have been seen, and the vehicle is in that space anyway:
//
//   body = (robot radius + half a cell diagonal) / sin(alpha).

#include <Eigen/Core>

#include "navstack/common/camera.h"
#include "navstack/common/work.h"
#include "navstack/map/voxel_grid.h"

namespace enavi::navstack {

struct ObservedSpaceRule {
  Eigen::Vector3d vehicle = Eigen::Vector3d::Zero();  ///< where the vehicle is, world frame
  /// Where the plan starts (the reference a little ahead, or `vehicle`): the segment from vehicle
  /// to start is flown anyway, so `body` is measured from it.
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  double body = 0.0;   ///< m: nearer than this to the segment vehicle-start, unknown stays free
  double reach = 0.0;  ///< m: nearer than this to `vehicle`, unknown counts as occupied

  /// The rule for a vehicle at `vehicle` (plan start `start`) flying at up to `speed` with
  /// reaction time `t_react`, braking at `a_brake`, with body radius `radius`, on a map of cell
  /// size `resolution`, seen by `camera`.
  /// @throws std::domain_error if speed, t_react or radius is negative or not finite;
  ///         std::invalid_argument if a_brake or resolution is not positive and finite, or the
  ///         camera's field of view is empty.
  static ObservedSpaceRule For(const Eigen::Vector3d& vehicle, const Eigen::Vector3d& start, double speed,
                               double t_react, double a_brake, double radius, double resolution,
                               const CameraIntrinsics& camera);

  /// True if an unknown cell centred at p_W counts as occupied.
  bool Blocks(const Eigen::Vector3d& p_W) const;
};

/// Marks the unknown cells of *grid that the rule blocks as occupied (before planning on it).
/// Adds one kCellProbe per cell inside the reach.
void BlockUnobserved(const ObservedSpaceRule& rule, VoxelGrid* grid, WorkCounts* work);

}  // namespace enavi::navstack
