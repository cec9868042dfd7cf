#pragma once
// Private to enavi_sim: the Bullet objects behind StaticCollisionWorld.

#include <memory>
#include <vector>

#include <btBulletCollisionCommon.h>

#include "workers/sim/static_world.h"

namespace enavi::sim {

struct StaticCollisionWorld::Impl {
  std::vector<btScalar> vertices;  // x, y, z per vertex
  std::vector<int> indices;     // 3 per triangle
  std::unique_ptr<btTriangleIndexVertexArray> mesh_interface;
  // Null for a mesh without triangles: nothing to collide with.
  std::unique_ptr<btBvhTriangleMeshShape> shape;

  /// Bullet's API takes non-const shapes even where it only reads them; the shape is never
  /// modified after construction.
  btCollisionShape* mutable_shape() const { return shape.get(); }
};

}  // namespace enavi::sim
