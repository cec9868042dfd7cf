// Reaction constraint: the task periods must let the vehicle stop before the nearest obstacle it
// sees (reaction_constraint.h), its masking next to C1-C4, and the speed limit.

#include "navstack/adapt/reaction_constraint.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "navstack/adapt/frequency_constraints.h"

namespace enavi::navstack {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const TaskWcets kWcet{0.02, 0.1, 0.005, 0.002};  // per, plan, col, dif: board seconds

// Distance from now to standstill: on at v for T_react, then braking at a.
double StoppingDistance(double v, double t_react, double a) { return v * t_react + v * v / (2.0 * a); }

ReactionInputs Moving(double d0, double v) {
  ReactionInputs in;
  in.d0 = d0;
  in.speed = v;
  in.a_brake = 3.0;
  in.margin = 0.3;
  return in;
}

TEST(ReactionTimeTest, IsFramePlusMapUpdatePlusCheckPlusPlanning) {
  // 1/30 + (1/10 + 0.02) + (1/5 + 0.005) + 0.1.
  EXPECT_NEAR(ReactionTime({10, 5, 0}, kWcet, 30.0), 1.0 / 30 + 0.12 + 0.205 + 0.1, 1e-12);
  // Slower rates, longer wait: the issue's 5 Hz / 2 Hz near a corner.
  EXPECT_NEAR(ReactionTime({5, 2, 0}, kWcet, 30.0), 1.0 / 30 + 0.22 + 0.505 + 0.1, 1e-12);
  EXPECT_EQ(ReactionTime({10, 0, 5}, kWcet, 30.0), kInf) << "no collision check: never reacts";
}

TEST(ReactionConstraintTest, HoldsExactlyWhenTheStoppingDistanceFitsBeforeTheObstacle) {
  // Inequality (1): v T + v^2 / 2a <= d0 - margin, compared as (2) in Eq. 1's t0 = 2 d0 / v.
  const TaskFrequencies f{10, 5, 0};
  const double v = 1.7, t = ReactionTime(f, kWcet, 30.0);
  const double d0_edge = StoppingDistance(v, t, 3.0) + 0.3;
  EXPECT_TRUE(CheckReaction(Moving(d0_edge + 1e-6, v), f, kWcet, 30.0).holds);
  EXPECT_FALSE(CheckReaction(Moving(d0_edge - 1e-6, v), f, kWcet, 30.0).holds);
  const ReactionStatus s = CheckReaction(Moving(2.0, v), f, kWcet, 30.0);
  EXPECT_NEAR(s.lhs, 2 * t + v / 3.0, 1e-12);
  EXPECT_NEAR(s.budget, 2 * 2.0 / v - 2 * 0.3 / v, 1e-12) << "t0 = 2 d0 / v, less the margin";
}

TEST(ReactionConstraintTest, TheIssuesCornerFailsAtFiveAndTwoHertzAndHoldsFasterFurtherOut) {
  // A wall 1.5 m away at 1.7 m/s (1.2 m to the margin): 5 Hz maps and 2 Hz checks stop 1.94 m
  // on, past the wall; 30 Hz / 30 Hz in 0.86 m.
  EXPECT_FALSE(CheckReaction(Moving(1.5, 1.7), {5, 2, 0}, kWcet, 30.0).holds);
  EXPECT_TRUE(CheckReaction(Moving(1.5, 1.7), {30, 30, 0}, kWcet, 30.0).holds);
  // The same rates are fine with the wall 3 m away, or at a walk.
  EXPECT_TRUE(CheckReaction(Moving(3.0, 1.7), {5, 2, 0}, kWcet, 30.0).holds);
  EXPECT_TRUE(CheckReaction(Moving(1.5, 0.5), {5, 2, 0}, kWcet, 30.0).holds);
}

TEST(ReactionConstraintTest, HoldsWithNothingInViewOrStandingStill) {
  EXPECT_TRUE(CheckReaction(Moving(kInf, 2.0), {5, 2, 0}, kWcet, 30.0).holds);
  EXPECT_TRUE(CheckReaction(Moving(0.5, 0.0), {5, 2, 0}, kWcet, 30.0).holds);
  EXPECT_TRUE(CheckReaction(ReactionInputs{}, {5, 0, 0}, kWcet, 30.0).holds) << "the default holds";
  EXPECT_FALSE(CheckReaction(Moving(5.0, 1.0), {5, 0, 0}, kWcet, 30.0).holds) << "moving, never checked";
}

TEST(ReactionConstraintTest, BadInputsThrow) {
  const TaskFrequencies f{10, 5, 0};
  EXPECT_THROW(CheckReaction(Moving(std::nan(""), 1.0), f, kWcet, 30.0), std::domain_error);
  EXPECT_THROW(CheckReaction(Moving(0.0, 1.0), f, kWcet, 30.0), std::domain_error);
  EXPECT_THROW(CheckReaction(Moving(2.0, -1.0), f, kWcet, 30.0), std::domain_error);
  ReactionInputs no_brakes = Moving(2.0, 1.0);
  no_brakes.a_brake = 0.0;
  EXPECT_THROW(CheckReaction(no_brakes, f, kWcet, 30.0), std::domain_error);
}

TEST(SafeSpeedTest, StopsExactlyAtTheMargin) {
  for (double d0 : {0.8, 1.5, 3.0, 10.0}) {
    for (double t : {0.05, 0.3, 1.0}) {
      const double v = SafeSpeed(d0, 0.3, 3.0, t);
      EXPECT_NEAR(StoppingDistance(v, t, 3.0), d0 - 0.3, 1e-9) << d0 << " m, " << t << " s";
    }
  }
  EXPECT_LT(SafeSpeed(1.5, 0.3, 3.0, 0.9), SafeSpeed(1.5, 0.3, 3.0, 0.2)) << "slower rates, slower flight";
  EXPECT_LT(SafeSpeed(1.5, 0.55, 3.0, 0.2), SafeSpeed(1.5, 0.3, 3.0, 0.2)) << "a coarse map, slower flight";
  EXPECT_EQ(SafeSpeed(0.3, 0.3, 3.0, 0.2), 0.0);
  EXPECT_EQ(SafeSpeed(kInf, 0.3, 3.0, 0.2), kInf);
  EXPECT_EQ(SafeSpeed(2.0, 0.3, 3.0, kInf), 0.0);
}

// The mask: an action is allowed when C1-C4 and the reaction constraint all hold.
ConstraintInputs Roomy() {
  ConstraintInputs in;
  in.f_sen = 30.0;
  in.trajectory_duration = 5.0;
  in.wcet = kWcet;
  in.num_cores = 4;
  in.u_cur = 0.3;
  in.current = {10.0, 5.0, 5.0};
  return in;
}

TEST(ReactionMaskTest, MasksTheSlowActionsNearAWall) {
  const ActionGrid grid;
  ConstraintInputs in = Roomy();
  const FeasibleSet far = ComputeFeasibleSet(grid, in);
  EXPECT_EQ(far.num_feasible, grid.size()) << "without d0 the reaction constraint holds everywhere";
  in.reaction = Moving(1.5, 1.7);
  const FeasibleSet near = ComputeFeasibleSet(grid, in);
  EXPECT_FALSE(near.fallback_used);
  EXPECT_FALSE(near.reaction_infeasible);
  EXPECT_GT(near.num_feasible, 0);
  EXPECT_LT(near.num_feasible, grid.size());
  for (int i = 0; i < grid.size(); ++i) {
    const bool reacts = CheckReaction(in.reaction, grid.At(i), in.wcet, in.f_sen).holds;
    EXPECT_EQ(near.mask[static_cast<std::size_t>(i)] == 1, reacts) << i;
  }
  EXPECT_EQ(near.mask[static_cast<std::size_t>(*grid.Find({5, 2, 0}))], 0);
  EXPECT_EQ(near.mask[static_cast<std::size_t>(*grid.Find({30, 30, 0}))], 1);
}

TEST(ReactionMaskTest, SafetyBeforeCpuWhenTheyConflict) {
  // One busy core: only the cheapest actions fit C3/C4, and none of them reacts in time. The
  // fallback is the cheapest action that does, not the cheapest one.
  const ActionGrid grid;
  ConstraintInputs in = Roomy();
  in.num_cores = 1;
  in.u_cur = 2.0;
  in.reaction = Moving(1.5, 1.7);
  const FeasibleSet fs = ComputeFeasibleSet(grid, in);
  ASSERT_TRUE(fs.fallback_used);
  EXPECT_FALSE(fs.reaction_infeasible);
  const TaskFrequencies chosen = grid.At(fs.fallback_action);
  EXPECT_TRUE(CheckReaction(in.reaction, chosen, in.wcet, in.f_sen).holds);
  for (int i = 0; i < grid.size(); ++i) {
    const ConstraintStatus s = CheckConstraints(in, grid.At(i));
    if (s.reaction.holds) {
      EXPECT_GE(s.c3_load, CheckConstraints(in, chosen).c3_load) << i;
    }
  }
}

TEST(ReactionMaskTest, QuickestActionWhenNoneCanReactInTime) {
  // The wall 0.2 s ahead at 1.7 m/s (the issue's x86 flight): no rate stops in 0.34 m. The
  // fallback reacts quickest, at the least CPU among equals; the speed limit must do the rest.
  const ActionGrid grid;
  ConstraintInputs in = Roomy();
  in.reaction = Moving(0.64, 1.7);
  const FeasibleSet fs = ComputeFeasibleSet(grid, in);
  ASSERT_TRUE(fs.fallback_used);
  EXPECT_TRUE(fs.reaction_infeasible);
  EXPECT_EQ(grid.At(fs.fallback_action), (TaskFrequencies{30, 30, 0}));
}

}  // namespace
}  // namespace enavi::navstack
