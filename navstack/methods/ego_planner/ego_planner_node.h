#pragma once
// The paper's baseline as it runs: Ego-Planner's ROS node (ZJU-FAST-Lab/ego-planner, the
// `ego_planner_node` of plan_manage), its runtime mechanisms rebuilt on our map, planner and
// collision check. Where each mechanism comes from (file names in that repository):
//
// - ego_planner_node.cpp: one single-threaded ros::spin() queue serves every callback of the
//   node: the grid map's depth+odom callback and occupancy timer, the FSM timer (0.01 s), the
//   safety-check timer (0.05 s) and odometry. Here: the three timers are tasks of one FIFO,
//   non-preemptive thread (MethodInfo::scheduler); a busy callback delays all others, and a late
//   roscpp timer skips its missed ticks (the executor's skip-on-overrun).
// - grid_map.cpp (depthOdomCallback / updateOccupancyCallback): the depth callback only keeps the
//   newest frame; the occupancy timer projects and raycasts that one frame (skip_pixel 2 on its
//   640x480 camera, depth filter 0.2-5.0 m, rays 0.1-4.5 m, local update range 5.5 x 5.5 x 4.5 m,
//   p_hit 0.65, p_miss 0.35, clamp 0.12-0.90, occupied above 0.80, resolution 0.1 m;
//   launch/advanced_param.xml).
// - ego_replan_fsm.cpp (execFSMCallback): GEN_NEW_TRAJ plans from odometry with zero
//   acceleration; in EXEC_TRAJ it replans (REPLAN_TRAJ) once the reference is thresh_replan
//   1.5 m past the local trajectory's start, never within thresh_no_replan 2.0 m of the goal;
//   the local target lies planning_horizon 7.5 m ahead on the global path (getLocalTarget; a
//   start farther than that from the last progress point keeps the previous target);
//   failed plans are retried every FSM tick without limit. planFromCurrentTraj starts from the
//   current trajectory evaluated when planning begins and tries three initialisations.
// - planner_manager.cpp (reboundReplan -> updateTrajInfo(pos, ros::Time::now())): the new
//   trajectory is stamped with the time planning ends, so at every replan the reference jumps
//   back by v x t_plan (no latency compensation).
// - ego_replan_fsm.cpp (checkCollisionCallback): samples the remaining trajectory every 0.01 s,
//   only its first 2/3 while t < 2/3 of its duration; on a hit it replans at once inside the
//   callback; if that fails and the hit is less than emergency_time 1.0 s ahead: EMERGENCY_STOP
//   (planner_manager.cpp EmergencyStop: a trajectory holding the current position), wait until
//   the speed is below 0.1 m/s, then GEN_NEW_TRAJ.
// - dyn_a_star.cpp: the path search gives up after 0.2 s (board time here, so it holds on the
//   virtual clock too).
// - traj_server.cpp: a separate 100 Hz process that holds the last point at zero velocity once a
//   trajectory runs out (Trajectory::Sample's rule after the end; it runs on the flight
//   controller here, as our SE(3) controller does).
//
// Each mechanism is switchable by a tunable (ego_planner_method.cc) for ablations.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "navstack/methods/navigator.h"
#include "navstack/perception/occupancy_map.h"
#include "navstack/perception/points.h"
#include "navstack/planning/planner.h"
#include "navstack/runtime/executor.h"

namespace enavi::navstack {

/// The node's parameters: Ego-Planner's defaults (launch/advanced_param.xml, ego_replan_fsm.cpp)
/// with the paper's rates (Sec. VI: perception 30 Hz, planning 20 Hz, 0.1 m).
struct EgoPlannerOptions {
  double occupancy_hz = 30.0;    ///< occupancy timer (Ego-Planner's default 0.05 s; paper: 30 Hz)
  double safety_hz = 20.0;       ///< safety-check timer, 0.05 s: the paper's "planning 20 Hz"
  double fsm_hz = 100.0;         ///< FSM timer, 0.01 s
  int skip_pixel = 2;            ///< of the full 640x480 sensor frame
  double thresh_replan = 1.5;    ///< m past the local trajectory's start
  double thresh_no_replan = 2.0; ///< m to the goal
  double planning_horizon = 7.5; ///< m, local target distance
  double emergency_time = 1.0;   ///< s: a hit sooner than this after a failed replan stops
  double stop_speed = 0.1;       ///< m/s: EMERGENCY_STOP waits for this before GEN_NEW_TRAJ
  double search_time_limit = 0.2;  ///< board s a path search may take; 0: none
  // Mechanism switches (1 = as Ego-Planner does it).
  bool stamp_at_plan_end = true;   ///< 0: stamped at planning start (latency compensated)
  bool safety_replan_inline = true;  ///< 0: a hit goes to REPLAN_TRAJ instead of planning at once
  bool emergency_stop = true;      ///< 0: a hit never stops, it only replans
  bool check_two_thirds = true;    ///< 0: the safety check samples the whole remaining trajectory
  bool newest_frame_only = true;   ///< 0: the occupancy update inserts every frame since the last
  MapOptions map;                  ///< grid_map's parameters
  PerceptionOptions perception;    ///< depth filter range (the stride comes from skip_pixel)
  /// Plans stay at most this far above the start, m (as our stack's NavStackOptions::max_climb).
  double max_climb = 1.5;
};

/// getLocalTarget (ego_replan_fsm.cpp) on a one-segment global path, the straight line from the
/// start to the goal (planGlobalTraj without waypoints): walks the path from the last progress
/// point in steps of horizon / 20 to the first point `horizon` away from `from`, and moves the
/// progress point to the path point nearest to `from` on the way; the goal when none is that far.
class GlobalPathTarget {
 public:
  GlobalPathTarget(const Eigen::Vector3d& start, const Eigen::Vector3d& goal, double horizon);

  /// The local target for a plan from `from`. If even the progress point is more than `horizon`
  /// from `from` (the vehicle was driven off the path), getLocalTarget returns at once
  /// ("last_progress_time_ ERROR") and the previous target stands.
  Eigen::Vector3d Next(const Eigen::Vector3d& from);

 private:
  Eigen::Vector3d start_, goal_;
  double horizon_;
  double progress_ = 0;  ///< arc length of the last progress point
  Eigen::Vector3d target_;  ///< the last target given
};

class EgoPlannerNode final : public Navigator {
 public:
  enum class State { kGenNewTraj, kReplanTraj, kExecTraj, kWaitTarget, kEmergencyStop };

  EgoPlannerNode(const MethodOptions& options, const EgoPlannerOptions& ego, TaskExecutor* executor,
                 const VehicleState& initial);

  void OnFrame(DepthFramePtr frame) override;
  void OnState(const VehicleState& state) override { state_ = state; }
  TrajectorySample Reference(double t) const override;
  std::vector<NavEvent> TakeEvents() override;
  TaskRates rates() const override;
  double map_resolution() const override { return map_->resolution(); }
  std::shared_ptr<const Trajectory> trajectory() const override { return trajectory_; }
  std::int64_t plan_failures() const override { return plan_failures_; }

  State state() const { return fsm_; }
  const OccupancyMap& map() const { return *map_; }

 private:
  struct Attempt;  // one callReboundReplan

  JobOutput OccupancyJob();
  JobOutput FsmJob();
  JobOutput SafetyJob();

  /// One planning call from `start` (planning began at `t_begin`), its work added to `work`.
  std::shared_ptr<const Attempt> PlanOnce(TaskId task, const TrajectorySample& start, double t_begin,
                                          WorkCounts* work);
  /// planFromCurrentTraj: up to three attempts from the current trajectory at `t_begin`.
  std::shared_ptr<const Attempt> PlanFromCurrentTrajectory(TaskId task, double t_begin, WorkCounts* work);
  /// Applies a finished attempt (at the job's finish): the trajectory, or a failure.
  bool Land(const Attempt& attempt, const std::string& trigger);
  void AddEvent(std::string kind, std::string detail = {});

  MethodOptions options_;
  EgoPlannerOptions ego_;
  TaskExecutor* executor_;
  std::shared_ptr<OccupancyMap> map_;
  PerceptionOptions perception_;
  VehicleState state_;
  DepthFramePtr latest_frame_;
  DepthFramePtr last_mapped_frame_;
  std::vector<DepthFramePtr> unmapped_frames_;  ///< newest_frame_only = false

  State fsm_ = State::kGenNewTraj;
  int consecutive_gen_calls_ = 0;
  bool escape_emergency_ = false;  ///< EMERGENCY_STOP publishes its hold once
  std::shared_ptr<const Trajectory> trajectory_;
  Eigen::Vector3d local_start_ = Eigen::Vector3d::Zero();  ///< where the local trajectory started
  bool holding_ = false;
  TrajectorySample hold_;

  GlobalPathTarget local_target_;

  std::int64_t plan_calls_ = 0;
  std::int64_t plan_failures_ = 0;
  std::vector<NavEvent> events_;
};

}  // namespace enavi::navstack
