#include "worlds/validate.h"

#include <cmath>

#include <gtest/gtest.h>

#include "worlds/detmath.h"
#include "worlds/obj_import.h"

namespace enavi::worlds {
namespace {

World Yard() {
  World w;
  w.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -5, 0), Eigen::Vector3d(5, 5, 3));
  w.start = Eigen::Vector3d(-3, 0, 1.5);
  w.goal = Eigen::Vector3d(3, 0, 1.5);
  return w;
}

Box MakeBox(Eigen::Vector3d centre, Eigen::Vector3d size, double yaw = 0.0) {
  Box b;
  b.center = centre;
  b.size = size;
  b.yaw = yaw;
  return b;
}

// Top view: a wall across the yard at x = 0, taller than the bounds, with one gap at y = 0.
//
//   y  5 |   ##   |
//        |   ##   |
//      0 | S gap G|
//        |   ##   |
//     -5 |   ##   |
//          -5  0  5  x
World WallWithGap(double gap) {
  World w = Yard();
  const double half = 0.5 * gap, len = 5.0 - half;
  w.objects.emplace_back(MakeBox({0, -half - 0.5 * len, 2}, {0.2, len, 4}));
  w.objects.emplace_back(MakeBox({0, half + 0.5 * len, 2}, {0.2, len, 4}));
  return w;
}

TEST(ValidateTest, WallWithANarrowGapHasNoMetreWideRoute) {
  const ValidationResult r = ValidateWorld(WallWithGap(0.6));
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.field, "goal");
  EXPECT_NE(r.reason.find("no collision-free route at least 1.00 m wide"), std::string::npos) << r.reason;
}

TEST(ValidateTest, WallWithAWideGapHasARoute) {
  const ValidationResult r = ValidateWorld(WallWithGap(1.5));
  EXPECT_TRUE(r.ok) << r.field << ": " << r.reason;
  EXPECT_DOUBLE_EQ(r.cell, 0.2);
  EXPECT_GT(r.cells_reached, 0);
}

TEST(ValidateTest, EmptyYardIsValid) {
  const ValidationResult r = ValidateWorld(Yard());
  EXPECT_TRUE(r.ok) << r.field << ": " << r.reason;
}

TEST(ValidateTest, StartAndGoalFailuresNameTheField) {
  World w = Yard();
  w.objects.emplace_back(MakeBox({-3, 0, 1}, {1, 1, 2}));
  ValidationResult r = ValidateWorld(w);
  EXPECT_EQ(r.field, "start");
  EXPECT_NE(r.reason.find("is inside objects[0] (box)"), std::string::npos) << r.reason;

  w = Yard();
  w.objects.emplace_back(MakeBox({3.8, 0, 1}, {1, 1, 4}));  // face at x = 3.3: 0.3 m from the goal
  r = ValidateWorld(w);
  EXPECT_EQ(r.field, "goal");
  EXPECT_NE(r.reason.find("is 0.30 m from objects[0] (box); needs at least 0.50 m clearance"), std::string::npos)
      << r.reason;

  w = Yard();
  w.goal = Eigen::Vector3d(6, 0, 1.5);
  r = ValidateWorld(w);
  EXPECT_EQ(r.field, "goal");
  EXPECT_NE(r.reason.find("outside the bounds"), std::string::npos) << r.reason;

  w = Yard();
  w.start.z() = 0.2;
  r = ValidateWorld(w);
  EXPECT_EQ(r.field, "start");
  EXPECT_NE(r.reason.find("0.20 m from the ground"), std::string::npos) << r.reason;

  w = Yard();
  w.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -5, 0), Eigen::Vector3d(2500, 5, 3));
  r = ValidateWorld(w);
  EXPECT_EQ(r.field, "bounds");
}

TEST(ValidateTest, BoxDistanceIsExactIncludingYaw) {
  World w = Yard();
  w.objects.emplace_back(MakeBox({0, 0, 1}, {2, 1, 2}, 0.5 * detmath::kPi));  // now 1 wide in x, 2 in y
  const ObstacleField f(w, /*include_ground=*/false);
  EXPECT_NEAR(f.Distance({1.5, 0, 1}), 1.0, 1e-12);                     // face at x = 0.5
  EXPECT_NEAR(f.Distance({0, 3, 1}), 2.0, 1e-12);                       // face at y = 1
  EXPECT_NEAR(f.Distance({1.5, 2, 3}), std::sqrt(1.0 + 1.0 + 1.0), 1e-12);  // corner
  EXPECT_NEAR(f.Distance({0, 0, 1}), -0.5, 1e-12);                      // inside: depth to the nearest face
}

TEST(ValidateTest, CylinderDistanceCoversSideCapAndRim) {
  World w = Yard();
  Cylinder c;
  c.base = {0, 0, 0};
  c.radius = 1.0;
  c.height = 2.0;
  w.objects.emplace_back(c);
  const ObstacleField f(w, false);
  EXPECT_NEAR(f.Distance({3, 0, 1}), 2.0, 1e-12);
  EXPECT_NEAR(f.Distance({0, 0, 2.5}), 0.5, 1e-12);
  EXPECT_NEAR(f.Distance({4, 0, 6}), 5.0, 1e-12);  // rim: (3, 4) triangle
  EXPECT_LT(f.Distance({0.5, 0, 1}), 0.0);
}

TEST(ValidateTest, EllipsoidDistanceMatchesADenseSurfaceSample) {
  World w = Yard();
  Ellipsoid e;
  e.center = {0, 0, 1.5};
  e.radii = {2.0, 0.7, 1.2};
  w.objects.emplace_back(e);
  const ObstacleField f(w, false);
  const Eigen::Vector3d probes[] = {{3.1, 0.4, 1.9}, {0.2, 1.5, 1.1}, {1.0, 1.0, 3.5}, {-2.6, -0.1, 0.2}};
  for (const auto& p : probes) {
    double best = 1e9;
    for (int i = 0; i <= 400; ++i) {
      for (int j = 0; j < 800; ++j) {
        const double polar = M_PI * i / 400, az = 2 * M_PI * j / 800;
        const Eigen::Vector3d q(e.center.x() + e.radii.x() * std::sin(polar) * std::cos(az),
                                e.center.y() + e.radii.y() * std::sin(polar) * std::sin(az),
                                e.center.z() + e.radii.z() * std::cos(polar));
        best = std::min(best, (q - p).norm());
      }
    }
    EXPECT_NEAR(f.Distance(p), best, 2e-3) << "probe " << p.transpose();
  }
  EXPECT_LT(f.Distance({0.5, 0.1, 1.5}), 0.0);
}

TEST(ValidateTest, ClosedMeshHasAnInsideAndAnOpenMeshOnlyASurface) {
  World w = Yard();
  MeshObject cube = PlaceMesh(ParseObj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                       "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
                                       "cube.obj"),
                              {}, "cube.obj", "cube.obj");
  cube.position = {1, 1, 0};
  cube.scale = 2.0;  // occupies [1, 3] x [1, 3] x [0, 2]
  w.objects.emplace_back(cube);
  ObstacleField f(w, false);
  EXPECT_NEAR(f.Distance({2, 2, 1}), -1.0, 1e-9);
  EXPECT_NEAR(f.Distance({4, 2, 1}), 1.0, 1e-9);

  cube.mesh.triangles.pop_back();  // a hole: no inside any more
  w.objects[0] = cube;
  ObstacleField open(w, false);
  EXPECT_GT(open.Distance({2, 2, 1}), 0.0);
}

TEST(ValidateTest, CoarseGridStillSeesAThinWall) {
  // 2 km x 2 km: the grid cell grows far beyond the wall's thickness, yet the wall must block.
  World w;
  w.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-1000, -1000, 0), Eigen::Vector3d(1000, 1000, 50));
  w.start = Eigen::Vector3d(-500, 0, 10);
  w.goal = Eigen::Vector3d(500, 0, 10);
  w.objects.emplace_back(MakeBox({0, 0, 25}, {0.1, 2000, 60}));
  ValidationOptions options;
  options.max_cells = 1'000'000;
  const ValidationResult r = ValidateWorld(w, options);
  EXPECT_GT(r.cell, 1.0) << "the grid should have been coarsened";
  EXPECT_FALSE(r.ok) << "a thin wall must not leak through a coarse grid";
  EXPECT_EQ(r.field, "goal");
}

TEST(ValidateTest, SegmentClearanceFindsTheObstacleOnTheLine) {
  World w = Yard();
  w.objects.emplace_back(MakeBox({0, 0.5, 1.5}, {0.2, 0.2, 0.2}));  // 0.4 m beside the line
  const ObstacleField f(w, false);
  EXPECT_NEAR(f.SegmentClearance(w.start, w.goal, 0.01), 0.4, 1e-9);
}

}  // namespace
}  // namespace enavi::worlds
