#include "navstack/common/camera.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace enavi::navstack {

CameraIntrinsics CameraIntrinsics::FromFov(int width, int height, double hfov_deg,
                                           double vfov_deg, double min_range, double max_range) {
  CameraIntrinsics k;
  k.width = width;
  k.height = height;
  const double deg = M_PI / 180.0;
  k.fx = 0.5 * width / std::tan(0.5 * hfov_deg * deg);
  k.fy = 0.5 * height / std::tan(0.5 * vfov_deg * deg);
  k.cx = 0.5 * width;
  k.cy = 0.5 * height;
  k.min_range = min_range;
  k.max_range = max_range;
  return k;
}

CameraIntrinsics CameraIntrinsics::Decimated(int n) const {
  if (n < 1 || n > width || n > height) {
    throw std::invalid_argument("CameraIntrinsics.decimation: must be in [1, " +
                                std::to_string(std::min(width, height)) + "], got " + std::to_string(n));
  }
  // Block centre of decimated pixel u is n (u + 0.5) in this camera's pixels, so PixelRay's
  // (u + 0.5 - cx) / fx holds with cx and fx divided by n.
  CameraIntrinsics k = *this;
  k.width = width / n;
  k.height = height / n;
  k.fx = fx / n;
  k.fy = fy / n;
  k.cx = cx / n;
  k.cy = cy / n;
  return k;
}

}  // namespace enavi::navstack
