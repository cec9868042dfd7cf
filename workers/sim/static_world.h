#pragma once
// The world's triangles as a Bullet collision shape, built once per world and shared read-only
// by every episode (and every Bullet ray caster) in the process.

#include <cstddef>
#include <memory>

#include "worlds/mesh.h"

namespace enavi::sim {

/// Static triangle-mesh collision geometry (Bullet btBvhTriangleMeshShape over a
/// btTriangleIndexVertexArray, quantized AABB compression). Holds its own copy of the triangles,
/// the same ones the Embree camera sees. Immutable after construction: share it as
/// std::shared_ptr<const StaticCollisionWorld>; each user adds it to its own Bullet world.
class StaticCollisionWorld {
 public:
  struct Impl;

  /// @throws std::invalid_argument if a triangle index is out of range or a vertex is not finite.
  explicit StaticCollisionWorld(const worlds::TriangleMesh& mesh);
  ~StaticCollisionWorld();
  StaticCollisionWorld(const StaticCollisionWorld&) = delete;
  StaticCollisionWorld& operator=(const StaticCollisionWorld&) = delete;

  std::size_t triangle_count() const;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::sim
