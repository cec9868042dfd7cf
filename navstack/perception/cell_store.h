#pragma once
// Where the occupancy map keeps its cells' log-odds: OctoMap's octree (E-Navi's multi-resolution
// map) or a dense block grid (Ego-Planner's grid_map keeps dense arrays). Both apply OctoMap's
// update rule to the same float values, so a map's cell states do not depend on the store.
// Internal to enavi::perception.

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>

#include <Eigen/Core>

#include "navstack/perception/occupancy_map.h"

namespace enavi::navstack::detail {

/// OctoMap's tree_max_val for its 16-level trees: key = floor(x / resolution) + kKeyOffset.
inline constexpr int kKeyOffset = 32768;

/// Key of coordinate `x` on one axis, as OcTree::coordToKey (`inv` = 1 / resolution).
inline int KeyOf(double inv, double x) { return static_cast<int>(std::floor(inv * x)) + kKeyOffset; }

/// The three 16-bit keys packed by OccupancyMap::PackKey.
inline Eigen::Vector3i UnpackKey(std::uint64_t k) {
  return {static_cast<int>(k & 0xFFFF), static_cast<int>((k >> 16) & 0xFFFF),
          static_cast<int>((k >> 32) & 0xFFFF)};
}

/// Inclusive range of keys (OctoMap's 16-bit key space) on each axis.
struct KeyBox {
  Eigen::Vector3i lo, hi;
  std::int64_t Cells() const {
    return std::int64_t{hi.x() - lo.x() + 1} * (hi.y() - lo.y() + 1) * (hi.z() - lo.z() + 1);
  }
};

class CellStore {
 public:
  /// fill(lo, hi, occupied) for a block of known cells with one state, clipped to the box.
  using BlockFn = std::function<void(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi, bool occupied)>;
  /// leaf(centre, edge) for each occupied leaf overlapping the box (not clipped).
  using LeafFn = std::function<void(const Eigen::Vector3d& centre, double edge)>;

  virtual ~CellStore() = default;
  /// One hit or one miss, as OcTree::updateNode(key, occupied): add the log-odds, clamp.
  virtual void Update(std::uint64_t packed_key, bool occupied) = 0;
  /// Sets a cell's log-odds (clamped), as OcTree::setNodeValue.
  virtual void Set(std::uint64_t packed_key, float log_odds) = 0;
  /// State of one cell.
  virtual CellState State(std::uint64_t packed_key) const = 0;
  virtual void ForEachKnownBlock(const KeyBox& box, const BlockFn& fill) const = 0;
  virtual void ForEachOccupiedLeaf(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                   const LeafFn& leaf) const = 0;
  /// Log-odds of one hit.
  virtual float HitLogOdds() const = 0;
  /// Leaves (octree) or known cells (block grid): the memory footprint.
  virtual std::size_t NumLeaves() const = 0;
  virtual void Clear() = 0;
};

std::unique_ptr<CellStore> MakeOctreeStore(const MapOptions& options, double resolution);
std::unique_ptr<CellStore> MakeBlockStore(const MapOptions& options);

}  // namespace enavi::navstack::detail
