#pragma once
// What every navigation method is to the episode: frames and odometry in, a reference out, events
// and counters for the results (the plug-in interface of navstack/methods/method.h). The options
// every method is built from live here too.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/camera.h"
#include "navstack/common/state.h"
#include "navstack/eci/eci.h"
#include "navstack/perception/difference.h"
#include "navstack/perception/occupancy_map.h"
#include "navstack/perception/points.h"
#include "navstack/planning/planner.h"
#include "navstack/stack/strategy_controller.h"

namespace enavi::navstack {

/// Task configuration: fixed for `fixed`, changed by E-Navi's strategy controller; for other
/// methods what their tasks run at (for the time series).
struct TaskRates {
  double f_per = 30.0;   ///< perception (map update), Hz
  double f_plan = 20.0;  ///< planning timer, Hz; 0: planning only on triggers
  double f_col = 0.0;    ///< collision check, Hz; 0 with collision_on_map_update: after every map update
  double f_dif = 0.0;    ///< difference detection, Hz; 0: off
  bool collision_on_map_update = true;
  double resolution = 0.1;  ///< map resolution, m
};

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
  /// The method's own tunables by name (MethodInfo::tunables), defaults filled in and ranges
  /// checked by MakeMethodOptions().
  std::map<std::string, double> params;

  /// The value of method tunable `name`. @throws std::logic_error if the method never declared it.
  double Param(const std::string& name) const {
    const auto it = params.find(name);
    if (it == params.end()) throw std::logic_error("method parameter '" + name + "' was never declared");
    return it->second;
  }
};

struct NavEvent {
  double t = 0;
  std::string kind;
  std::string detail;
};

/// One navigation method running on a TaskExecutor (which it registers its jobs with and which
/// must outlive it).
class Navigator {
 public:
  virtual ~Navigator() = default;

  /// A new sensor frame (call at capture time, before advancing the executor).
  virtual void OnFrame(DepthFramePtr frame) = 0;
  /// Latest odometry.
  virtual void OnState(const VehicleState& state) = 0;
  /// What the flight controller tracks at time t.
  virtual TrajectorySample Reference(double t) const = 0;
  /// Events since the last call. Kinds every method uses for the results: "replan" (detail: the
  /// trigger), "plan_failed", "emergency_stop".
  virtual std::vector<NavEvent> TakeEvents() = 0;

  /// What the tasks run at now, and the map's resolution (time series).
  virtual TaskRates rates() const = 0;
  virtual double map_resolution() const = 0;
  /// The trajectory being followed, or null.
  virtual std::shared_ptr<const Trajectory> trajectory() const = 0;
  virtual std::int64_t plan_failures() const = 0;

  /// The episode ended (learning methods close their rollout).
  virtual void FinishEpisode(bool /*collided*/, bool /*reached_goal*/) {}
  /// The rollout recorded for training, or null.
  virtual const rl::Rollout* rollout() const { return nullptr; }
};

}  // namespace enavi::navstack
