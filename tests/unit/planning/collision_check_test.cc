#include "navstack/planning/collision_check.h"

#include <gtest/gtest.h>

#include "tests/unit/planning/planning_test_worlds.h"

namespace enavi::navstack {
namespace {

// A straight 8 m flight along y = 2, z = 1.5 through an empty 10 x 4 x 3 m grid; the tests put
// a 0.4 m box (B) on it or beside it. Plan view, 1 char = 0.5 m:
//   ....................
//   .........B..........   <- beside: y in [2.6, 3.0]
//   ..S=======B=======G.   <- on it:  y in [1.8, 2.2], x in [4.8, 5.2]
//   ....................
struct Corridor {
  VoxelGrid grid{Eigen::Vector3d::Zero(), 0.1, {100, 40, 30}, CellState::kFree};
  Trajectory traj{BsplineFromPath(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                  {{1, 2, 1.5}, {9, 2, 1.5}}, 2.0, 3.0, 0.4),
                  100.0, 0.0};
};

TEST(CollisionCheckTest, FindsABoxPlacedOnTheTrajectory) {
  Corridor c;
  // A 0.4 m box centred on the path at x = 5.
  testing::FillBox(&c.grid, Eigen::Vector3d(4.8, 1.8, 1.3), Eigen::Vector3d(5.2, 2.2, 1.7));
  WorkCounts work;
  const CollisionCheckResult r =
      CheckTrajectory(c.traj, c.traj.start_time(), c.traj.end_time(), c.grid, 0.3, &work);
  ASSERT_TRUE(r.collides);
  // First contact: the sphere's front (radius 0.3) touches the box's face at x = 4.75.
  EXPECT_NEAR(r.p_hit.x(), 4.75 - 0.3, 0.1) << r.p_hit.transpose();
  EXPECT_NEAR((c.traj.Sample(r.t_hit).p - r.p_hit).norm(), 0.0, 1e-9);
  EXPECT_GT(work.Get(WorkUnit::kTrajectorySample), 0);
  EXPECT_GT(work.Get(WorkUnit::kCellProbe), 0);
}

TEST(CollisionCheckTest, NoHitOnAClearTrajectory) {
  Corridor c;
  // The same box, 0.6 m beside the path: the 0.3 m sphere passes it.
  testing::FillBox(&c.grid, Eigen::Vector3d(4.8, 2.6, 1.3), Eigen::Vector3d(5.2, 3.0, 1.7));
  const CollisionCheckResult r =
      CheckTrajectory(c.traj, c.traj.start_time(), c.traj.end_time(), c.grid, 0.3, nullptr);
  EXPECT_FALSE(r.collides);
}

TEST(CollisionCheckTest, OnlyTheRequestedIntervalIsChecked) {
  Corridor c;
  testing::FillBox(&c.grid, Eigen::Vector3d(4.8, 1.8, 1.3), Eigen::Vector3d(5.2, 2.2, 1.7));
  // Until the vehicle is 1.5 m short of the box.
  double t_before = c.traj.start_time();
  while (c.traj.Sample(t_before).p.x() < 3.3) t_before += 0.01;
  EXPECT_FALSE(CheckTrajectory(c.traj, c.traj.start_time(), t_before, c.grid, 0.3, nullptr).collides);
  EXPECT_TRUE(CheckTrajectory(c.traj, t_before, c.traj.end_time() + 5.0, c.grid, 0.3, nullptr).collides);
}

TEST(CollisionCheckTest, UnknownSpaceIsNotACollision) {
  Corridor c;
  testing::FillBox(&c.grid, Eigen::Vector3d(4.8, 1.8, 1.3), Eigen::Vector3d(5.2, 2.2, 1.7),
                   CellState::kUnknown);
  EXPECT_FALSE(CheckTrajectory(c.traj, 0.0, 1e9, c.grid, 0.3, nullptr).collides);
}

TEST(CollisionCheckTest, UnobservedSpaceWithinReachIsAHitGivenTheRule) {
  Corridor c;
  // Unknown cells on the path from x = 2.4 on, 1.4 m ahead of the vehicle at the start (x = 1).
  testing::FillBox(&c.grid, Eigen::Vector3d(2.4, 1.7, 1.2), Eigen::Vector3d(9.5, 2.3, 1.8), CellState::kUnknown);
  ObservedSpaceRule rule;
  rule.vehicle = rule.start = Eigen::Vector3d(1, 2, 1.5);
  rule.body = 0.5;
  rule.reach = 2.0;
  const CollisionCheckResult r = CheckTrajectory(c.traj, 0.0, 1e9, c.grid, 0.3, nullptr, &rule);
  ASSERT_TRUE(r.collides);
  EXPECT_TRUE(r.unobserved);
  EXPECT_NEAR(r.p_hit.x(), 2.4, 0.06) << r.p_hit.transpose();
  // Beyond the reach, unknown stays optimistic.
  rule.reach = 1.2;
  EXPECT_FALSE(CheckTrajectory(c.traj, 0.0, 1e9, c.grid, 0.3, nullptr, &rule).collides);
  // Within the body, too.
  rule.reach = 2.0;
  rule.body = 2.1;
  EXPECT_FALSE(CheckTrajectory(c.traj, 0.0, 1e9, c.grid, 0.3, nullptr, &rule).collides);
}

}  // namespace
}  // namespace enavi::navstack
