#include "navstack/common/camera.h"

#include <cmath>

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

}  // namespace enavi::navstack
