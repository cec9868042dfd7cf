#pragma once
// Simulated depth camera: an Embree ray per pixel against the world's triangles.

#include <cstdint>

#include <Eigen/Geometry>

#include "navstack/common/camera.h"
#include "navstack/control/vehicle.h"
#include "workers/sim/embree_scene.h"

namespace enavi::sim {

class MovingScene;

/// Depth noise model: zero-mean Gaussian on z-depth with sigma = k * d^2 (stereo-like: error
/// grows with the square of depth). k = 0 disables noise (the default).
struct DepthNoise {
  double k = 0.0;  ///< 1/m; a RealSense D435 is roughly 0.001-0.005
};

/// How rays are handed to Embree. All modes give the same image; they differ only in speed.
/// kPacket16 (4x4 pixel tiles, coherent) was the fastest on the reference machine (AMD EPYC
/// Zen 4, AVX-512), see bench/sim/bench_sim.cc and the raycast benchmark.
enum class EmbreeRayMode {
  kSingle,    ///< rtcIntersect1 per pixel
  kPacket4,   ///< rtcIntersect4 over 2x2 tiles
  kPacket8,   ///< rtcIntersect8 over 4x2 tiles
  kPacket16,  ///< rtcIntersect16 over 4x4 tiles
  kStream,    ///< rtcIntersect1M over 16x16 tiles
};
const char* ToString(EmbreeRayMode mode);

/// Pinhole depth camera in optical frame C (z forward, x right, y down). Renders z-depth (along
/// the optical axis, not ray length) in metres; pixels whose nearest surface is outside
/// [min_range, max_range] are DepthImage::kNoReturn (a surface nearer than min_range hides what
/// is behind it, as on a real sensor). Stateless after construction: Render may be called from
/// several threads at once. Single-threaded per call: the farm parallelises episodes, not frames.
class DepthCamera {
 public:
  /// @throws std::invalid_argument naming the field if the intrinsics are unusable
  /// (size <= 0, focal length <= 0, ranges not 0 <= min_range < max_range) or noise.k < 0.
  explicit DepthCamera(const navstack::CameraIntrinsics& intrinsics, const DepthNoise& noise = {},
                       EmbreeRayMode mode = EmbreeRayMode::kPacket16);

  /// Renders `scene` seen from camera pose X_WC into `out` (resized to the intrinsics). With
  /// noise enabled, the same noise_seed gives the same image bit for bit.
  void Render(const EmbreeScene& scene, const Eigen::Isometry3d& X_WC, navstack::DepthImage* out,
              std::uint64_t noise_seed = 0) const;
  /// Renders a world with movers, at the poses of MovingScene's last SetPoses.
  void Render(const MovingScene& scene, const Eigen::Isometry3d& X_WC, navstack::DepthImage* out,
              std::uint64_t noise_seed = 0) const;

  const navstack::CameraIntrinsics& intrinsics() const { return intrinsics_; }
  const DepthNoise& noise() const { return noise_; }
  EmbreeRayMode mode() const { return mode_; }

 private:
  navstack::CameraIntrinsics intrinsics_;
  DepthNoise noise_;
  EmbreeRayMode mode_;
};

/// Adds the noise of `noise` to every valid pixel of `image` from a generator seeded with
/// `seed` (one draw per pixel, valid or not, so a pixel's noise does not depend on the others);
/// pixels pushed outside [min_range, max_range] become kNoReturn. No-op when noise.k == 0.
void ApplyDepthNoise(const DepthNoise& noise, const navstack::CameraIntrinsics& intrinsics,
                     std::uint64_t seed, navstack::DepthImage* image);

/// Orientation of the optical frame C in body frame B (camera looking along body +x):
/// optical z -> body x, optical x -> body -y, optical y -> body -z.
Eigen::Matrix3d CameraRotationInBody();

/// Camera pose in world from body pose: X_WC = X_WB * X_BC, X_BC = (CameraRotationInBody(),
/// vehicle.p_BC).
Eigen::Isometry3d CameraPoseInWorld(const Eigen::Isometry3d& X_WB,
                                    const navstack::VehicleParams& vehicle);

/// Checks intrinsics for rendering. @throws std::invalid_argument naming the field.
void CheckIntrinsics(const navstack::CameraIntrinsics& intrinsics);

}  // namespace enavi::sim
