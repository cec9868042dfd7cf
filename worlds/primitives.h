#pragma once
// Per-object geometry shared by the mesh export, the validator and the plots: tessellation,
// bounds, and the rigid placement of mesh objects.

#include <cstddef>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "worlds/mesh.h"
#include "worlds/world.h"

namespace enavi::worlds {

/// Tessellation of the curved primitives (fixed, so meshes are deterministic).
inline constexpr int kCylinderSegments = 24;
inline constexpr int kEllipsoidSlices = 16;  ///< around the z axis
inline constexpr int kEllipsoidStacks = 8;   ///< pole to pole

/// Triangles BuildWorldMesh emits for one object: box 12, cylinder 4 x segments,
/// ellipsoid 2 x slices x (stacks - 1), mesh its own count.
std::size_t TriangleCount(const Object& object);

/// The object as a closed triangle mesh in the world frame, outward (counter-clockwise) winding.
TriangleMesh ObjectMesh(const Object& object);

/// Axis-aligned bounds of the object in the world frame (exact for primitives, of the placed
/// mesh for mesh objects).
Eigen::AlignedBox3d ObjectBounds(const Object& object);

/// Placement of a mesh object: p_W = position + Rz(yaw) * (scale * (offset + p_object)).
/// Uses detmath, so it is the same transform on every machine.
Eigen::Affine3d MeshObjectPose(const MeshObject& mesh);

/// Short type name used in messages and plots: "box", "cylinder", "ellipsoid", "mesh".
const char* ObjectKind(const Object& object);

}  // namespace enavi::worlds
