#pragma once
// World validation: start and goal in free space with clearance, and a collision-free route at
// least 1 m wide between them (checked on an inflated 3-D occupancy grid).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "worlds/world.h"

namespace enavi::worlds {

struct ValidationOptions {
  double clearance = 0.5;     ///< m, least distance from start/goal to any obstacle (and the ground)
  double route_radius = 0.5;  ///< m, half the width of the required route (1 m wide)
  double cell = 0.2;          ///< m, occupancy grid cell; grown by 1.25x steps past max_cells
  std::size_t max_cells = 16'000'000;
  bool check_route = true;
};

/// Outcome of ValidateWorld. A failure names the field ("bounds", "start", "goal") and the reason.
struct ValidationResult {
  bool ok = true;
  std::string field;
  std::string reason;
  double cell = 0.0;                ///< m, grid cell the route check used (0 if not run)
  std::int64_t cells_reached = 0;   ///< free cells the flood fill reached from start
};

/// Checks that start and goal are inside the bounds, at least `clearance` from every obstacle
/// and the ground, and that a route of width 2 x route_radius joins them.
///
/// Route check: obstacles are rasterised into a grid over the bounds; a cell is blocked when its
/// centre is closer than route_radius + cell/2 to an obstacle, so any path through 6-connected
/// free cells keeps a ball of radius route_radius clear of every obstacle (sound, slightly
/// conservative). The flood fill starts from the free cells of the 3x3x3 block around start and
/// succeeds on reaching the block around goal. Deterministic: same World, same answer everywhere.
ValidationResult ValidateWorld(const World& world, const ValidationOptions& options = {});

/// Distance to the nearest obstacle of a World, object by object. Prepared once (mesh objects
/// are placed in the world frame), queried many times.
class ObstacleField {
 public:
  /// `include_ground`: treat the ground plane (if enabled) as an obstacle.
  explicit ObstacleField(const World& world, bool include_ground = true);

  /// Signed distance from p_W to the nearest obstacle surface: > 0 outside, <= 0 inside (for
  /// open meshes: unsigned). Distances above 20 m may be lower bounds. `nearest` receives the
  /// object index, -1 for the ground, -2 when there is no obstacle (distance = +inf).
  double Distance(const Eigen::Vector3d& p_W, int* nearest = nullptr) const;

  /// Signed distance to one object (index into World::objects).
  double ObjectDistance(int index, const Eigen::Vector3d& p_W) const;

  /// Least distance to obstacles along the segment a-b, sampled every `step` metres.
  double SegmentClearance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double step = 0.05) const;

  std::size_t object_count() const { return items_.size(); }
  const Eigen::AlignedBox3d& object_bounds(int index) const { return items_[index].bounds; }

 private:
  struct Item {
    Eigen::AlignedBox3d bounds;
    int first_triangle = 0;  ///< mesh objects: range into triangles_
    int triangle_count = 0;
    bool closed = false;     ///< mesh objects: watertight, so inside tests are meaningful
    double cos_yaw = 1.0, sin_yaw = 0.0;  ///< boxes: rotation, computed once
  };
  friend class OccupancyRaster;
  // Exact when below `cap`, otherwise some value >= cap.
  double ObjectDistanceCapped(int index, const Eigen::Vector3d& p_W, double cap) const;
  const World& world_;
  bool include_ground_;
  std::vector<Item> items_;
  std::vector<Eigen::Matrix3d> triangles_;  ///< columns = world-frame corners
};

}  // namespace enavi::worlds
