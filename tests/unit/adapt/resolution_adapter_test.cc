// Resolution Adapter (paper Sec. V.A): greedy coarsest feasible resolution, refinement on collision
// triggers, low path scores and high eci, refinement steps that expire one level at a time, the
// Manhattan rule.

#include "navstack/adapt/resolution_adapter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace enavi::navstack {
namespace {

// Ladder: 0.5 0.4 0.3 0.2 0.15 0.1 (levels 0..5). A start and a goal 10 m apart.
const Eigen::Vector3d kStart(0.05, 0.05, 1.05);
const Eigen::Vector3d kFarGoal(10.05, 0.05, 1.05);

TEST(ResolutionAdapterTest, GreedyPicksTheCoarsestLevel) {
  ResolutionAdapter ra;
  const ResolutionDecision d = ra.Select(kStart, kFarGoal);
  EXPECT_EQ(d.level, 0);
  EXPECT_DOUBLE_EQ(d.resolution, 0.5);
  EXPECT_EQ(d.reason, ResolutionReason::kGreedy);
  EXPECT_FALSE(d.changed) << "first decision";
}

TEST(ResolutionAdapterTest, FailedPlanningMovesToTheNextFinerLevelAndIsRemembered) {
  ResolutionAdapter ra;
  ra.Select(kStart, kFarGoal);
  ra.ReportPlanningOutcome(0, false);
  ResolutionDecision d = ra.Select(kStart, kFarGoal);
  EXPECT_EQ(d.level, 1);
  EXPECT_TRUE(d.changed);
  ra.ReportPlanningOutcome(1, false);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 2);
  ra.ReportPlanningOutcome(2, true);
  d = ra.Select(kStart, kFarGoal);
  EXPECT_EQ(d.level, 2) << "levels 0 and 1 failed last time; 2 found a path";
  EXPECT_FALSE(d.changed);
}

TEST(ResolutionAdapterTest, CollisionTriggerRefinesOneStep) {
  ResolutionAdapter ra;
  ra.Select(kStart, kFarGoal);
  ra.ReportPlanningOutcome(0, true);
  ra.OnCollisionTrigger(1.0);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  ra.OnCollisionTrigger(3.0);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 2);
  EXPECT_EQ(ra.floor_level(), 2);
}

TEST(ResolutionAdapterTest, ABurstOfTriggersRefinesOnlyOnce) {
  ResolutionAdapter ra;  // min_refine_interval 2 s
  ra.Select(kStart, kFarGoal);
  for (double t : {1.0, 1.2, 1.5, 2.9}) ra.OnCollisionTrigger(t);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 1) << "one step for the whole burst";
  ra.OnCollisionTrigger(3.0);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 2) << "2 s after the last refinement";
}

TEST(ResolutionAdapterTest, RefinementStopsAtTheFinestLevel) {
  ResolutionAdapter ra;
  for (int i = 0; i < 10; ++i) {
    ra.Select(kStart, kFarGoal);
    ra.OnCollisionTrigger(2.0 * i);
  }
  EXPECT_DOUBLE_EQ(ra.Select(kStart, kFarGoal).resolution, 0.1);
}

TEST(PathScoreTest, MatchesThePaperFormulaAndClampsShortPaths) {
  // Lbar = 10 m, 1 % occupied, gamma = 2: L* = (1 + 2 * 0.01) * 10 = 10.2 m.
  const double gamma = 2.0;
  EXPECT_NEAR(PathScore({14.0, 10.0, 10.0, 1000.0}, gamma), std::exp(-(14.0 - 10.2) / 10.0), 1e-15);
  EXPECT_DOUBLE_EQ(PathScore({10.2, 10.0, 10.0, 1000.0}, gamma), 1.0);
  EXPECT_DOUBLE_EQ(PathScore({10.1, 10.0, 10.0, 1000.0}, gamma), 1.0) << "|L| < |L*|: clamp to 1";
  EXPECT_DOUBLE_EQ(PathScore({5.0, 0.0, 0.0, 0.0}, gamma), 1.0) << "degenerate Lbar";
  EXPECT_THROW(PathScore({-1.0, 10.0, 0.0, 1.0}, gamma), std::domain_error);
}

TEST(ResolutionAdapterTest, LowPathScoreRefinesAndAGoodOneDoesNot) {
  ResolutionAdapter ra;  // threshold 0.9, gamma 1
  ra.Select(kStart, kFarGoal);
  // L* = 10.1; |L| = 10.5 scores exp(-0.04) = 0.96: keep.
  EXPECT_GT(ra.OnPathPlanned(1.0, {10.5, 10.0, 10.0, 1000.0}), 0.9);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 0);
  // |L| = 14 scores exp(-0.39) = 0.68: refine.
  EXPECT_LT(ra.OnPathPlanned(2.0, {14.0, 10.0, 10.0, 1000.0}), 0.9);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 1);
}

TEST(ResolutionAdapterTest, HighEciRefinesAtMostOncePerInterval) {
  ResolutionAdapter ra;  // high_eci 0.5, min_refine_interval 2 s
  ra.Select(kStart, kFarGoal);
  ra.ObserveEci(1.0, 0.4);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 0) << "moderate eci changes nothing";
  for (double t = 1.1; t < 3.0; t += 0.1) ra.ObserveEci(t, 0.8);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  ra.ObserveEci(3.2, 0.8);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 2);
}

// eci 0.4 is below high_eci: it neither refines nor holds a step.
constexpr double kModerateEci = 0.4;

// Level chosen after an eci sample at t.
int LevelAt(ResolutionAdapter& ra, double t) {
  ra.ObserveEci(t, kModerateEci);
  return ra.Select(kStart, kFarGoal).level;
}

TEST(ResolutionAdapterTest, ARefinementStepLastsItsLifetimeWhateverTheEci) {
  ResolutionAdapter ra;  // step_lifetime 3 s
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(1.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  for (int k = 11; k < 40; ++k) ASSERT_EQ(LevelAt(ra, 0.1 * k), 1) << "t = " << 0.1 * k;
  EXPECT_EQ(LevelAt(ra, 4.0), 0) << "3 s after the trigger the step is gone";
}

TEST(ResolutionAdapterTest, StepsExpireOneByOneInTheOrderTheyCame) {
  ResolutionAdapter ra;
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(0.0);
  ra.Select(kStart, kFarGoal);
  ra.OnPathPlanned(2.0, {.path_length = 20.0, .straight_length = 10.0});  // score e^-1
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 2);
  EXPECT_EQ(LevelAt(ra, 2.9), 2);
  EXPECT_EQ(LevelAt(ra, 3.0), 1) << "the first step expires";
  EXPECT_EQ(LevelAt(ra, 4.9), 1);
  EXPECT_EQ(LevelAt(ra, 5.0), 0) << "then the second";
}

// The rule this replaced coarsened only after a trigger-free period, so triggers coming a little
// more often than that period refined one step each and never let go (s2 nx: some flights drifted
// to 0.1 m, others did not). Steps that expire keep the level at the number of recent triggers.
TEST(ResolutionAdapterTest, TriggersComingAsOftenAsTheLifetimeDoNotRatchetTheMapFiner) {
  ResolutionAdapter ra;  // step_lifetime 3 s, min_refine_interval 2 s
  ra.Select(kStart, kFarGoal);
  int finest = 0;
  for (int k = 0; k <= 600; ++k) {
    const double t = 0.1 * k;
    if (k % 29 == 0) ra.OnCollisionTrigger(t);  // every 2.9 s
    finest = std::max(finest, LevelAt(ra, t));
  }
  EXPECT_EQ(finest, 2) << "two steps live at most: each trigger's, and the one before it";
  EXPECT_GE(ra.level(), 1);
}

TEST(ResolutionAdapterTest, ATriggerHeldBackByTheIntervalDoesNotExtendAStep) {
  ResolutionAdapter ra;  // min_refine_interval 2 s
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(0.0);
  ra.OnCollisionTrigger(1.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  EXPECT_EQ(LevelAt(ra, 3.0), 0) << "the step of t = 0 expires; the held-back trigger added nothing";
}

TEST(ResolutionAdapterTest, HighEciKeepsRefiningWhileItLasts) {
  ResolutionAdapter ra;
  ra.Select(kStart, kFarGoal);
  for (int k = 0; k <= 40; ++k) {
    ra.ObserveEci(0.1 * k, 0.8);
    ra.Select(kStart, kFarGoal);
  }
  EXPECT_EQ(ra.level(), 2) << "refinements at 0, 2 and 4 s; the first expired at 3 s";
}

TEST(ResolutionAdapterTest, WithNoStepLiveAFailedLevelGetsAnotherTryAfterTheLifetime) {
  ResolutionAdapter ra;
  ra.Select(kStart, kFarGoal);
  ra.ReportPlanningOutcome(0, false);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  EXPECT_EQ(LevelAt(ra, 2.9), 1);
  EXPECT_EQ(LevelAt(ra, 3.0), 0) << "3 s without a refinement or coarsening";
}

// s3 seed 2 on nx: plans failing at 0.4 m took the map down to 0.1 m level by level; when the
// refinement step under them expired, picking the coarsest level not known to fail jumped straight
// to 0.5 m, beside the wall, into an emergency stop. Coarsening goes one level at a time.
TEST(ResolutionAdapterTest, ExpiryCoarsensOneLevelAtATimePastLevelsThatFailed) {
  ResolutionAdapter ra;
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(0.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  for (int l = 1; l <= 3; ++l) {
    ra.ReportPlanningOutcome(l, false);
    ASSERT_EQ(ra.Select(kStart, kFarGoal).level, l + 1);
  }
  EXPECT_EQ(LevelAt(ra, 3.0), 3) << "the step expires: one level coarser than 4, not back to 0";
  EXPECT_EQ(LevelAt(ra, 5.9), 3);
  EXPECT_EQ(LevelAt(ra, 6.0), 2) << "then one more each 3 s without a refinement";
  EXPECT_EQ(LevelAt(ra, 9.0), 1);
  EXPECT_EQ(LevelAt(ra, 12.0), 0);
}

TEST(ResolutionAdapterTest, ShortHopGoesFinerUntilStartAndGoalAreInDifferentCells) {
  // 0.3 m hop: x cells floor(0.05/r) and floor(0.35/r) are equal for r = 0.5 and 0.4 and differ
  // for r = 0.3 (0 vs 1).
  const Eigen::Vector3d goal(0.35, 0.05, 1.05);
  EXPECT_EQ(ManhattanCellDistance(kStart, goal, 0.5), 0);
  EXPECT_EQ(ManhattanCellDistance(kStart, goal, 0.4), 0);
  EXPECT_EQ(ManhattanCellDistance(kStart, goal, 0.3), 1);
  ResolutionAdapter ra;
  const ResolutionDecision d = ra.Select(kStart, goal);
  EXPECT_DOUBLE_EQ(d.resolution, 0.3);
  EXPECT_EQ(d.reason, ResolutionReason::kGreedy);
}

TEST(ResolutionAdapterTest, ManhattanDistanceSumsAllAxes) {
  EXPECT_EQ(ManhattanCellDistance({0.05, 0.05, 0.05}, {1.05, -0.45, 0.55}, 0.5), 2 + 1 + 1)
      << "cells (0, 0, 0) and (2, -1, 1)";
  EXPECT_EQ(ManhattanCellDistance({0.05, 0, 0}, {0.15, 0, 0}, 0.5, {0.1, 0, 0}), 1)
      << "origin shifts the cell boundary to x = 0.1";
}

TEST(ResolutionAdapterTest, SameCellAndAllFailedFallBackToTheFinestLevel) {
  ResolutionAdapter ra;
  ResolutionDecision d = ra.Select(kStart, kStart);
  EXPECT_EQ(d.reason, ResolutionReason::kSameCell);
  EXPECT_DOUBLE_EQ(d.resolution, 0.1);
  ResolutionAdapter rb;
  for (int l = 0; l < rb.num_levels(); ++l) rb.ReportPlanningOutcome(l, false);
  d = rb.Select(kStart, kFarGoal);
  EXPECT_EQ(d.reason, ResolutionReason::kAllFailed);
  EXPECT_EQ(d.level, rb.num_levels() - 1);
}

TEST(ResolutionAdapterTest, RefusesBadOptions) {
  EXPECT_THROW(ResolutionAdapter({.ladder = {0.1, 0.2}}), std::invalid_argument) << "ascending";
  EXPECT_THROW(ResolutionAdapter({.ladder = {}}), std::invalid_argument);
  EXPECT_THROW(ResolutionAdapter({.score_threshold = 1.5}), std::invalid_argument);
  EXPECT_THROW(ResolutionAdapter({.high_eci = 1.5}), std::invalid_argument);
  EXPECT_THROW(ResolutionAdapter({.step_lifetime = 0.0}), std::invalid_argument);
  EXPECT_THROW(ResolutionAdapter({.min_refine_interval = -1.0}), std::invalid_argument);
  ResolutionAdapter ra;
  EXPECT_THROW(ra.ReportPlanningOutcome(6, true), std::out_of_range);
  EXPECT_THROW(ra.ObserveEci(std::nan(""), 0.5), std::domain_error);
}

}  // namespace
}  // namespace enavi::navstack
