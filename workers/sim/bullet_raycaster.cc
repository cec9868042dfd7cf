#include "workers/sim/bullet_raycaster.h"

#include <stdexcept>
#include <utility>

#include "workers/sim/bullet_impl.h"
#include "workers/sim/camera_rays.h"
#include "workers/sim/depth_camera.h"

namespace enavi::sim {

struct BulletRayCaster::Impl {
  navstack::CameraIntrinsics intrinsics;
  std::shared_ptr<const StaticCollisionWorld> static_world;
  PixelRays rays;
  std::unique_ptr<btDefaultCollisionConfiguration> configuration;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btCollisionWorld> world;
  std::unique_ptr<btCollisionObject> static_object;

  Impl(std::shared_ptr<const StaticCollisionWorld> w, const navstack::CameraIntrinsics& k)
      : intrinsics(k), static_world(std::move(w)), rays(k) {}
  ~Impl() {
    if (world && static_object) world->removeCollisionObject(static_object.get());
  }
};

BulletRayCaster::BulletRayCaster(std::shared_ptr<const StaticCollisionWorld> world,
                                 const navstack::CameraIntrinsics& intrinsics) {
  if (!world) throw std::invalid_argument("BulletRayCaster: static world is null");
  CheckIntrinsics(intrinsics);
  impl_ = std::make_unique<Impl>(std::move(world), intrinsics);
  Impl& s = *impl_;
  s.configuration = std::make_unique<btDefaultCollisionConfiguration>();
  s.dispatcher = std::make_unique<btCollisionDispatcher>(s.configuration.get());
  s.broadphase = std::make_unique<btDbvtBroadphase>();
  s.world = std::make_unique<btCollisionWorld>(s.dispatcher.get(), s.broadphase.get(),
                                               s.configuration.get());
  if (btCollisionShape* shape = s.static_world->impl().mutable_shape()) {
    s.static_object = std::make_unique<btCollisionObject>();
    s.static_object->setCollisionShape(shape);
    s.static_object->setCollisionFlags(btCollisionObject::CF_STATIC_OBJECT);
    s.world->addCollisionObject(s.static_object.get());
  }
}

BulletRayCaster::~BulletRayCaster() = default;
BulletRayCaster::BulletRayCaster(BulletRayCaster&&) noexcept = default;
BulletRayCaster& BulletRayCaster::operator=(BulletRayCaster&&) noexcept = default;

const navstack::CameraIntrinsics& BulletRayCaster::intrinsics() const {
  return impl_->intrinsics;
}

void BulletRayCaster::Render(const Eigen::Isometry3d& X_WC, navstack::DepthImage* out) {
  if (out == nullptr) throw std::invalid_argument("BulletRayCaster::Render: out is null");
  if (!X_WC.matrix().allFinite()) {
    throw std::invalid_argument("BulletRayCaster::Render: X_WC is not finite");
  }
  const Impl& s = *impl_;
  const navstack::CameraIntrinsics& k = s.intrinsics;
  *out = navstack::DepthImage(k.width, k.height);
  const CameraRayFrame frame(X_WC);
  const float min_range = static_cast<float>(k.min_range);
  const float max_range = static_cast<float>(k.max_range);
  const btVector3 from(frame.origin.x(), frame.origin.y(), frame.origin.z());
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      // The segment spans z-depth 0 .. max_range, so z-depth = hit fraction * max_range.
      const Eigen::Vector3f d = frame.Direction(s.rays.x_of_u[u], s.rays.y_of_v[v]) * max_range;
      const btVector3 to = from + btVector3(d.x(), d.y(), d.z());
      btCollisionWorld::ClosestRayResultCallback callback(from, to);
      s.world->rayTest(from, to, callback);
      out->at(u, v) = DepthOrNoReturn(callback.hasHit(),
                                      callback.m_closestHitFraction * max_range, min_range,
                                      max_range);
    }
  }
}

}  // namespace enavi::sim
