#pragma once
// Probabilistic occupancy map of the perception task: an OctoMap octree (or a dense block grid, as
// Ego-Planner keeps) fed by depth frames,
// updated in two phases so the simulated scheduler can apply a job's output at its finish time
// (docs/design.md, "Time: two clocks"), and rebuilt when the resolution adapter changes `res` (paper Sec. V.A).

#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/camera.h"
#include "navstack/common/work.h"
#include "navstack/map/voxel_grid.h"
#include "navstack/perception/points.h"

namespace enavi::navstack {

namespace detail {
class CellStore;
}

/// Where the cells live. Both apply OctoMap's log-odds rule to the same floats, so the cell states
/// and work counts are the same; they differ in speed, memory and rebuild granularity.
enum class MapStorage {
  /// OctoMap's pruned octree: compact for large uniform regions (E-Navi's multi-resolution map).
  kOctree,
  /// Dense blocks of 8^3 cells, allocated where rays reach: an update is an index, not an octree
  /// descent (Ego-Planner's grid_map keeps dense arrays). A rebuild carries each occupied cell, not
  /// each pruned leaf, so its work count can differ from the octree's.
  kBlocks,
};

/// Map parameters. Probabilities follow OctoMap's defaults (one hit marks a cell occupied, one
/// miss marks unknown space free, three misses clear a once-hit cell).
struct MapOptions {
  double resolution = 0.1;           ///< m, leaf edge length. [0.02, 5]
  double prob_hit = 0.7;             ///< P(occ | return in cell). (0.5, 1)
  double prob_miss = 0.4;            ///< P(occ | ray through cell). (0, 0.5)
  double clamp_min = 0.12;           ///< lower clamping probability. (0, occupancy_threshold)
  double clamp_max = 0.97;           ///< upper clamping probability. (occupancy_threshold, 1)
  double occupancy_threshold = 0.5;  ///< cells at or above are occupied, below free. (0, 1)
  /// Half-size of the box around the sensor that one frame may update (Ego-Planner's local
  /// update range): rays are cut at its faces, returns outside it only clear space. m, each > 0
  Eigen::Vector3d local_half_extent{8.0, 8.0, 4.0};
  /// Frames kept (as points) to rebuild the map when the resolution changes. [0, 1000]
  int rebuild_frames = 10;
  /// No-return pixels clear free space up to PerceptionOptions::max_range. Right for the farm's
  /// simulated camera, whose no-return means "nothing within range" (Fast-/Ego-Planner do the
  /// same); turn off for a real sensor whose dropouts can hide surfaces.
  bool clear_no_return = true;
  /// Cast one ray per distinct end voxel (to its centre) instead of one per point, as OctoMap's
  /// discretised insertion does: far returns share voxels, so this cuts ray steps several-fold.
  bool discretize_endpoints = true;
  /// Ego-Planner's raycast (plan_env/grid_map.cpp, raycastProcess): one ray per distinct end
  /// voxel, cast from the end point back towards the sensor, stopping at the first voxel a ray of
  /// the same frame has already cleared. Rays converge at the sensor, so most stop a few voxels
  /// from their end; a voxel that only the skipped part of a ray crossed stays as it was.
  bool stop_at_traversed = false;
  MapStorage storage = MapStorage::kOctree;

  /// Throws std::invalid_argument naming the field and its allowed range.
  void Validate() const;
};

/// The expensive half of a map update, computed without touching the map: deduplicated octree
/// keys to mark free and occupied (a key in both is occupied, as in OctoMap's computeUpdate).
struct MapUpdate {
  double resolution = 0.0;                   ///< map resolution the keys were computed at
  std::shared_ptr<const ScanPoints> scan;    ///< the frame's points (kept for rebuilds)
  std::vector<std::uint64_t> free_keys;      ///< packed octree keys (see OccupancyMap::PackKey)
  std::vector<std::uint64_t> occupied_keys;  ///< packed octree keys
  std::int64_t ray_steps = 0;                ///< voxels traversed while casting
};

/// What Apply did.
struct ApplyResult {
  /// The update was computed at another resolution than the map's (the map was rebuilt in
  /// between); its keys were recomputed from its points at the current resolution.
  bool recomputed = false;
  std::int64_t voxel_updates = 0;
};

/// Cell counts over a box at the map resolution: rho_c = occupied, rho*_c = total (Sec. V.A).
struct OccupancyStats {
  std::int64_t occupied = 0;
  std::int64_t free = 0;
  std::int64_t unknown = 0;
  std::int64_t total = 0;
};

/// Occupancy map (OctoMap's update rule) with two-phase updates, rebuild-on-resolution-change and dense
/// extraction. Not thread-safe for writes; const members may run concurrently with each other.
class OccupancyMap {
 public:
  explicit OccupancyMap(const MapOptions& options = {});
  ~OccupancyMap();
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;
  OccupancyMap(const OccupancyMap&) = delete;
  OccupancyMap& operator=(const OccupancyMap&) = delete;

  /// Phase 1: back-projects `frame` and casts its rays at the current resolution. Does not
  /// modify the map. Counts kBackProjection (sampled pixels), kRay (rays cast) and kRayStep (voxels
  /// traversed, with repeats: the cost of casting, before deduplication).
  MapUpdate ComputeUpdate(const DepthFrame& frame, const CameraIntrinsics& intrinsics,
                          const PerceptionOptions& perception, WorkCounts* work = nullptr) const;
  /// Phase 1 from points already back-projected.
  MapUpdate ComputeUpdate(std::shared_ptr<const ScanPoints> scan, WorkCounts* work = nullptr) const;

  /// Phase 2: integrates `update` (free first, then occupied, like OctoMap) and keeps its points
  /// for rebuilds. An update computed at another resolution is recomputed from its points first
  /// (counted as phase 1 work): a frame is never silently lost. Counts kVoxelUpdate.
  ApplyResult Apply(const MapUpdate& update, WorkCounts* work = nullptr);

  /// Both phases at once.
  void Insert(const DepthFrame& frame, const CameraIntrinsics& intrinsics,
              const PerceptionOptions& perception, WorkCounts* work = nullptr);

  /// Rebuilds the map at `resolution`: occupied leaves within the local update box of the newest
  /// kept frame carry over (as one hit on every new cell they overlap), then the last
  /// MapOptions::rebuild_frames frames are replayed; older free space is dropped. No-op if
  /// unchanged. Counts the replay's kRay and kRayStep, and every cell written as kRebuildVoxel. Throws std::invalid_argument if out of range.
  void SetResolution(double resolution, WorkCounts* work = nullptr);
  /// The same rebuild into a new map, leaving this one untouched: the perception job builds it
  /// when it starts and swaps it in when it finishes. Only occupied leaves whose centre is within
  /// `carry_radius` of the newest frame's origin carry over; the rest of the map is forgotten
  /// (unknown) unless a kept frame sees it again: the stack's recovery from obstacles it cannot
  /// re-observe (NavStackOptions::scan_reset_distance).
  std::shared_ptr<OccupancyMap> Rebuilt(double resolution, WorkCounts* work = nullptr,
                                        double carry_radius = std::numeric_limits<double>::infinity()) const;

  /// Dense snapshot of the cells overlapping `box`, aligned to the octree keys (the grid origin is
  /// a cell corner of the map). Filled from the octree leaves in the box (pruned leaves fill
  /// whole blocks). Counts kGridCell (cells in the grid). Throws std::invalid_argument for an
  /// empty box or one of more than 2^28 cells.
  VoxelGrid ExtractGrid(const Eigen::AlignedBox3d& box, WorkCounts* work = nullptr) const;

  /// Occupancy counts over the cells overlapping `box` (same cells as ExtractGrid). Counts
  /// kGridCell (cells in the box).
  OccupancyStats Stats(const Eigen::AlignedBox3d& box, WorkCounts* work = nullptr) const;

  /// State of the cell containing `p_W`; outside the map's key range is unknown.
  CellState Query(const Eigen::Vector3d& p_W) const;

  /// Drops all content and the rebuild history.
  void Clear();

  double resolution() const { return options_.resolution; }
  const MapOptions& options() const { return options_; }
  /// Frames currently kept for a rebuild.
  int history_size() const { return static_cast<int>(history_.size()); }
  /// Octree leaves, or known cells of the block grid (memory footprint).
  std::size_t num_leaves() const;

  /// Packs an octree key (16 bits per axis) into the integer stored in a MapUpdate.
  static std::uint64_t PackKey(std::uint16_t kx, std::uint16_t ky, std::uint16_t kz) {
    return std::uint64_t{kx} | (std::uint64_t{ky} << 16) | (std::uint64_t{kz} << 32);
  }

 private:
  MapOptions options_;
  std::unique_ptr<detail::CellStore> store_;
  std::deque<std::shared_ptr<const ScanPoints>> history_;
};

}  // namespace enavi::navstack
