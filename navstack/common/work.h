#pragma once
// Work counts: what a navstack job did, in units the board cost model prices
// (time = ns_per_job[task] + sum(count x ns_per_unit[board]), docs/design.md, "Time: two clocks").
// Counting, not timing, is what makes the virtual clock bit-reproducible on any host.

#include <array>
#include <cstdint>
#include <string_view>

namespace enavi::navstack {

enum class WorkUnit : int {
  kPixel = 0,          ///< depth pixel binned by the eci (read, range, zone and layer)
  kBackProjection,     ///< depth pixel back-projected into a world point (perception)
  kWarpPixel,          ///< depth pixel warped into another frame and compared (difference)
  kRay,                ///< one ray cast during map insertion: its end point's key, clipping, set-up
  kRayStep,            ///< one voxel traversed by a ray during map insertion
  kVoxelUpdate,        ///< one octree leaf updated (log-odds, with tree descent)
  kRebuildVoxel,       ///< one voxel written into a map rebuilt at another resolution (a fresh tree: allocations)
  kGridCell,           ///< one cell of a dense grid extracted from the map
  kDistanceCell,       ///< one cell of the planner's Euclidean distance transform
  kStateCheck,         ///< one planner state validity / motion check
  kPlannerIteration,   ///< one iteration of the sampling-based search
  kOptimizerEval,      ///< one B-spline control point visited in one cost evaluation
  kTrajectorySample,   ///< one trajectory sample checked against the map
  kCellProbe,          ///< one grid cell read while checking a trajectory sample's clearance
  kPolicyFlop,         ///< one multiply-add in the frequency adapter's network
  kAstarExpansion,     ///< one node expanded by the planner's grid A* (26 neighbours scored)
  kInflateCell,        ///< one grid cell packed into bits or dilated once (rebound planner's map)
  kCount
};

constexpr std::array<std::string_view, static_cast<int>(WorkUnit::kCount)> kWorkUnitNames = {
    "pixel",          "back_projection", "warp_pixel", "ray", "ray_step",           "voxel_update", "rebuild_voxel", "grid_cell", "distance_cell", "state_check",
    "planner_iteration", "optimizer_eval", "trajectory_sample", "cell_probe", "policy_flop",
    "astar_expansion", "inflate_cell"};

struct WorkCounts {
  std::array<std::int64_t, static_cast<int>(WorkUnit::kCount)> n{};

  void Add(WorkUnit unit, std::int64_t count) { n[static_cast<int>(unit)] += count; }
  std::int64_t Get(WorkUnit unit) const { return n[static_cast<int>(unit)]; }
  /// No unit counted: a job that found nothing to do and returned.
  bool Idle() const {
    for (std::int64_t c : n)
      if (c != 0) return false;
    return true;
  }
  WorkCounts& operator+=(const WorkCounts& o) {
    for (std::size_t i = 0; i < n.size(); ++i) n[i] += o.n[i];
    return *this;
  }
};

}  // namespace enavi::navstack
