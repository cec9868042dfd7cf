#pragma once
// The local planner shared by E-Navi and the baseline. Two pipelines, chosen by
// PlannerOptions::optimizer: kEsdf (distance field of the map snapshot, OMPL path search,
// B-spline optimisation on the field) and kRebound (Ego-Planner's ESDF-free optimisation on the
// grid's inflated occupancy, rebound_optimizer.h); both then allocate time and set yaw along the
// flight direction.

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
  /// Optional work budget (e.g. Ego-Planner's 0.2 s A* limit, priced in board time by the
  /// caller): asked with this plan's WorkCounts so far before every RRT-Connect sample and every
  /// A* expansion; true stops the search and the plan ends with kSearchTimeout.
  OverBudget over_budget;
};

enum class PlanStatus {
  kOk,
  kNoPath,                 ///< the search found no path within its iteration budget
  kStartInCollision,       ///< the start is in inflated space and no escape was found
  kStartOutsideGrid,       ///< the start is not inside the grid's box / flight bounds
  kGoalUnreachable,        ///< neither the goal nor any local goal is a valid state
  kTrajectoryInCollision,  ///< a path exists but the optimised trajectory keeps too little clearance
  kSearchTimeout,          ///< request.over_budget stopped a search ("search_timeout")
};

const char* ToString(PlanStatus status);

struct PlanResult {
  PlanStatus status = PlanStatus::kNoPath;
  std::string message;
  std::shared_ptr<const Trajectory> trajectory;  ///< set only when status is kOk
  std::vector<Eigen::Vector3d> search_path;  ///< kEsdf: shortcut search path; kRebound: the initial path (start .. goal used)
  double path_length = 0.0;                      ///< of search_path [m]
  bool goal_is_local = false;  ///< the path ends at a local goal, not at the final goal
  Eigen::Vector3d goal_used_W = Eigen::Vector3d::Zero();  ///< where the trajectory ends
  bool start_escape = false;   ///< the start was in inflated space; validity was relaxed near it
  int search_iterations = 0;      ///< kEsdf: RRT-Connect samples; kRebound: A* expansions
  double min_clearance = 0.0;     ///< of the trajectory, outside the escape ball [m]; kRebound: capped at robot_radius
  double max_speed = 0.0;         ///< control-point bound after the start [m/s]
  double max_acceleration = 0.0;  ///< control-point bound after the start [m/s^2]
  WorkCounts work;                ///< everything this call did, for the board cost model

  bool ok() const { return status == PlanStatus::kOk; }
};

/// Plans a smooth trajectory from request.start towards request.goal_W through request.grid
/// (unknown = free), in the grid box intersected with the flight bounds (floor at
/// options.min_altitude; a start below it climbs), to the goal or to a local goal on the way to it.
/// kEsdf: exact distance transform, straight line or RRT-Connect + shortcut, then the B-spline
/// optimisation on the field. kRebound: the straight line, then Ego-Planner's rebound optimisation
/// with A*-guided {p, v} pairs on the inflated occupancy (kNoPath if an obstacle on the line has
/// no way around it for every goal candidate).
/// Starting in inflated space is allowed (see MakeClearanceRule). Deterministic: the same request
/// and options give a bit-identical result in any process state.
/// @throws std::invalid_argument for a missing/malformed grid, non-finite start or goal, or
///         options out of range.
PlanResult Plan(const PlanRequest& request, const PlannerOptions& options = {});

}  // namespace enavi::navstack
