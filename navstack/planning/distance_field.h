#pragma once
// Euclidean distance field over a VoxelGrid snapshot: what the path search and the B-spline
// optimiser use for clearance (Ego-Planner's ESDF, unsigned: unknown space is optimistic/free).

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/work.h"
#include "navstack/planning/clearance_map.h"
#include "navstack/map/voxel_grid.h"

namespace enavi::navstack {

/// Exact Euclidean distance transform of the occupied cells of a VoxelGrid (unknown counts as
/// free), by Felzenszwalb-Huttenlocher separable lower-envelope passes along x, y and z.
///
/// The value at a cell is the distance from its centre to the nearest occupied cell centre minus
/// half a resolution, i.e. approximately the distance to the nearest occupied voxel's face:
/// -resolution/2 inside occupied cells, 0.5 * resolution next to them. Between cell centres the
/// field is trilinear; outside the grid it is clamped to the border (nothing is known there).
/// A grid without occupied cells gives kNoObstacleDistance everywhere.
class DistanceField : public ClearanceMap {
 public:
  /// Value everywhere when the grid has no occupied cell [m].
  static constexpr double kNoObstacleDistance = 1e3;

  /// Builds the field. Adds grid.dims.prod() WorkUnit::kDistanceCell to *work (may be null).
  /// @throws std::invalid_argument if the grid is malformed (cells.size() != dims.prod(),
  ///         non-positive dims or resolution).
  explicit DistanceField(const VoxelGrid& grid, WorkCounts* work = nullptr);

  /// Trilinear distance at a world point [m].
  double Distance(const Eigen::Vector3d& p_W) const;
  /// Trilinear distance and its exact gradient (zero along axes where p_W is clamped) [m, m/m].
  double Distance(const Eigen::Vector3d& p_W, Eigen::Vector3d* grad_W) const;
  /// Value stored at a cell (no interpolation). @pre InBounds(cell).
  double CellDistance(const Eigen::Vector3i& cell) const { return dist_[Index(cell)]; }
  /// The trilinear distance (exact everywhere, whatever is needed).
  double Clearance(const Eigen::Vector3d& p_W, double /*needed*/) const override { return Distance(p_W); }
  bool IsClear(const Eigen::Vector3d& p_W, double needed) const override { return Distance(p_W) >= needed; }

  const Eigen::Vector3d& origin() const { return origin_; }
  double resolution() const override { return resolution_; }
  const Eigen::Vector3i& dims() const { return dims_; }
  bool has_obstacles() const { return has_obstacles_; }
  Eigen::AlignedBox3d Box() const override { return {origin_, origin_ + dims_.cast<double>() * resolution_}; }
  bool InBounds(const Eigen::Vector3i& c) const {
    return (c.array() >= 0).all() && (c.array() < dims_.array()).all();
  }
  Eigen::Vector3i CellOf(const Eigen::Vector3d& p_W) const {
    return ((p_W - origin_) / resolution_).array().floor().cast<int>();
  }
  Eigen::Vector3d CenterOf(const Eigen::Vector3i& c) const {
    return origin_ + (c.cast<double>().array() + 0.5).matrix() * resolution_;
  }

 private:
  std::size_t Index(const Eigen::Vector3i& c) const {
    return static_cast<std::size_t>(c.x()) +
           static_cast<std::size_t>(dims_.x()) *
               (static_cast<std::size_t>(c.y()) + static_cast<std::size_t>(dims_.y()) * c.z());
  }

  Eigen::Vector3d origin_;
  double resolution_;
  Eigen::Vector3i dims_;
  bool has_obstacles_ = false;
  std::vector<double> dist_;  ///< x fastest, then y, then z (as VoxelGrid)
};

}  // namespace enavi::navstack
