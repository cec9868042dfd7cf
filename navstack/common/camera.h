#pragma once
// Depth camera model and frames as the navigation stack sees them (simulator-agnostic).

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace enavi::navstack {

/// Pinhole camera. Optical frame C: z forward (optical axis), x right, y down.
struct CameraIntrinsics {
  int width = 640;
  int height = 480;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double min_range = 0.2;   ///< m; nearer returns are dropped
  double max_range = 10.0;  ///< m; d_per in the paper

  /// Intrinsics from image size and full horizontal/vertical field of view in degrees.
  static CameraIntrinsics FromFov(int width, int height, double hfov_deg, double vfov_deg,
                                  double min_range, double max_range);
  /// The farm's depth sensor at full resolution: 640x480, 87 x 58 deg, 0.2 - 10 m (RealSense
  /// D435-like).
  static CameraIntrinsics Default() { return FromFov(640, 480, 87.0, 58.0, 0.2, 10.0); }
  /// The stream the navigation stack reads by default: Default() decimated 2 x 2 (320x240).
  static CameraIntrinsics DefaultStream() { return Default().Decimated(2); }

  /// The same field of view through an n x n decimation (RealSense's decimation filter):
  /// floor(width / n) x floor(height / n) pixels, each one ray through the centre of an n x n
  /// block of this camera's pixels. Throws std::invalid_argument unless 1 <= n <= min(width, height).
  CameraIntrinsics Decimated(int n) const;

  /// Unit-depth ray direction of pixel centre (u, v) in frame C: (x, y, 1).
  Eigen::Vector3d PixelRay(double u, double v) const {
    return {(u + 0.5 - cx) / fx, (v + 0.5 - cy) / fy, 1.0};
  }
};

/// Depth image: z-depth in metres along the optical axis (not ray length), row-major,
/// data[v * width + u]. kNoReturn marks pixels with no surface within [min_range, max_range].
struct DepthImage {
  static constexpr float kNoReturn = 0.0f;
  int width = 0;
  int height = 0;
  std::vector<float> data;

  DepthImage() = default;
  DepthImage(int w, int h) : width(w), height(h), data(static_cast<std::size_t>(w) * h, kNoReturn) {}
  float at(int u, int v) const { return data[static_cast<std::size_t>(v) * width + u]; }
  float& at(int u, int v) { return data[static_cast<std::size_t>(v) * width + u]; }
  static bool Valid(float d) { return d > 0.0f; }
};

/// One sensor frame: the image and where the camera was when it was taken.
struct DepthFrame {
  std::int64_t index = 0;  ///< frame counter since episode start
  double t = 0.0;          ///< sim time of capture, s
  DepthImage image;
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();  ///< camera pose in world
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();            ///< vehicle velocity at capture
};
using DepthFramePtr = std::shared_ptr<const DepthFrame>;

}  // namespace enavi::navstack
