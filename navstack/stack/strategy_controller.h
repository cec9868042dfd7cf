#pragma once
// E-Navi's Strategy Controller (paper Sec. V, Fig. framework): from eci, |d eci| and the system
// monitor's utilisation to the map resolution (Resolution Adapter) and the task frequencies
// (Frequency Adapter under Frequency Constraints C1-C4), with proportional period scaling and the
// hover fail-safe on persistent overload. One Decide() per adapter epoch; plain inputs, so the
// stack can run it as a job under the board's scheduler.

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "navstack/adapt/frequency_constraints.h"
#include "navstack/adapt/resolution_adapter.h"
#include "navstack/rl/frequency_adapter.h"
#include "navstack/rl/policy_io.h"
#include "navstack/rl/random.h"
#include "navstack/rl/rewards.h"
#include "navstack/rl/rollout.h"

namespace enavi::navstack {

struct StrategyOptions {
  std::shared_ptr<const rl::PolicyFile> policy;  ///< the frequency adapter's network (required)
  double f_adapt = 5.0;                          ///< decisions per second, Hz
  rl::ActMode mode = rl::ActMode::kGreedy;       ///< kSample explores (training rollouts)
  rl::ActionChoice choice = rl::ActionChoice::kPolicy;  ///< kLeastLoad: the ablation rule
  std::uint64_t seed = 1;                        ///< sampling seed
  bool record = false;                           ///< keep the rollout for training
  /// Sampled decisions wait here for an action from outside (rl/decision_port.h), or null.
  rl::DecisionPort* decisions = nullptr;
  ResolutionAdapterOptions resolution;
  ConstraintOptions constraints;
  OverloadMonitorOptions overload;
  rl::RewardWeights rewards;
};

/// Everything one decision looks at, measured over the epoch that just ended.
struct StrategyInputs {
  double t = 0;
  double f_sen = 30;
  int cores = 1;
  double u_cur = 0;                    ///< navigation utilisation over the epoch, cores
  TaskWcets wcet;                      ///< recent job times, board seconds
  double trajectory_duration = 0;      ///< C_L, s; +inf without a trajectory
  TaskFrequencies current;
  rl::FlightContext flight;            ///< eci, d_eci, resolution, pose, velocity, goal
  double distance_to_goal = 0;
  double straight_length = 1;          ///< |Lbar| of the episode
  double expected_path = 0;            ///< |L_e|: flown + planned + rest to the goal, m
  int stops = 0;                       ///< emergency stops and fail-safe hovers so far
  /// Reaction constraint: the nearest obstacle ahead in the latest frame (EciResult::d_ahead;
  /// +inf before the first), the emergency stop's deceleration and the robot radius. The speed
  /// is |flight.v_WB|, the margin the radius plus half a cell of flight.resolution.
  double d_ahead = std::numeric_limits<double>::infinity();
  double a_brake = 3.0;                ///< m/s^2
  double robot_radius = 0.3;           ///< m
};

struct StrategyDecision {
  TaskFrequencies f;
  double resolution = 0.1;
  bool scaled = false;          ///< periods scaled down proportionally (U_cur > U_total)
  bool fallback = false;        ///< nothing satisfied C1-C4
  bool failsafe = false;        ///< persistent overload: hover
  bool recovered = false;       ///< left the fail-safe this epoch
  /// Speed limit for plans, m/s (the stack replaces a faster plan being flown), when no action
  /// satisfies the reaction constraint: the largest speed at which the chosen rates still stop
  /// the vehicle before the nearest obstacle ahead (reaction_constraint.h, SafeSpeed), at least
  /// 0.3 m/s. +inf otherwise.
  double v_limit = std::numeric_limits<double>::infinity();
  bool reaction_infeasible = false;  ///< no action could react in time at the current speed
  WorkCounts work;              ///< the decision's own work (network multiply-adds)
  /// The frequency action waits in the DecisionPort: `f` and `v_limit` are known after
  /// StrategyController::Resolve().
  bool pending = false;
};

class StrategyController {
 public:
  /// @throws std::invalid_argument without a policy, for a policy of another build, or when a
  ///   rollout is to be recorded with ActionChoice::kLeastLoad.
  explicit StrategyController(const StrategyOptions& options);

  StrategyDecision Decide(const StrategyInputs& in, const Eigen::Vector3d& goal_W);
  /// Completes a pending decision (StrategyDecision::pending) with the action supplied to the
  /// DecisionPort. @throws std::logic_error when none was supplied.
  void Resolve(StrategyDecision* decision);

  // Events the stack reports to the Resolution Adapter (paper Sec. V.A).
  void ObserveEci(double t, double eci) { resolution_.ObserveEci(t, eci); }
  void OnCollisionTrigger(double t) { resolution_.OnCollisionTrigger(t); }
  /// The stack did not adopt the map at `resolution` (a ladder level, coarser than the one in
  /// use): the trajectory being flown collides with it. The level counts as failed.
  void OnCoarserMapRejected(double resolution);
  void OnPlanned(double t, bool found, const PathScoreInputs& path);

  /// Ends the rollout: the last step's reward and terminal flag (goal or collision), or the
  /// critic's bootstrap value for a time-out.
  void Finish(const StrategyInputs& last, bool collided, bool reached_goal);
  /// The recorded rollout (empty unless options.record).
  const rl::Rollout& rollout() const { return rollout_; }

  double resolution() const { return resolution_.resolution(); }
  const StrategyOptions& options() const { return options_; }

 private:
  double Reward(const StrategyInputs& in, bool collided, bool reached_goal) const;
  /// The part of a decision that follows from the chosen frequencies.
  void ApplyFrequencies(const rl::FrequencyDecision& f, const StrategyInputs& in, StrategyDecision* d) const;

  StrategyOptions options_;
  rl::FrequencyAdapter adapter_;
  ResolutionAdapter resolution_;
  OverloadMonitor overload_;
  rl::Rng rng_;
  rl::Rollout rollout_;
  std::optional<StrategyInputs> previous_;  ///< inputs of the previous decision (reward baseline)
  /// A decision waiting for its action: the adapter's part and the inputs it was made from.
  std::optional<std::pair<rl::FrequencyDecision, StrategyInputs>> pending_;
  bool failsafe_ = false;
};

}  // namespace enavi::navstack
