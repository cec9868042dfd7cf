#include "navstack/planning/grid_astar.h"

#include <gtest/gtest.h>

#include "tests/unit/planning/planning_test_worlds.h"

namespace enavi::navstack {
namespace {

// 6 x 4 m at 0.1 m, 2 m tall: a wall with a 1 m opening near the top, S and G on either side.
testing::AsciiWorld WallWorld() {
  return testing::WorldFromAscii(R"(
      ............
      ............
      ......#.....
      ......#.....
      .S....#...G.
      ......#.....
      ......#.....
      ......#.....)", 0.5, 0.1, 2.0, 1.0);
}

TEST(GridAstarTest, GoesThroughTheOpeningOnFreeCells) {
  const testing::AsciiWorld w = WallWorld();
  const OccupancyBits bits(w.grid, nullptr);
  const InflatedOccupancy occ(bits, 0.3, nullptr);
  WorkCounts work;
  const AstarResult r = GridAstar(occ, w.grid.Box(), w.start, w.goal, &work);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(work.Get(WorkUnit::kAstarExpansion), r.expansions);
  EXPECT_LT((r.path.front() - w.start).norm(), 0.1);
  EXPECT_LT((r.path.back() - w.goal).norm(), 0.1);
  bool through_opening = false;
  for (std::size_t i = 0; i < r.path.size(); ++i) {
    EXPECT_FALSE(occ.Occupied(r.path[i])) << i;
    if (i > 0) {
      EXPECT_LE((r.path[i] - r.path[i - 1]).norm(), 0.1 * std::sqrt(3.0) + 1e-9);
    }
    if (std::abs(r.path[i].x() - 3.25) < 0.25) through_opening = through_opening || r.path[i].y() > 3.0;
  }
  EXPECT_TRUE(through_opening);
  // Same inputs, same path.
  EXPECT_EQ(GridAstar(occ, w.grid.Box(), w.start, w.goal, nullptr).path, r.path);
}

TEST(GridAstarTest, AnOccupiedEndIsMovedAwayFromTheOtherEnd) {
  // As Ego-Planner's ConvertToIndexAndAdjustStartEndPoints: a goal in the wall moves on, away
  // from the start, until it is free: to the wall's far side.
  const testing::AsciiWorld w = WallWorld();
  const OccupancyBits bits(w.grid, nullptr);
  const InflatedOccupancy occ(bits, 0.3, nullptr);
  const Eigen::Vector3d in_wall(3.25, 1.0, 1.0);
  const AstarResult r = GridAstar(occ, w.grid.Box(), w.start, in_wall, nullptr);
  ASSERT_TRUE(r.ok());
  EXPECT_GT(r.path.back().x(), 3.5 + 0.3);
  EXPECT_LT(r.path.back().x(), 3.5 + 0.3 + 0.2);
  EXPECT_FALSE(occ.Occupied(r.path.back()));
}

TEST(GridAstarTest, NoPathOutOfAClosedBox) {
  VoxelGrid grid(Eigen::Vector3d::Zero(), 0.1, {40, 40, 30}, CellState::kFree);
  testing::FillBox(&grid, Eigen::Vector3d(1.0, 1.0, 0.5), Eigen::Vector3d(3.0, 3.0, 2.5));
  testing::FillBox(&grid, Eigen::Vector3d(1.3, 1.3, 0.8), Eigen::Vector3d(2.7, 2.7, 2.2), CellState::kFree);
  const OccupancyBits bits(grid, nullptr);
  const InflatedOccupancy occ(bits, 0.1, nullptr);
  const AstarResult r = GridAstar(occ, grid.Box(), {2, 2, 1.5}, {3.7, 3.7, 1.5}, nullptr);
  EXPECT_EQ(r.status, AstarStatus::kNoPath);
  EXPECT_GT(r.expansions, 0);
  EXPECT_TRUE(r.path.empty());
}

TEST(GridAstarTest, TheBudgetHookStopsItAfterNExpansions) {
  const testing::AsciiWorld w = WallWorld();
  const OccupancyBits bits(w.grid, nullptr);
  const InflatedOccupancy occ(bits, 0.3, nullptr);
  WorkCounts work;
  work.Add(WorkUnit::kAstarExpansion, 100);  // work done before the search counts too
  const AstarResult r = GridAstar(occ, w.grid.Box(), w.start, w.goal, &work, [](const WorkCounts& c) {
    return c.Get(WorkUnit::kAstarExpansion) >= 125;
  });
  EXPECT_EQ(r.status, AstarStatus::kOverBudget);
  EXPECT_EQ(r.expansions, 25);
  EXPECT_EQ(work.Get(WorkUnit::kAstarExpansion), 125);
  EXPECT_TRUE(r.path.empty());
}

}  // namespace
}  // namespace enavi::navstack
