// FrequencyAdapter: one decision composes constraint status, policy state, mask and policy.

#include "navstack/rl/frequency_adapter.h"

#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/unit/rl/adapter_inputs.h"

namespace enavi::navstack::rl {
namespace {

using testing::ExampleBoard;
using testing::ExampleFlight;

TEST(FrequencyAdapterTest, GreedyDecisionIsAFeasibleGridTripleAndCountsItsWork) {
  FrequencyAdapter fa(MakeFrequencyPolicy(ActionGrid(), 1));
  WorkCounts work;
  const FrequencyDecision d =
      fa.Decide(ExampleBoard(), ExampleFlight(), ActMode::kGreedy, nullptr, &work);
  ASSERT_GE(d.action, 0);
  EXPECT_EQ(fa.grid().At(d.action), d.f);
  EXPECT_TRUE(CheckConstraints(ExampleBoard(), d.f).AllHold());
  EXPECT_FALSE(d.fallback_used);
  EXPECT_TRUE(d.current_status.AllHold());
  EXPECT_EQ(d.macs, 16 * 150 + 150 * 150 + 150 * 98 + FrequencyAdapter::kMaskMacsPerAction * 98);
  EXPECT_EQ(work.Get(WorkUnit::kPolicyFlop), d.macs);
}

TEST(FrequencyAdapterTest, SampledDecisionsStayFeasibleUnderATightBudget) {
  // 3.9 of 4 cores busy: only reconfigurations that do not add load are allowed.
  ConstraintInputs c = ExampleBoard();
  c.u_cur = 3.9;
  FrequencyAdapter fa(MakeFrequencyPolicy(ActionGrid(), 2));
  Rng rng(3);
  for (int k = 0; k < 300; ++k) {
    const FrequencyDecision d = fa.Decide(c, ExampleFlight(), ActMode::kSample, &rng);
    ASSERT_TRUE(CheckConstraints(c, d.f).AllHold()) << "draw " << k;
  }
}

TEST(FrequencyAdapterTest, FallbackIsTakenAndFlaggedWhenNothingIsFeasible) {
  ConstraintInputs c = ExampleBoard();
  c.num_cores = 1;
  c.u_cur = 3.0;
  FrequencyAdapter fa(MakeFrequencyPolicy(ActionGrid(), 2));
  const FrequencyDecision d = fa.Decide(c, ExampleFlight(), ActMode::kGreedy);
  EXPECT_TRUE(d.fallback_used);
  EXPECT_EQ(d.f, (TaskFrequencies{5, 2, 0}));
  EXPECT_FALSE(d.current_status.holds[3]) << "the running configuration breaks C4";
}

TEST(FrequencyAdapterTest, RecordingFillsARolloutStep) {
  FrequencyAdapter fa(MakeFrequencyPolicy(ActionGrid(), 4));
  Rng rng(5);
  RolloutStep step;
  const FrequencyDecision d =
      fa.Decide(ExampleBoard(), ExampleFlight(), ActMode::kSample, &rng, nullptr, &step);
  EXPECT_EQ(step.action, d.action);
  EXPECT_EQ(step.obs.size(), kPolicyStateDim);
  EXPECT_EQ(step.mask.size(), 98u);
  EXPECT_TRUE(step.mask[static_cast<std::size_t>(d.action)]);
  EXPECT_LT(step.log_prob, 0.0);
  EXPECT_EQ(step.log_prob, d.log_prob);
  EXPECT_EQ(step.value, d.value);
  // The critic's work fills the record off board: the decision costs what a deployed one does.
  EXPECT_EQ(d.macs,
            fa.policy().net.MacsPerDecision(false) + FrequencyAdapter::kMaskMacsPerAction * 98);
}

TEST(FrequencyAdapterTest, TheLeastLoadRuleRunsTheCheapestFeasibleActionWithoutTheNetwork) {
  // A budget that masks the dearest actions, so the cheapest is not the only one feasible.
  ConstraintInputs c = ExampleBoard();
  c.u_cur = 3.0;
  const FeasibleSet feasible = ComputeFeasibleSet(ActionGrid(), c);
  ASSERT_GT(feasible.num_feasible, 1);
  ASSERT_FALSE(feasible.fallback_used);
  FrequencyAdapter rule(MakeFrequencyPolicy(ActionGrid(), 2), {}, {}, ActionChoice::kLeastLoad);
  WorkCounts work;
  const FrequencyDecision d = rule.Decide(c, ExampleFlight(), ActMode::kGreedy, nullptr, &work);
  EXPECT_EQ(d.action, feasible.least_load_action);
  const double load = CheckConstraints(c, d.f).c3_load;
  for (int i = 0; i < rule.grid().size(); ++i) {
    if (feasible.mask[static_cast<std::size_t>(i)]) {
      EXPECT_LE(load, CheckConstraints(c, rule.grid().At(i)).c3_load) << "action " << i;
    }
  }
  // The policy would have chosen otherwise here, so the rule is not the network by chance.
  FrequencyAdapter policy(MakeFrequencyPolicy(ActionGrid(), 2));
  EXPECT_NE(policy.Decide(c, ExampleFlight(), ActMode::kGreedy).action, d.action);
  EXPECT_EQ(d.macs, FrequencyAdapter::kMaskMacsPerAction * 98);
  EXPECT_EQ(work.Get(WorkUnit::kPolicyFlop), d.macs);
  RolloutStep step;
  EXPECT_THROW(rule.Decide(c, ExampleFlight(), ActMode::kGreedy, nullptr, nullptr, &step),
               std::invalid_argument);
}

TEST(FrequencyAdapterTest, RefusesPoliciesWithoutGridOrWithOtherFeatures) {
  PolicyFile p = MakeFrequencyPolicy(ActionGrid(), 1);
  p.action_grid.reset();
  EXPECT_THROW(FrequencyAdapter{p}, std::invalid_argument);
  PolicyFile q = MakeFrequencyPolicy(ActionGrid(), 1);
  q.feature_names[0] = "something";
  EXPECT_THROW(FrequencyAdapter{q}, std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack::rl
