#pragma once
// Depth image -> world-frame points: the first stage of the perception task (docs/design.md, "One episode").

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "navstack/common/camera.h"
#include "navstack/common/work.h"

namespace enavi::navstack {

/// How a depth frame is sampled for mapping. Ranges are z-depths (the unit of DepthImage).
struct PerceptionOptions {
  /// Pixel stride in u and v: every `stride`-th pixel of every `stride`-th row is used. 2 on the
  /// default 320x240 stream (4 on the full 640x480 frame) samples a surface every 6 cm at 5 m,
  /// still finer than the finest 0.1 m map cell, for a quarter of stride 1's rays. [1, 64]
  int stride = 2;
  /// Returns nearer than this are dropped (no information: too close to trust). m, [0, max_range)
  double min_range = 0.2;
  /// Returns farther than this are not inserted as obstacles; their ray (and, if the map is told
  /// so, the ray of a no-return pixel) only clears space up to this depth. 5 m is close to the
  /// baseline Ego-Planner's 4.5 m ray length; 10 m costs ~2.6x per frame. m, (min_range, 100]
  double max_range = 5.0;

  /// Throws std::invalid_argument naming the field and its allowed range.
  void Validate() const;
};

/// One frame back-projected into the world: what the map needs to cast rays, and what it keeps
/// to rebuild itself at another resolution. Stored in float: a frame is ~20k points.
struct ScanPoints {
  Eigen::Vector3d origin_W = Eigen::Vector3d::Zero();  ///< sensor origin (camera centre) in W
  /// End points of returns within [min_range, max_range]: surfaces.
  std::vector<Eigen::Vector3f> hits_W;
  /// Returns beyond max_range, cut at z = max_range: free space up to there, nothing known beyond.
  std::vector<Eigen::Vector3f> far_W;
  /// No-return pixels, placed at z = max_range along their ray: free only if the map says so.
  std::vector<Eigen::Vector3f> no_return_W;
};

/// Back-projects the pixels of `frame` on the stride grid (u, v = 0, stride, 2 stride, ...) with
/// the pinhole model and `frame.X_WC`. Counts one WorkUnit::kBackProjection per sampled pixel.
/// @pre frame.image matches intrinsics.width x intrinsics.height.
ScanPoints BackProject(const DepthFrame& frame, const CameraIntrinsics& intrinsics,
                       const PerceptionOptions& options = {}, WorkCounts* work = nullptr);

}  // namespace enavi::navstack
