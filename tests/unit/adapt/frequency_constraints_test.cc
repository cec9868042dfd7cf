// Frequency constraints C1-C4 (paper Sec. V.B), the feasible set, proportional scaling and the
// overload fail-safe.

#include "navstack/adapt/frequency_constraints.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

namespace enavi::navstack {
namespace {

// A 4-core board, 30 Hz sensor, a 5 s trajectory (C1 floor 0.2 Hz), running (10, 5, 5) Hz.
// Model load of the running configuration: 10*0.02 + 0.1/5 + 5*0.005 + 5*0.002 = 0.255 cores.
ConstraintInputs Nominal() {
  ConstraintInputs in;
  in.f_sen = 30.0;
  in.trajectory_duration = 5.0;
  in.wcet = {0.02, 0.1, 0.005, 0.002};
  in.num_cores = 4;
  in.u_cur = 0.3;
  in.current = {10.0, 5.0, 5.0};
  return in;
}

std::string Holds(const ConstraintStatus& s) {
  std::string out;
  for (int k = 0; k < 4; ++k) out += s.holds[static_cast<std::size_t>(k)] ? '1' : '0';
  return out;
}

TEST(FrequencyConstraintsTest, RunningConfigurationSatisfiesAll) {
  const ConstraintStatus s = CheckConstraints(Nominal(), Nominal().current);
  EXPECT_EQ(Holds(s), "1111");
  EXPECT_NEAR(s.c3_load, 0.255, 1e-12);
  EXPECT_NEAR(s.u_after, 0.3, 1e-12) << "no change -> dU = 0";
  EXPECT_DOUBLE_EQ(s.u_total, 4.0);
  EXPECT_DOUBLE_EQ(s.f_per_min, 0.2);
}

TEST(FrequencyConstraintsTest, OnlyC1FailsBelowOnePerceptionPerTrajectory) {
  // 0.1 Hz < 1 / C_L = 0.2 Hz: the UAV would fly blind for part of the trajectory.
  EXPECT_EQ(Holds(CheckConstraints(Nominal(), {0.1, 0.0, 0.0})), "0111");
}

TEST(FrequencyConstraintsTest, OnlyC1FailsAboveSensorRate) {
  EXPECT_EQ(Holds(CheckConstraints(Nominal(), {40.0, 0.0, 0.0})), "0111");
}

TEST(FrequencyConstraintsTest, OnlyC2FailsWhenCollisionCheckOutrunsPerception) {
  EXPECT_EQ(Holds(CheckConstraints(Nominal(), {5.0, 10.0, 0.0})), "1011");
}

TEST(FrequencyConstraintsTest, OnlyC2FailsWhenDifferenceDetectionOutrunsSensor) {
  EXPECT_EQ(Holds(CheckConstraints(Nominal(), {10.0, 0.0, 40.0})), "1011");
}

TEST(FrequencyConstraintsTest, OnlyC3FailsWhenPlanningBudgetExceedsCores) {
  // A 0.5 s trajectory and a 2.5 s planner: C_plan / C_L = 5 cores > N = 4, although the
  // measured utilisation (C4) is low and nothing changes.
  ConstraintInputs in = Nominal();
  in.trajectory_duration = 0.5;
  in.wcet.plan = 2.5;
  const ConstraintStatus s = CheckConstraints(in, in.current);
  EXPECT_EQ(Holds(s), "1101");
  EXPECT_GT(s.c3_load, 4.0);
}

TEST(FrequencyConstraintsTest, OnlyC4FailsWhenIncreaseExceedsMeasuredHeadroom) {
  // Measured 3.95 cores busy; raising f_per by 5 Hz adds 0.1 core -> 4.05 > 4.
  ConstraintInputs in = Nominal();
  in.u_cur = 3.95;
  const ConstraintStatus s = CheckConstraints(in, {15.0, 5.0, 5.0});
  EXPECT_EQ(Holds(s), "1110");
  EXPECT_NEAR(s.u_after, 4.05, 1e-12);
  // Lowering instead frees headroom: C4 holds.
  EXPECT_EQ(Holds(CheckConstraints(in, {5.0, 5.0, 5.0})), "1111");
}

TEST(FrequencyConstraintsTest, ValuesExactlyOnTheBoundsHold) {
  ConstraintInputs in = Nominal();
  in.trajectory_duration = 0.5;  // f_per_min = 2
  EXPECT_EQ(Holds(CheckConstraints(in, {2.0, 2.0, 30.0})), "1111");
  EXPECT_EQ(Holds(CheckConstraints(in, {30.0, 30.0, 30.0})), "1111");
}

TEST(FrequencyConstraintsTest, NoTrajectoryRemovesTheC1FloorAndPlanningTerm) {
  ConstraintInputs in = Nominal();
  in.trajectory_duration = std::numeric_limits<double>::infinity();
  const ConstraintStatus s = CheckConstraints(in, {0.05, 0.0, 0.0});
  EXPECT_EQ(Holds(s), "1111");
  EXPECT_NEAR(s.c3_load, 0.05 * 0.02, 1e-15);
}

TEST(FrequencyConstraintsTest, CapacityFractionLowersUTotal) {
  ConstraintInputs in = Nominal();
  in.u_cur = 1.95;
  const ConstraintOptions half{.capacity_fraction = 0.5};
  EXPECT_EQ(Holds(CheckConstraints(in, {15.0, 5.0, 5.0}, half)), "1110") << "U_total = 2 cores";
}

TEST(FrequencyConstraintsTest, BrokenInputsThrow) {
  ConstraintInputs in = Nominal();
  in.trajectory_duration = 0.0;
  EXPECT_THROW(CheckConstraints(in, in.current), std::domain_error);
  in = Nominal();
  in.u_cur = std::nan("");
  EXPECT_THROW(CheckConstraints(in, in.current), std::domain_error);
  EXPECT_THROW(CheckConstraints(Nominal(), {-1.0, 0.0, 0.0}), std::domain_error);
}

TEST(FeasibleSetTest, MaskAgreesWithTheCheckerForEveryGridAction) {
  const ActionGrid grid;
  ConstraintInputs in = Nominal();
  in.num_cores = 1;
  in.u_cur = 0.6;
  in.trajectory_duration = 0.4;  // f_per >= 2.5 Hz
  const FeasibleSet fs = ComputeFeasibleSet(grid, in);
  ASSERT_EQ(fs.mask.size(), static_cast<std::size_t>(grid.size()));
  int count = 0;
  for (int i = 0; i < grid.size(); ++i) {
    const bool ok = CheckConstraints(in, grid.At(i)).AllHold();
    EXPECT_EQ(fs.mask[static_cast<std::size_t>(i)] != 0, ok) << "action " << i;
    count += ok ? 1 : 0;
  }
  EXPECT_EQ(fs.num_feasible, count);
  EXPECT_FALSE(fs.fallback_used);
  EXPECT_GT(count, 0);
  EXPECT_LT(count, grid.size()) << "this case must mask something";
  // The C1 floor of 2.5 Hz masks every 1 and 2 Hz perception action.
  for (int i = 0; i < grid.size(); ++i) {
    if (grid.At(i).f_per < 2.5) {
      EXPECT_EQ(fs.mask[static_cast<std::size_t>(i)], 0) << "action " << i;
    }
  }
  // C4: from u_cur = 0.6 on one core, (30, 30, 30) would add 0.4 + 0.125 + 0.05 -> 1.175 > 1.
  EXPECT_EQ(fs.mask[static_cast<std::size_t>(*grid.Find({30, 30, 30}))], 0);
  EXPECT_EQ(fs.mask[static_cast<std::size_t>(*grid.Find({5, 5, 5}))], 1);
}

TEST(FeasibleSetTest, TheLeastLoadActionIsTheCheapestFeasibleOne) {
  const ActionGrid grid;
  ConstraintInputs in = Nominal();
  in.trajectory_duration = 0.1;  // C1: f_per >= 10 Hz, so the grid's cheapest (5, 2, 0) is masked
  const FeasibleSet fs = ComputeFeasibleSet(grid, in);
  ASSERT_FALSE(fs.fallback_used);
  ASSERT_EQ(fs.mask[static_cast<std::size_t>(*grid.Find({5, 2, 0}))], 0);
  ASSERT_GE(fs.least_load_action, 0);
  EXPECT_EQ(grid.At(fs.least_load_action), (TaskFrequencies{10, 2, 0}));
  const double least = CheckConstraints(in, grid.At(fs.least_load_action)).c3_load;
  for (int i = 0; i < grid.size(); ++i) {
    if (fs.mask[static_cast<std::size_t>(i)]) {
      EXPECT_LE(least, CheckConstraints(in, grid.At(i)).c3_load) << "action " << i;
    }
  }
  // Nothing feasible: the least-load action is the fallback, the mask's only action.
  in.num_cores = 1;
  in.u_cur = 2.0;
  const FeasibleSet none = ComputeFeasibleSet(grid, in);
  ASSERT_TRUE(none.fallback_used);
  EXPECT_EQ(none.least_load_action, none.fallback_action);
}

TEST(FeasibleSetTest, FallbackIsTheCheapestActionWhenNothingIsFeasible) {
  // One core already at 2.0: even the cheapest action (1, 0, 0) leaves 1.785 > 1.
  const ActionGrid grid;
  ConstraintInputs in = Nominal();
  in.num_cores = 1;
  in.u_cur = 2.0;
  const FeasibleSet fs = ComputeFeasibleSet(grid, in);
  EXPECT_TRUE(fs.fallback_used);
  EXPECT_EQ(fs.num_feasible, 0);
  ASSERT_EQ(fs.fallback_action, *grid.Find({5, 2, 0}));
  int ones = 0;
  for (std::uint8_t m : fs.mask) ones += m;
  EXPECT_EQ(ones, 1) << "the mask holds exactly the fallback";
  EXPECT_EQ(fs.mask[static_cast<std::size_t>(fs.fallback_action)], 1);
}

TEST(FeasibleSetTest, FallbackRespectsTheC1FloorWhenPossible) {
  // C_L = 0.3 s -> f_per >= 3.33 Hz: the cheapest action keeping C1 and C2 is (5, 2, 0).
  const ActionGrid grid;
  ConstraintInputs in = Nominal();
  in.num_cores = 1;
  in.u_cur = 2.0;
  in.trajectory_duration = 0.3;
  const FeasibleSet fs = ComputeFeasibleSet(grid, in);
  ASSERT_TRUE(fs.fallback_used);
  EXPECT_EQ(grid.At(fs.fallback_action), (TaskFrequencies{5, 2, 0}));
}

TEST(FeasibleSetTest, FallbackIsCheapestOverallWhenC1CannotHold) {
  // A 0.5 Hz sensor: every grid perception rate (>= 5 Hz) breaks C1.
  const ActionGrid grid;
  ConstraintInputs in = Nominal();
  in.f_sen = 0.5;
  in.current = {0.5, 0, 0};
  const FeasibleSet fs = ComputeFeasibleSet(grid, in);
  ASSERT_TRUE(fs.fallback_used);
  EXPECT_EQ(grid.At(fs.fallback_action), (TaskFrequencies{5, 2, 0}));
}

TEST(ScaleToCapacityTest, NoOverloadLeavesFrequenciesAlone) {
  const ScaledFrequencies s = ScaleToCapacity(Nominal());
  EXPECT_FALSE(s.scaled);
  EXPECT_EQ(s.f, Nominal().current);
  EXPECT_DOUBLE_EQ(s.scale, 1.0);
}

TEST(ScaleToCapacityTest, AllScalableLoadScalesByUTotalOverU) {
  // One core; the measured 1.2 cores are exactly the periodic tasks' load.
  ConstraintInputs in = Nominal();
  in.num_cores = 1;
  in.wcet = {0.03, 0.0, 0.005, 0.005};
  in.current = {30, 30, 30};
  in.u_cur = 30 * 0.03 + 30 * 0.005 + 30 * 0.005;  // 1.2
  const ScaledFrequencies s = ScaleToCapacity(in);
  ASSERT_TRUE(s.scaled);
  EXPECT_FALSE(s.f_per_floored);
  EXPECT_NEAR(s.scale, 1.0 / 1.2, 1e-12) << "k = U_total / U";
  EXPECT_NEAR(s.f.f_per, 25.0, 1e-9);
  EXPECT_NEAR(s.f.f_col, 25.0, 1e-9);
  EXPECT_NEAR(s.f.f_dif, 25.0, 1e-9);
  EXPECT_NEAR(s.u_predicted, 1.0, 1e-12);
}

TEST(ScaleToCapacityTest, PerceptionHeldAtC1FloorAndRestTakesTheCut) {
  // One core at 1.5 (all periodic). k = 1 - 0.5/1.5 = 2/3 would put f_per at 20 Hz, below the
  // 25 Hz floor of a 0.04 s trajectory: f_per stays at 25 and col/dif pay for it.
  ConstraintInputs in = Nominal();
  in.num_cores = 1;
  in.trajectory_duration = 0.04;
  in.wcet = {0.03, 0.0, 0.01, 0.01};
  in.current = {30, 30, 30};
  in.u_cur = 30 * 0.03 + 30 * 0.01 + 30 * 0.01;  // 1.5
  const ScaledFrequencies s = ScaleToCapacity(in);
  ASSERT_TRUE(s.scaled);
  EXPECT_TRUE(s.f_per_floored);
  EXPECT_NEAR(s.f.f_per, 25.0, 1e-9);
  EXPECT_LT(s.scale, 2.0 / 3.0) << "col/dif cut deeper than the uniform factor";
  EXPECT_NEAR(s.f.f_col, s.scale * 30.0, 1e-9);
  EXPECT_NEAR(s.f.f_dif, s.scale * 30.0, 1e-9);
  EXPECT_LE(s.f.f_col, s.f.f_per) << "C2 kept";
  EXPECT_NEAR(s.u_predicted, 1.0, 1e-9) << "the overload is removed exactly";
}

TEST(ScaleToCapacityTest, OverloadFromPlanningCannotBeScaledAway) {
  ConstraintInputs in = Nominal();
  in.num_cores = 1;
  in.u_cur = 2.0;  // the periodic tasks are only 0.235 of it
  const ScaledFrequencies s = ScaleToCapacity(in);
  ASSERT_TRUE(s.scaled);
  EXPECT_GT(s.u_predicted, 1.0) << "the monitor must see the overload persist";
  EXPECT_NEAR(s.f.f_per, 0.2, 1e-12) << "perception held at the C1 floor 1 / C_L";
  EXPECT_DOUBLE_EQ(s.f.f_col, 0.0);
}

// Checks every 0.1 s of sim time.
double T(int k) { return 0.1 * k; }

TEST(OverloadMonitorTest, FailSafeAfterOneSecondOfOverloadAndNotBefore) {
  OverloadMonitor m;  // 1 s
  for (int k = 0; k < 10; ++k) {
    const auto up = m.Observe(T(k), 4.4, 4.0);
    EXPECT_TRUE(up.overloaded);
    EXPECT_EQ(up.mode, OverloadMonitor::Mode::kOverloaded) << "t = " << T(k);
    EXPECT_FALSE(up.entered_failsafe) << "t = " << T(k);
  }
  const auto up = m.Observe(T(10), 4.4, 4.0);
  EXPECT_TRUE(up.entered_failsafe) << "1.0 s of overload";
  EXPECT_EQ(up.mode, OverloadMonitor::Mode::kFailSafe);
  EXPECT_FALSE(m.Observe(T(11), 4.4, 4.0).entered_failsafe) << "the event fires once";
  EXPECT_TRUE(m.in_failsafe());
}

TEST(OverloadMonitorTest, InterruptedOverloadDoesNotAccumulate) {
  OverloadMonitor m;
  int k = 0;
  for (; k < 8; ++k) m.Observe(T(k), 4.4, 4.0);
  EXPECT_EQ(m.Observe(T(k++), 3.0, 4.0).mode, OverloadMonitor::Mode::kNominal);
  for (int j = 0; j < 9; ++j, ++k) {
    EXPECT_FALSE(m.Observe(T(k), 4.4, 4.0).entered_failsafe) << "streak restarted at t = 0.9";
  }
  EXPECT_FALSE(m.in_failsafe());
}

TEST(OverloadMonitorTest, ConsecutiveCheckCriterion) {
  OverloadMonitor m({.max_overload_duration = 0.0, .max_consecutive_overloaded = 5});
  for (int k = 0; k < 4; ++k) EXPECT_FALSE(m.Observe(100.0 + k, 2.0, 1.0).entered_failsafe);
  EXPECT_TRUE(m.Observe(104.0, 2.0, 1.0).entered_failsafe);
}

TEST(OverloadMonitorTest, RecoversAfterSustainedLowUtilisation) {
  OverloadMonitor m;  // recovery below 0.9 U_total for 0.5 s
  int k = 0;
  for (; k <= 10; ++k) m.Observe(T(k), 4.4, 4.0);
  ASSERT_TRUE(m.in_failsafe());
  // 3.8 / 4 = 0.95: below overload but above the recovery level: stays in fail-safe.
  for (int j = 0; j < 10; ++j, ++k) EXPECT_FALSE(m.Observe(T(k), 3.8, 4.0).recovered);
  ASSERT_TRUE(m.in_failsafe());
  const int start = k;
  for (; k < start + 5; ++k) EXPECT_FALSE(m.Observe(T(k), 2.0, 4.0).recovered) << "t = " << T(k);
  const auto up = m.Observe(T(k), 2.0, 4.0);
  EXPECT_TRUE(up.recovered) << "0.5 s below 90 %";
  EXPECT_EQ(up.mode, OverloadMonitor::Mode::kNominal);
  // A new overload needs a new full second.
  ++k;
  for (int j = 0; j < 10; ++j, ++k) EXPECT_FALSE(m.Observe(T(k), 4.4, 4.0).entered_failsafe);
}

TEST(OverloadMonitorTest, RefusesBadOptionsAndBackwardTime) {
  EXPECT_THROW(OverloadMonitor({.max_overload_duration = 0.0, .max_consecutive_overloaded = 0}),
               std::invalid_argument);
  EXPECT_THROW(OverloadMonitor({.recovery_fraction = 1.5}), std::invalid_argument);
  OverloadMonitor m;
  m.Observe(1.0, 0.5, 1.0);
  EXPECT_THROW(m.Observe(0.5, 0.5, 1.0), std::domain_error);
}

TEST(ActionGridTest, DefaultGridDropsCascadeViolationsAndRoundTripsIndices) {
  const ActionGrid grid;
  EXPECT_EQ(grid.size(), 98) << "14 (f_per, f_col) pairs with f_col <= f_per, x 7 f_dif levels";
  for (int i = 0; i < grid.size(); ++i) {
    const TaskFrequencies& f = grid.At(i);
    EXPECT_LE(f.f_col, f.f_per);
    ASSERT_TRUE(grid.Find(f).has_value());
    EXPECT_EQ(*grid.Find(f), i);
    EXPECT_EQ(grid.Nearest(f), i);
  }
  EXPECT_EQ(grid.At(0), (TaskFrequencies{5, 2, 0})) << "cheapest first";
  EXPECT_EQ(grid.At(grid.size() - 1), (TaskFrequencies{30, 30, 30}));
  EXPECT_FALSE(grid.Find({20, 0, 0}).has_value());
  EXPECT_EQ(grid.At(grid.Nearest({19, 0.2, 0.4})), (TaskFrequencies{15, 2, 0}));
  EXPECT_THROW(grid.At(98), std::out_of_range);
}

TEST(ActionGridTest, RefusesBadLevels) {
  EXPECT_THROW(ActionGrid::FromLevels({0, 5}, {0}, {0}), std::invalid_argument) << "f_per 0";
  EXPECT_THROW(ActionGrid::FromLevels({5, 2}, {0}, {0}), std::invalid_argument) << "unsorted";
  EXPECT_THROW(ActionGrid::FromLevels({5}, {}, {0}), std::invalid_argument) << "empty";
  EXPECT_THROW(ActionGrid::FromTriples({{1, 0, 0}, {1, 0, 0}}), std::invalid_argument) << "repeat";
  EXPECT_EQ(ActionGrid::FromLevels({1, 2}, {0, 2}, {0}, false).size(), 4);
}

}  // namespace
}  // namespace enavi::navstack
