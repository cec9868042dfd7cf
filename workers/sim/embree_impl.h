#pragma once
// Private to enavi_sim: the Embree handles behind EmbreeDevice and EmbreeScene.

#include <memory>
#include <vector>

#include <embree3/rtcore.h>

#include "workers/sim/embree_scene.h"
#include "workers/sim/moving_scene.h"

namespace enavi::sim {

struct EmbreeDevice::Impl {
  RTCDevice device = nullptr;
};

struct EmbreeScene::Impl {
  RTCDevice device = nullptr;  ///< the device the scene was made on
  RTCScene scene = nullptr;
  /// Per triangle, its plane in double: normal n = (b - a) x (c - a) and offset n . a, from the
  /// float corners (the depth camera's hit distances; depth_camera.cc).
  std::vector<Eigen::Vector4d> planes;
  std::size_t triangle_count = 0;
  Eigen::AlignedBox3f bounds;
  ~Impl();
};

struct MovingScene::Impl {
  RTCDevice device = nullptr;
  RTCScene movers = nullptr;  ///< the movers alone: geometry i is mover i
  std::shared_ptr<const EmbreeScene> world;  ///< the static world, rendered as without movers
  std::vector<worlds::TriangleMesh> local;   ///< movers' triangles in their own frames
  std::vector<RTCGeometry> geometries;       ///< movers' Embree triangle geometries
  std::vector<std::vector<Eigen::Vector4d>> mover_planes;  ///< at the last poses, as EmbreeScene's
  std::vector<const std::vector<Eigen::Vector4d>*> planes;  ///< mover_planes by geometry id
  std::vector<Eigen::AlignedBox3d> bounds_W;  ///< each mover's vertices at the last poses
  ~Impl();
};

/// Throws std::runtime_error naming `call` and Embree's message if the device has a pending
/// error (recorded by the device's error callback on this thread).
void ThrowIfEmbreeError(RTCDevice device, const char* call);

}  // namespace enavi::sim
