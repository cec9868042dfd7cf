#include "navstack/planning/trajectory.h"

#include <cmath>

#include <gtest/gtest.h>

namespace enavi::navstack {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A trajectory along a path from a start state, without obstacles or optimisation.
Trajectory Along(const std::vector<Eigen::Vector3d>& path, const Eigen::Vector3d& v0, double t0,
                 double yaw0) {
  return Trajectory(BsplineFromPath(v0, Eigen::Vector3d::Zero(), path, 2.0, 3.0, 0.4), t0, yaw0);
}

TEST(TrajectoryTest, SampleIsClampedAndAtRestAfterTheEnd) {
  const Trajectory traj = Along({{0, 0, 1}, {4, 0, 1}}, Eigen::Vector3d::Zero(), 10.0, 0.0);
  EXPECT_DOUBLE_EQ(traj.start_time(), 10.0);
  EXPECT_NEAR(traj.end_time() - traj.start_time(), traj.duration(), 1e-12);
  EXPECT_TRUE(traj.Sample(5.0).p.isApprox(traj.Sample(10.0).p));
  const TrajectorySample after = traj.Sample(traj.end_time() + 3.0);
  EXPECT_LT((after.p - Eigen::Vector3d(4, 0, 1)).norm(), 1e-9);
  EXPECT_EQ(after.v, Eigen::Vector3d::Zero());
  EXPECT_EQ(after.a, Eigen::Vector3d::Zero());
  EXPECT_EQ(after.yaw_rate, 0.0);
  EXPECT_NEAR(traj.length(), 4.0, 1e-3);
}

TEST(TrajectoryTest, YawFollowsTheHorizontalVelocity) {
  // Flying +y; starting with yaw 0 it turns to +pi/2 (rate limited) and stays there.
  const Trajectory traj = Along({{0, 0, 1}, {0, 8, 1}}, Eigen::Vector3d::Zero(), 0.0, 0.0);
  EXPECT_DOUBLE_EQ(traj.Sample(0.0).yaw, 0.0) << "the heading starts where the vehicle points";
  const TrajectorySample mid = traj.Sample(0.5 * traj.duration());
  EXPECT_NEAR(mid.yaw, kPi / 2, 1e-6);
  // The turn never exceeds the rate limit (2 rad/s by default).
  for (double t = 0.0; t < traj.duration(); t += 0.01) {
    EXPECT_LE(std::abs(traj.Sample(t).yaw_rate), 2.0 + 1e-9) << "t = " << t;
  }
}

TEST(TrajectoryTest, YawIsHeldWhenHovering) {
  // No horizontal motion at all (a vertical climb): the heading given at the start is kept.
  const Trajectory traj = Along({{0, 0, 1}, {0, 0, 3}}, Eigen::Vector3d::Zero(), 0.0, 2.5);
  for (double t = 0.0; t <= traj.duration(); t += 0.1) {
    EXPECT_NEAR(traj.Sample(t).yaw, 2.5, 1e-12) << "t = " << t;
  }
}

TEST(TrajectoryTest, YawTakesTheShortWayRoundThroughPi) {
  // Flying -x with a start yaw just below +pi: the heading stays near +-pi and wraps.
  const Trajectory traj = Along({{0, 0, 1}, {-6, -0.1, 1}}, Eigen::Vector3d::Zero(), 0.0, 3.1);
  const double yaw = traj.Sample(0.5 * traj.duration()).yaw;
  EXPECT_GT(std::abs(yaw), 3.0) << yaw;
  EXPECT_LE(yaw, kPi);
  EXPECT_GT(yaw, -kPi);
}

}  // namespace
}  // namespace enavi::navstack
