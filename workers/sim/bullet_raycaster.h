#pragma once
// Reference depth renderer on Bullet's ray test, to compare the Embree camera against (speed and
// agreement): same pixel rays, same z-depth convention, same triangles.

#include <memory>

#include <Eigen/Geometry>

#include "navstack/common/camera.h"
#include "workers/sim/static_world.h"

namespace enavi::sim {

/// Depth image by btCollisionWorld::rayTest (closest hit) per pixel against a
/// StaticCollisionWorld. Owns a small Bullet collision world, so one instance serves one thread.
class BulletRayCaster {
 public:
  /// @throws std::invalid_argument if world is null or the intrinsics are unusable.
  BulletRayCaster(std::shared_ptr<const StaticCollisionWorld> world,
                  const navstack::CameraIntrinsics& intrinsics);
  ~BulletRayCaster();
  BulletRayCaster(BulletRayCaster&&) noexcept;
  BulletRayCaster& operator=(BulletRayCaster&&) noexcept;
  BulletRayCaster(const BulletRayCaster&) = delete;
  BulletRayCaster& operator=(const BulletRayCaster&) = delete;

  /// Renders the world seen from camera pose X_WC (optical frame, as DepthCamera) into `out`.
  void Render(const Eigen::Isometry3d& X_WC, navstack::DepthImage* out);

  const navstack::CameraIntrinsics& intrinsics() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::sim
