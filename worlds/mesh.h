#pragma once
// Triangle soup shared by the ray caster (Embree) and the physics (Bullet): one source of truth
// for what is solid, so the depth camera and the collision checker can never disagree.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace enavi::worlds {

struct World;

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3i> triangles;  ///< indices into vertices, counter-clockwise seen from outside

  std::size_t triangle_count() const { return triangles.size(); }
  Eigen::AlignedBox3f Bounds() const;
  /// Appends `other` transformed by `X` (rotation + translation, optional uniform scale inside X).
  void Append(const TriangleMesh& other, const Eigen::Affine3f& X = Eigen::Affine3f::Identity());
};

/// Everything solid in the world (objects and the ground over the bounds) as one mesh in the
/// world frame. Deterministic: the same World gives the same vertices in the same order.
TriangleMesh BuildWorldMesh(const World& world);

}  // namespace enavi::worlds
