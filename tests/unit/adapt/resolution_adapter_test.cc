// Resolution Adapter (paper Sec. V.A): greedy coarsest feasible resolution, refinement on collision
// triggers and low path scores, coarsening after sustained low eci or a quiet period without
// triggers, the Manhattan rule.

#include "navstack/adapt/resolution_adapter.h"

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

TEST(ResolutionAdapterTest, SustainedLowEciCoarsensOneStepPerPeriod) {
  ResolutionAdapterOptions o;  // low_eci 0.3, coarsen_after 3 s, refine_hold 3 s
  o.min_refine_interval = 0.0;
  o.quiet_period = 100.0;  // the eci rule alone
  ResolutionAdapter ra(o);
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(0.0);
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(0.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 2);
  int level_at_29 = -1, level_at_30 = -1, level_at_59 = -1, level_at_60 = -1;
  for (int k = 0; k <= 60; ++k) {
    const double t = 0.1 * k;
    ra.ObserveEci(t, 0.1);
    const int level = ra.Select(kStart, kFarGoal).level;
    if (k == 29) level_at_29 = level;
    if (k == 30) level_at_30 = level;
    if (k == 59) level_at_59 = level;
    if (k == 60) level_at_60 = level;
  }
  EXPECT_EQ(level_at_29, 2) << "2.9 s of low eci is not enough";
  EXPECT_EQ(level_at_30, 1) << "3 s of low eci: one step coarser";
  EXPECT_EQ(level_at_59, 1) << "the next step needs another full period";
  EXPECT_EQ(level_at_60, 0);
}

TEST(ResolutionAdapterTest, HighEciRestartsTheLowEciPeriod) {
  ResolutionAdapter ra({.quiet_period = 100.0});  // the eci rule alone
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(0.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  for (int k = 0; k <= 40; ++k) {
    const double t = 0.1 * k;
    ra.ObserveEci(t, k == 20 ? 0.4 : 0.1);  // one busier frame at t = 2 s (not high enough to refine)
    ra.Select(kStart, kFarGoal);
  }
  EXPECT_EQ(ra.level(), 1) << "low again only since t = 2.1 s";
  for (int k = 41; k <= 51; ++k) {
    ra.ObserveEci(0.1 * k, 0.1);
    ra.Select(kStart, kFarGoal);
  }
  EXPECT_EQ(ra.level(), 0) << "3 s of low eci since t = 2.1 s";
}

TEST(ResolutionAdapterTest, NoCoarseningWithinTheHoldAfterARefinement) {
  ResolutionAdapterOptions opt;
  opt.coarsen_after = 1.0;
  opt.refine_hold = 4.0;
  ResolutionAdapter ra(opt);
  ra.Select(kStart, kFarGoal);
  for (int k = 0; k <= 20; ++k) ra.ObserveEci(0.1 * k, 0.05);  // eci low since t = 0
  ra.OnCollisionTrigger(2.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  for (int k = 21; k < 60; ++k) {
    ra.ObserveEci(0.1 * k, 0.05);
    ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1) << "t = " << 0.1 * k << " < 2 + 4";
  }
  ra.ObserveEci(6.0, 0.05);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 0);
}

// The quiet rule: eci 0.4 is neither low (<= 0.3) nor high (>= 0.5), so only it can coarsen.
constexpr double kModerateEci = 0.4;

TEST(ResolutionAdapterTest, CoarsensAfterTheQuietPeriodWhateverTheEci) {
  ResolutionAdapter ra({.quiet_period = 5.0});
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(0.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  for (int k = 1; k < 50; ++k) {
    ra.ObserveEci(0.1 * k, kModerateEci);
    ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1) << "t = " << 0.1 * k << " < 5 s since the trigger";
  }
  ra.ObserveEci(5.0, kModerateEci);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 0) << "5 s without a trigger: one step coarser";
}

TEST(ResolutionAdapterTest, ATriggerInsideTheQuietPeriodRestartsIt) {
  ResolutionAdapter ra({.quiet_period = 5.0});  // min_refine_interval 2 s, threshold 0.9
  ra.Select(kStart, kFarGoal);
  ra.OnCollisionTrigger(0.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  // A collision trigger at 1 s is held back by min_refine_interval, but still restarts the period.
  ra.OnCollisionTrigger(1.0);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  const auto level_at = [&ra](double t) {
    ra.ObserveEci(t, kModerateEci);
    return ra.Select(kStart, kFarGoal).level;
  };
  EXPECT_EQ(level_at(5.9), 1) << "4.9 s since the held-back trigger";
  // A poor path (score e^-1) at 5.95 s, just before the period ends: one step finer, and the
  // period starts again from there.
  ra.OnPathPlanned(5.95, {.path_length = 20.0, .straight_length = 10.0});
  EXPECT_EQ(level_at(6.0), 2);
  EXPECT_EQ(level_at(10.9), 2) << "4.95 s since the poor path";
  EXPECT_EQ(level_at(10.95), 1) << "5 s since it";
  EXPECT_EQ(level_at(15.9), 1) << "the next step needs another full period";
  EXPECT_EQ(level_at(15.95), 0);
}

TEST(ResolutionAdapterTest, CoarseningGivesAFailedLevelAnotherTry) {
  ResolutionAdapter ra;
  ra.Select(kStart, kFarGoal);
  ra.ReportPlanningOutcome(0, false);
  ASSERT_EQ(ra.Select(kStart, kFarGoal).level, 1);
  for (int k = 0; k <= 30; ++k) ra.ObserveEci(0.1 * k, 0.0);
  EXPECT_EQ(ra.Select(kStart, kFarGoal).level, 0);
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
  EXPECT_THROW(ResolutionAdapter({.coarsen_after = 0.0}), std::invalid_argument);
  EXPECT_THROW(ResolutionAdapter({.quiet_period = 0.0}), std::invalid_argument);
  ResolutionAdapter ra;
  EXPECT_THROW(ra.ReportPlanningOutcome(6, true), std::out_of_range);
}

}  // namespace
}  // namespace enavi::navstack
