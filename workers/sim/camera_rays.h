#pragma once
// Private to enavi_sim: the pixel rays both renderers (Embree and Bullet) shoot, so the two see
// exactly the same rays and use the same z-depth convention.

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/camera.h"

namespace enavi::sim {

/// Pixel-centre ray directions in C with unit z: (x_of_u[u], y_of_v[v], 1). A ray parameter t
/// along such a direction is the z-depth of the point it reaches.
struct PixelRays {
  std::vector<float> x_of_u;
  std::vector<float> y_of_v;

  explicit PixelRays(const navstack::CameraIntrinsics& k) : x_of_u(k.width), y_of_v(k.height) {
    for (int u = 0; u < k.width; ++u) x_of_u[u] = static_cast<float>(k.PixelRay(u, 0).x());
    for (int v = 0; v < k.height; ++v) y_of_v[v] = static_cast<float>(k.PixelRay(0, v).y());
  }
};

/// The camera pose in single precision (what both ray casters work in).
struct CameraRayFrame {
  Eigen::Vector3f origin;
  Eigen::Vector3f ex, ey, ez;  ///< columns of R_WC

  explicit CameraRayFrame(const Eigen::Isometry3d& X_WC)
      : origin(X_WC.translation().cast<float>()),
        ex(X_WC.linear().col(0).cast<float>()),
        ey(X_WC.linear().col(1).cast<float>()),
        ez(X_WC.linear().col(2).cast<float>()) {}

  /// World direction of the C ray (x, y, 1).
  Eigen::Vector3f Direction(float x, float y) const { return ex * x + ey * y + ez; }
};

/// Depth image value for a hit at z-depth t (or no hit): kNoReturn outside [min, max].
inline float DepthOrNoReturn(bool hit, float t, float min_range, float max_range) {
  return (hit && t >= min_range && t <= max_range) ? t : navstack::DepthImage::kNoReturn;
}

}  // namespace enavi::sim
