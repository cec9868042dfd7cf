#pragma once
// Our navigation stack as one unit: perception, collision check, difference detection and
// planning as jobs of a TaskExecutor, and the reference the flight controller tracks. It is the
// methods `enavi` (with the Strategy Controller) and `fixed` (the same stack at fixed rates).
// Simulator-agnostic: frames and odometry come in, a trajectory goes out, so the same class could
// fly a real drone through an adapter.

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/methods/navigator.h"
#include "navstack/stack/nav_stack_options.h"
#include "navstack/planning/collision_check.h"
#include "navstack/planning/observed_space.h"
#include "navstack/planning/planner.h"
#include "navstack/runtime/executor.h"

namespace enavi::navstack {

class NavStack final : public Navigator {
 public:
  /// Registers the stack's jobs with `executor` (which must outlive the stack) and starts the
  /// baseline task rates. The vehicle hovers at `initial` until the first plan lands.
  NavStack(const NavStackOptions& options, TaskExecutor* executor, const VehicleState& initial);

  /// A new sensor frame (call at capture time, before advancing the executor).
  void OnFrame(DepthFramePtr frame) override;
  /// Latest odometry.
  void OnState(const VehicleState& state) override;

  /// What the flight controller tracks at time t.
  TrajectorySample Reference(double t) const override;

  /// Applies a task configuration: rates to the executor, resolution to the map (rebuilt by the
  /// next perception job, paper Sec. V.A).
  void SetRates(const TaskRates& rates);
  TaskRates rates() const override { return rates_; }
  double map_resolution() const override { return map_->resolution(); }

  const OccupancyMap& map() const { return *map_; }
  std::shared_ptr<const Trajectory> trajectory() const override { return trajectory_; }
  const std::vector<Eigen::Vector3d>& last_search_path() const { return last_search_path_; }
  std::int64_t replans() const { return replans_; }
  std::int64_t plan_failures() const override { return plan_failures_; }
  /// Events since the last call (replans, triggers, emergency stops).
  std::vector<NavEvent> TakeEvents() override;

  /// E-Navi only: ends the Strategy Controller's rollout (training) with the episode's outcome.
  void FinishEpisode(bool collided, bool reached_goal) override;
  /// The recorded rollout, or null (baseline, or not recording).
  const rl::Rollout* rollout() const override;
  double eci() const { return eci_; }

 private:
  JobOutput PerceptionJob();
  JobOutput PlanningJob();
  /// A plan made at board time t from the current reference (or state), map and speed limit.
  struct PlanAttempt {
    PlanResult result;
    PathScoreInputs score;  ///< for the Resolution Adapter (E-Navi)
    double t = 0;           ///< when planning began
    double v_max = 0;       ///< the speed it was made for
  };
  std::shared_ptr<const PlanAttempt> MakePlan(double t, WorkCounts* work);
  /// Adopts a finished plan (or books its failure) at the job's finish; false if not adopted.
  bool Land(const PlanAttempt& attempt, const std::string& trigger);
  /// Checks the remaining trajectory; on a hit it replans inside the job (Ego-Planner's safety
  /// check) and stops only when that plan fails with the hit near.
  JobOutput CollisionJob();
  /// First hit of `traj` from t on against `map`, looking past a hit right at the vehicle when the
  /// trajectory is escaping inflated space (see CollisionJob).
  CollisionCheckResult PredictHit(const OccupancyMap& map, const Trajectory& traj, double t,
                                  const ObservedSpaceRule* observed, WorkCounts* work) const;
  JobOutput DifferenceJob();
  JobOutput EciJob();
  JobOutput AdapterJob();
  StrategyInputs GatherStrategyInputs(double t);
  /// Unobserved space the vehicle could reach before it stops (planning/observed_space.h), for a
  /// plan from `start` at the current rates, speed limit and resolution.
  ObservedSpaceRule ObservedRule(const Eigen::Vector3d& start) const;
  TaskWcets RecentWcets() const;  ///< each task's recent job time, board seconds
  void Stop(const char* why);
  /// Starts turning on the spot at the current position (NavStackOptions::scan_after_failures).
  void Scan();
  /// No trajectory to follow: stopped, none yet, or the last one has ended.
  bool Hovering(double t) const;
  void AddEvent(std::string kind, std::string detail = {});
  void RequestReplan(const char* why);
  void PromoteNextTrigger();

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
  bool emergency_stopped_ = false;     ///< stopped for a predicted collision: no plan while braking
  double emergency_stop_t_ = 0;        ///< when; plans started before it are not adopted
  bool scanning_ = false;              ///< turning on the spot at hold_ until the next plan lands
  double scan_t0_ = 0;                 ///< when the scan began (hold_.yaw is the yaw then)
  bool scan_reset_done_ = false;       ///< this scan has asked for the map reset
  bool map_reset_pending_ = false;     ///< the next perception job rebuilds the map without far cells
  int stops_ = 0;                      ///< emergency stops, fail-safe hovers and scans so far
  std::vector<Eigen::Vector3d> last_search_path_;
  std::int64_t replans_ = 0;
  std::int64_t plan_failures_ = 0;
  int failed_plans_in_row_ = 0;
  std::int64_t plan_calls_ = 0;
  double plan_latency_estimate_ = 0.05;
  std::string pending_trigger_;  ///< what asked for the released triggered plan
  std::string next_trigger_;     ///< what asked for the one the executor releases after it
  std::vector<NavEvent> events_;

  // E-Navi: the Strategy Controller and what it observes.
  std::unique_ptr<StrategyController> strategy_;
  EciTracker eci_tracker_;
  DepthFramePtr last_eci_frame_;
  double eci_ = 0, d_eci_ = 0;
  double d_ahead_ = std::numeric_limits<double>::infinity();      ///< EciResult::d_ahead, latest frame
  double speed_limit_ = std::numeric_limits<double>::infinity();  ///< StrategyDecision::v_limit
  double plan_speed_cap_ = std::numeric_limits<double>::infinity();  ///< v_max of the plan being flown
  double straight_length_ = 0;
  double flown_ = 0;
  Eigen::Vector3d last_p_ = Eigen::Vector3d::Zero();
  double last_adapt_t_ = 0, last_adapt_busy_ = 0;
  bool failsafe_ = false;
  double next_retry_t_ = 0;
};

}  // namespace enavi::navstack
