#include "navstack/planning/observed_space.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <gtest/gtest.h>

namespace enavi::navstack {
namespace {

// The farm's stream: 87 x 58 deg, so the narrower half-angle is 29 deg (vertical).
ObservedSpaceRule Rule(const Eigen::Vector3d& vehicle, const Eigen::Vector3d& start, double speed, double t_react) {
  return ObservedSpaceRule::For(vehicle, start, speed, t_react, 3.0, 0.3, 0.1, CameraIntrinsics::DefaultStream());
}

// 6 x 6 x 6 m of unknown cells at 0.1 m; the vehicle in the middle.
struct Unknown {
  VoxelGrid grid{Eigen::Vector3d::Zero(), 0.1, {60, 60, 60}, CellState::kUnknown};
  Eigen::Vector3d vehicle{3.05, 3.05, 3.05};
  CellState At(const Eigen::Vector3d& offset) const { return grid.At(vehicle + offset); }
};

TEST(ObservedSpaceTest, ReachIsTheStoppingDistanceAndBodyWhereTheViewConeHoldsTheVehicle) {
  const ObservedSpaceRule r = Rule(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 2.0, 0.5);
  // v T + v^2 / (2 a) + radius = 1 + 0.667 + 0.3.
  EXPECT_NEAR(r.reach, 1.0 + 4.0 / 6.0 + 0.3, 1e-9);
  // (radius + a cell diagonal) / sin(29 deg), within the decimated stream's pixel rounding.
  EXPECT_NEAR(r.body, (0.3 + std::sqrt(3.0) * 0.1) / std::sin(29.0 * std::numbers::pi / 180.0), 0.01);
}

TEST(ObservedSpaceTest, BlocksUnknownCellsBetweenBodyAndReachOnly) {
  Unknown u;
  const ObservedSpaceRule r = Rule(u.vehicle, u.vehicle, 2.0, 0.5);  // body ~0.98 m, reach ~1.97 m
  ASSERT_GT(r.reach, r.body + 0.5);
  const Eigen::Vector3d free_cell(0.0, 1.5, 0.0), occupied_cell(0.0, -1.5, 0.0);
  u.grid.cells[u.grid.Index(u.grid.CellOf(u.vehicle + free_cell))] = CellState::kFree;
  u.grid.cells[u.grid.Index(u.grid.CellOf(u.vehicle + occupied_cell))] = CellState::kOccupied;
  WorkCounts work;
  BlockUnobserved(r, &u.grid, &work);
  EXPECT_EQ(u.At({0.5, 0, 0}), CellState::kUnknown);   // inside the body: the vehicle is there
  EXPECT_EQ(u.At({1.5, 0, 0}), CellState::kOccupied);  // between: never seen, within reach
  EXPECT_EQ(u.At({0, 0, -1.5}), CellState::kOccupied);  // below as well
  EXPECT_EQ(u.At({2.5, 0, 0}), CellState::kUnknown);   // beyond reach: optimistic as before
  EXPECT_EQ(u.At(free_cell), CellState::kFree);         // what was seen stays as seen
  EXPECT_EQ(u.At(occupied_cell), CellState::kOccupied);
  EXPECT_GT(work.Get(WorkUnit::kCellProbe), 0);
}

TEST(ObservedSpaceTest, TheWayToThePlanStartCountsAsBody) {
  Unknown u;
  const Eigen::Vector3d start = u.vehicle + Eigen::Vector3d(1.2, 0, 0);
  const ObservedSpaceRule r = Rule(u.vehicle, start, 2.0, 0.5);
  BlockUnobserved(r, &u.grid, nullptr);
  EXPECT_EQ(u.At({1.5, 0, 0}), CellState::kUnknown);   // 0.3 m past the start: within the body
  EXPECT_EQ(u.At({-1.5, 0, 0}), CellState::kOccupied);  // behind the vehicle: blocked
}

TEST(ObservedSpaceTest, NothingIsBlockedWhenTheReachEndsInsideTheBody) {
  Unknown u;
  const ObservedSpaceRule r = Rule(u.vehicle, u.vehicle, 0.0, 0.0);  // at rest, instant reaction
  ASSERT_LT(r.reach, r.body);
  BlockUnobserved(r, &u.grid, nullptr);
  for (const CellState c : u.grid.cells) ASSERT_EQ(c, CellState::kUnknown);
}

TEST(ObservedSpaceTest, RejectsInvalidInputs) {
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  const CameraIntrinsics cam = CameraIntrinsics::DefaultStream();
  EXPECT_THROW(ObservedSpaceRule::For(o, o, -1.0, 0.1, 3.0, 0.3, 0.1, cam), std::domain_error);
  EXPECT_THROW(ObservedSpaceRule::For(o, o, 1.0, NAN, 3.0, 0.3, 0.1, cam), std::domain_error);
  EXPECT_THROW(ObservedSpaceRule::For(o, o, 1.0, 0.1, 0.0, 0.3, 0.1, cam), std::invalid_argument);
  EXPECT_THROW(ObservedSpaceRule::For(o, o, 1.0, 0.1, 3.0, 0.3, 0.0, cam), std::invalid_argument);
  EXPECT_THROW(ObservedSpaceRule::For(o, o, 1.0, 0.1, 3.0, 0.3, 0.1, CameraIntrinsics{}), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
