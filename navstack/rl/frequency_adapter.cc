#include "navstack/rl/frequency_adapter.h"

#include <stdexcept>


namespace enavi::navstack::rl {

FrequencyAdapter::FrequencyAdapter(PolicyFile policy, const ConstraintOptions& constraints,
                                   const PolicyStateOptions& state, ActionChoice choice, DecisionPort* decisions)
    : policy_(std::move(policy)),
      constraint_options_(constraints),
      state_options_(state),
      choice_(choice),
      decisions_(decisions) {
  if (!policy_.action_grid) {
    throw std::invalid_argument("frequency adapter: the policy has no action grid");
  }
  if (policy_.feature_names != PolicyStateFeatureNames()) {
    throw std::invalid_argument(
        "frequency adapter: the policy's observation features do not match policy_state.h");
  }
  ws_ = policy_.net.MakeWorkspace();
  obs_.resize(kPolicyStateDim);
}

FrequencyDecision FrequencyAdapter::Decide(const ConstraintInputs& constraints,
                                           const FlightContext& context, ActMode mode, Rng* rng,
                                           WorkCounts* work, RolloutStep* record) {
  FrequencyDecision d;
  // The policy state sees which constraints the running configuration satisfies.
  d.current_status = CheckConstraints(constraints, constraints.current, constraint_options_);
  const FeasibleSet feasible = ComputeFeasibleSet(grid(), constraints, constraint_options_);
  d.fallback_used = feasible.fallback_used;
  d.num_feasible = feasible.num_feasible;
  d.reaction_infeasible = feasible.reaction_infeasible;

  const bool recording = record != nullptr;
  const std::int64_t mask_macs = kMaskMacsPerAction * grid().size();
  if (choice_ == ActionChoice::kLeastLoad) {
    if (recording) {
      throw std::invalid_argument("frequency adapter: the least-load rule's decisions cannot be recorded for training");
    }
    d.action = feasible.least_load_action;
    d.f = grid().At(d.action);
    d.macs = mask_macs;
    if (work != nullptr) work->Add(WorkUnit::kPolicyFlop, d.macs);
    return d;
  }
  PolicyStateInputs s;
  s.eci = context.eci;
  s.d_eci = context.d_eci;
  s.constraints_hold = d.current_status.holds;
  s.current = constraints.current;
  s.f_sen = constraints.f_sen;
  s.resolution = context.resolution;
  s.u_cur = constraints.u_cur;
  s.u_total = d.current_status.u_total;
  s.p_WB = context.p_WB;
  s.v_WB = context.v_WB;
  s.q_WB = context.q_WB;
  s.p_goal_W = context.p_goal_W;
  BuildPolicyState(s, state_options_, obs_);
  PolicyOutput out =
      policy_.net.Act(obs_, feasible.mask, mode, rng, &ws_, /*want_log_prob=*/recording,
                      /*want_value=*/recording);
  // A sampled decision may be taken outside the stack (decision_port.h): it waits there, and
  // the network's own numbers stay in the record while its action does not count.
  d.pending = decisions_ != nullptr && mode == ActMode::kSample;
  if (d.pending) {
    decisions_->Open(obs_, feasible.mask);
  } else {
    d.action = out.action;
    d.f = grid().At(out.action);
  }
  d.log_prob = out.log_prob;
  d.value = out.value;
  // The onboard work is the actor's: the critic runs only to fill a training record, off board,
  // so recording a rollout does not change what the decision costs on the board's clock (it did:
  // a collection flight then flew differently from the same spec flown without one).
  d.macs = policy_.net.MacsPerDecision(/*with_value=*/false) + mask_macs;
  if (work != nullptr) work->Add(WorkUnit::kPolicyFlop, d.macs);
  if (recording) {
    record->obs = obs_;
    record->action = d.action;
    record->mask = feasible.mask;
    record->log_prob = out.log_prob;
    record->value = out.value;
    record->reward = 0.0;
    record->done = false;
  }
  return d;
}

void FrequencyAdapter::Resolve(FrequencyDecision* decision, RolloutStep* record) {
  if (!decision->pending) return;
  decision->action = decisions_->Take();
  decision->f = grid().At(decision->action);
  decision->pending = false;
  if (record != nullptr) record->action = decision->action;
}

}  // namespace enavi::navstack::rl
