#include "navstack/planning/inflated_occupancy.h"

#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "navstack/planning/distance_field.h"
#include "tests/unit/planning/planning_test_worlds.h"

namespace enavi::navstack {
namespace {

// A 0.3 m cube of occupied cells in the middle of a 2 x 2 x 2 m grid at 0.1 m.
VoxelGrid CubeGrid() {
  VoxelGrid g(Eigen::Vector3d::Zero(), 0.1, {20, 20, 20}, CellState::kFree);
  testing::FillBox(&g, Eigen::Vector3d(0.88, 0.88, 0.88), Eigen::Vector3d(1.18, 1.18, 1.18));
  return g;
}

TEST(InflatedOccupancyTest, InflatesByACubeOfCeilInflationOverResolutionCells) {
  const VoxelGrid g = CubeGrid();  // occupied cells 9..11 on every axis
  const OccupancyBits bits(g, nullptr);
  const InflatedOccupancy inflated(bits, 0.25, nullptr);  // ceil(2.5) = 3 cells
  EXPECT_DOUBLE_EQ(inflated.guaranteed_clearance(), 0.3);
  for (int x = 0; x < 20; ++x) {
    const bool inside = x >= 6 && x <= 14;
    EXPECT_EQ(inflated.CellOccupied({x, 10, 10}), inside) << "x = " << x;
    EXPECT_EQ(inflated.CellOccupied({x, 6, 14}), inside) << "corner of the cube, x = " << x;
  }
  EXPECT_FALSE(inflated.CellOccupied({10, 10, 15}));
  EXPECT_FALSE(inflated.CellOccupied({-1, 10, 10})) << "outside the grid is free";
  // Ego-Planner's 0.099 m at 0.1 m is one cell.
  const InflatedOccupancy ego(bits, 0.099, nullptr);
  EXPECT_TRUE(ego.CellOccupied({8, 8, 8}));
  EXPECT_FALSE(ego.CellOccupied({7, 10, 10}));
}

TEST(InflatedOccupancyTest, RowsWiderThanOneWordDilateAcrossWordBoundaries) {
  VoxelGrid g(Eigen::Vector3d::Zero(), 0.1, {150, 3, 3}, CellState::kFree);
  g.cells[g.Index({63, 1, 1})] = CellState::kOccupied;
  g.cells[g.Index({128, 1, 1})] = CellState::kOccupied;
  const OccupancyBits bits(g, nullptr);
  const InflatedOccupancy inflated(bits, 0.2, nullptr);
  for (int x = 0; x < 150; ++x) {
    const bool expected = (x >= 61 && x <= 65) || (x >= 126 && x <= 130);
    EXPECT_EQ(inflated.CellOccupied({x, 1, 1}), expected) << "x = " << x;
  }
}

TEST(InflatedOccupancyTest, ClearanceMatchesTheDistanceToTheNearestOccupiedBox) {
  const testing::AsciiWorld park = testing::ParkWorld(6.0, 3.0, 0.1, 12, 3, 5);
  const OccupancyBits bits(park.grid, nullptr);
  const InflatedOccupancy inflated(bits, 0.3, nullptr);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.2, 5.8), uz(0.3, 2.7);
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), uz(rng));
    // Brute force over all occupied cells.
    double best = 1e9;
    for (int z = 0; z < park.grid.dims.z(); ++z) {
      for (int y = 0; y < park.grid.dims.y(); ++y) {
        for (int x = 0; x < park.grid.dims.x(); ++x) {
          if (park.grid.cells[park.grid.Index({x, y, z})] != CellState::kOccupied) continue;
          const Eigen::Vector3d lo = park.grid.origin + Eigen::Vector3d(x, y, z) * 0.1;
          best = std::min(best, (p.cwiseMax(lo).cwiseMin(lo + Eigen::Vector3d::Constant(0.1)) - p).norm());
        }
      }
    }
    const double needed = 0.5;
    EXPECT_NEAR(inflated.Clearance(p, needed), std::min(best, needed), 1e-9) << p.transpose();
    // A free inflated cell guarantees its clearance; IsClear never says yes for a closer point.
    if (!inflated.Occupied(p)) {
      EXPECT_GE(best, inflated.guaranteed_clearance()) << p.transpose();
    }
    if (inflated.IsClear(p, 0.3)) {
      EXPECT_GE(best, 0.3) << p.transpose();
    }
  }
}

TEST(InflatedOccupancyTest, CountsItsWork) {
  const VoxelGrid g = CubeGrid();
  WorkCounts work;
  const OccupancyBits bits(g, &work);
  const InflatedOccupancy inflated(bits, 0.3, &work);
  EXPECT_EQ(work.Get(WorkUnit::kInflateCell), 2 * 20 * 20 * 20) << "packing plus one dilation";
  inflated.Occupied(Eigen::Vector3d(0.5, 0.5, 0.5));
  EXPECT_EQ(work.Get(WorkUnit::kStateCheck), 1);
  EXPECT_EQ(work.Get(WorkUnit::kCellProbe), 0);
  inflated.Clearance(Eigen::Vector3d(1.05, 1.05, 1.32), 0.2);  // inflated cell: the grid is read
  EXPECT_EQ(work.Get(WorkUnit::kCellProbe), 5 * 5 * 5);
}

TEST(InflatedOccupancyTest, RefusesBadInput) {
  VoxelGrid bad(Eigen::Vector3d::Zero(), 0.1, {4, 4, 4});
  bad.cells.pop_back();
  EXPECT_THROW(OccupancyBits(bad, nullptr), std::invalid_argument);
  const VoxelGrid g = CubeGrid();
  const OccupancyBits bits(g, nullptr);
  EXPECT_THROW(InflatedOccupancy(bits, -0.1, nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
