#include "navstack/planning/trajectory.h"

#include <algorithm>
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

TEST(TrajectoryTest, AHeadingReversalIsAccelerationLimitedFromTheStartRate) {
  // Flying +y while the previous reference turned the other way at the full 2 rad/s: the
  // heading brakes that turn and swings round to +y, its rate changing by at most
  // yaw_accel_max per second (a reversal in one step is what the vehicle could not follow),
  // and arrives without overshooting.
  const PlannerOptions options;
  const Trajectory traj(BsplineFromPath(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), {{0, 0, 1}, {0, 8, 1}},
                                        2.0, 3.0, 0.4),
                        0.0, 0.0, options, -2.0);
  EXPECT_DOUBLE_EQ(traj.start_yaw_rate(), -2.0);
  const double step = 0.01;
  double previous_rate = -2.0, least_yaw = 0.0;
  for (double t = step; t < traj.duration(); t += step) {
    const TrajectorySample s = traj.Sample(t);
    EXPECT_LE(std::abs(s.yaw_rate - previous_rate), options.yaw_accel_max * 0.03 + 1e-9) << "t = " << t;
    EXPECT_LE(std::abs(s.yaw_rate), options.yaw_rate_max + 1e-9) << "t = " << t;
    EXPECT_LE(s.yaw, kPi / 2 + 1e-9) << "t = " << t;
    least_yaw = std::min(least_yaw, s.yaw);
    previous_rate = s.yaw_rate;
  }
  // Braking from -2 rad/s at 3 rad/s^2 carries it 2^2 / (2 x 3) = 0.67 rad the old way first.
  EXPECT_NEAR(least_yaw, -4.0 / (2.0 * options.yaw_accel_max), 0.05);
  EXPECT_NEAR(traj.Sample(0.5 * traj.duration()).yaw, kPi / 2, 1e-6);
  // The start rate is kept within the rate limit.
  EXPECT_DOUBLE_EQ(Trajectory(traj.spline(), 0.0, 0.0, options, 50.0).start_yaw_rate(), options.yaw_rate_max);
}

}  // namespace
}  // namespace enavi::navstack
