#pragma once
// Analytic depth rendering of boxes and planes for tests and benchmarks (no Embree): exact
// z-depths, so expectations can be worked out by hand.

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/camera.h"

namespace enavi::navstack::testing {

/// Infinite plane n . p = offset (n unit).
struct Plane {
  Eigen::Vector3d n;
  double offset;
};

struct Scene {
  std::vector<Eigen::AlignedBox3d> boxes;
  std::vector<Plane> planes;
};

/// Camera at p_WC looking horizontally along world yaw angle `yaw` (0: +x), world z up;
/// optical frame C: z forward, x right, y down. `pitch` > 0 tilts the view up.
inline Eigen::Isometry3d CameraPose(const Eigen::Vector3d& p_WC, double yaw = 0.0,
                                    double pitch = 0.0) {
  Eigen::Matrix3d R_W_level;  // columns: camera x (right), y (down), z (forward) at yaw 0
  R_W_level << 0, 0, 1,
              -1, 0, 0,
               0, -1, 0;
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
  X_WC.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_W_level *
                  Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()).toRotationMatrix();
  X_WC.translation() = p_WC;
  return X_WC;
}

/// Ray parameter (= z-depth for a unit-depth ray) of the first hit, or +inf.
inline double Intersect(const Scene& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::AlignedBox3d& b : scene.boxes) {
    double t0 = 0.0, t1 = best;
    bool hit = true;
    for (int a = 0; a < 3 && hit; ++a) {
      if (std::abs(d[a]) < 1e-12) {
        hit = o[a] >= b.min()[a] && o[a] <= b.max()[a];
        continue;
      }
      double ta = (b.min()[a] - o[a]) / d[a], tb = (b.max()[a] - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      hit = t0 <= t1;
    }
    if (hit && t0 > 0.0) best = std::min(best, t0);
  }
  for (const Plane& p : scene.planes) {
    const double nd = p.n.dot(d);
    if (std::abs(nd) < 1e-12) continue;
    const double t = (p.offset - p.n.dot(o)) / nd;
    if (t > 0.0) best = std::min(best, t);
  }
  return best;
}

/// Renders z-depth; returns outside [min_range, max_range] are DepthImage::kNoReturn.
inline DepthImage Render(const Scene& scene, const CameraIntrinsics& k, const Eigen::Isometry3d& X_WC) {
  DepthImage image(k.width, k.height);
  const Eigen::Matrix3d R = X_WC.linear();
  const Eigen::Vector3d o = X_WC.translation();
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const double t = Intersect(scene, o, R * k.PixelRay(u, v));
      if (t >= k.min_range && t <= k.max_range) image.at(u, v) = static_cast<float>(t);
    }
  }
  return image;
}

inline DepthFrame RenderFrame(const Scene& scene, const CameraIntrinsics& k,
                              const Eigen::Isometry3d& X_WC, std::int64_t index = 0) {
  DepthFrame frame;
  frame.index = index;
  frame.image = Render(scene, k, X_WC);
  frame.X_WC = X_WC;
  return frame;
}

/// A box given by centre and size.
inline Eigen::AlignedBox3d BoxAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& size) {
  return {centre - 0.5 * size, centre + 0.5 * size};
}

}  // namespace enavi::navstack::testing
