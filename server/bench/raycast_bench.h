#pragma once
// Raycast benchmark core behind `enavi bench raycast`: Embree camera vs Bullet ray tests on the
// same frames of a world, per-core throughput and agreement.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "navstack/common/camera.h"
#include "navstack/control/vehicle.h"
#include "workers/sim/depth_camera.h"
#include "worlds/mesh.h"

namespace enavi::bench {

struct RaycastBenchOptions {
  navstack::CameraIntrinsics intrinsics = navstack::CameraIntrinsics::Default();
  navstack::VehicleParams vehicle;  ///< camera mount (p_BC)
  int frames = 60;                  ///< Embree frames, evenly spaced from start to goal
  /// Of those frames, this many (evenly spaced, first and last included) are also rendered by
  /// Bullet; throughput and disagreement are measured on them. 0 skips Bullet.
  int bullet_frames = 10;
  sim::EmbreeRayMode mode = sim::EmbreeRayMode::kPacket16;  ///< the mode the headline figure is for
  /// Further modes timed on the same frames for comparison (reported in `modes`).
  std::vector<sim::EmbreeRayMode> compare_modes;
};

struct RaycastModeTiming {
  std::string mode;
  double cpu_s = 0.0;
  double mrays_per_s_per_core = 0.0;
};

struct RaycastBenchResult {
  std::size_t triangles = 0;
  int width = 0, height = 0;
  int frames = 0;         ///< rendered by Embree
  int bullet_frames = 0;  ///< rendered by both
  std::int64_t embree_rays = 0, bullet_rays = 0;
  double embree_build_s = 0.0;  ///< wall time of the one-off scene build (may use threads)
  double bullet_build_s = 0.0;
  double embree_cpu_s = 0.0;  ///< thread CPU time of rendering
  double bullet_cpu_s = 0.0;
  double embree_mrays_per_s_per_core = 0.0;
  double bullet_mrays_per_s_per_core = 0.0;
  double speedup_vs_bullet = 0.0;  ///< ratio of the per-core throughputs
  /// Over the pixels of the shared frames where both return a depth: max |z_embree - z_bullet|.
  /// Dominated by rays grazing a silhouette edge, which Bullet's triangle test (widened by a
  /// relative edge tolerance) hits and Embree's exact test passes by.
  double max_depth_disagreement_m = 0.0;
  /// The same maximum over interior pixels (see DepthComparison): the depth accuracy proper.
  double max_depth_disagreement_interior_m = 0.0;
  std::int64_t both_hit_pixels = 0;
  std::int64_t disagreeing_pixels = 0;  ///< both hit, depths differ by more than 1 mm
  std::int64_t one_sided_pixels = 0;    ///< exactly one renderer returned (grazing edges)
  double embree_valid_fraction = 0.0;  ///< share of Embree pixels with a return (all frames)
  std::string embree_mode;
  sim::EmbreeDeviceInfo embree;
  std::vector<RaycastModeTiming> modes;  ///< headline mode first, then compare_modes
};

/// Pixel-by-pixel agreement of two depth images of the same view.
struct DepthComparison {
  std::int64_t both_hit = 0;     ///< pixels where both images have a return
  std::int64_t one_sided = 0;    ///< pixels where exactly one has a return
  std::int64_t disagreeing = 0;  ///< both hit and |a - b| > tolerance
  double max_diff = 0.0;         ///< max |a - b| over both_hit pixels
  /// Max |a - b| over interior pixels: both hit, and in `a` the pixel lies on a locally planar
  /// surface (inverse depth linear across its 3x3 neighbourhood): no silhouette or crease.
  double max_diff_interior = 0.0;

  DepthComparison& operator+=(const DepthComparison& o);
};

/// Compares `b` against reference `a` (same size). @throws std::invalid_argument on size mismatch.
DepthComparison CompareDepthImages(const navstack::DepthImage& a, const navstack::DepthImage& b,
                                   double tolerance = 1e-3);

/// Renders options.frames depth frames with the camera moving along the straight line from
/// `start` to `goal` at start's height, looking along the line (body yaw = line heading, camera
/// mounted as in CameraPoseInWorld). Times each renderer with the calling thread's CPU time.
/// @throws std::invalid_argument for start == goal (horizontally), frames < 1,
/// bullet_frames outside [0, frames], bad intrinsics or a bad mesh.
RaycastBenchResult RunRaycastBench(const worlds::TriangleMesh& mesh, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& goal,
                                   const RaycastBenchOptions& options = {});

/// JSON object with every field of `result` (names as in the struct).
nlohmann::json ToJson(const RaycastBenchResult& result);


}  // namespace enavi::bench
