#pragma once
// Dense snapshot of the occupancy map over a box: what planning and collision checking read.
// Produced by perception (from OctoMap), consumed by planning; neither knows the other.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace enavi::navstack {

enum class CellState : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

struct VoxelGrid {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< world position of cell (0,0,0)'s min corner
  double resolution = 0.1;
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  std::vector<CellState> cells;  ///< x fastest, then y, then z

  VoxelGrid() = default;
  VoxelGrid(const Eigen::Vector3d& origin_in, double res, const Eigen::Vector3i& dims_in,
            CellState fill = CellState::kUnknown)
      : origin(origin_in), resolution(res), dims(dims_in),
        cells(static_cast<std::size_t>(dims_in.prod()), fill) {}

  bool InBounds(const Eigen::Vector3i& c) const {
    return (c.array() >= 0).all() && (c.array() < dims.array()).all();
  }
  std::size_t Index(const Eigen::Vector3i& c) const {
    return static_cast<std::size_t>(c.x()) +
           static_cast<std::size_t>(dims.x()) * (c.y() + static_cast<std::size_t>(dims.y()) * c.z());
  }
  Eigen::Vector3i CellOf(const Eigen::Vector3d& p_W) const {
    return ((p_W - origin) / resolution).array().floor().cast<int>();
  }
  Eigen::Vector3d CenterOf(const Eigen::Vector3i& c) const {
    return origin + (c.cast<double>().array() + 0.5).matrix() * resolution;
  }
  /// State at a world point; outside the grid counts as unknown.
  CellState At(const Eigen::Vector3d& p_W) const {
    const Eigen::Vector3i c = CellOf(p_W);
    return InBounds(c) ? cells[Index(c)] : CellState::kUnknown;
  }
  Eigen::AlignedBox3d Box() const {
    return {origin, origin + dims.cast<double>() * resolution};
  }
};

}  // namespace enavi::navstack
