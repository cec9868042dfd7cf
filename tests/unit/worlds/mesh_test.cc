#include "worlds/mesh.h"

#include <map>
#include <utility>

#include <gtest/gtest.h>

#include "worlds/detmath.h"
#include "worlds/primitives.h"
#include "worlds/world.h"

namespace enavi::worlds {
namespace {

// Every triangle's normal points away from `centre` (outward winding for convex solids).
void ExpectOutward(const TriangleMesh& m, const Eigen::Vector3f& centre, const std::string& what) {
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    const auto& t = m.triangles[i];
    const Eigen::Vector3f a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    const Eigen::Vector3f centroid = (a + b + c) / 3.0f;
    EXPECT_GT(n.dot(centroid - centre), 0.0f) << what << ": triangle " << i << " faces inward";
  }
}

// Closed and consistently wound: each directed edge appears once and its reverse once.
void ExpectWatertight(const TriangleMesh& m, const std::string& what) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << what << ": edge " << edge.first << "->" << edge.second << " used " << count << " times";
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << what << ": edge without a twin";
  }
}

void ExpectBounds(const TriangleMesh& m, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float tol = 1e-5f) {
  const Eigen::AlignedBox3f b = m.Bounds();
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(b.min()[a], lo[a], tol) << "min along axis " << a;
    EXPECT_NEAR(b.max()[a], hi[a], tol) << "max along axis " << a;
  }
}

TEST(MeshTest, BoxIsTwelveOutwardTrianglesWithExactBounds) {
  Box box;
  box.center = {1.0, 2.0, 3.0};
  box.size = {2.0, 4.0, 6.0};
  const TriangleMesh m = ObjectMesh(box);
  EXPECT_EQ(m.triangle_count(), 12u);
  EXPECT_EQ(TriangleCount(box), 12u);
  ExpectBounds(m, {0, 0, 0}, {2, 4, 6});
  ExpectOutward(m, {1, 2, 3}, "box");
  ExpectWatertight(m, "box");
}

TEST(MeshTest, BoxYawRotatesAboutItsVerticalAxis) {
  Box box;
  box.size = {2.0, 4.0, 1.0};
  box.yaw = 0.5 * detmath::kPi;  // x extent becomes 4, y extent 2
  const TriangleMesh m = ObjectMesh(box);
  ExpectBounds(m, {-2, -1, -0.5f}, {2, 1, 0.5f});
  ExpectOutward(m, {0, 0, 0}, "yawed box");
  const Eigen::AlignedBox3d b = ObjectBounds(box);
  EXPECT_NEAR(b.max().x(), 2.0, 1e-12);
  EXPECT_NEAR(b.max().y(), 1.0, 1e-12);
}

TEST(MeshTest, CylinderHasSideAndCapsFacingOutward) {
  Cylinder c;
  c.base = {5.0, -1.0, 0.5};
  c.radius = 0.5;
  c.height = 3.0;
  const TriangleMesh m = ObjectMesh(c);
  EXPECT_EQ(m.triangle_count(), static_cast<std::size_t>(4 * kCylinderSegments));
  EXPECT_EQ(TriangleCount(c), m.triangle_count());
  ExpectBounds(m, {4.5f, -1.5f, 0.5f}, {5.5f, -0.5f, 3.5f});
  ExpectOutward(m, {5.0f, -1.0f, 2.0f}, "cylinder");
  ExpectWatertight(m, "cylinder");
}

TEST(MeshTest, EllipsoidIsAClosedUvSphereScaledByItsRadii) {
  Ellipsoid e;
  e.center = {0.0, 1.0, 2.0};
  e.radii = {3.0, 1.0, 0.5};
  const TriangleMesh m = ObjectMesh(e);
  EXPECT_EQ(m.triangle_count(), static_cast<std::size_t>(2 * kEllipsoidSlices * (kEllipsoidStacks - 1)));
  EXPECT_EQ(TriangleCount(e), m.triangle_count());
  ExpectBounds(m, {-3.0f, 0.0f, 1.5f}, {3.0f, 2.0f, 2.5f});
  ExpectOutward(m, {0.0f, 1.0f, 2.0f}, "ellipsoid");
  ExpectWatertight(m, "ellipsoid");
}

TEST(MeshTest, MeshObjectIsScaledThenYawedThenMoved) {
  MeshObject obj;
  obj.mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  obj.mesh.triangles = {{0, 1, 2}};
  obj.scale = 2.0;
  obj.yaw = 0.5 * detmath::kPi;
  obj.position = {10.0, 0.0, 1.0};
  const TriangleMesh m = ObjectMesh(obj);
  ASSERT_EQ(m.vertices.size(), 3u);
  // (1,0,0) -> scaled (2,0,0) -> yawed (0,2,0) -> moved (10,2,1).
  EXPECT_NEAR(m.vertices[1].x(), 10.0f, 1e-5f);
  EXPECT_NEAR(m.vertices[1].y(), 2.0f, 1e-5f);
  EXPECT_NEAR(m.vertices[1].z(), 1.0f, 1e-5f);
  EXPECT_NEAR(m.vertices[2].x(), 8.0f, 1e-5f);
  EXPECT_NEAR(m.vertices[2].y(), 0.0f, 1e-5f);
}

TEST(MeshTest, AppendOffsetsIndicesAndAppliesTheTransform) {
  TriangleMesh a;
  a.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  a.triangles = {{0, 1, 2}};
  TriangleMesh m = a;
  Eigen::Affine3f X = Eigen::Affine3f::Identity();
  X.translation() = Eigen::Vector3f(0, 0, 5);
  m.Append(a, X);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(3, 4, 5));
  EXPECT_FLOAT_EQ(m.vertices[4].z(), 5.0f);
  EXPECT_TRUE(TriangleMesh{}.Bounds().isEmpty());
}

TEST(MeshTest, WorldMeshHasEveryObjectAndTwoGroundTrianglesOverTheBounds) {
  World w;
  w.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-10, -5, 0), Eigen::Vector3d(10, 5, 4));
  w.ground.z = 0.25;
  w.objects.emplace_back(Box{});
  w.objects.emplace_back(Cylinder{});
  w.objects.emplace_back(Ellipsoid{});
  const TriangleMesh m = BuildWorldMesh(w);
  const std::size_t objects = 12 + 4 * kCylinderSegments + 2 * kEllipsoidSlices * (kEllipsoidStacks - 1);
  ASSERT_EQ(m.triangle_count(), objects + 2);
  // The ground: the last two triangles, facing up, spanning the bounds' xy at ground.z.
  Eigen::AlignedBox3f ground;
  for (std::size_t i = objects; i < objects + 2; ++i) {
    const auto& t = m.triangles[i];
    const Eigen::Vector3f n = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
    EXPECT_GT(n.z(), 0.0f) << "ground triangle " << i << " faces down";
    for (int k = 0; k < 3; ++k) ground.extend(m.vertices[t[k]]);
  }
  EXPECT_EQ(ground.min(), Eigen::Vector3f(-10, -5, 0.25f));
  EXPECT_EQ(ground.max(), Eigen::Vector3f(10, 5, 0.25f));

  w.ground.enabled = false;
  EXPECT_EQ(BuildWorldMesh(w).triangle_count(), objects);
}

TEST(MeshTest, WorldMeshIsDeterministic) {
  World w;
  w.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-10, -5, 0), Eigen::Vector3d(10, 5, 4));
  Box b;
  b.yaw = 0.7;
  w.objects.emplace_back(b);
  w.objects.emplace_back(Ellipsoid{});
  const TriangleMesh m1 = BuildWorldMesh(w), m2 = BuildWorldMesh(w);
  ASSERT_EQ(m1.vertices.size(), m2.vertices.size());
  for (std::size_t i = 0; i < m1.vertices.size(); ++i) EXPECT_EQ(m1.vertices[i], m2.vertices[i]);
  EXPECT_EQ(m1.triangles, m2.triangles);
}

}  // namespace
}  // namespace enavi::worlds
