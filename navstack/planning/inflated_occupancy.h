#pragma once
// Occupancy of a VoxelGrid snapshot as Ego-Planner's optimiser and A* read their map
// (plan_env/grid_map.cpp, getInflateOccupancy): occupied cells inflated by a cube of cells, one bit
// per cell, no distance transform. What the rebound pipeline uses instead of DistanceField.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/work.h"
#include "navstack/map/voxel_grid.h"
#include "navstack/planning/clearance_map.h"

namespace enavi::navstack {

/// The occupied cells of a grid packed into bits, one run of 64-bit words per x-row. Unknown
/// cells count as free, as in the ESDF pipeline. Adds one kInflateCell per grid cell to *work.
/// @throws std::invalid_argument if the grid is malformed.
class OccupancyBits {
 public:
  OccupancyBits(const VoxelGrid& grid, WorkCounts* work);

  const VoxelGrid& grid() const { return grid_; }
  int words_per_row() const { return words_; }
  /// Bits of the x-row (y, z): bit x % 64 of word x / 64 is cell (x, y, z).
  const std::uint64_t* Row(int y, int z) const { return &bits_[RowIndex(y, z)]; }
  std::size_t RowIndex(int y, int z) const {
    return (static_cast<std::size_t>(z) * grid_.dims.y() + y) * words_;
  }

 private:
  const VoxelGrid& grid_;
  int words_;
  std::vector<std::uint64_t> bits_;
};

/// Occupancy inflated by k = ceil(inflation / resolution) cells along every axis (Ego-Planner's
/// inflatePoint cube, grid_map/obstacles_inflation 0.099 m at 0.1 m in advanced_param.xml), by
/// separable bit dilation: one kInflateCell per grid cell. A cell that is not inflated has no
/// occupied cell within k cells on some axis, so every point in it has clearance >= k x
/// resolution (>= inflation). Exact clearance probes read the grid cell by cell (kCellProbe).
/// `base` (and its grid) must outlive this object.
class InflatedOccupancy : public ClearanceMap {
 public:
  /// @throws std::invalid_argument if inflation < 0 or not finite.
  InflatedOccupancy(const OccupancyBits& base, double inflation, WorkCounts* work);

  /// True if the cell containing p_W is inflated-occupied (false outside the grid). Adds one
  /// kStateCheck.
  bool Occupied(const Eigen::Vector3d& p_W) const { return CellOccupied(grid_.CellOf(p_W)); }
  /// Same for a cell index.
  bool CellOccupied(const Eigen::Vector3i& cell) const;

  /// Exact distance from p_W to the nearest occupied cell's box, reading the grid cells within
  /// `needed` of p_W; `needed` if there is none that close. Skips the reads (returns `needed`) when
  /// the inflation already guarantees it.
  double Clearance(const Eigen::Vector3d& p_W, double needed) const override;
  /// As Clearance(p, needed) >= needed, but an inflated cell with needed > (k - 1) x resolution
  /// answers false without reading the grid (conservative: the cube inflation's test).
  bool IsClear(const Eigen::Vector3d& p_W, double needed) const override;
  double resolution() const override { return grid_.resolution; }
  Eigen::AlignedBox3d Box() const override { return grid_.Box(); }

  const VoxelGrid& grid() const { return grid_; }
  /// Clearance every free cell guarantees: k x resolution [m].
  double guaranteed_clearance() const { return cells_ * grid_.resolution; }

 private:
  const VoxelGrid& grid_;
  int cells_;  ///< k
  int words_;
  WorkCounts* work_;
  std::vector<std::uint64_t> bits_;
};

}  // namespace enavi::navstack
