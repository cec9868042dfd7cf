#include "navstack/planning/distance_field.h"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/unit/planning/planning_test_worlds.h"

namespace enavi::navstack {
namespace {

// Random small grid: ~8 % occupied, ~20 % unknown, rest free (mt19937 raw output: portable).
VoxelGrid RandomGrid(const Eigen::Vector3i& dims, double res, std::uint32_t seed) {
  VoxelGrid grid(Eigen::Vector3d(-1.0, 2.0, 0.5), res, dims, CellState::kFree);
  std::mt19937 rng(seed);
  for (auto& c : grid.cells) {
    const std::uint32_t r = rng() % 100;
    c = r < 8 ? CellState::kOccupied : r < 28 ? CellState::kUnknown : CellState::kFree;
  }
  return grid;
}

TEST(DistanceFieldTest, EqualsBruteForceOnSmallRandomGrid) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const VoxelGrid grid = RandomGrid({11, 7, 5}, 0.2, seed);
    const DistanceField field(grid);
    ASSERT_TRUE(field.has_obstacles());
    for (int z = 0; z < grid.dims.z(); ++z) {
      for (int y = 0; y < grid.dims.y(); ++y) {
        for (int x = 0; x < grid.dims.x(); ++x) {
          // Brute force: nearest occupied centre, minus half a cell (the field's definition).
          double best = std::numeric_limits<double>::infinity();
          for (int k = 0; k < grid.dims.z(); ++k) {
            for (int j = 0; j < grid.dims.y(); ++j) {
              for (int i = 0; i < grid.dims.x(); ++i) {
                if (grid.cells[grid.Index({i, j, k})] != CellState::kOccupied) continue;
                best = std::min(best, (grid.CenterOf({x, y, z}) - grid.CenterOf({i, j, k})).norm());
              }
            }
          }
          ASSERT_NEAR(field.CellDistance({x, y, z}), best - 0.1, 1e-9)
              << "seed " << seed << " cell (" << x << ", " << y << ", " << z << ")";
        }
      }
    }
  }
}

TEST(DistanceFieldTest, UnknownCountsAsFree) {
  // A single occupied cell in a grid otherwise unknown: distances grow from it.
  VoxelGrid grid(Eigen::Vector3d::Zero(), 0.1, {9, 9, 9}, CellState::kUnknown);
  grid.cells[grid.Index({4, 4, 4})] = CellState::kOccupied;
  const DistanceField field(grid);
  EXPECT_NEAR(field.CellDistance({4, 4, 4}), -0.05, 1e-12);
  EXPECT_NEAR(field.CellDistance({8, 4, 4}), 0.4 - 0.05, 1e-12);
  EXPECT_NEAR(field.CellDistance({0, 0, 0}), std::sqrt(3.0) * 0.4 - 0.05, 1e-12);
}

TEST(DistanceFieldTest, EmptyGridIsFarEverywhere) {
  const VoxelGrid grid(Eigen::Vector3d::Zero(), 0.5, {4, 3, 2}, CellState::kFree);
  const DistanceField field(grid);
  EXPECT_FALSE(field.has_obstacles());
  Eigen::Vector3d grad;
  EXPECT_EQ(field.Distance(Eigen::Vector3d(1.0, 0.7, 0.3), &grad), DistanceField::kNoObstacleDistance);
  EXPECT_EQ(grad, Eigen::Vector3d::Zero());
}

TEST(DistanceFieldTest, InterpolationHitsCellValuesAndGradientMatchesFiniteDifferences) {
  const VoxelGrid grid = RandomGrid({12, 10, 8}, 0.25, 11);
  const DistanceField field(grid);
  // At cell centres the trilinear field equals the stored value.
  EXPECT_NEAR(field.Distance(grid.CenterOf({3, 4, 5})), field.CellDistance({3, 4, 5}), 1e-12);
  // Inside a trilinear cell the analytic gradient equals central differences.
  std::mt19937 rng(5);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d p = grid.origin + Eigen::Vector3d(0.3 + 2.2 * (rng() % 1000) / 1000.0,
                                                            0.3 + 1.7 * (rng() % 1000) / 1000.0,
                                                            0.3 + 1.2 * (rng() % 1000) / 1000.0);
    Eigen::Vector3d grad;
    field.Distance(p, &grad);
    for (int k = 0; k < 3; ++k) {
      const double h = 1e-6;
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(k) * h;
      const double fd = (field.Distance(p + e) - field.Distance(p - e)) / (2 * h);
      EXPECT_NEAR(grad[k], fd, 1e-4) << "axis " << k << " at " << p.transpose();
    }
  }
}

TEST(DistanceFieldTest, GradientPointsAwayFromAWall) {
  // Wall at x in [1.0, 1.2] across the grid: left of it the distance falls towards +x.
  VoxelGrid grid(Eigen::Vector3d::Zero(), 0.1, {30, 10, 10}, CellState::kFree);
  testing::FillBox(&grid, Eigen::Vector3d(1.0, -1, -1), Eigen::Vector3d(1.2, 2, 2));
  const DistanceField field(grid);
  Eigen::Vector3d grad;
  const double d = field.Distance(Eigen::Vector3d(0.52, 0.5, 0.5), &grad);
  EXPECT_NEAR(d, 0.48, 0.051) << "about the distance to the wall's face at x = 1.0";
  EXPECT_LT(grad.x(), -0.9);
  EXPECT_NEAR(grad.y(), 0.0, 1e-9);
}

TEST(DistanceFieldTest, CountsEveryCellAsWork) {
  WorkCounts small, large;
  DistanceField a(VoxelGrid(Eigen::Vector3d::Zero(), 0.1, {10, 10, 10}, CellState::kFree), &small);
  DistanceField b(VoxelGrid(Eigen::Vector3d::Zero(), 0.1, {20, 20, 10}, CellState::kFree), &large);
  EXPECT_EQ(small.Get(WorkUnit::kDistanceCell), 1000);
  EXPECT_EQ(large.Get(WorkUnit::kDistanceCell), 4000);
}

TEST(DistanceFieldTest, RejectsMalformedGrid) {
  VoxelGrid grid(Eigen::Vector3d::Zero(), 0.1, {4, 4, 4});
  grid.cells.pop_back();
  EXPECT_THROW(DistanceField{grid}, std::invalid_argument);
  VoxelGrid zero_res(Eigen::Vector3d::Zero(), 0.0, {4, 4, 4});
  EXPECT_THROW(DistanceField{zero_res}, std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
