#include "worlds/mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <variant>

#include "worlds/detmath.h"
#include "worlds/primitives.h"
#include "worlds/world.h"

namespace enavi::worlds {
namespace {

// Adds quad a-b-c-d (counter-clockwise seen from outside) as two triangles.
void AddQuad(TriangleMesh* m, int a, int b, int c, int d) {
  m->triangles.emplace_back(a, b, c);
  m->triangles.emplace_back(a, c, d);
}

int AddVertex(TriangleMesh* m, double x, double y, double z) {
  m->vertices.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  return static_cast<int>(m->vertices.size()) - 1;
}

// Unit circle at kCylinderSegments (or kEllipsoidSlices) angles, from detmath for portability.
template <int N>
std::array<std::array<double, 2>, N> CirclePoints() {
  std::array<std::array<double, 2>, N> pts{};
  for (int k = 0; k < N; ++k) {
    detmath::SinCos(2.0 * detmath::kPi * k / N, &pts[k][1], &pts[k][0]);
  }
  return pts;
}

TriangleMesh BoxMesh(const Box& b) {
  TriangleMesh m;
  double s, c;
  detmath::SinCos(b.yaw, &s, &c);
  // Corner i has x = +hx if bit 0, y = +hy if bit 1, z = +hz if bit 2.
  for (int i = 0; i < 8; ++i) {
    const double lx = (i & 1 ? 0.5 : -0.5) * b.size.x();
    const double ly = (i & 2 ? 0.5 : -0.5) * b.size.y();
    const double lz = (i & 4 ? 0.5 : -0.5) * b.size.z();
    AddVertex(&m, b.center.x() + c * lx - s * ly, b.center.y() + s * lx + c * ly, b.center.z() + lz);
  }
  AddQuad(&m, 0, 2, 3, 1);  // -z
  AddQuad(&m, 4, 5, 7, 6);  // +z
  AddQuad(&m, 0, 1, 5, 4);  // -y
  AddQuad(&m, 2, 6, 7, 3);  // +y
  AddQuad(&m, 0, 4, 6, 2);  // -x
  AddQuad(&m, 1, 3, 7, 5);  // +x
  return m;
}

TriangleMesh CylinderMesh(const Cylinder& cyl) {
  constexpr int n = kCylinderSegments;
  static const auto circle = CirclePoints<n>();
  TriangleMesh m;
  for (int ring = 0; ring < 2; ++ring) {
    const double z = cyl.base.z() + (ring == 0 ? 0.0 : cyl.height);
    for (int k = 0; k < n; ++k) {
      AddVertex(&m, cyl.base.x() + cyl.radius * circle[k][0], cyl.base.y() + cyl.radius * circle[k][1], z);
    }
  }
  const int bottom_centre = AddVertex(&m, cyl.base.x(), cyl.base.y(), cyl.base.z());
  const int top_centre = AddVertex(&m, cyl.base.x(), cyl.base.y(), cyl.base.z() + cyl.height);
  for (int k = 0; k < n; ++k) {
    const int k1 = (k + 1) % n;
    AddQuad(&m, k, k1, n + k1, n + k);
    m.triangles.emplace_back(top_centre, n + k, n + k1);
    m.triangles.emplace_back(bottom_centre, k1, k);
  }
  return m;
}

TriangleMesh EllipsoidMesh(const Ellipsoid& e) {
  constexpr int slices = kEllipsoidSlices;
  constexpr int stacks = kEllipsoidStacks;
  static const auto circle = CirclePoints<slices>();
  static const auto meridian = CirclePoints<2 * stacks>();  // polar angles pi * i / stacks
  TriangleMesh m;
  const int north = AddVertex(&m, e.center.x(), e.center.y(), e.center.z() + e.radii.z());
  // Rings 1 .. stacks-1 from north to south; vertex of ring i, slice j: 1 + (i-1)*slices + j.
  for (int i = 1; i < stacks; ++i) {
    const double z = meridian[i][0];
    const double r = meridian[i][1];
    for (int j = 0; j < slices; ++j) {
      AddVertex(&m, e.center.x() + e.radii.x() * r * circle[j][0],
                e.center.y() + e.radii.y() * r * circle[j][1], e.center.z() + e.radii.z() * z);
    }
  }
  const int south = AddVertex(&m, e.center.x(), e.center.y(), e.center.z() - e.radii.z());
  auto ring = [](int i, int j) { return 1 + (i - 1) * slices + (j % slices); };
  for (int j = 0; j < slices; ++j) {
    m.triangles.emplace_back(north, ring(1, j), ring(1, j + 1));
    for (int i = 1; i + 1 < stacks; ++i) AddQuad(&m, ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1));
    m.triangles.emplace_back(south, ring(stacks - 1, j + 1), ring(stacks - 1, j));
  }
  return m;
}

}  // namespace

Eigen::AlignedBox3f TriangleMesh::Bounds() const {
  Eigen::AlignedBox3f box;  // empty
  for (const auto& v : vertices) box.extend(v);
  return box;
}

void TriangleMesh::Append(const TriangleMesh& other, const Eigen::Affine3f& X) {
  const int offset = static_cast<int>(vertices.size());
  const Eigen::Matrix4f& T = X.matrix();
  vertices.reserve(vertices.size() + other.vertices.size());
  // Scalar arithmetic in a fixed order (no SIMD fused multiply-add): the same floats everywhere.
  for (const auto& v : other.vertices) {
    Eigen::Vector3f out;
    for (int r = 0; r < 3; ++r) {
      float acc = T(r, 0) * v.x();
      acc = acc + T(r, 1) * v.y();
      acc = acc + T(r, 2) * v.z();
      out[r] = acc + T(r, 3);
    }
    vertices.push_back(out);
  }
  triangles.reserve(triangles.size() + other.triangles.size());
  for (const auto& t : other.triangles) triangles.emplace_back(t.x() + offset, t.y() + offset, t.z() + offset);
}

Eigen::Affine3d MeshObjectPose(const MeshObject& mesh) {
  double s, c;
  detmath::SinCos(mesh.yaw, &s, &c);
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(0, 0) = c * mesh.scale;
  T(0, 1) = -s * mesh.scale;
  T(1, 0) = s * mesh.scale;
  T(1, 1) = c * mesh.scale;
  T(2, 2) = mesh.scale;
  // The anchor offset is part of the rigid map: p_W = position + Rz(yaw) * scale * (offset + p).
  const Eigen::Vector3d& o = mesh.offset;
  T(0, 3) = mesh.position.x() + (T(0, 0) * o.x() + T(0, 1) * o.y());
  T(1, 3) = mesh.position.y() + (T(1, 0) * o.x() + T(1, 1) * o.y());
  T(2, 3) = mesh.position.z() + T(2, 2) * o.z();
  Eigen::Affine3d X;
  X.matrix() = T;
  return X;
}

std::size_t TriangleCount(const Object& object) {
  struct Visitor {
    std::size_t operator()(const Box&) const { return 12; }
    std::size_t operator()(const Cylinder&) const { return 4 * kCylinderSegments; }
    std::size_t operator()(const Ellipsoid&) const { return 2 * kEllipsoidSlices * (kEllipsoidStacks - 1); }
    std::size_t operator()(const MeshObject& m) const { return m.mesh.triangle_count(); }
  };
  return std::visit(Visitor{}, object);
}

TriangleMesh ObjectMesh(const Object& object) {
  struct Visitor {
    TriangleMesh operator()(const Box& b) const { return BoxMesh(b); }
    TriangleMesh operator()(const Cylinder& c) const { return CylinderMesh(c); }
    TriangleMesh operator()(const Ellipsoid& e) const { return EllipsoidMesh(e); }
    TriangleMesh operator()(const MeshObject& m) const {
      TriangleMesh out;
      out.Append(m.mesh, MeshObjectPose(m).cast<float>());
      return out;
    }
  };
  return std::visit(Visitor{}, object);
}

Eigen::AlignedBox3d ObjectBounds(const Object& object) {
  struct Visitor {
    Eigen::AlignedBox3d operator()(const Box& b) const {
      double s, c;
      detmath::SinCos(b.yaw, &s, &c);
      const double hx = std::abs(c) * 0.5 * b.size.x() + std::abs(s) * 0.5 * b.size.y();
      const double hy = std::abs(s) * 0.5 * b.size.x() + std::abs(c) * 0.5 * b.size.y();
      const Eigen::Vector3d h(hx, hy, 0.5 * b.size.z());
      return Eigen::AlignedBox3d(b.center - h, b.center + h);
    }
    Eigen::AlignedBox3d operator()(const Cylinder& c) const {
      return Eigen::AlignedBox3d(c.base - Eigen::Vector3d(c.radius, c.radius, 0.0),
                                 c.base + Eigen::Vector3d(c.radius, c.radius, c.height));
    }
    Eigen::AlignedBox3d operator()(const Ellipsoid& e) const {
      return Eigen::AlignedBox3d(e.center - e.radii, e.center + e.radii);
    }
    Eigen::AlignedBox3d operator()(const MeshObject& m) const {
      const Eigen::Affine3d X = MeshObjectPose(m);
      Eigen::AlignedBox3d box;
      for (const auto& v : m.mesh.vertices) box.extend(X * v.cast<double>());
      return box;
    }
  };
  return std::visit(Visitor{}, object);
}

const char* ObjectKind(const Object& object) {
  struct Visitor {
    const char* operator()(const Box&) const { return "box"; }
    const char* operator()(const Cylinder&) const { return "cylinder"; }
    const char* operator()(const Ellipsoid&) const { return "ellipsoid"; }
    const char* operator()(const MeshObject&) const { return "mesh"; }
  };
  return std::visit(Visitor{}, object);
}

TriangleMesh BuildWorldMesh(const World& world) {
  TriangleMesh mesh;
  std::size_t total = 0;
  for (const auto& o : world.objects) total += TriangleCount(o);
  mesh.triangles.reserve(total + 2);
  for (const auto& o : world.objects) mesh.Append(ObjectMesh(o));
  // Ground: two triangles over the bounds' xy, facing up.
  if (world.ground.enabled) {
    const auto& lo = world.bounds.min();
    const auto& hi = world.bounds.max();
    const double z = world.ground.z;
    const int a = AddVertex(&mesh, lo.x(), lo.y(), z);
    const int b = AddVertex(&mesh, hi.x(), lo.y(), z);
    const int c = AddVertex(&mesh, hi.x(), hi.y(), z);
    const int d = AddVertex(&mesh, lo.x(), hi.y(), z);
    AddQuad(&mesh, a, b, c, d);
  }
  return mesh;
}

}  // namespace enavi::worlds
