// Policy observation: every feature's value and normalisation (see policy_state.h).

#include "navstack/adapt/policy_state.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <gtest/gtest.h>

namespace enavi::navstack {
namespace {

// Flying with yaw 90 deg (body x along world +y) at 1.5 m/s, goal 10 m ahead along +y.
PolicyStateInputs Facing90() {
  PolicyStateInputs in;
  in.eci = 0.4;
  in.d_eci = -0.1;
  in.constraints_hold = {true, false, true, true};
  in.current = {15, 5, 0};
  in.f_sen = 30;
  in.resolution = 0.25;
  in.u_cur = 2.0;
  in.u_total = 4.0;
  in.p_WB = {1, 2, 3};
  in.v_WB = {0, 1.5, 0};
  in.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()));
  in.p_goal_W = {1, 12, 3};
  return in;
}

TEST(PolicyStateTest, FeaturesHaveTheDocumentedValues) {
  const Eigen::VectorXd x = BuildPolicyState(Facing90());
  ASSERT_EQ(x.size(), kPolicyStateDim);
  ASSERT_EQ(PolicyStateFeatureNames().size(), static_cast<std::size_t>(kPolicyStateDim));
  EXPECT_DOUBLE_EQ(x[0], 0.4) << "eci";
  EXPECT_NEAR(x[1], std::tanh(1.0), 1e-12) << "|d eci| / 0.1 squashed";
  EXPECT_EQ(x.segment<4>(2), Eigen::Vector4d(1, 0, 1, 1)) << "C1-C4 status";
  EXPECT_NEAR(x[6], 0.5, 1e-15) << "f_per / f_sen";
  EXPECT_NEAR(x[7], 1.0 / 6.0, 1e-15);
  EXPECT_EQ(x[8], 0.0);
  EXPECT_NEAR(x[9], 0.5, 1e-15) << "0.25 m / 0.5 m";
  EXPECT_NEAR(x[10], 0.5, 1e-15) << "1.5 / 3 m/s";
  EXPECT_NEAR(x[11], 0.5, 1e-15) << "U_cur / U_total";
  EXPECT_NEAR((x.segment<3>(12) - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-12)
      << "goal straight ahead in the heading frame";
  EXPECT_NEAR(x[15], 0.5, 1e-15) << "10 m / (10 m + 10 m)";
}

TEST(PolicyStateTest, GoalDirectionIsInTheHeadingFrameAndIgnoresTilt) {
  PolicyStateInputs in = Facing90();
  in.p_goal_W = in.p_WB + Eigen::Vector3d(5, 0, 0);  // world +x = to the right when facing +y
  in.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX()));
  const Eigen::VectorXd x = BuildPolicyState(in);
  EXPECT_NEAR((x.segment<3>(12) - Eigen::Vector3d(0, -1, 0)).norm(), 0.0, 1e-12);
}

TEST(PolicyStateTest, SaturatingFeaturesStayBounded) {
  PolicyStateInputs in = Facing90();
  in.v_WB = {100, 0, 0};
  in.u_cur = 50.0;
  in.d_eci = 5.0;
  in.p_goal_W = in.p_WB;
  const Eigen::VectorXd x = BuildPolicyState(in);
  EXPECT_EQ(x[10], 2.0);
  EXPECT_EQ(x[11], 2.0);
  EXPECT_LE(x[1], 1.0);
  EXPECT_EQ(x.segment<3>(12), Eigen::Vector3d::Zero()) << "at the goal: no direction";
  EXPECT_EQ(x[15], 0.0);
}

TEST(PolicyStateTest, RefusesNaNAndBadScales) {
  PolicyStateInputs in = Facing90();
  in.eci = std::nan("");
  EXPECT_THROW(BuildPolicyState(in), std::domain_error);
  EXPECT_THROW(BuildPolicyState(Facing90(), {.speed_ref = 0.0}), std::domain_error);
}

}  // namespace
}  // namespace enavi::navstack
