#include "workers/sim/static_world.h"

#include "workers/sim/bullet_impl.h"
#include "workers/sim/mesh_check.h"

namespace enavi::sim {

StaticCollisionWorld::StaticCollisionWorld(const worlds::TriangleMesh& mesh)
    : impl_(std::make_unique<Impl>()) {
  CheckTriangleMesh(mesh, "StaticCollisionWorld");
  if (mesh.triangles.empty()) return;

  // Own copies with explicit strides: Bullet keeps pointers into these arrays.
  impl_->vertices.reserve(3 * mesh.vertices.size());
  for (const Eigen::Vector3f& p : mesh.vertices) {
    impl_->vertices.insert(impl_->vertices.end(), {p.x(), p.y(), p.z()});
  }
  impl_->indices.reserve(3 * mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    impl_->indices.insert(impl_->indices.end(), {t.x(), t.y(), t.z()});
  }
  impl_->mesh_interface = std::make_unique<btTriangleIndexVertexArray>(
      static_cast<int>(mesh.triangles.size()), impl_->indices.data(), 3 * sizeof(int),
      static_cast<int>(mesh.vertices.size()), impl_->vertices.data(), 3 * sizeof(btScalar));
  constexpr bool kQuantizedAabbCompression = true;
  constexpr bool kBuildBvh = true;
  impl_->shape = std::make_unique<btBvhTriangleMeshShape>(
      impl_->mesh_interface.get(), kQuantizedAabbCompression, kBuildBvh);
  // Surfaces are exact: no collision margin around the triangles.
  impl_->shape->setMargin(0.0f);
}

StaticCollisionWorld::~StaticCollisionWorld() = default;

std::size_t StaticCollisionWorld::triangle_count() const {
  return impl_->indices.size() / 3;
}

}  // namespace enavi::sim
