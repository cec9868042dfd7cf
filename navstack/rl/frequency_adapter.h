#pragma once
// Frequency Adapter (paper Sec. V.C): one decision = constraint status of the running
// configuration -> policy state -> feasible mask over the action grid (C1-C4) -> masked policy ->
// (f_per, f_col, f_dif). The composition the navigation stack calls; the pieces live in
// navstack/adapt (constraints, grid, state) and navstack/rl (policy).

#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/adapt/frequency_constraints.h"
#include "navstack/adapt/policy_state.h"
#include "navstack/common/work.h"
#include "navstack/rl/decision_port.h"
#include "navstack/rl/policy_io.h"
#include "navstack/rl/rollout.h"

namespace enavi::navstack::rl {

/// The part of the policy state that is not in ConstraintInputs.
struct FlightContext {
  double eci = 0.0;
  double d_eci = 0.0;
  double resolution = 0.1;  ///< current map resolution, m
  Eigen::Vector3d p_WB = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_WB = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_goal_W = Eigen::Vector3d::Zero();
};

/// What picks among the feasible actions. kLeastLoad is an ablation, not E-Navi: the constraints,
/// the masks and the Resolution Adapter as they are, with the learned choice replaced by "run the
/// feasible action with the least C3 load" (FeasibleSet::least_load_action). A policy that does
/// not beat it has learned nothing the constraints did not already give.
enum class ActionChoice { kPolicy, kLeastLoad };

/// One decision.
struct FrequencyDecision {
  TaskFrequencies f;              ///< the chosen grid triple, Hz
  int action = -1;                ///< its grid index
  bool fallback_used = false;     ///< nothing satisfied all constraints; `f` is the fallback (record an event)
  bool reaction_infeasible = false;  ///< no action satisfied the reaction constraint
  int num_feasible = 0;
  ConstraintStatus current_status;///< C1-C4 for the configuration that was running
  double log_prob = 0.0;          ///< filled when a rollout step is recorded
  double value = 0.0;             ///< filled when a rollout step is recorded
  std::int64_t macs = 0;          ///< multiply-adds of this decision (also added to WorkCounts)
  /// The action waits in the DecisionPort: `action` and `f` are not known until Resolve().
  bool pending = false;
};

class FrequencyAdapter {
 public:
  /// @throws std::invalid_argument when the policy has no action grid or its features are not
  ///   PolicyStateFeatureNames() (e.g. a policy for another build).
  /// `decisions`: where sampled decisions are left for an action from outside (decision_port.h),
  /// or null; it must outlive the adapter.
  explicit FrequencyAdapter(PolicyFile policy, const ConstraintOptions& constraints = {},
                            const PolicyStateOptions& state = {},
                            ActionChoice choice = ActionChoice::kPolicy, DecisionPort* decisions = nullptr);

  /// Decides the frequencies for the next epoch. Greedy for flights, kSample (with `rng`) for
  /// training. When `record` is given it receives obs, mask, action, log-prob and value (the
  /// critic then runs too); the caller fills in reward and done. Work: the network's multiply-adds
  /// plus kMaskMacsPerAction per grid action for the constraint mask, as WorkUnit::kPolicyFlop;
  /// with ActionChoice::kLeastLoad the mask's only (the network does not run).
  /// @throws std::invalid_argument when `record` is given with ActionChoice::kLeastLoad: the
  ///   rule's actions are not the policy's, so they cannot train it.
  /// With a DecisionPort and kSample, the decision is left pending there (`pending`): the
  /// network still samples (its numbers stay in the record, its action does not count), and
  /// Resolve() completes the decision with the action supplied.
  FrequencyDecision Decide(const ConstraintInputs& constraints, const FlightContext& context,
                           ActMode mode, Rng* rng = nullptr, WorkCounts* work = nullptr,
                           RolloutStep* record = nullptr);
  /// Completes a pending decision with the port's action (and the record's action, if given).
  /// @throws std::logic_error when no action was supplied.
  void Resolve(FrequencyDecision* decision, RolloutStep* record = nullptr);

  /// Multiply-adds C3 and C4 need per grid action.
  static constexpr std::int64_t kMaskMacsPerAction = 6;

  const PolicyFile& policy() const { return policy_; }
  const ActionGrid& grid() const { return *policy_.action_grid; }

 private:
  PolicyFile policy_;
  ConstraintOptions constraint_options_;
  PolicyStateOptions state_options_;
  ActionChoice choice_;
  DecisionPort* decisions_;
  ActorCritic::Workspace ws_;
  Eigen::VectorXd obs_;
};

}  // namespace enavi::navstack::rl
