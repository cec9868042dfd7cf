#pragma once
// The options of our stack (NavStack: methods fixed and enavi), built by their factories
// (navstack/methods/stack/) from the common MethodOptions and their tunables.

#include <cstdint>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/camera.h"
#include "navstack/eci/eci.h"
#include "navstack/methods/navigator.h"
#include "navstack/perception/difference.h"
#include "navstack/perception/occupancy_map.h"
#include "navstack/perception/points.h"
#include "navstack/planning/planner_options.h"
#include "navstack/stack/strategy_controller.h"

namespace enavi::navstack {

struct NavStackOptions {
  /// The depth stream the stack reads (and the simulator renders): 320x240 by default.
  CameraIntrinsics camera = CameraIntrinsics::DefaultStream();
  MapOptions map;
  PerceptionOptions perception;
  PlannerOptions planner;
  EciOptions eci;
  DifferenceOptions difference;
  TaskRates rates;        ///< initial configuration (`fixed`: 30 Hz / 20 Hz / 0.1 m)
  double f_sen = 30.0;    ///< sensor rate, Hz
  /// Replan when the current trajectory has less than this left and the goal is not its end
  /// (planning "by reaching the end of the current trajectory").
  double replan_before_end_s = 2.0;
  /// Triggered planning retries this often while there is no trajectory to follow, s.
  double plan_retry_period_s = 0.2;
  /// A hovering vehicle whose last this many plans all failed turns on the spot (scan) until one
  /// lands: what boxes it in is often what it cannot see from where it looks (NavStack::Scan).
  int scan_after_failures = 3;
  double scan_yaw_rate = 1.0;  ///< rad/s: a full turn in 6.3 s, 200 frames at 30 Hz
  /// A scan that has turned a full circle without a plan forgets the occupied cells farther than
  /// this from the vehicle (the next map rebuild carries only nearer ones), m; 0: never. ROS
  /// move_base's recovery does the same after its rotation fails (clear_costmap_recovery,
  /// conservative_reset_dist 3 m). What it clears here is what the vehicle cannot see again from
  /// where it hovers: cells a coarser map left behind when the map was refined (a 0.5 m leaf
  /// carried as 125 occupied 0.1 m cells) that close a doorway beyond the mapping range.
  double scan_reset_distance = 3.0;
  /// A predicted collision sooner than this is the vehicle already inside inflated space, s.
  double escape_window_s = 0.15;
  /// A collision predicted sooner than this triggers an emergency stop, not only a replan.
  double emergency_horizon_s = 0.6;
  /// After an emergency stop no plan is made until the vehicle is slower than this, m/s
  /// (Ego-Planner's EMERGENCY_STOP state waits for odom speed < 0.1 before GEN_NEW_TRAJ): a plan
  /// started from the braking vehicle's velocity keeps it moving towards the wall it stopped for.
  double stop_speed = 0.1;
  /// Relative deadline of a triggered (sporadic) planning job, s.
  double triggered_plan_deadline_s = 0.1;
  /// Plan from the measured state instead of the reference when tracking error exceeds this, m.
  double max_tracking_error = 0.5;
  /// Plans stay at most this far above the start, m: the camera's 58 deg vertical field of view
  /// sees little of what is above, and optimistic planning through that unknown space is how
  /// vehicles climbed into buildings.
  double max_climb = 1.5;
  std::uint64_t seed = 1;
  Eigen::AlignedBox3d flight_bounds;
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
  /// E-Navi: the Strategy Controller adapts rates and resolution, planning is triggered, the eci
  /// and the adapter run as tasks on the board. Absent: the fixed configuration `rates`.
  std::optional<StrategyOptions> strategy;
};

/// The common part of our stack's options from `o` (camera, sensor rate, goal, bounds, seed,
/// planner, perception overrides); rates, strategy and the tunables are the factory's.
inline NavStackOptions StackOptionsFrom(const MethodOptions& o) {
  NavStackOptions s;
  s.camera = o.camera;
  s.f_sen = o.f_sen;
  s.goal = o.goal;
  s.flight_bounds = o.flight_bounds;
  s.seed = o.seed;
  s.planner = o.planner;
  if (o.perception_stride) s.perception.stride = *o.perception_stride;
  if (o.perception_max_range) s.perception.max_range = *o.perception_max_range;
  return s;
}

}  // namespace enavi::navstack
