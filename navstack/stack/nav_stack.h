#pragma once
// The navigation stack as one unit: perception, collision check, difference detection and
// planning as jobs of a TaskExecutor, and the reference the flight controller tracks
// (DESIGN.md sections 3 and 5). Simulator-agnostic: frames and odometry come in, a trajectory
// goes out, so the same class could fly a real drone through an adapter.

#include <cstdint>
#include <limits>
#include <memory>
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
#include "navstack/runtime/executor.h"
#include "navstack/stack/strategy_controller.h"

namespace enavi::navstack {

/// Task configuration: the baseline's is fixed, E-Navi's strategy controller changes it.
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
  TaskRates rates;        ///< initial configuration (the baseline's: 30 Hz / 20 Hz / 0.1 m)
  double f_sen = 30.0;    ///< sensor rate, Hz
  /// Replan when the current trajectory has less than this left and the goal is not its end
  /// (planning "by reaching the end of the current trajectory").
  double replan_before_end_s = 2.0;
  /// Triggered planning retries this often while there is no trajectory to follow, s.
  double plan_retry_period_s = 0.2;
  /// A predicted collision sooner than this is the vehicle already inside inflated space, s.
  double escape_window_s = 0.15;
  /// A collision predicted sooner than this triggers an emergency stop, not only a replan.
  double emergency_horizon_s = 0.6;
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

struct NavEvent {
  double t = 0;
  std::string kind;
  std::string detail;
};

class NavStack {
 public:
  /// Registers the stack's jobs with `executor` (which must outlive the stack) and starts the
  /// baseline task rates. The vehicle hovers at `initial` until the first plan lands.
  NavStack(const NavStackOptions& options, TaskExecutor* executor, const VehicleState& initial);

  /// A new sensor frame (call at capture time, before advancing the executor).
  void OnFrame(DepthFramePtr frame);
  /// Latest odometry.
  void OnState(const VehicleState& state);

  /// What the flight controller tracks at time t.
  TrajectorySample Reference(double t) const;

  /// Applies a task configuration: rates to the executor, resolution to the map (rebuilt by the
  /// next perception job, paper Sec. V.A).
  void SetRates(const TaskRates& rates);
  const TaskRates& rates() const { return rates_; }
  double map_resolution() const { return map_->resolution(); }

  const OccupancyMap& map() const { return *map_; }
  std::shared_ptr<const Trajectory> trajectory() const { return trajectory_; }
  const std::vector<Eigen::Vector3d>& last_search_path() const { return last_search_path_; }
  std::int64_t replans() const { return replans_; }
  std::int64_t plan_failures() const { return plan_failures_; }
  /// Events since the last call (replans, triggers, emergency stops).
  std::vector<NavEvent> TakeEvents();

  /// E-Navi only: ends the Strategy Controller's rollout (training) with the episode's outcome.
  void FinishEpisode(bool collided, bool reached_goal);
  /// The recorded rollout, or null (baseline, or not recording).
  const rl::Rollout* rollout() const;
  double eci() const { return eci_; }

 private:
  JobOutput PerceptionJob();
  JobOutput PlanningJob();
  JobOutput CollisionJob();
  JobOutput DifferenceJob();
  JobOutput EciJob();
  JobOutput AdapterJob();
  StrategyInputs GatherStrategyInputs(double t);
  void Stop(const char* why);
  void AddEvent(std::string kind, std::string detail = {});
  void RequestReplan(const char* why);
  /// Bounding box of the trajectory from t on, padded by the check radius.
  Eigen::AlignedBox3d RemainingBox(const Trajectory& traj, double t, double pad) const;

  NavStackOptions options_;
  TaskExecutor* executor_;
  TaskRates rates_;
  std::shared_ptr<OccupancyMap> map_;
  double pending_resolution_;
  VehicleState state_;
  DepthFramePtr latest_frame_;
  DepthFramePtr last_mapped_frame_;
  DepthFramePtr last_diff_frame_;
  std::shared_ptr<const Trajectory> trajectory_;
  std::shared_ptr<const Trajectory> previous_trajectory_;
  TrajectorySample hold_;              ///< reference while no trajectory exists or after a stop
  bool stopped_ = false;               ///< emergency stop active until the next plan lands
  std::vector<Eigen::Vector3d> last_search_path_;
  std::int64_t replans_ = 0;
  std::int64_t plan_failures_ = 0;
  std::int64_t plan_calls_ = 0;
  double plan_latency_estimate_ = 0.05;
  std::vector<NavEvent> events_;

  // E-Navi: the Strategy Controller and what it observes.
  std::unique_ptr<StrategyController> strategy_;
  EciTracker eci_tracker_;
  DepthFramePtr last_eci_frame_;
  double eci_ = 0, d_eci_ = 0;
  double d_ahead_ = std::numeric_limits<double>::infinity();      ///< EciResult::d_ahead, latest frame
  double speed_limit_ = std::numeric_limits<double>::infinity();  ///< StrategyDecision::v_limit
  double straight_length_ = 0;
  double flown_ = 0;
  Eigen::Vector3d last_p_ = Eigen::Vector3d::Zero();
  double last_adapt_t_ = 0, last_adapt_busy_ = 0;
  bool failsafe_ = false;
  double next_retry_t_ = 0;
};

}  // namespace enavi::navstack
