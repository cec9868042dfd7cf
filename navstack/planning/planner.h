#pragma once
// The local planner shared by E-Navi and the baseline (DESIGN.md section 5, "Planner"): distance
// field of the map snapshot, OMPL path search, Ego-Planner-style B-spline optimisation and time
// allocation, yaw along the flight direction.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/state.h"
#include "navstack/common/work.h"
#include "navstack/map/voxel_grid.h"
#include "navstack/planning/path_search.h"
#include "navstack/planning/planner_options.h"
#include "navstack/planning/trajectory.h"

namespace enavi::navstack {

struct PlanRequest {
  double t_start = 0.0;     ///< absolute time at which the new trajectory starts
  TrajectorySample start;   ///< p, v, a the trajectory starts from exactly, and the yaw it starts with
  Eigen::Vector3d goal_W = Eigen::Vector3d::Zero();  ///< final goal (may lie outside the grid)
  Eigen::AlignedBox3d flight_bounds_W;               ///< where the vehicle may fly
  std::shared_ptr<const VoxelGrid> grid;             ///< map snapshot (e.g. over PlanningVolume())
  std::uint32_t seed = 0;                            ///< search seed: same request -> same result
};

enum class PlanStatus {
  kOk,
  kNoPath,                 ///< the search found no path within its iteration budget
  kStartInCollision,       ///< the start is in inflated space and no escape was found
  kStartOutsideGrid,       ///< the start is not inside the grid's box / flight bounds
  kGoalUnreachable,        ///< neither the goal nor any local goal is a valid state
  kTrajectoryInCollision,  ///< a path exists but the optimised trajectory keeps too little clearance
};

const char* ToString(PlanStatus status);

struct PlanResult {
  PlanStatus status = PlanStatus::kNoPath;
  std::string message;
  std::shared_ptr<const Trajectory> trajectory;  ///< set only when status is kOk
  std::vector<Eigen::Vector3d> search_path;      ///< shortcut search path (start .. goal used)
  double path_length = 0.0;                      ///< of search_path [m]
  bool goal_is_local = false;  ///< the path ends at a local goal, not at the final goal
  Eigen::Vector3d goal_used_W = Eigen::Vector3d::Zero();  ///< where the trajectory ends
  bool start_escape = false;   ///< the start was in inflated space; validity was relaxed near it
  int search_iterations = 0;
  double min_clearance = 0.0;     ///< of the trajectory, outside the escape ball [m]
  double max_speed = 0.0;         ///< control-point bound after the start [m/s]
  double max_acceleration = 0.0;  ///< control-point bound after the start [m/s^2]
  WorkCounts work;                ///< everything this call did, for the board cost model

  bool ok() const { return status == PlanStatus::kOk; }
};

/// Plans a smooth trajectory from request.start towards request.goal_W through request.grid:
/// exact distance transform (unknown = free), straight line or RRT-Connect + shortcut in the grid
/// box intersected with the flight bounds (floor at options.min_altitude; a start below it
/// climbs), to the goal or to a local goal on the way to it, then the B-spline optimisation.
/// Starting in inflated space is allowed (see MakeClearanceRule). Deterministic: the same request
/// and options give a bit-identical result in any process state.
/// @throws std::invalid_argument for a missing/malformed grid, non-finite start or goal, or
///         options out of range.
PlanResult Plan(const PlanRequest& request, const PlannerOptions& options = {});

}  // namespace enavi::navstack
