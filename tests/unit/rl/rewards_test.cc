// Rewards R_c and R_f: signs, scales and the documented formulas (rewards.h).

#include "navstack/rl/rewards.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace enavi::navstack::rl {
namespace {

// A quiet epoch: 0.2 s, 1 of 4 cores busy, 0.5 m closer to a goal 20 m away, path unchanged.
RewardInputs Quiet() {
  RewardInputs in;
  in.dt = 0.2;
  in.u_nav = 1.0;
  in.u_total = 4.0;
  in.dist_prev = 10.5;
  in.dist = 10.0;
  in.straight_length = 20.0;
  in.path_prev = 22.0;
  in.path = 22.0;
  return in;
}

TEST(RewardsTest, QuietEpochTermsMatchTheFormulas) {
  const RewardWeights w;
  const RewardTerms r = ComputeReward(Quiet(), w);
  EXPECT_NEAR(r.utilisation, -w.w_util * 0.25 * 0.2, 1e-15);
  EXPECT_EQ(r.overload, 0.0);
  EXPECT_NEAR(r.progress, w.w_progress * 0.5 / 20.0, 1e-15);
  EXPECT_EQ(r.path_growth, 0.0);
  EXPECT_NEAR(r.time, -w.w_time * 0.2, 1e-15);
  EXPECT_NEAR(r.total, r.r_c + r.r_f, 1e-15);
  EXPECT_NEAR(r.r_c, r.utilisation + r.overload, 1e-15);
}

TEST(RewardsTest, MoreUtilisationIsWorseAndOverCapacityIsMuchWorse) {
  RewardInputs low = Quiet(), high = Quiet(), over = Quiet();
  high.u_nav = 3.0;
  over.u_nav = 5.0;
  const double r_low = ComputeReward(low).r_c;
  const double r_high = ComputeReward(high).r_c;
  const double r_over = ComputeReward(over).r_c;
  EXPECT_LT(r_high, r_low);
  EXPECT_LT(r_over, r_high);
  // The hinge: past capacity each extra core costs more than below it.
  EXPECT_GT(r_high - r_over, 5.0 * (r_low - r_high)) << "3 -> 5 cores vs 1 -> 3 cores";
}

TEST(RewardsTest, PathGrowthIsPenalisedAndShorteningRewarded) {
  RewardInputs grow = Quiet(), shrink = Quiet();
  grow.path = 24.2;  // +10 %
  shrink.path = 19.8;
  EXPECT_NEAR(ComputeReward(grow).path_growth, -RewardWeights{}.w_path * 0.1, 1e-12);
  EXPECT_GT(ComputeReward(shrink).path_growth, 0.0);
  RewardInputs unknown = Quiet();
  unknown.path_prev = 0.0;
  EXPECT_EQ(ComputeReward(unknown).path_growth, 0.0) << "no previous path";
}

TEST(RewardsTest, TerminalEventsDominate) {
  RewardInputs crash = Quiet(), arrive = Quiet();
  crash.collided = true;
  arrive.reached_goal = true;
  EXPECT_LT(ComputeReward(crash).total, -10.0);
  EXPECT_GT(ComputeReward(arrive).total, 5.0);
}

TEST(RewardsTest, EachEmergencyStopCostsAndTimeIsWorthAQuarterOfAFourCoreBoard) {
  RewardInputs calm = Quiet(), stopped = Quiet();
  stopped.stops = 2;
  const RewardWeights w;
  EXPECT_EQ(ComputeReward(calm).stops, 0.0);
  EXPECT_NEAR(ComputeReward(stopped).stops, -2.0 * w.w_stop, 1e-15);
  EXPECT_NEAR(ComputeReward(calm).total - ComputeReward(stopped).total, 2.0 * w.w_stop, 1e-12);
  // A second in the air costs as much as one of four cores busy for that second.
  EXPECT_NEAR(w.w_time, w.w_util / 4.0, 1e-15);
  stopped.stops = -1;
  EXPECT_THROW(ComputeReward(stopped), std::domain_error);
}

TEST(RewardsTest, ProgressTelescopesOverAnEpisode) {
  // 40 epochs from 20 m to 0 m in uneven steps, with one detour: the sum is w_progress.
  double d = 20.0, sum = 0.0;
  for (int e = 0; e < 40; ++e) {
    RewardInputs in = Quiet();
    in.dist_prev = d;
    d = e == 39 ? 0.0 : std::max(0.0, d - (e % 5 == 0 ? -0.3 : 0.7));
    in.dist = d;
    sum += ComputeReward(in).progress;
  }
  EXPECT_NEAR(sum, RewardWeights{}.w_progress, 1e-12);
}

TEST(RewardsTest, RefusesBadInputsAndWeights) {
  RewardInputs in = Quiet();
  in.u_total = 0.0;
  EXPECT_THROW(ComputeReward(in), std::domain_error);
  in = Quiet();
  in.dist = std::nan("");
  EXPECT_THROW(ComputeReward(in), std::domain_error);
  RewardWeights w;
  w.w_goal = -1.0;
  EXPECT_THROW(w.Validate(), std::invalid_argument);
  EXPECT_NO_THROW(RewardWeights{}.Validate());
}

}  // namespace
}  // namespace enavi::navstack::rl
